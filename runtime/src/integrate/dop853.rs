//! Dormand–Prince 8(5,3) (Hairer's `DOP853`).
//!
//! Coefficients from Hairer, Nørsett & Wanner, *Solving Ordinary Differential Equations I*
//! (2nd ed., §II.10), as in Hairer's `dop853.f`: 12 stages for the 8th-order solution, a
//! 5th-order and a 3rd-order error estimate combined as
//! `err = h·e5²/sqrt(n·(e5² + 0.01·e3²))` (sums of squares of the scaled estimates), and a
//! 7th-order continuous extension that needs 3 more stages.
//!
//! Consumes the right-hand side through the adaptive shell ([`AdaptiveStepper`]); produces
//! the 8th-order solution of each step, its combined error norm and, for a step that is
//! interpolated, the continuous extension.

// The coefficients are kept digit for digit as published (the compiler rounds them to f64).
#![allow(clippy::excessive_precision)]

use super::adaptive::{AdaptiveMethod, Step, StepControl};
use super::{AdaptiveStepper, Ode};
use crate::RuntimeError;
// For the documentation's links only.
#[cfg(doc)]
use super::AdaptiveOptions;

const C2: f64 = 0.526001519587677318785587544488e-01;
const C3: f64 = 0.789002279381515978178381316732e-01;
const C4: f64 = 0.118350341907227396726757197510;
const C5: f64 = 0.281649658092772603273242802490;
const C6: f64 = 0.333333333333333333333333333333;
const C7: f64 = 0.25;
const C8: f64 = 0.307692307692307692307692307692;
const C9: f64 = 0.651282051282051282051282051282;
const C10: f64 = 0.6;
const C11: f64 = 0.857142857142857142857142857142;
const C14: f64 = 0.1;
const C15: f64 = 0.2;
const C16: f64 = 0.777777777777777777777777777778;

const B1: f64 = 5.42937341165687622380535766363e-2;
const B6: f64 = 4.45031289275240888144113950566;
const B7: f64 = 1.89151789931450038304281599044;
const B8: f64 = -5.8012039600105847814672114227;
const B9: f64 = 3.1116436695781989440891606237e-1;
const B10: f64 = -1.52160949662516078556178806805e-1;
const B11: f64 = 2.01365400804030348374776537501e-1;
const B12: f64 = 4.47106157277725905176885569043e-2;

// 3rd-order estimate: b − bhh.
const BHH1: f64 = 0.244094488188976377952755905512;
const BHH2: f64 = 0.733846688281611857341361741547;
const BHH3: f64 = 0.220588235294117647058823529412e-01;

// 5th-order estimate.
const ER1: f64 = 0.1312004499419488073250102996e-01;
const ER6: f64 = -0.1225156446376204440720569753e+01;
const ER7: f64 = -0.4957589496572501915214079952;
const ER8: f64 = 0.1664377182454986536961530415e+01;
const ER9: f64 = -0.3503288487499736816886487290;
const ER10: f64 = 0.3341791187130174790297318841;
const ER11: f64 = 0.8192320648511571246570742613e-01;
const ER12: f64 = -0.2235530786388629525884427845e-01;

const A21: f64 = 5.26001519587677318785587544488e-2;
const A31: f64 = 1.97250569845378994544595329183e-2;
const A32: f64 = 5.91751709536136983633785987549e-2;
const A41: f64 = 2.95875854768068491816892993775e-2;
const A43: f64 = 8.87627564304205475450678981324e-2;
const A51: f64 = 2.41365134159266685502369798665e-1;
const A53: f64 = -8.84549479328286085344864962717e-1;
const A54: f64 = 9.24834003261792003115737966543e-1;
const A61: f64 = 3.7037037037037037037037037037e-2;
const A64: f64 = 1.70828608729473871279604482173e-1;
const A65: f64 = 1.25467687566822425016691814123e-1;
const A71: f64 = 3.7109375e-2;
const A74: f64 = 1.70252211019544039314978060272e-1;
const A75: f64 = 6.02165389804559606850219397283e-2;
const A76: f64 = -1.7578125e-2;
const A81: f64 = 3.70920001185047927108779319836e-2;
const A84: f64 = 1.70383925712239993810214054705e-1;
const A85: f64 = 1.07262030446373284651809199168e-1;
const A86: f64 = -1.53194377486244017527936158236e-2;
const A87: f64 = 8.27378916381402288758473766002e-3;
const A91: f64 = 6.24110958716075717114429577812e-1;
const A94: f64 = -3.36089262944694129406857109825;
const A95: f64 = -8.68219346841726006818189891453e-1;
const A96: f64 = 2.75920996994467083049415600797e1;
const A97: f64 = 2.01540675504778934086186788979e1;
const A98: f64 = -4.34898841810699588477366255144e1;
const A101: f64 = 4.77662536438264365890433908527e-1;
const A104: f64 = -2.48811461997166764192642586468;
const A105: f64 = -5.90290826836842996371446475743e-1;
const A106: f64 = 2.12300514481811942347288949897e1;
const A107: f64 = 1.52792336328824235832596922938e1;
const A108: f64 = -3.32882109689848629194453265587e1;
const A109: f64 = -2.03312017085086261358222928593e-2;
const A111: f64 = -9.3714243008598732571704021658e-1;
const A114: f64 = 5.18637242884406370830023853209;
const A115: f64 = 1.09143734899672957818500254654;
const A116: f64 = -8.14978701074692612513997267357;
const A117: f64 = -1.85200656599969598641566180701e1;
const A118: f64 = 2.27394870993505042818970056734e1;
const A119: f64 = 2.49360555267965238987089396762;
const A1110: f64 = -3.0467644718982195003823669022;
const A121: f64 = 2.27331014751653820792359768449;
const A124: f64 = -1.05344954667372501984066689879e1;
const A125: f64 = -2.00087205822486249909675718444;
const A126: f64 = -1.79589318631187989172765950534e1;
const A127: f64 = 2.79488845294199600508499808837e1;
const A128: f64 = -2.85899827713502369474065508674;
const A129: f64 = -8.87285693353062954433549289258;
const A1210: f64 = 1.23605671757943030647266201528e1;
const A1211: f64 = 6.43392746015763530355970484046e-1;

// The three extra stages of the continuous extension.
const A141: f64 = 5.61675022830479523392909219681e-2;
const A147: f64 = 2.53500210216624811088794765333e-1;
const A148: f64 = -2.46239037470802489917441475441e-1;
const A149: f64 = -1.24191423263816360469010140626e-1;
const A1410: f64 = 1.5329179827876569731206322685e-1;
const A1411: f64 = 8.20105229563468988491666602057e-3;
const A1412: f64 = 7.56789766054569976138603589584e-3;
const A1413: f64 = -8.298e-3;
const A151: f64 = 3.18346481635021405060768473261e-2;
const A156: f64 = 2.83009096723667755288322961402e-2;
const A157: f64 = 5.35419883074385676223797384372e-2;
const A158: f64 = -5.49237485713909884646569340306e-2;
const A1511: f64 = -1.08347328697249322858509316994e-4;
const A1512: f64 = 3.82571090835658412954920192323e-4;
const A1513: f64 = -3.40465008687404560802977114492e-4;
const A1514: f64 = 1.41312443674632500278074618366e-1;
const A161: f64 = -4.28896301583791923408573538692e-1;
const A166: f64 = -4.69762141536116384314449447206;
const A167: f64 = 7.68342119606259904184240953878;
const A168: f64 = 4.06898981839711007970213554331;
const A169: f64 = 3.56727187455281109270669543021e-1;
const A1613: f64 = -1.39902416515901462129418009734e-3;
const A1614: f64 = 2.9475147891527723389556272149;
const A1615: f64 = -9.15095847217987001081870187138;

// Continuous extension: rows 4–7, over the stages 1, 6–12 and 13 (the end derivative)–16.
const D4: [f64; 12] = [
    -0.84289382761090128651353491142e+01,
    0.56671495351937776962531783590,
    -0.30689499459498916912797304727e+01,
    0.23846676565120698287728149680e+01,
    0.21170345824450282767155149946e+01,
    -0.87139158377797299206789907490,
    0.22404374302607882758541771650e+01,
    0.63157877876946881815570249290,
    -0.88990336451333310820698117400e-01,
    0.18148505520854727256656404962e+02,
    -0.91946323924783554000451984436e+01,
    -0.44360363875948939664310572000e+01,
];
const D5: [f64; 12] = [
    0.10427508642579134603413151009e+02,
    0.24228349177525818288430175319e+03,
    0.16520045171727028198505394887e+03,
    -0.37454675472269020279518312152e+03,
    -0.22113666853125306036270938578e+02,
    0.77334326684722638389603898808e+01,
    -0.30674084731089398182061213626e+02,
    -0.93321305264302278729567221706e+01,
    0.15697238121770843886131091075e+02,
    -0.31139403219565177677282850411e+02,
    -0.93529243588444783865713862664e+01,
    0.35816841486394083752465898540e+02,
];
const D6: [f64; 12] = [
    0.19985053242002433820987653617e+02,
    -0.38703730874935176555105901742e+03,
    -0.18917813819516756882830838328e+03,
    0.52780815920542364900561016686e+03,
    -0.11573902539959630126141871134e+02,
    0.68812326946963000169666922661e+01,
    -0.10006050966910838403183860980e+01,
    0.77771377980534432092869265740,
    -0.27782057523535084065932004339e+01,
    -0.60196695231264120758267380846e+02,
    0.84320405506677161018159903784e+02,
    0.11992291136182789328035130030e+02,
];
const D7: [f64; 12] = [
    -0.25693933462703749003312586129e+02,
    -0.15418974869023643374053993627e+03,
    -0.23152937917604549567536039109e+03,
    0.35763911791061412378285349910e+03,
    0.93405324183624310003907691704e+02,
    -0.37458323136451633156875139351e+02,
    0.10409964950896230045147246184e+03,
    0.29840293426660503123344363579e+02,
    -0.43533456590011143754432175058e+02,
    0.96324553959188282948394950600e+02,
    -0.39177261675615439165231486172e+02,
    -0.14972683625798562581422125276e+03,
];

/// Adaptive Dormand–Prince 8(5,3) integrator (Hairer's `DOP853`) with dense output.
///
/// The 8th-order solution is propagated; step-size control uses the combined 5th/3rd-order
/// estimate with the controller exponent `1/8 − 0.2β`. The derivative at the new point is the
/// first stage of the next step (FSAL), so an accepted step costs 12 evaluations. Options:
/// start from [`AdaptiveOptions::dop853`] to get Hairer's defaults.
///
/// Dense output (7th order) costs 3 more evaluations; they are made only for a step that is
/// interpolated inside (at most once per step), so a caller that never samples within steps
/// pays nothing for it. It describes the step as computed, even if the state was modified
/// through [`Stepper::state_mut`] afterwards (`interpolate(t())` returns the modified state).
///
/// [`Stepper::state_mut`]: super::Stepper::state_mut
pub type Dop853<O> = AdaptiveStepper<O, Dop853Method>;

/// The stages of [`Dop853`], the last step as computed and its continuous extension.
/// The current state and its derivative are the shell's.
pub struct Dop853Method {
    x_stage: Vec<f64>,
    /// The last step as computed: start and end states, end derivative, and stages
    /// `k[0]` = f at the start, `k[1..12]` = stages 2–12; stages 14–16 of the dense output
    /// overwrite `k[1..4]` (not needed by it) when it is prepared.
    x_start: Vec<f64>,
    x_end: Vec<f64>,
    f_end: Vec<f64>,
    k: [Vec<f64>; 12],
    /// Continuous extension of the last step, valid when `dense_ready`.
    cont: [Vec<f64>; 8],
    dense_ready: bool,
}

impl<O: Ode> Dop853<O> {
    /// Mutable access to the system; call [`Stepper::reset`] afterwards if the change alters
    /// the derivative at the current state. Dense output of the last step is prepared first
    /// (with the system as it was), so that it keeps describing that step.
    ///
    /// [`Stepper::reset`]: super::Stepper::reset
    pub fn ode_mut(&mut self) -> Result<&mut O, RuntimeError> {
        self.method
            .prepare_dense(&mut self.ode, &mut self.control)?;
        self.dirty = true;
        Ok(&mut self.ode)
    }
}

impl AdaptiveMethod for Dop853Method {
    const ORDER: i32 = 8;
    /// Stages 2–12; the derivative at the new point is evaluated on acceptance.
    const EVALUATIONS_PER_TRIAL: usize = 11;

    fn error_exponent(beta: f64) -> f64 {
        0.125 - beta * 0.2
    }

    fn new(x0: &[f64]) -> Self {
        let zeros = vec![0.0; x0.len()];
        Dop853Method {
            x_stage: zeros.clone(),
            x_start: x0.to_vec(),
            x_end: x0.to_vec(),
            f_end: zeros.clone(),
            k: std::array::from_fn(|_| zeros.clone()),
            cont: std::array::from_fn(|_| zeros.clone()),
            dense_ready: false,
        }
    }

    /// Computes stages 2–12 of a trial step of size `h` from `(t, x)` with `k[0] = f(t, x)`:
    /// the step's end holds the 8th-order solution; returns the scaled error norm (NaN if
    /// anything is non-finite).
    fn trial<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<f64, RuntimeError> {
        let (opts, now, t, h) = (step.opts, step.now, step.t, step.h);
        let n = now.x.len();
        let (x, x_end, xs, k) = (&now.x, &mut step.next.x, &mut self.x_stage, &mut self.k);
        // Stage i: x + h·Σ_j a_ij k_j, evaluated into k[i − 1].
        macro_rules! stage {
            ($dst:expr, $c:expr, $($a:expr => $j:expr),+) => {{
                for i in 0..n {
                    xs[i] = x[i] + h * (0.0 $(+ $a * k[$j][i])+);
                }
                ode.rhs(t + $c * h, xs, &mut k[$dst])?;
            }};
        }
        k[0].copy_from_slice(&now.f);
        // Stage 2 associates as `dop853.f` does (`Y + H*A21*K1`), so steps match it exactly.
        for i in 0..n {
            xs[i] = x[i] + h * A21 * k[0][i];
        }
        ode.rhs(t + C2 * h, xs, &mut k[1])?;
        stage!(2, C3, A31 => 0, A32 => 1);
        stage!(3, C4, A41 => 0, A43 => 2);
        stage!(4, C5, A51 => 0, A53 => 2, A54 => 3);
        stage!(5, C6, A61 => 0, A64 => 3, A65 => 4);
        stage!(6, C7, A71 => 0, A74 => 3, A75 => 4, A76 => 5);
        stage!(7, C8, A81 => 0, A84 => 3, A85 => 4, A86 => 5, A87 => 6);
        stage!(8, C9, A91 => 0, A94 => 3, A95 => 4, A96 => 5, A97 => 6, A98 => 7);
        stage!(9, C10, A101 => 0, A104 => 3, A105 => 4, A106 => 5, A107 => 6, A108 => 7,
            A109 => 8);
        stage!(10, C11, A111 => 0, A114 => 3, A115 => 4, A116 => 5, A117 => 6, A118 => 7,
            A119 => 8, A1110 => 9);
        stage!(11, 1.0, A121 => 0, A124 => 3, A125 => 4, A126 => 5, A127 => 6, A128 => 7,
            A129 => 8, A1210 => 9, A1211 => 10);

        let (rtol, atol) = (opts.rtol, opts.atol);
        let (mut err5, mut err3) = (0.0, 0.0);
        let mut finite = true;
        for i in 0..n {
            let slope = B1 * k[0][i]
                + B6 * k[5][i]
                + B7 * k[6][i]
                + B8 * k[7][i]
                + B9 * k[8][i]
                + B10 * k[9][i]
                + B11 * k[10][i]
                + B12 * k[11][i];
            x_end[i] = x[i] + h * slope;
            let sk = atol + rtol * x[i].abs().max(x_end[i].abs());
            let e3 = slope - BHH1 * k[0][i] - BHH2 * k[8][i] - BHH3 * k[11][i];
            let e5 = ER1 * k[0][i]
                + ER6 * k[5][i]
                + ER7 * k[6][i]
                + ER8 * k[7][i]
                + ER9 * k[8][i]
                + ER10 * k[9][i]
                + ER11 * k[10][i]
                + ER12 * k[11][i];
            err3 += (e3 / sk).powi(2);
            err5 += (e5 / sk).powi(2);
            finite &= x_end[i].is_finite();
        }
        let deno = match err5 + 0.01 * err3 {
            d if d > 0.0 => d,
            _ => 1.0,
        };
        let err = h.abs() * err5 * (1.0 / (n.max(1) as f64 * deno)).sqrt();
        Ok(if finite { err } else { f64::NAN })
    }

    /// Evaluates the derivative at the step's end, and keeps the step as computed.
    fn accept<O: Ode>(&mut self, ode: &mut O, step: Step<'_>) -> Result<(), RuntimeError> {
        let next = step.next;
        // At `t + h`, where the stages put the step's end (the controller sets the last
        // step's end to `t_end` exactly).
        ode.rhs(step.t + step.h, &next.x, &mut next.f)?;
        step.stats.rhs_evaluations += 1;
        self.x_start.copy_from_slice(&step.now.x);
        self.x_end.copy_from_slice(&next.x);
        self.f_end.copy_from_slice(&next.f);
        self.dense_ready = false;
        Ok(())
    }

    /// Computes the continuous extension of the last step (3 evaluations), once.
    fn prepare_dense<O: Ode>(
        &mut self,
        ode: &mut O,
        control: &mut StepControl,
    ) -> Result<(), RuntimeError> {
        if self.dense_ready || control.t == control.t_prev {
            return Ok(());
        }
        let n = self.x_start.len();
        let (t, h) = (control.t_prev, control.t - control.t_prev);
        let (x, fe, xs) = (&self.x_start, &self.f_end, &mut self.x_stage);
        let k = &mut self.k;
        // The parts of rows 4–7 over stages 1 and 6–12, before k[1..4] are overwritten.
        let [c0, c1, c2, c3, c4, c5, c6, c7] = &mut self.cont;
        for i in 0..n {
            let stages = [
                k[0][i], k[5][i], k[6][i], k[7][i], k[8][i], k[9][i], k[10][i], k[11][i],
            ];
            let dot = |d: &[f64; 12]| stages.iter().zip(d).map(|(s, d)| s * d).sum::<f64>();
            let ydiff = self.x_end[i] - x[i];
            let bspl = h * k[0][i] - ydiff;
            c0[i] = x[i];
            c1[i] = ydiff;
            c2[i] = bspl;
            c3[i] = ydiff - h * fe[i] - bspl;
            c4[i] = dot(&D4);
            c5[i] = dot(&D5);
            c6[i] = dot(&D6);
            c7[i] = dot(&D7);
        }
        for i in 0..n {
            xs[i] = x[i]
                + h * (A141 * k[0][i]
                    + A147 * k[6][i]
                    + A148 * k[7][i]
                    + A149 * k[8][i]
                    + A1410 * k[9][i]
                    + A1411 * k[10][i]
                    + A1412 * k[11][i]
                    + A1413 * fe[i]);
        }
        ode.rhs(t + C14 * h, xs, &mut k[1])?;
        for i in 0..n {
            xs[i] = x[i]
                + h * (A151 * k[0][i]
                    + A156 * k[5][i]
                    + A157 * k[6][i]
                    + A158 * k[7][i]
                    + A1511 * k[10][i]
                    + A1512 * k[11][i]
                    + A1513 * fe[i]
                    + A1514 * k[1][i]);
        }
        ode.rhs(t + C15 * h, xs, &mut k[2])?;
        for i in 0..n {
            xs[i] = x[i]
                + h * (A161 * k[0][i]
                    + A166 * k[5][i]
                    + A167 * k[6][i]
                    + A168 * k[7][i]
                    + A169 * k[8][i]
                    + A1613 * fe[i]
                    + A1614 * k[1][i]
                    + A1615 * k[2][i]);
        }
        ode.rhs(t + C16 * h, xs, &mut k[3])?;
        control.stats.rhs_evaluations += 3;
        for i in 0..n {
            // Summed left to right onto the first part, as `dop853.f` does.
            let tail = [fe[i], k[1][i], k[2][i], k[3][i]];
            let add =
                |c: f64, d: &[f64; 12]| tail.iter().zip(&d[8..]).fold(c, |a, (s, d)| a + s * d);
            c4[i] = h * add(c4[i], &D4);
            c5[i] = h * add(c5[i], &D5);
            c6[i] = h * add(c6[i], &D6);
            c7[i] = h * add(c7[i], &D7);
        }
        self.dense_ready = true;
        Ok(())
    }

    fn interpolate(&mut self, _t: f64, s: f64, out: &mut [f64]) -> Result<(), RuntimeError> {
        let s1 = 1.0 - s;
        let [c0, c1, c2, c3, c4, c5, c6, c7] = &self.cont;
        for (i, o) in out.iter_mut().enumerate() {
            let conpar = c4[i] + s * (c5[i] + s1 * (c6[i] + s * c7[i]));
            *o = c0[i] + s * (c1[i] + s1 * (c2[i] + s * (c3[i] + s1 * conpar)));
        }
        Ok(())
    }
}
