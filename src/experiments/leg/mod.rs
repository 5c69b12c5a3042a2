//! One HAMR leg as the experiments drive it: the model with its two drive voltages, the
//! foot position output, static equilibria (optionally with the foot against a sensor) and
//! the force/deflection procedure of the paper (seed Sec. V.A, Fig. 7).
//!
//! `mech fit` and `mech diagnose` also hold other models in a [`Leg`] (e.g. the flexure
//! pendulum rig, which has neither drive nor foot): [`Leg::open_any`] opens a model without
//! the HAMR ports, and the HAMR-only methods ([`Leg::inputs`], [`Leg::foot_at`], ...) are
//! for legs that have them ([`Leg::require_hamr`]).

use mech_codegen::ir::transform::AXES;
use mech_runtime::{
    assemble, solve_statics_with_loads, AssemblyOptions, Equilibrium, Fixture, Linearization,
    Model, SideLoad, StaticsOptions,
};
use serde::Deserialize;

mod error;

pub use error::Error;

use crate::session::ModelSpec;
use crate::session::Session;

/// A degree of freedom of the leg.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dof {
    Lift,
    Swing,
}

impl Dof {
    pub fn name(self) -> &'static str {
        match self {
            Dof::Lift => "lift",
            Dof::Swing => "swing",
        }
    }
    /// The drive input.
    pub fn input(self) -> &'static str {
        match self {
            Dof::Lift => "v_lift",
            Dof::Swing => "v_swing",
        }
    }
    /// The actuator coordinate.
    pub fn actuator(self) -> &'static str {
        match self {
            Dof::Lift => "qlact",
            Dof::Swing => "qsact",
        }
    }
    /// The on-axis direction of the paper's force tests: z for lift, x for swing (Sec. V.A).
    pub fn axis(self) -> usize {
        match self {
            Dof::Lift => 2,
            Dof::Swing => 0,
        }
    }
    /// `"+z"`/`"-z"` (lift) or `"+x"`/`"-x"` (swing): the way the foot moves along the
    /// dof's axis, as ±1; `None` for any other text.
    pub fn direction(self, text: &str) -> Option<f64> {
        let axis = if self.axis() == 2 { 'z' } else { 'x' };
        let mut chars = text.trim().chars();
        let sign = match chars.next() {
            Some('+') => 1.0,
            Some('-') => -1.0,
            _ => return None,
        };
        match (chars.next(), chars.next()) {
            (Some(a), None) if a == axis => Some(sign),
            _ => None,
        }
    }
    /// The crank-arm parameter (`l_i`, `s_i`) that sets the transmission ratio.
    pub fn arm(self) -> &'static str {
        match self {
            Dof::Lift => "lift_arm",
            Dof::Swing => "swing_arm",
        }
    }
}

/// An opened leg model.
pub struct Leg {
    pub session: Session,
    pub independent: Vec<usize>,
    /// The HAMR drive inputs and foot output; `None` for a model without them (opened by
    /// [`Leg::open_any`]).
    ports: Option<Ports>,
    /// The assembled initial state (loops closed, no load).
    pub q0: Vec<f64>,
    /// Where a rest equilibrium's Newton starts again when it fails from `q0`: `q0`, or for
    /// a model extension the base model's rest with the new coordinates at 0
    /// ([`Leg::start_rest_at`], [`Leg::warm_rest`]). From `q0`, a leg with stiff off-axis
    /// springs and a preload (HAMR-V2.0) must move its hinges by 0.08 rad through nonlinear
    /// kinematics that couple into the stiff directions, and Newton's halved steps stall;
    /// from the base model's rest it converges in 2–3. (Only as the second start: starting
    /// every extension there moves its fits by round-off, enough to reorder near-ties of the
    /// catalog's tests.)
    pub rest_start: Vec<f64>,
}

/// A HAMR leg's drive inputs and foot output (indices into the model's inputs and outputs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Ports {
    v_lift: usize,
    v_swing: usize,
    /// Output indices of foot.x, foot.y, foot.z.
    foot: [usize; 3],
}

/// The coordinates a HAMR leg holds independent when closing its loops, unless its
/// experiment file names others: the swing and lift actuator tips.
const ACTUATOR_COORDINATES: [&str; 2] = ["qsact", "qlact"];

impl Leg {
    pub fn open(spec: &ModelSpec) -> Result<Leg, Error> {
        Leg::open_with(spec, &[])
    }

    /// As [`Leg::open`], with `params` (name, SI value) set after `spec.set`: sweeps set
    /// their values directly, without a round trip through text.
    pub fn open_with(spec: &ModelSpec, params: &[(&str, f64)]) -> Result<Leg, Error> {
        let session = open_session(spec)?;
        // Checked before the assembly, whose default independent coordinates are HAMR's.
        hamr_ports(&session.model, &spec.path.display().to_string())?;
        Leg::from_session(session, spec, params)
    }

    /// As [`Leg::open_with`] for any model: the HAMR drive and foot are optional (a model
    /// without them, e.g. the flexure pendulum rig, only serves the experiments that do not
    /// drive it; those that do check [`Leg::require_hamr`]).
    pub fn open_any(spec: &ModelSpec, params: &[(&str, f64)]) -> Result<Leg, Error> {
        Leg::from_session(open_session(spec)?, spec, params)
    }

    /// A leg from an opened session (e.g. of a transformed model), with `params` set. The
    /// HAMR ports are optional, as for [`Leg::open_any`].
    pub fn from_session(
        mut session: Session,
        spec: &ModelSpec,
        params: &[(&str, f64)],
    ) -> Result<Leg, Error> {
        for &(name, value) in params {
            let index = session
                .model
                .param_index(name)
                .ok_or_else(|| Error::NoParameter {
                    model: spec.path.display().to_string(),
                    name: name.to_string(),
                    purpose: None,
                })?;
            session.model.set_param(index, value);
        }
        let ports = hamr_ports(&session.model, "").ok();
        let independent = match (&ports, spec.independent.is_empty()) {
            (Some(_), true) => ACTUATOR_COORDINATES.map(String::from).to_vec(),
            _ => spec.independent.clone(),
        };
        let state = session.assemble(&independent)?;
        Ok(Leg {
            independent: state.independent.clone(),
            rest_start: state.q.clone(),
            q0: state.q,
            session,
            ports,
        })
    }

    /// Starts rest equilibria at `rest` of `other` (another model of the same mechanism,
    /// e.g. the one this leg extends), coordinate by name; coordinates `other` lacks keep
    /// their `q0` values. Kept only if the loops close there (else `q0` stays the start).
    pub fn start_rest_at(&mut self, other: &Leg, rest: &[f64]) {
        let model = self.model();
        let mut start = self.q0.clone();
        for (i, value) in start.iter_mut().enumerate() {
            if let Some(j) = other.model().coordinate_index(model.coordinate_name(i)) {
                *value = rest[j];
            }
        }
        let mut phi = vec![0.0_f64; model.nc()];
        model.constraints(0.0, &start, &mut phi);
        if phi.iter().all(|p| p.abs() <= 1e-9) {
            self.rest_start = start;
        }
    }

    /// An error naming the model unless the leg has HAMR's drive inputs `v_lift` and
    /// `v_swing` and the foot position output `foot`, which the HAMR-only methods use.
    pub fn require_hamr(&self) -> Result<(), Error> {
        hamr_ports(self.model(), self.model().name()).map(|_| ())
    }

    /// The HAMR ports; panics for a leg without them (a programming error: every path
    /// that reaches a HAMR-only method opened the leg with [`Leg::open`] or checked
    /// [`Leg::require_hamr`]).
    fn ports(&self) -> Ports {
        self.ports
            .expect("a HAMR-only method on a model without v_lift, v_swing and foot")
    }

    /// The index of the input `v_lift` (HAMR legs only).
    pub fn v_lift(&self) -> usize {
        self.ports().v_lift
    }

    /// The index of the input `v_swing` (HAMR legs only).
    pub fn v_swing(&self) -> usize {
        self.ports().v_swing
    }

    /// The output indices of foot.x, foot.y, foot.z (HAMR legs only).
    pub fn foot(&self) -> [usize; 3] {
        self.ports().foot
    }

    pub fn model(&self) -> &dyn Model {
        &self.session.model
    }

    /// A model parameter's value (SI), if the model has it.
    pub fn param(&self, name: &str) -> Option<f64> {
        let model = &self.session.model;
        model.param_index(name).map(|i| model.param(i))
    }

    /// The model's inputs at their defaults with the drive voltages set (HAMR legs only).
    pub fn inputs(&self, lift: f64, swing: f64) -> Vec<f64> {
        let ports = self.ports();
        let mut inputs = self.default_inputs();
        inputs[ports.v_lift] = lift;
        inputs[ports.v_swing] = swing;
        inputs
    }

    pub fn drive(&self, dof: Dof, volts: f64) -> Vec<f64> {
        match dof {
            Dof::Lift => self.inputs(volts, 0.0),
            Dof::Swing => self.inputs(0.0, volts),
        }
    }

    pub fn foot_at(&self, q: &[f64], inputs: &[f64]) -> [f64; 3] {
        let model = self.model();
        let mut y = vec![0.0; model.noutputs()];
        model.outputs(0.0, q, &vec![0.0; model.nu()], inputs, &mut y);
        self.foot().map(|i| y[i])
    }

    /// The static equilibrium nearest `start` under `inputs` and `fixtures` (the runtime's
    /// `solve_statics`).
    pub fn equilibrium(
        &self,
        start: &[f64],
        inputs: &[f64],
        fixtures: &[Fixture],
    ) -> Result<Equilibrium, Error> {
        self.loaded_equilibrium(start, inputs, fixtures, &[])
    }

    /// [`Leg::equilibrium`] with side loads on the fixtures (`solve_statics_with_loads`).
    pub fn loaded_equilibrium(
        &self,
        start: &[f64],
        inputs: &[f64],
        fixtures: &[Fixture],
        loads: &[SideLoad],
    ) -> Result<Equilibrium, Error> {
        let mut q = start.to_vec();
        solve_statics_with_loads(
            self.model(),
            0.0,
            &mut q,
            inputs,
            fixtures,
            loads,
            &StaticsOptions::default(),
        )
        .map_err(|error| Error::Statics {
            model: self.model().name().to_string(),
            error,
        })
    }

    /// [`Leg::loaded_equilibrium`] started from the solution `warm` holds in `slot` (a
    /// previous sweep's, with parameters a fit has since moved a little), else from `start`;
    /// the solution is recorded in the slot. A warm start that fails is retried from `start`.
    pub fn warm_equilibrium(
        &self,
        warm: &mut WarmStarts,
        slot: usize,
        start: &[f64],
        inputs: &[f64],
        fixtures: &[Fixture],
        loads: &[SideLoad],
    ) -> Result<Equilibrium, Error> {
        let solved = match warm.slots.get(slot) {
            Some(Some(previous)) if previous.len() == start.len() => self
                .loaded_equilibrium(previous, inputs, fixtures, loads)
                .or_else(|_| self.loaded_equilibrium(start, inputs, fixtures, loads)),
            _ => self.loaded_equilibrium(start, inputs, fixtures, loads),
        }?;
        if warm.slots.len() <= slot {
            warm.slots.resize(slot + 1, None);
        }
        warm.slots[slot] = Some(solved.q.clone());
        Ok(solved)
    }

    /// The rest equilibrium under `inputs` as [`Leg::warm_equilibrium`] in `slot`, from
    /// `q0`; where that fails, again from [`Leg::rest_start`] if it is another start.
    pub fn warm_rest(
        &self,
        warm: &mut WarmStarts,
        slot: usize,
        inputs: &[f64],
    ) -> Result<Equilibrium, Error> {
        self.warm_equilibrium(warm, slot, &self.q0, inputs, &[], &[])
            .or_else(|error| {
                if self.rest_start == self.q0 {
                    Err(error)
                } else {
                    self.warm_equilibrium(warm, slot, &self.rest_start, inputs, &[], &[])
                }
            })
    }

    /// The model's inputs at their default signals' values at t = 0 (any model).
    pub fn default_inputs(&self) -> Vec<f64> {
        self.session.signals.iter().map(|s| s.value(0.0)).collect()
    }

    /// The rest equilibrium under the default inputs (from `q0`) and the linearization
    /// about it in the leg's independent coordinates.
    pub fn rest_linearization(&self) -> Result<(Vec<f64>, Linearization), Error> {
        let inputs = self.default_inputs();
        let rest_q = self.equilibrium(&self.q0, &inputs, &[])?.q;
        let linear =
            mech_runtime::linearize(self.model(), 0.0, &rest_q, &inputs, &self.independent)
                .map_err(Error::Linearization)?;
        Ok((rest_q, linear))
    }

    /// A fixture holding the listed foot components at `target`.
    pub fn fixture(&self, target: [f64; 3], components: Vec<usize>) -> Fixture {
        Fixture {
            name: "foot".into(),
            outputs: self.foot(),
            target,
            components,
        }
    }

    /// How far the loop kinematics alone let the foot move from its rest position along
    /// `dof`'s axis in `direction` (±1), the other actuator held: `dof`'s actuator is walked
    /// from rest in steps of 1 µm (each configuration closed from the last) until the foot
    /// turns back (a toggle of the linkage: a maximum of the foot's travel, refined by a
    /// parabola through the three steps around it) or the loops stop closing; `None` when the
    /// foot still advances after `travel` of the actuator. No actuator force can push the foot
    /// beyond this.
    pub fn stroke_limit(
        &self,
        dof: Dof,
        direction: f64,
        travel: f64,
    ) -> Result<Option<StrokeLimit>, Error> {
        const STEP: f64 = 1e-6;
        let actuator = self.session.coordinate_index(dof.actuator())?;
        let axis = dof.axis();
        let inputs = self.inputs(0.0, 0.0);
        let rest = self.foot_at(&self.q0, &inputs)[axis];
        // The actuator's way that moves the foot in `direction`.
        let sign = direction * self.kinematic_ratio(&self.q0, dof, axis)?.signum();
        let mut q = self.q0.clone();
        // The foot's travel (along `direction`) at the last two closed steps.
        let (mut before, mut last) = (f64::NAN, 0.0);
        for k in 1..=(travel / STEP).ceil() as usize {
            let mut next = q.clone();
            next[actuator] = self.q0[actuator] + sign * STEP * k as f64;
            let closed = assemble(
                self.model(),
                0.0,
                &mut next,
                &self.independent,
                &AssemblyOptions::default(),
            );
            let moved = closed
                .ok()
                .map(|_| direction * (self.foot_at(&next, &inputs)[axis] - rest));
            let limit = match moved {
                Some(travelled) if travelled > last => {
                    (before, last) = (last, travelled);
                    q = next;
                    continue;
                }
                // The foot turned back: the vertex of the parabola through the last three.
                Some(travelled) if before.is_finite() => {
                    let curvature = before - 2.0 * last + travelled;
                    let offset = 0.5 * (before - travelled) / curvature;
                    StrokeLimit {
                        foot: last - 0.25 * (before - travelled) * offset,
                        actuator: STEP * ((k - 1) as f64 + offset),
                    }
                }
                // The loops stop closing (or the foot never advanced): the last closed step.
                _ => StrokeLimit {
                    foot: last,
                    actuator: STEP * (k - 1) as f64,
                },
            };
            return Ok(Some(limit));
        }
        Ok(None)
    }

    /// Small-motion ratio of foot displacement along `axis` to the actuator's displacement,
    /// from the loop kinematics at `q` (central differences of the assembled foot position).
    pub fn kinematic_ratio(&self, q: &[f64], dof: Dof, axis: usize) -> Result<f64, Error> {
        let actuator = self.session.coordinate_index(dof.actuator())?;
        let h = 1e-7;
        let inputs = self.inputs(0.0, 0.0);
        let at = |delta: f64| -> Result<f64, Error> {
            let mut q = q.to_vec();
            q[actuator] += delta;
            assemble(
                self.model(),
                0.0,
                &mut q,
                &self.independent,
                &AssemblyOptions::default(),
            )
            .map_err(Error::Assembly)?;
            Ok(self.foot_at(&q, &inputs)[axis])
        };
        Ok((at(h)? - at(-h)?) / (2.0 * h))
    }
}

fn open_session(spec: &ModelSpec) -> Result<Session, Error> {
    Session::open(&spec.path, &spec.set, &[]).map_err(|error| Error::Model {
        model: spec.path.clone(),
        error: Box::new(error),
    })
}

/// The HAMR ports of `model` (named `shown` in errors), or what is missing.
fn hamr_ports(model: &dyn Model, shown: &str) -> Result<Ports, Error> {
    let missing = |what: String| Error::NotHamr {
        model: shown.to_string(),
        missing: what,
    };
    let input = |name: &str| {
        model.input_index(name).ok_or_else(|| {
            missing(format!(
                "input `{name}` (a HAMR leg needs v_lift and v_swing)"
            ))
        })
    };
    let (v_lift, v_swing) = (input("v_lift")?, input("v_swing")?);
    let mut foot = [0; 3];
    for (slot, axis) in foot.iter_mut().zip(AXES) {
        *slot = model
            .output_index(&format!("foot.{axis}"))
            .ok_or_else(|| missing("position output `foot`".into()))?;
    }
    Ok(Ports {
        v_lift,
        v_swing,
        foot,
    })
}

/// The equilibria a sweep solved, by slot (its own numbering: rest, free, one per sensor
/// position or data row), for [`Leg::warm_equilibrium`]. A fit predicts the same sweep many
/// times with parameters that move a little: started from the last prediction's equilibria,
/// Newton takes about half the iterations (one step and the polish) that a start from the
/// previous sensor position takes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WarmStarts {
    slots: Vec<Option<Vec<f64>>>,
    /// The warm starts of the separate sweeps of one prediction (one per test).
    parts: Vec<WarmStarts>,
}

impl WarmStarts {
    /// The warm starts of the `index`-th of several sweeps predicted together.
    pub fn part(&mut self, index: usize) -> &mut WarmStarts {
        if self.parts.len() <= index {
            self.parts.resize_with(index + 1, WarmStarts::default);
        }
        &mut self.parts[index]
    }
}

/// One sensor position of a force/deflection test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPoint {
    /// Distance of the sensor from the foot's rest position along the motion (m, ≥ 0).
    pub distance: f64,
    /// Force of the foot on the sensor along the motion direction (N, ≥ 0 when pushing).
    pub force: f64,
    /// Force of the foot on the sensor along y (N).
    pub force_y: f64,
    /// The foot's y displacement from rest (m).
    pub foot_y: f64,
}

/// A force/deflection test of one degree of freedom at one voltage.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceDeflection {
    pub dof: Dof,
    pub axis: usize,
    pub voltage: f64,
    /// The rest equilibrium (no drive).
    pub rest_q: Vec<f64>,
    /// The foot at rest (no drive) and free at `voltage` (m, chassis frame).
    pub rest: [f64; 3],
    pub free: [f64; 3],
    /// Free deflection along the axis, one way, from rest (m, ≥ 0; `direction` gives the sign).
    pub free_deflection: f64,
    /// +1 or −1: the direction of the foot's free motion along the axis.
    pub direction: f64,
    /// The sensor at increasing distances, from 0 until the free foot no longer reaches it.
    pub points: Vec<SensorPoint>,
    /// Fraction of the on-axis force applied along y (opposing the free foot's y motion).
    pub off_axis_fraction: f64,
}

impl ForceDeflection {
    /// The blocked force: the on-axis force with the sensor at the foot's rest position.
    pub fn blocked_force(&self) -> f64 {
        self.points.first().map_or(0.0, |p| p.force)
    }
    /// `F·d` of Table IV: blocked force times free deflection (J).
    pub fn work(&self) -> f64 {
        self.blocked_force() * self.free_deflection
    }
}

/// The kinematic limit of a foot's travel ([`Leg::stroke_limit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeLimit {
    /// The foot's largest travel from rest along the axis, in the direction asked (m, ≥ 0).
    pub foot: f64,
    /// The actuator's travel from rest there (m, ≥ 0).
    pub actuator: f64,
}

/// Where the force sensor of a [`ForceTest`] is placed: distances from the foot's rest
/// position along its free motion.
#[derive(Debug, Clone, PartialEq)]
pub enum Sensor {
    /// Only at the foot's rest position (the blocked force).
    Blocked,
    /// At `0, step, 2·step, …` until the free foot no longer reaches it (the paper's 127 µm).
    Steps(f64),
    /// At these distances (measured data's sensor positions), in this order; one beyond the
    /// free deflection is not touched (force 0, the foot free).
    At(Vec<f64>),
}

impl Sensor {
    /// The sensor's `k`-th distance from the foot's rest position, or `None` after the last.
    fn position(&self, k: usize, free_deflection: f64) -> Option<f64> {
        match self {
            Sensor::Blocked => (k == 0).then_some(0.0),
            Sensor::Steps(step) if k > 0 && k as f64 * step >= free_deflection => None,
            Sensor::Steps(step) => Some(k as f64 * step),
            Sensor::At(distances) => distances.get(k).copied(),
        }
    }
}

/// The paper's force/deflection test (seed Sec. V.A, Fig. 7): the leg driven at `voltage`
/// on `dof` pushes against a sensor (a frictionless plane normal to the dof's axis) placed
/// as `sensor` says. With `off_axis_fraction = c > 0` the sensor also pushes on the foot
/// along y with `c` times the on-axis force, opposing the free foot's y motion (the paper's
/// ~30 % off-axis load): a side load of the sensor's fixture ([`SideLoad`]).
#[derive(Clone, Debug)]
pub struct ForceTest {
    pub dof: Dof,
    /// Drive voltage of the dof's input (V).
    pub voltage: f64,
    pub sensor: Sensor,
    pub off_axis_fraction: f64,
}

impl ForceTest {
    /// The test without off-axis load.
    pub fn new(dof: Dof, voltage: f64, sensor: Sensor) -> ForceTest {
        ForceTest {
            dof,
            voltage,
            sensor,
            off_axis_fraction: 0.0,
        }
    }

    /// The same test with the sensor's y load `c` times the on-axis force.
    pub fn off_axis(self, off_axis_fraction: f64) -> ForceTest {
        ForceTest {
            off_axis_fraction,
            ..self
        }
    }

    pub fn run(&self, leg: &Leg) -> Result<ForceDeflection, Error> {
        self.run_warm(leg, &mut WarmStarts::default())
    }

    /// The test with the foot moving the way `direction` (±1 along the axis) says: run at
    /// `voltage`, and again at `−voltage` when that moves the foot the other way (the paper
    /// pushes HAMR's lift foot down onto a sensor under the leg). `None`: as driven. Warm
    /// starts: `warm.part(0)` forward, `warm.part(1)` reversed.
    pub fn run_toward(
        &self,
        leg: &Leg,
        direction: Option<f64>,
        warm: &mut WarmStarts,
    ) -> Result<ForceDeflection, Error> {
        let forward = self.run_warm(leg, warm.part(0))?;
        match direction {
            Some(way) if way != forward.direction => ForceTest {
                voltage: -self.voltage,
                ..self.clone()
            }
            .run_warm(leg, warm.part(1)),
            _ => Ok(forward),
        }
    }

    /// [`ForceTest::run`] with each equilibrium started from its counterpart in `warm`
    /// (and recorded there): slots 0 rest, 1 free, 2 + k the k-th sensor position.
    pub fn run_warm(&self, leg: &Leg, warm: &mut WarmStarts) -> Result<ForceDeflection, Error> {
        let ForceTest {
            dof,
            voltage,
            ref sensor,
            off_axis_fraction,
        } = *self;
        let axis = dof.axis();
        let rest_inputs = leg.inputs(0.0, 0.0);
        let rest_q = leg.warm_rest(warm, 0, &rest_inputs)?.q;
        let rest = leg.foot_at(&rest_q, &rest_inputs);
        let inputs = leg.drive(dof, voltage);
        let free_q = leg.warm_equilibrium(warm, 1, &rest_q, &inputs, &[], &[])?.q;
        let free = leg.foot_at(&free_q, &inputs);
        let signed = free[axis] - rest[axis];
        let direction = if signed < 0.0 { -1.0 } else { 1.0 };
        let free_deflection = signed.abs();
        let y_direction = if free[1] < rest[1] { -1.0 } else { 1.0 };

        let mut points = Vec::new();
        let mut q = rest_q.clone();
        let mut k = 0usize;
        while let Some(distance) = sensor.position(k, free_deflection) {
            if distance > free_deflection {
                // Beyond the free foot's reach the sensor is not touched: no equilibrium to
                // solve (holding the foot there would pull on it, and such a pulled leg far
                // from its working range is where Newton struggles).
                points.push(SensorPoint {
                    distance,
                    force: 0.0,
                    force_y: 0.0,
                    foot_y: free[1] - rest[1],
                });
                k += 1;
                continue;
            }
            let mut target = rest;
            target[axis] = rest[axis] + direction * distance;
            // The sensor pushes the foot along y with c·F, opposing the free y motion: with
            // the fixture's force on the foot μ along the axis, F = −μ·direction, so the
            // applied y force is y_direction·c·direction·μ.
            let load_y = y_direction * off_axis_fraction * direction;
            let fixture = leg.fixture(target, vec![axis]);
            let loads: Vec<SideLoad> = (load_y != 0.0)
                .then_some(SideLoad {
                    fixture: 0,
                    held: axis,
                    along: 1,
                    ratio: load_y,
                })
                .into_iter()
                .collect();
            let equilibrium = leg.warm_equilibrium(warm, 2 + k, &q, &inputs, &[fixture], &loads)?;
            let (solved, f) = (equilibrium.q, equilibrium.fixture_forces[0]);
            let foot = leg.foot_at(&solved, &inputs);
            let force = -f[axis] * direction;
            // The sensor's y force on the foot is the side load, `load_y·f[axis]` (= f[1]);
            // the foot's on the sensor, minus it.
            let point = SensorPoint {
                distance,
                force,
                force_y: -load_y * f[axis],
                foot_y: foot[1] - rest[1],
            };
            q = solved;
            points.push(point);
            k += 1;
            if matches!(sensor, Sensor::Steps(_)) && points.len() > 1000 {
                return Err(Error::Test(
                    "more than 1000 sensor positions: is the step too small?",
                ));
            }
        }
        Ok(ForceDeflection {
            dof,
            axis,
            voltage,
            rest_q,
            rest,
            free,
            free_deflection,
            direction,
            points,
            off_axis_fraction,
        })
    }
}
