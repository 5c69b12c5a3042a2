//! `mech._mech`: the native module of the Python package `mech` (`python/mech/`, which
//! wraps it with keyword conveniences and docstrings).
//!
//! Consumes: Python calls with a `.mech` path, `NAME=VALUE` settings (units checked, as on
//! the command line) or SI numbers, and NumPy arrays of states. Produces: NumPy arrays and
//! dicts of them from the library's analyses ([`mech::session::Session`]: assembly,
//! simulation, statics, linearization) and the model's own functions (`M(q)`, `F(q, u)`,
//! outputs). Errors are raised as `mech.MechError` carrying the library's message (a model
//! text error shows its file, line, column and hint, as `mech check` prints it).
//!
//! Long computations (simulate, statics, linearize) run with the Python thread detached, on a
//! copy of the session, so other Python threads go on meanwhile. One evaluation (`rhs`) is
//! too short to gain from that: it runs under the GIL on scratch
//! kept between calls, so it allocates only copies of its arguments and the array it returns.

use std::f64::consts::TAU;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use mech::session::{Assembled, Session};
use mech::tape_model::TapeModel;
use mech_runtime::nalgebra::DMatrix;
use mech_runtime::{ConstrainedSolver, FlexureDamping, Method, Model as _, SimOptions};
use numpy::{Complex64, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

create_exception!(
    _mech,
    MechError,
    PyException,
    "A model that cannot be read or an analysis that cannot be done; the message says where and why."
);

fn error(message: impl std::fmt::Display) -> PyErr {
    MechError::new_err(message.to_string())
}

/// A compiled `.mech` model with its parameter values and input signals. Behind a mutex: a
/// Python object may be used from several threads, and the tape's register file is not
/// shared-safe.
#[pyclass(module = "mech._mech")]
struct Model {
    session: Mutex<Session>,
    /// Scratch of `rhs`; locked after `session` when both are.
    evaluation: Mutex<Evaluation>,
}

/// What one `u̇` evaluation reuses from call to call: the constrained solver's storage (`M`,
/// `F`, `J`, `J̇u` and their factors), the inputs' values and `u̇` itself.
struct Evaluation {
    solver: ConstrainedSolver,
    inputs: Vec<f64>,
    udot: Vec<f64>,
}

impl Evaluation {
    fn for_session(session: &Session) -> Evaluation {
        let model = &session.model;
        Evaluation {
            solver: ConstrainedSolver::for_model(model),
            inputs: vec![0.0; model.ninputs()],
            udot: vec![0.0; model.nu()],
        }
    }

    /// `u̇` of `M u̇ = F + Jᵀλ`, `J u̇ = −J̇u` at `(t, q, u)` into `self.udot`, with `inputs`
    /// (else the input signals at `t`). Lengths are the caller's to check.
    fn accelerations(
        &mut self,
        session: &Session,
        t: f64,
        q: &[f64],
        u: &[f64],
        inputs: Option<&[f64]>,
    ) -> Result<(), mech_runtime::RuntimeError> {
        match inputs {
            Some(values) => self.inputs.copy_from_slice(values),
            None => {
                for (value, signal) in self.inputs.iter_mut().zip(&session.signals) {
                    *value = signal.value(t);
                }
            }
        }
        self.solver
            .accelerations(&session.model, t, q, u, &self.inputs, &mut self.udot)
    }
}

/// A matrix as a 2-D array.
fn matrix<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    let rows: Vec<Vec<f64>> = m.row_iter().map(|r| r.iter().copied().collect()).collect();
    rows_array(py, &rows, m.ncols())
}

/// Rows of equal length as a 2-D array (`columns` wide when there are no rows).
fn rows_array<'py>(
    py: Python<'py>,
    rows: &[Vec<f64>],
    columns: usize,
) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    PyArray1::from_vec(py, flat)
        .reshape([rows.len(), columns])
        .expect("rows of equal length")
}

/// A 1-D float array's values, copied (strided views too). Cheaper for a state vector than
/// `PyReadonlyArray`, whose borrow registration cost `rhs` about 0.1 µs per array
/// (`docs/benchmarks.md` §15).
fn values(array: &Bound<'_, PyArray1<f64>>) -> Vec<f64> {
    array
        .to_vec()
        .unwrap_or_else(|_| array.to_owned_array().to_vec())
}

/// `independent=` as Python gives it: `None`, a list of names (held at their `q0`), or a
/// dict of names to values (a string with a unit, or a number in SI units).
fn independent_list(given: Option<Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(given) = given else {
        return Ok(Vec::new());
    };
    if let Ok(dict) = given.cast::<PyDict>() {
        return dict
            .iter()
            .map(|(name, value)| {
                let name: String = name.extract()?;
                Ok(if value.is_none() {
                    name
                } else if let Ok(text) = value.extract::<String>() {
                    format!("{name}={text}")
                } else {
                    format!("{name}={}", value.extract::<f64>()?)
                })
            })
            .collect();
    }
    given.extract::<Vec<String>>().map_err(|_| {
        error("`independent` is a list of coordinate names or a dict of names to values")
    })
}

fn method(name: &str, rtol: f64, atol: f64, step: Option<f64>) -> PyResult<Method> {
    let h_max = f64::INFINITY;
    Ok(match name {
        "dopri5" => Method::Dopri5 { rtol, atol, h_max },
        "dop853" => Method::Dop853 { rtol, atol, h_max },
        "rosenbrock" => Method::Rosenbrock { rtol, atol, h_max },
        "rosenbrock-w" | "rosenbrock_w" => Method::RosenbrockW { rtol, atol, h_max },
        "exp-rosenbrock" | "exp_rosenbrock" => Method::ExpRosenbrock { rtol, atol, h_max },
        "rk4" => Method::Rk4 {
            step: step.ok_or_else(|| error("method `rk4` needs `step` (seconds)"))?,
        },
        other => {
            return Err(error(format!(
                "unknown method `{other}`; the methods are dopri5, dop853, rk4, rosenbrock, \
                 rosenbrock-w, exp-rosenbrock"
            )))
        }
    })
}

impl Model {
    /// The session, locked (a panic elsewhere leaves it usable: it holds no invariant a panic
    /// could break).
    fn session(&self) -> MutexGuard<'_, Session> {
        self.session
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The `rhs` scratch, locked (as `session`, a panic leaves nothing to repair).
    fn evaluation(&self) -> MutexGuard<'_, Evaluation> {
        self.evaluation
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Checks the lengths of an `rhs` call's `q`, `u` and `inputs` against `session`'s model.
    fn check_lengths(
        session: &Session,
        q: &[f64],
        u: &[f64],
        inputs: Option<&[f64]>,
    ) -> PyResult<()> {
        let model = &session.model;
        let given = [
            ("q", q.len(), model.nq(), "coordinates"),
            ("u", u.len(), model.nu(), "speeds"),
            (
                "inputs",
                inputs.map_or(model.ninputs(), <[f64]>::len),
                model.ninputs(),
                "inputs",
            ),
        ];
        for (what, len, n, entries) in given {
            if len != n {
                return Err(error(format!(
                    "`{what}` has {len} values; `{}` has {n} {entries}",
                    model.name()
                )));
            }
        }
        Ok(())
    }

    /// The model's inputs as given (`None`: their current signals at t = 0), checked.
    fn input_values(&self, inputs: Option<PyReadonlyArray1<f64>>) -> PyResult<Vec<f64>> {
        let session = self.session();
        let model = &session.model;
        match inputs {
            Some(values) => {
                let values = values.as_slice()?.to_vec();
                if values.len() != model.ninputs() {
                    return Err(error(format!(
                        "`{}` has {} inputs, got {} values",
                        model.name(),
                        model.ninputs(),
                        values.len()
                    )));
                }
                Ok(values)
            }
            None => Ok(session.signals.iter().map(|s| s.value(0.0)).collect()),
        }
    }

    /// `analysis` of a copy of the session with the `independent=` argument, run with the
    /// Python thread detached (other Python threads go on meanwhile).
    fn detached<T: Send>(
        &self,
        py: Python<'_>,
        independent: Option<Bound<'_, PyAny>>,
        analysis: impl FnOnce(&Session, &[String]) -> Result<T, mech::session::Error> + Send,
    ) -> PyResult<T> {
        let independent = independent_list(independent)?;
        let session = self.session().clone();
        py.detach(move || analysis(&session, &independent))
            .map_err(error)
    }

    /// A state vector of the model's length, or an error naming it.
    fn state(&self, what: &str, values: PyReadonlyArray1<f64>) -> PyResult<Vec<f64>> {
        let values = values.as_slice()?.to_vec();
        let model = &self.session().model;
        // `u` has one entry per speed: fewer than `q` with quaternions (ball, free joints).
        let (n, entries) = match what {
            "u" => (model.nu(), "speeds"),
            _ => (model.nq(), "coordinates"),
        };
        if values.len() != n {
            return Err(error(format!(
                "`{what}` has {} values; `{}` has {n} {entries}",
                values.len(),
                model.name()
            )));
        }
        Ok(values)
    }

    /// The names the model lists: `count` of them, the i-th by `name`.
    fn names(
        &self,
        count: fn(&TapeModel) -> usize,
        name: for<'a> fn(&'a TapeModel, usize) -> &'a str,
    ) -> Vec<String> {
        let session = self.session();
        let model = &session.model;
        (0..count(model))
            .map(|i| name(model, i).to_string())
            .collect()
    }
}

#[pymethods]
impl Model {
    /// Compiles the `.mech` file at `path` and applies `NAME=VALUE` settings (`set`, units
    /// checked against each parameter) and input signals (`inputs`, e.g.
    /// `drive=sine(amplitude=1 mN, frequency=10 Hz)`).
    #[new]
    #[pyo3(signature = (path, set=Vec::new(), inputs=Vec::new()))]
    fn new(path: PathBuf, set: Vec<String>, inputs: Vec<String>) -> PyResult<Self> {
        let session = Session::open(&path, &set, &inputs).map_err(error)?;
        Ok(Model {
            evaluation: Mutex::new(Evaluation::for_session(&session)),
            session: Mutex::new(session),
        })
    }

    #[getter]
    fn name(&self) -> String {
        self.session().model.name().to_string()
    }

    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.names(|m| m.nq(), |m, i| m.coordinate_name(i))
    }

    /// The speeds' names: the coordinates' where `q̇ = u`, fewer with quaternions.
    #[getter]
    fn speeds(&self) -> Vec<String> {
        self.names(|m| m.nu(), |m, i| m.speed_name(i))
    }

    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.names(|m| m.ninputs(), |m, i| m.input_name(i))
    }

    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.names(|m| m.noutputs(), |m, i| m.output_name(i))
    }

    #[getter]
    fn constraints(&self) -> Vec<String> {
        self.names(|m| m.nc(), |m, i| m.constraint_name(i))
    }

    /// Parameter values by name, SI units.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let session = self.session();
        let model = &session.model;
        let dict = PyDict::new(py);
        for i in 0..model.nparams() {
            dict.set_item(model.param_name(i), model.param(i))?;
        }
        Ok(dict)
    }

    /// `NAME=VALUE` with a unit (`k=3 N/m`), checked as `--set` is.
    fn set(&mut self, assignment: &str) -> PyResult<()> {
        self.session().set(assignment).map_err(error)
    }

    /// Sets parameter `name` to `value` in SI units (no unit check; the physical rules are).
    fn set_si(&mut self, name: &str, value: f64) -> PyResult<()> {
        let mut session = self.session();
        let model = &session.model;
        let index = model.param_index(name).ok_or_else(|| {
            let known: Vec<&str> = (0..model.nparams()).map(|i| model.param_name(i)).collect();
            error(format!(
                "`{}` has no parameter `{name}`; its parameters: {}",
                model.name(),
                known.join(", ")
            ))
        })?;
        session.set_si(index, value).map_err(error)
    }

    /// `NAME=SIGNAL` (`drive=sine(amplitude=1 mN, frequency=10 Hz)`), checked as `--input` is.
    fn input(&mut self, assignment: &str) -> PyResult<()> {
        self.session().input(assignment).map_err(error)
    }

    /// The equations `M(q) u̇ = F` and the outputs as s-expressions (`mech derive`).
    fn equations(&self) -> PyResult<String> {
        mech::describe::equations_text(&self.session().compiled).map_err(error)
    }

    /// What `mech check` reports, as data: the model's `name`, its `bodies` (names),
    /// `joints`, `loops` and `velocity_constraints` (counts), and its degrees of freedom:
    /// `dof` of the configuration and `speed_dof` of the motion (fewer with velocity
    /// constraints). For a model with loops or velocity constraints these come from the
    /// assembled `q0`, with the constraint `rows`, their `rank` and the `singular_values` of
    /// `J`. Raises `MechError` where `mech check` fails (a loop that does not close).
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let session = self.session();
        let model = &session.compiled.model;
        let dict = PyDict::new(py);
        dict.set_item("name", model.name.as_str())?;
        let bodies: Vec<&str> = model.bodies.iter().map(|(_, b)| b.name.as_str()).collect();
        dict.set_item("bodies", bodies)?;
        dict.set_item("joints", model.joints.len())?;
        dict.set_item("loops", model.loops.len())?;
        dict.set_item("velocity_constraints", model.velocity_constraints.len())?;
        let state = session.assemble(&[]).map_err(error)?;
        match &state.mobility {
            Some(mobility) => {
                dict.set_item("dof", mobility.dof())?;
                dict.set_item("speed_dof", mobility.speed_dof())?;
                dict.set_item("rows", mobility.rows)?;
                dict.set_item("rank", mobility.rank)?;
                let values = PyArray1::from_vec(py, mobility.singular_values.clone());
                dict.set_item("singular_values", values)?;
            }
            None => {
                let free = session.model.nu();
                dict.set_item("dof", free)?;
                dict.set_item("speed_dof", free)?;
            }
        }
        Ok(dict)
    }

    /// The initial state with the loops closed: `independent` coordinates held
    /// (`NAME` or `NAME=VALUE`). A dict of `q`, `u`, the names held independent, and for a
    /// model with loops its mobility (`rank`, `dof`, `singular_values`).
    #[pyo3(signature = (independent=None))]
    fn assemble<'py>(
        &self,
        py: Python<'py>,
        independent: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let independent = independent_list(independent)?;
        let state = self.session().assemble(&independent).map_err(error)?;
        self.state_dict(py, &state)
    }

    /// Integrates from the assembled initial state to `t_end` (seconds), sampled every
    /// `dt_out` (default `t_end / 1000`). A dict of arrays: `t` (n), `q` and `u` (n × nq),
    /// `outputs` (n × outputs), `inputs` (n × inputs), and the integrator's `steps`.
    /// With `as_frame=True`, a pandas DataFrame instead: one row per sample indexed by `t`,
    /// columns `q_NAME`, `u_NAME`, the outputs and the inputs, `attrs["steps"]`.
    #[pyo3(signature = (t_end, dt_out=None, method="dopri5", rtol=1e-9, atol=1e-12, step=None, independent=None, max_steps=1_000_000, as_frame=false))]
    #[allow(clippy::too_many_arguments)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        t_end: f64,
        dt_out: Option<f64>,
        method: &str,
        rtol: f64,
        atol: f64,
        step: Option<f64>,
        independent: Option<Bound<'py, PyAny>>,
        max_steps: usize,
        as_frame: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if !(t_end.is_finite() && t_end > 0.0) {
            return Err(error(format!(
                "`t_end` must be a positive number of seconds, got {t_end}"
            )));
        }
        let options = SimOptions {
            t_end,
            output_interval: dt_out.unwrap_or(t_end / 1000.0),
            method: self::method(method, rtol, atol, step)?,
            max_steps,
            ..SimOptions::default()
        };
        let trajectory = self.detached(py, independent, move |session, independent| {
            let state = session.assemble(independent)?;
            session.simulate(&state, &options, &mut |_| {})
        })?;
        let (nq, nu, no, ni) = {
            let model = &self.session().model;
            (model.nq(), model.nu(), model.noutputs(), model.ninputs())
        };
        let dict = PyDict::new(py);
        dict.set_item("t", PyArray1::from_vec(py, trajectory.times))?;
        dict.set_item("q", rows_array(py, &trajectory.q, nq))?;
        dict.set_item("u", rows_array(py, &trajectory.u, nu))?;
        dict.set_item("outputs", rows_array(py, &trajectory.outputs, no))?;
        dict.set_item("inputs", rows_array(py, &trajectory.inputs, ni))?;
        dict.set_item("steps", trajectory.stats.accepted_steps)?;
        if !as_frame {
            return Ok(dict.into_any());
        }
        let names = (
            self.coordinates(),
            self.speeds(),
            self.outputs(),
            self.inputs(),
        );
        frames(py)?.call_method1("simulation", (dict, names.0, names.1, names.2, names.3))
    }

    /// A static equilibrium near the assembled initial state under constant `inputs` (default:
    /// the signals at t = 0). A dict of `q` and the loop multipliers `lambda`, with the
    /// residuals `force_residual` (max |F + Jᵀλ|) and `constraint_residual` (max |φ|).
    #[pyo3(signature = (independent=None, inputs=None))]
    fn statics<'py>(
        &self,
        py: Python<'py>,
        independent: Option<Bound<'py, PyAny>>,
        inputs: Option<PyReadonlyArray1<f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let inputs = self.input_values(inputs)?;
        let (equilibrium, _) = self.detached(py, independent, move |session, independent| {
            session.equilibrium(independent, &inputs, &[])
        })?;
        let dict = PyDict::new(py);
        dict.set_item("q", PyArray1::from_vec(py, equilibrium.q))?;
        dict.set_item(
            "lambda",
            PyArray1::from_vec(py, equilibrium.loop_multipliers),
        )?;
        dict.set_item("force_residual", equilibrium.force_residual)?;
        dict.set_item("constraint_residual", equilibrium.constraint_residual)?;
        Ok(dict)
    }

    /// The linear model about the static equilibrium, `M δz̈ + C δż + K δz = B δin` in the
    /// minimal coordinates `z` (names in `coordinates`), its first-order form
    /// `ẋ = A x + B_s δin`, `y = C_s x + D_s δin` with `x = [δz; δż]`, and the undamped
    /// modes (`frequency_hz`, `damping_ratio`, `shapes` one column per mode).
    #[pyo3(signature = (independent=None, inputs=None))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        independent: Option<Bound<'py, PyAny>>,
        inputs: Option<PyReadonlyArray1<f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let inputs = self.input_values(inputs)?;
        let linear = self.detached(py, independent, move |session, independent| {
            session.linearization(independent, &inputs)
        })?;
        let matrices = mech::session::named_matrices(&linear)
            .ok_or_else(|| error("the reduced mass matrix is singular"))?;
        let modes = linear
            .modes()
            .ok_or_else(|| error("the reduced mass matrix is not positive definite"))?;
        let session = self.session();
        let model = &session.model;
        let dict = PyDict::new(py);
        let names = mech::session::coordinate_names(model, &linear.independent);
        dict.set_item("coordinates", names.clone())?;
        for (key, value) in &matrices {
            dict.set_item(*key, matrix(py, value))?;
        }
        let frequencies: Vec<f64> = modes.iter().map(|m| m.frequency_hz()).collect();
        let ratios: Vec<f64> = modes.iter().map(|m| m.damping_ratio).collect();
        let shapes: Vec<Vec<f64>> = (0..names.len())
            .map(|r| modes.iter().map(|m| m.shape[r]).collect())
            .collect();
        dict.set_item("frequency_hz", PyArray1::from_vec(py, frequencies))?;
        dict.set_item("damping_ratio", PyArray1::from_vec(py, ratios))?;
        dict.set_item("shapes", rows_array(py, &shapes, modes.len()))?;
        Ok(dict)
    }

    /// The linear model about the steady motion through the assembled initial state (its
    /// `u0` at the current parameters: `set("v=3 m/s")` moves a `u0 = v / r`), `δẋ = A δx`:
    /// `states` (`q_NAME`, `u_NAME`: the independent coordinates that are not cyclic, then the
    /// independent speeds), `cyclic` (the coordinates dropped), `A`, `eigenvalues` (complex,
    /// sorted by real part), `unsteadiness` (max |ẋ| at the point), `cyclic_change` (how much
    /// `A` changes when the cyclic coordinates move on: round-off for a symmetry) and, when
    /// every kept coordinate's speed is independent, `coordinates`, `M`, `C`, `K` of
    /// `M δz̈ + C δż + K δz = 0`.
    #[pyo3(signature = (independent=None, inputs=None))]
    fn linearize_steady<'py>(
        &self,
        py: Python<'py>,
        independent: Option<Bound<'py, PyAny>>,
        inputs: Option<PyReadonlyArray1<f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let inputs = self.input_values(inputs)?;
        let linear = self.detached(py, independent, move |session, independent| {
            let point = mech::steady_motion::OperatingPoint {
                independent: independent.to_vec(),
                ..Default::default()
            };
            mech::steady_motion::linearize(session, &point, &inputs)
        })?;
        let session = self.session();
        let model = &session.model;
        let dict = PyDict::new(py);
        dict.set_item("states", mech::steady_motion::state_names(model, &linear))?;
        dict.set_item("cyclic", mech::steady_motion::cyclic_names(model, &linear))?;
        dict.set_item("A", matrix(py, &linear.a))?;
        let eigenvalues: Vec<Complex64> = linear
            .eigenvalues()
            .iter()
            .map(|z| Complex64::new(z.re, z.im))
            .collect();
        dict.set_item("eigenvalues", PyArray1::from_vec(py, eigenvalues))?;
        dict.set_item("unsteadiness", linear.unsteadiness())?;
        dict.set_item("cyclic_change", linear.cyclic_change)?;
        if let Some(form) = linear.second_order() {
            let names = mech::session::coordinate_names(model, &form.coordinates);
            dict.set_item("coordinates", names)?;
            dict.set_item("M", matrix(py, &form.mass))?;
            dict.set_item("C", matrix(py, &form.damping))?;
            dict.set_item("K", matrix(py, &form.stiffness))?;
        }
        Ok(dict)
    }

    /// The frequency response from input `input` to output `output` of the linear model about
    /// the static equilibrium, at `frequencies_hz`: complex gains (SI units). `damping` is
    /// `hysteretic` (flexures as complex stiffness k(1 + iη), exact at every frequency;
    /// default) or `viscous` (their time-domain dampers b = kη/ω_ref, as a simulation sees
    /// them). With `as_frame=True`, a pandas DataFrame indexed by `frequency_hz`: `gain`,
    /// `magnitude`, `phase_deg` (unwrapped).
    #[pyo3(signature = (input, output, frequencies_hz, damping="hysteretic", independent=None, as_frame=false))]
    #[allow(clippy::too_many_arguments)]
    fn bode<'py>(
        &self,
        py: Python<'py>,
        input: &str,
        output: &str,
        frequencies_hz: PyReadonlyArray1<'py, f64>,
        damping: &str,
        independent: Option<Bound<'py, PyAny>>,
        as_frame: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let damping = match damping {
            "hysteretic" => FlexureDamping::Hysteretic,
            "viscous" => FlexureDamping::Viscous,
            other => {
                return Err(error(format!(
                    "unknown damping `{other}`; write `hysteretic` or `viscous`"
                )))
            }
        };
        let (input, output) = {
            let session = self.session();
            let input = session.input_index(input).map_err(error)?;
            (input, session.output_index(output).map_err(error)?)
        };
        let frequencies = frequencies_hz.as_slice()?.to_vec();
        let inputs = self.input_values(None)?;
        let gains = self.detached(py, independent, move |session, independent| {
            let linear = session.linearization(independent, &inputs)?;
            Ok(frequencies
                .iter()
                .map(|&f| {
                    let gain = linear.frequency_response(input, output, TAU * f, damping);
                    (f, gain.map(|g| Complex64::new(g.re, g.im)))
                })
                .collect::<Vec<_>>())
        })?;
        let gains = gains
            .into_iter()
            .map(|(f, gain)| {
                gain.ok_or_else(|| error(format!("the linear model is singular at {f} Hz")))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let gains = PyArray1::from_vec(py, gains).into_any();
        if !as_frame {
            return Ok(gains);
        }
        frames(py)?.call_method1("bode", ((*frequencies_hz).clone(), gains))
    }

    /// The mass matrix `M(q)` (nu × nu: one row per speed, fewer than `q` with quaternions) at
    /// time `t`.
    #[pyo3(signature = (q, inputs=None, t=0.0))]
    fn mass_matrix<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArray1<f64>,
        inputs: Option<PyReadonlyArray1<f64>>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (q, inputs) = (self.state("q", q)?, self.input_values(inputs)?);
        let model = &self.session().model;
        let n = model.nu();
        let mut out = vec![0.0; n * n];
        model.mass_matrix(t, &q, &inputs, &mut out);
        PyArray1::from_vec(py, out).reshape([n, n])
    }

    /// The forcing vector `F(q, u)` of `M(q) u̇ = F` at time `t` (loop reactions excluded).
    #[pyo3(signature = (q, u, inputs=None, t=0.0))]
    fn forcing<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArray1<f64>,
        u: PyReadonlyArray1<f64>,
        inputs: Option<PyReadonlyArray1<f64>>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (q, u, inputs) = (
            self.state("q", q)?,
            self.state("u", u)?,
            self.input_values(inputs)?,
        );
        let mut out = vec![0.0; u.len()];
        self.session().model.forcing(t, &q, &u, &inputs, &mut out);
        Ok(PyArray1::from_vec(py, out))
    }

    /// The accelerations `u̇` at `(t, q, u)`: `M(q) u̇ = F(t, q, u, inputs)`, with the loops'
    /// reactions `Jᵀλ` where the model has loops (`J u̇ = −J̇u`), as the integrators see them.
    /// `inputs` default to the input signals at `t`. One call costs the Rust evaluation plus
    /// about 0.3 µs (`docs/benchmarks.md` §15).
    #[pyo3(signature = (t, q, u, inputs=None))]
    fn rhs<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyArray1<f64>>,
        u: &Bound<'py, PyArray1<f64>>,
        inputs: Option<&Bound<'py, PyArray1<f64>>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (q, u, inputs) = (values(q), values(u), inputs.map(values));
        let session = self.session();
        Self::check_lengths(&session, &q, &u, inputs.as_deref())?;
        let mut evaluation = self.evaluation();
        evaluation
            .accelerations(&session, t, &q, &u, inputs.as_deref())
            .map_err(error)?;
        Ok(PyArray1::from_slice(py, &evaluation.udot))
    }

    /// The model's outputs (names in `outputs`) at `(t, q, u)`.
    #[pyo3(signature = (q, u, inputs=None, t=0.0))]
    fn evaluate_outputs<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArray1<f64>,
        u: PyReadonlyArray1<f64>,
        inputs: Option<PyReadonlyArray1<f64>>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (q, u, inputs) = (
            self.state("q", q)?,
            self.state("u", u)?,
            self.input_values(inputs)?,
        );
        let mut out = vec![0.0; self.session().model.noutputs()];
        self.session().model.outputs(t, &q, &u, &inputs, &mut out);
        Ok(PyArray1::from_vec(py, out))
    }

    fn __repr__(&self) -> String {
        let session = self.session();
        let model = &session.model;
        format!(
            "<mech.Model `{}`: {} coordinates, {} inputs, {} outputs, {} loop rows>",
            model.name(),
            model.nq(),
            model.ninputs(),
            model.noutputs(),
            model.nc()
        )
    }
}

impl Model {
    fn state_dict<'py>(&self, py: Python<'py>, state: &Assembled) -> PyResult<Bound<'py, PyDict>> {
        let session = self.session();
        let model = &session.model;
        let dict = PyDict::new(py);
        dict.set_item("q", PyArray1::from_vec(py, state.q.clone()))?;
        dict.set_item("u", PyArray1::from_vec(py, state.u.clone()))?;
        let independent: Vec<&str> = state
            .independent
            .iter()
            .map(|&i| model.coordinate_name(i))
            .collect();
        dict.set_item("independent", independent)?;
        if let Some(mobility) = &state.mobility {
            dict.set_item("rank", mobility.rank)?;
            dict.set_item("dof", mobility.dof())?;
            dict.set_item(
                "singular_values",
                PyArray1::from_vec(py, mobility.singular_values.clone()),
            )?;
        }
        Ok(dict)
    }
}

/// Seconds per call of `model.rhs(t, q, u, inputs)`'s Rust part (the same evaluation on the
/// same scratch, without the Python call: argument conversion, locking, the result array),
/// the mean of `calls` calls in one loop. For `bench/python_overhead.py`, which times the
/// Python call beside it.
#[pyfunction]
#[pyo3(signature = (model, t, q, u, inputs=None, calls=1000))]
fn rhs_seconds(
    model: &Model,
    t: f64,
    q: &Bound<'_, PyArray1<f64>>,
    u: &Bound<'_, PyArray1<f64>>,
    inputs: Option<&Bound<'_, PyArray1<f64>>>,
    calls: usize,
) -> PyResult<f64> {
    let (q, u, inputs) = (values(q), values(u), inputs.map(values));
    let session = model.session();
    Model::check_lengths(&session, &q, &u, inputs.as_deref())?;
    let mut evaluation = model.evaluation();
    let started = std::time::Instant::now();
    for _ in 0..calls.max(1) {
        evaluation
            .accelerations(&session, t, std::hint::black_box(&q), &u, inputs.as_deref())
            .map_err(error)?;
        std::hint::black_box(&evaluation.udot);
    }
    Ok(started.elapsed().as_secs_f64() / calls.max(1) as f64)
}

/// The Python module that turns results into pandas frames (`as_frame=True`; it imports
/// pandas, and says how to install it when it is missing).
fn frames(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    py.import("mech._frames")
}

/// A JSON value as the Python object `json.loads` gives.
fn json_object<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(error)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Runs the experiment file at `path` (`mech experiment`): its title, method, tables (title,
/// header, rows of text cells), notes and key values (SI units). With `out_dir`, its CSV files
/// and plots are written there (in a subfolder named after the file), all or none, as the
/// command writes them; without, nothing is written.
#[pyfunction]
#[pyo3(signature = (path, out_dir=None))]
fn experiment<'py>(
    py: Python<'py>,
    path: PathBuf,
    out_dir: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let outcome = py
        .detach(|| {
            let dir = out_dir
                .clone()
                .unwrap_or_else(|| PathBuf::from("out/experiments"));
            let outcome =
                mech::render::experiments::run_file(&path, &dir).map_err(|e| e.to_string())?;
            if out_dir.is_some() {
                let read = mech::output::Read {
                    path: path.clone(),
                    what: "the experiment file",
                };
                mech::output::write_all(&outcome.rendered, &[read]).map_err(|e| e.to_string())?;
            }
            Ok::<_, String>(outcome)
        })
        .map_err(error)?;
    json_object(py, &outcome_json(&outcome, out_dir.is_some()))
}

/// An experiment's outcome as `experiment` returns it: name, title, method, tables (title,
/// header, rows of text cells), notes, key values (SI units), and the `files` it rendered when
/// they are `written` (else none).
fn outcome_json(outcome: &mech::render::report::Outcome, written: bool) -> serde_json::Value {
    let tables: Vec<serde_json::Value> = outcome
        .tables
        .iter()
        .map(|t| serde_json::json!({"title": t.title, "header": t.header, "rows": t.rows}))
        .collect();
    let files: Vec<String> = match written {
        true => outcome
            .rendered
            .iter()
            .map(|f| f.path.display().to_string())
            .collect(),
        false => Vec::new(),
    };
    serde_json::json!({
        "name": outcome.name,
        "title": outcome.title,
        "method": outcome.method,
        "tables": tables,
        "notes": outcome.notes,
        "values": outcome.values,
        "files": files,
    })
}

/// Runs every experiment file in `experiments` on all cores (`mech report`) and writes the
/// report into `out_dir`: `report.html`, `report.md` and each experiment's files, all or none.
/// Returns the pages' paths (`html`, `markdown`), the run's `seconds` and each experiment's
/// result as `experiment` returns it (`experiments`, in the report's order).
#[pyfunction]
#[pyo3(signature = (out_dir=None, experiments=None))]
fn report<'py>(
    py: Python<'py>,
    out_dir: Option<PathBuf>,
    experiments: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    use mech::render::report::{experiment_reads, Report};
    let out_dir = out_dir.unwrap_or_else(|| PathBuf::from("out/report"));
    let experiments = experiments.unwrap_or_else(|| PathBuf::from("experiments"));
    let summary = py
        .detach(|| {
            let text = |e: &dyn std::fmt::Display| e.to_string();
            let started = std::time::Instant::now();
            let files = mech::experiments::experiment_files(&experiments).map_err(|e| text(&e))?;
            let outcomes = mech::render::experiments::run_all(&files, &out_dir, &|_| {})
                .map_err(|e| text(&e))?;
            let seconds = started.elapsed().as_secs_f64();
            let report = Report::new(outcomes, &out_dir, seconds).map_err(|e| text(&e))?;
            let summary = serde_json::json!({
                "html": report.html.path.display().to_string(),
                "markdown": report.markdown.path.display().to_string(),
                "seconds": seconds,
                "experiments": report.outcomes.iter().map(|o| outcome_json(o, true)).collect::<Vec<_>>(),
            });
            mech::output::write_all(&report.into_files(), &experiment_reads(&files))
                .map_err(|e| text(&e))?;
            Ok::<_, String>(summary)
        })
        .map_err(error)?;
    json_object(py, &summary)
}

/// A diagnosis experiment file (its model replaced by `model`) and its measured data, read;
/// errors as their messages.
fn experiment_and_data(
    experiment: &std::path::Path,
    data: &std::path::Path,
    model: Option<PathBuf>,
) -> Result<
    (
        mech::diagnose::experiment::Experiment,
        mech::diagnose::data::MeasuredData,
    ),
    String,
> {
    let mut spec = mech::diagnose::experiment::load(experiment).map_err(|e| e.to_string())?;
    if let Some(model) = model {
        spec.set_model(model);
    }
    let measured = mech::diagnose::data::MeasuredData::load(data).map_err(|e| e.to_string())?;
    Ok((spec, measured))
}

/// Diagnoses measured data against a model (`mech diagnose`): every catalog cause fitted,
/// ranked on the held-out rows, the verdict. Returns what `diagnosis.json` holds (verdict,
/// summary sentence, every trial with its fitted values and standard errors, features, held-out
/// residuals); writes nothing.
#[pyfunction]
#[pyo3(signature = (experiment, data, model=None, fit=Vec::new(), holdout="every:3", causes=Vec::new()))]
fn diagnose<'py>(
    py: Python<'py>,
    experiment: PathBuf,
    data: PathBuf,
    model: Option<PathBuf>,
    fit: Vec<String>,
    holdout: &str,
    causes: Vec<String>,
) -> PyResult<Bound<'py, PyAny>> {
    use mech::diagnose::candidates::{diagnose_causes, Holdout};
    use mech::render::diagnosis::{diagnosis_json, verdict_text, Comparison};
    let summary = py
        .detach(|| {
            let text = |e: &dyn std::fmt::Display| e.to_string();
            let (spec, measured) = experiment_and_data(&experiment, &data, model)?;
            let holdout_rows = Holdout::parse(holdout).map_err(|e| text(&e))?;
            let d = diagnose_causes(&spec, &measured, &fit, holdout_rows, &causes)
                .map_err(|e| text(&e))?;
            let verdict = verdict_text(&d);
            let comparison = Comparison::new(&spec, &d);
            Ok::<_, String>(diagnosis_json(
                holdout,
                &data,
                &spec,
                &d,
                &verdict,
                &comparison,
            ))
        })
        .map_err(error)?;
    json_object(py, &summary)
}

/// Fits the parameters `fit` (`NAME`, or `NAME=LO..HI UNIT`) of the experiment's model (or
/// `model`) to measured data (`mech fit`): what `fit.json` holds (parameters with standard
/// errors and status, stop reason, cost, residual RMS per series, screening flags) and
/// `points`, one entry per measured value: `series`, `abscissa`, `row`, `measured`, the model
/// `before` and `after` the fit. Writes nothing.
#[pyfunction]
#[pyo3(signature = (experiment, data, fit, model=None))]
fn fit<'py>(
    py: Python<'py>,
    experiment: PathBuf,
    data: PathBuf,
    fit: Vec<String>,
    model: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    use mech::diagnose::fit::{fit as fit_leg, parameters, FitRequest};
    if fit.is_empty() {
        return Err(error(
            "`fit` names no parameter: give at least one `NAME` or `NAME=LO..HI UNIT`",
        ));
    }
    let (summary, report) = py
        .detach(|| {
            let text = |e: &dyn std::fmt::Display| e.to_string();
            let (spec, measured) = experiment_and_data(&experiment, &data, model)?;
            let mut leg =
                mech::experiments::leg::Leg::open_any(&spec.model, &[]).map_err(|e| text(&e))?;
            let requests = fit
                .iter()
                .map(|request| FitRequest::parse(request))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| text(&e))?;
            let fitted = parameters(&leg, &requests).map_err(|e| text(&e))?;
            // Checked before the screening, which reads the same columns (as `mech fit`).
            spec.observations(&leg, &measured).map_err(|e| text(&e))?;
            let screening = spec.screen(&measured).map_err(|e| text(&e))?;
            let report = fit_leg(&spec, &measured, &mut leg, &fitted).map_err(|e| text(&e))?;
            let summary =
                mech::render::diagnosis::fit_json(&spec, &data, &report, screening.as_ref());
            Ok::<_, String>((summary, report))
        })
        .map_err(error)?;
    let result = json_object(py, &summary)?;
    let observations = report.observations;
    let points = PyDict::new(py);
    points.set_item("series", observations.series)?;
    points.set_item("abscissa", PyArray1::from_vec(py, observations.abscissa))?;
    let rows: Vec<i64> = observations.row.iter().map(|&r| r as i64).collect();
    points.set_item("row", PyArray1::from_vec(py, rows))?;
    points.set_item("measured", PyArray1::from_vec(py, observations.values))?;
    points.set_item("before", PyArray1::from_vec(py, report.before))?;
    points.set_item("after", PyArray1::from_vec(py, report.after))?;
    result.set_item("points", points)?;
    Ok(result)
}

/// A study (`mech sweep`) with `samples` and `seed` in place of its own, model paths relative
/// to `cwd` (else the current directory).
fn sweep_study(
    study: &std::path::Path,
    samples: Option<u64>,
    seed: Option<u64>,
    cwd: Option<PathBuf>,
) -> PyResult<mech::sweep::Study> {
    let mut loaded = mech::sweep::load_in(study, cwd.as_deref()).map_err(error)?;
    if let Some(samples) = samples {
        let samples = i64::try_from(samples).unwrap_or(i64::MAX);
        let samples = mech::sweep::check_count("samples", None, samples).map_err(error)?;
        loaded = loaded.with_samples(samples).map_err(error)?;
    }
    if let Some(seed) = seed {
        loaded.seed = seed;
    }
    Ok(loaded)
}

/// The number of samples of the study at `study` (its grid's points, or `samples` draws).
#[pyfunction]
#[pyo3(signature = (study, samples=None, seed=None, cwd=None))]
fn sweep_size(
    study: PathBuf,
    samples: Option<u64>,
    seed: Option<u64>,
    cwd: Option<PathBuf>,
) -> PyResult<usize> {
    Ok(sweep_study(&study, samples, seed, cwd)?.samples)
}

/// Runs the samples `indices` (default: all) of the study at `study` on all cores: a dict
/// with `columns` (name → array: `sample`, the parameters, the outputs, `failed`),
/// `parameters` and `outputs` (column names), `units` (name → SI unit), `failures`
/// (`(sample, robot, message)`). Rows in the order of `indices`; a sample's values depend on
/// the seed and its index only.
#[pyfunction]
#[pyo3(signature = (study, samples=None, seed=None, indices=None, cwd=None))]
fn sweep_run<'py>(
    py: Python<'py>,
    study: PathBuf,
    samples: Option<u64>,
    seed: Option<u64>,
    indices: Option<Vec<usize>>,
    cwd: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let loaded = sweep_study(&study, samples, seed, cwd)?;
    let indices = indices.unwrap_or_else(|| (0..loaded.samples).collect());
    let table = py
        .detach(|| loaded.run(&indices, mech::parallel::threads(), &|| {}))
        .map_err(error)?;
    let columns = PyDict::new(py);
    let rows = &table.rows;
    let index: Vec<f64> = rows.iter().map(|r| r.index as f64).collect();
    columns.set_item("sample", PyArray1::from_vec(py, index))?;
    for (k, name) in table.parameters.iter().enumerate() {
        columns.set_item(name, PyArray1::from_vec(py, table.parameter_column(k)))?;
    }
    for (k, name) in table.outputs.iter().enumerate() {
        columns.set_item(name, PyArray1::from_vec(py, table.output_column(k)))?;
    }
    let failed: Vec<bool> = rows.iter().map(|r| !r.failures.is_empty()).collect();
    columns.set_item("failed", PyArray1::from_vec(py, failed))?;
    let units = PyDict::new(py);
    let names = table.parameters.iter().chain(&table.outputs);
    for (name, unit) in names.zip(table.parameter_units.iter().chain(&table.output_units)) {
        units.set_item(name, unit)?;
    }
    let failures: Vec<(usize, Option<String>, String)> = rows
        .iter()
        .flat_map(|r| {
            r.failures
                .iter()
                .map(|f| (r.index, f.robot.clone(), f.error.to_string()))
        })
        .collect();
    let result = PyDict::new(py);
    result.set_item("columns", columns)?;
    result.set_item("parameters", table.parameters.clone())?;
    result.set_item("outputs", table.outputs.clone())?;
    result.set_item("units", units)?;
    result.set_item("failures", failures)?;
    Ok(result)
}

/// Per output (in order), `(output, parameter, rho)` for every parameter by |Spearman ρ|,
/// largest first, over the rows where both are finite (`mech sweep`'s ranking).
#[pyfunction]
fn sweep_ranking(
    parameters: Vec<(String, Vec<f64>)>,
    outputs: Vec<(String, Vec<f64>)>,
) -> Vec<(String, String, f64)> {
    let xs: Vec<Vec<f64>> = parameters.iter().map(|(_, c)| c.clone()).collect();
    let ys: Vec<Vec<f64>> = outputs.iter().map(|(_, c)| c.clone()).collect();
    mech::sweep::stats::ranking(&xs, &ys)
        .into_iter()
        .flatten()
        .map(|c| {
            let (output, parameter) = (&outputs[c.output].0, &parameters[c.parameter].0);
            (output.clone(), parameter.clone(), c.rho)
        })
        .collect()
}

#[pymodule]
fn _mech(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_function(wrap_pyfunction!(experiment, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(report, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_size, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_run, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_ranking, m)?)?;
    m.add_function(wrap_pyfunction!(rhs_seconds, m)?)?;
    m.add("MechError", m.py().get_type::<MechError>())?;
    Ok(())
}
