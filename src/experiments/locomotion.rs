//! Experiment 8, the whole robot walks (seed Sec. V-C, Fig. 9): a legged robot on a floating
//! base driven by a gait from rest, at every gait frequency and payload of a grid; its speed,
//! body motion, foot slip and cost of transport once the walk has settled.
//!
//! Consumes: a [`Spec`] (the robot model, its legs' drive inputs and wiring, the gait, the
//! grid). Produces: [`Walks`]: one [`Walk`] (the averages of a [`Run`]) per grid point that
//! simulated, the failures named.
//!
//! A gait gives each leg a phase; a leg's swing drive is `A sin(2π f t + φ)` and its lift
//! drive is the same shifted by `lift_phase`. A leg whose actuator is wired the other way
//! (`swing_sign = -1`: a positive voltage moves its foot backwards) gets half a cycle more.
//! The robot starts at rest in its assembled pose with the drives switched on at t = 0; the
//! averages are taken over whole cycles after `settle_cycles`.

use mech_codegen::ir::Dimension;
use mech_runtime::{Method, Model, SimOptions, Trajectory};
use serde::Deserialize;

use super::trajectory::peak_to_peak;
use super::Error;
use crate::parallel::{parallel, threads};
use crate::quantity::{positive, quantity};
use crate::session::{ModelSpec, NameKind, Session};

/// Standard gravity (m/s²), the weight in the cost of transport.
const GRAVITY: f64 = 9.81;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    #[serde(flatten)]
    pub model: ModelSpec,
    /// The floating base's free joint (its `.vx` speed's row of `M` is the total mass).
    pub base: String,
    /// The output giving the base's position in the Newtonian frame (`chassis`).
    pub position: String,
    /// The output giving the drives' mechanical power (W), for the cost of transport.
    pub drive_power: String,
    /// The body length, for speeds in body lengths per second.
    pub body_length: String,
    /// The parameter the payloads set (a mass).
    pub payload: String,
    /// Drive amplitude (half the peak-to-peak voltage).
    pub amplitude: String,
    /// `trot` (diagonal pairs half a cycle apart), `pronk` (all in phase), `bound` (front
    /// and rear pairs half a cycle apart), `jump` (the rear pair a quarter cycle behind the
    /// front), `pace` (left and right half a cycle apart), or `custom` (each leg's `phase`).
    #[serde(default = "default_gait")]
    pub gait: String,
    /// The lift drive's phase relative to the swing drive's.
    pub lift_phase: String,
    pub frequencies: Vec<String>,
    pub payloads: Vec<String>,
    /// Cycles from rest before the averages start.
    #[serde(default = "default_settle")]
    pub settle_cycles: f64,
    /// Cycles averaged.
    #[serde(default = "default_cycles")]
    pub cycles: f64,
    /// The integrator: `dopri5` (the default) or `rosenbrock-w` (implicit in the contacts'
    /// damping; see `Method::RosenbrockW`).
    #[serde(default)]
    pub method: WalkMethod,
    /// Relative tolerance of the integration (the absolute one is 1e-3 of it).
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Samples per cycle (slip and airborne time are read from them).
    #[serde(default = "default_samples")]
    pub samples_per_cycle: usize,
    #[serde(rename = "leg")]
    pub legs: Vec<LegSpec>,
    /// A second robot with the same names (inputs, outputs, parameters), walked over the same
    /// grid and drawn beside the first (Fig. 9 sets HAMR-VI beside HAMR-V2.0).
    #[serde(default)]
    pub compare: Option<std::path::PathBuf>,
}

/// The integrators a walk may take (key `method`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum WalkMethod {
    #[default]
    Dopri5,
    RosenbrockW,
}

fn default_gait() -> String {
    "trot".into()
}
fn default_settle() -> f64 {
    1.0
}
fn default_cycles() -> f64 {
    2.0
}
fn default_rtol() -> f64 {
    1e-6
}
fn default_samples() -> usize {
    100
}

/// One leg: its drive inputs, contact and foot outputs, where it sits and how its actuators
/// are wired.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegSpec {
    pub name: String,
    /// The swing and lift drive inputs (voltages).
    pub swing: String,
    pub lift: String,
    /// The leg's `contact(...)` output (its `.normal_force` tells stance from flight).
    pub contact: String,
    /// The output giving the foot's position in the Newtonian frame.
    pub foot: String,
    pub front: bool,
    pub left: bool,
    /// +1 if a positive swing voltage moves the foot forwards (+x), −1 if backwards.
    pub swing_sign: f64,
    /// +1 if a positive lift voltage moves the foot up, −1 if down.
    pub lift_sign: f64,
    /// The leg's phase in a `custom` gait.
    pub phase: Option<String>,
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        self.settings()?;
        for leg in &self.legs {
            leg.phase(&self.gait)?;
            for (key, sign) in [("swing_sign", leg.swing_sign), ("lift_sign", leg.lift_sign)] {
                if sign.abs() != 1.0 {
                    return Err(key_error(format!(
                        "leg `{}`: `{key}` must be 1 or -1, got {sign}",
                        leg.name
                    )));
                }
            }
        }
        if self.legs.is_empty() {
            return Err(key_error("give the robot's legs as [[leg]] tables".into()));
        }
        let positive_count = |key: &str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(key_error(format!(
                    "key `{key}`: must be positive, got {value}"
                )))
            }
        };
        positive_count("cycles", self.cycles)?;
        positive_count("rtol", self.rtol)?;
        if !(self.settle_cycles.is_finite() && self.settle_cycles >= 0.0) {
            return Err(key_error(format!(
                "key `settle_cycles`: must be 0 or more, got {}",
                self.settle_cycles
            )));
        }
        if self.samples_per_cycle < 10 {
            return Err(key_error(format!(
                "key `samples_per_cycle`: at least 10, got {}",
                self.samples_per_cycle
            )));
        }
        Ok(())
    }

    /// The quantities in SI: amplitude (V), lift phase (rad), body length (m), frequencies
    /// (Hz) and payloads (kg).
    fn settings(&self) -> Result<Settings, Error> {
        let list = |key: &str, items: &[String], read: &dyn Fn(&str) -> Result<f64, Error>| {
            if items.is_empty() {
                return Err(key_error(format!("key `{key}`: give at least one value")));
            }
            items.iter().map(|text| read(text)).collect()
        };
        let frequency = |text: &str| Ok(positive("frequencies", text, Dimension::FREQUENCY)?);
        let payload = |text: &str| match quantity("payloads", text, Dimension::MASS)? {
            mass if mass < 0.0 => Err(key_error(format!(
                "key `payloads`: `{text}` must be 0 or more"
            ))),
            mass => Ok(mass),
        };
        Ok(Settings {
            amplitude: positive("amplitude", &self.amplitude, Dimension::VOLTAGE)?,
            lift_phase: quantity("lift_phase", &self.lift_phase, Dimension::NONE)?,
            body_length: positive("body_length", &self.body_length, Dimension::LENGTH)?,
            frequencies: list("frequencies", &self.frequencies, &frequency)?,
            payloads: list("payloads", &self.payloads, &payload)?,
        })
    }

    /// A rough relative cost: simulated seconds over the grid (the robot runs ~13× slower
    /// than real time; a leg experiment costs about 1).
    pub fn cost(&self) -> f64 {
        let Ok(settings) = self.settings() else {
            return 1.0;
        };
        let seconds: f64 = settings
            .frequencies
            .iter()
            .map(|f| (self.settle_cycles + self.cycles) / f)
            .sum();
        let robots = 1.0 + f64::from(u8::from(self.compare.is_some()));
        robots * seconds * settings.payloads.len() as f64 * 20.0
    }

    /// The drive signals of every leg at frequency `hz` (`NAME=sine(...)`, as for `--input`).
    pub fn drives(&self, hz: f64) -> Result<Vec<String>, Error> {
        let settings = self.settings()?;
        let mut inputs = Vec::new();
        for leg in &self.legs {
            let phase = leg.phase(&self.gait)?;
            let flip = |sign: f64| {
                if sign < 0.0 {
                    std::f64::consts::PI
                } else {
                    0.0
                }
            };
            let swing = phase + flip(leg.swing_sign);
            let lift = phase + settings.lift_phase + flip(leg.lift_sign);
            for (input, phase) in [(&leg.swing, swing), (&leg.lift, lift)] {
                inputs.push(format!(
                    "{input}=sine(amplitude={} V, frequency={hz} Hz, phase={} deg)",
                    settings.amplitude,
                    phase.to_degrees().rem_euclid(360.0)
                ));
            }
        }
        Ok(inputs)
    }
}

struct Settings {
    amplitude: f64,
    lift_phase: f64,
    body_length: f64,
    frequencies: Vec<f64>,
    payloads: Vec<f64>,
}

impl LegSpec {
    /// The leg's phase in `gait` (rad).
    fn phase(&self, gait: &str) -> Result<f64, Error> {
        let half = std::f64::consts::PI;
        let value = match gait {
            "trot" => half * f64::from(u8::from(self.front != self.left)),
            "pronk" => 0.0,
            "bound" => half * f64::from(u8::from(!self.front)),
            // The HAMR authors' `JUMP` (HarvardAgileRoboticsLab/drake,
            // `GenerateHueristicActTraj.m`): the rear pair a quarter cycle behind the front.
            "jump" => -half / 2.0 * f64::from(u8::from(!self.front)),
            "pace" => half * f64::from(u8::from(!self.left)),
            "custom" => match &self.phase {
                Some(text) => quantity("leg.phase", text, Dimension::NONE)?,
                None => {
                    return Err(key_error(format!(
                        "leg `{}`: a `custom` gait needs each leg's `phase`",
                        self.name
                    )))
                }
            },
            other => {
                return Err(key_error(format!(
                    "key `gait`: unknown gait `{other}`; \
                     one of trot, pronk, bound, jump, pace, custom"
                )))
            }
        };
        if gait != "custom" && self.phase.is_some() {
            return Err(key_error(format!(
                "leg `{}`: `phase` is for `gait = \"custom\"` (the {gait} sets the phases)",
                self.name
            )));
        }
        Ok(value)
    }
}

fn key_error(message: String) -> Error {
    Error::Key { message }
}

/// One simulated walk at one grid point, and what it measures.
#[derive(Debug, Clone)]
pub struct Walk {
    pub frequency: f64,
    pub payload: f64,
    /// The robot's mass without the payload (kg).
    pub robot_mass: f64,
    pub run: Run,
}

/// The averages of a walk over its measured cycles.
#[derive(Debug, Clone, Copy, Default)]
pub struct Run {
    /// Forward (+x) and sideways (+y) speed of the base (m/s).
    pub speed: f64,
    pub sideways: f64,
    /// Mean height of the base above its starting height, and its peak-to-peak (m).
    pub height: f64,
    pub height_range: f64,
    /// Mean pitch and roll and their peak-to-peak, and the change of heading (rad).
    pub pitch: f64,
    pub pitch_range: f64,
    pub roll: f64,
    pub roll_range: f64,
    pub yaw_change: f64,
    /// Distance the feet slide on the floor while in contact, per foot and cycle (m).
    pub slip_per_cycle: f64,
    /// Fraction of the time with no foot on the floor.
    pub airborne: f64,
    /// Mean mechanical power of the drives (W).
    pub drive_power: f64,
    /// Integrator steps of the whole run.
    pub steps: usize,
}

impl Walk {
    pub fn per_cycle(&self) -> f64 {
        self.run.speed / self.frequency
    }

    /// Mechanical cost of transport, drive power over weight times speed (NaN when the
    /// robot does not advance).
    pub fn cost_of_transport(&self) -> f64 {
        if self.run.speed > 0.0 {
            self.run.drive_power / ((self.robot_mass + self.payload) * GRAVITY * self.run.speed)
        } else {
            f64::NAN
        }
    }
}

/// Every grid point's walk.
pub struct Walks {
    pub model_name: String,
    /// The model at the first grid point (its names, for the shown walk's table).
    pub session: Session,
    pub body_length: f64,
    pub frequencies: Vec<f64>,
    pub payloads: Vec<f64>,
    pub walks: Vec<Walk>,
    /// Grid points that did not simulate, with the reason.
    pub failed: Vec<String>,
    /// A walk's trajectory to show (the first frequency's unloaded walk), if it ran.
    pub shown: Option<(Walk, Trajectory)>,
    /// The spec's `compare` robot over the same grid.
    pub compared: Option<Box<Walks>>,
}

/// Simulates every (frequency, payload) of the grid, for the robot and the one it is compared
/// with, on all cores, telling `progress` `(walks done, walks)` as each finishes.
pub fn compute(spec: &Spec, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<Walks, Error> {
    let settings = spec.settings()?;
    let mut specs = vec![spec.clone()];
    if let Some(path) = &spec.compare {
        let mut other = spec.clone();
        other.model.path = path.clone();
        other.compare = None;
        specs.push(other);
    }
    // Check the names once before the runs.
    let probes = specs
        .iter()
        .map(|spec| open(spec, settings.frequencies[0], 0.0))
        .collect::<Result<Vec<_>, Error>>()?;
    let grid: Vec<(f64, f64)> = settings
        .frequencies
        .iter()
        .flat_map(|&f| settings.payloads.iter().map(move |&m| (f, m)))
        .collect();
    let jobs: Vec<(usize, usize, f64, f64)> = (0..specs.len())
        .flat_map(|robot| {
            let grid = &grid;
            (0..grid.len()).map(move |k| (robot, k, grid[k].0, grid[k].1))
        })
        .collect();
    let total = jobs.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let results = parallel(jobs, threads(), |(robot, k, frequency, payload)| {
        let walk = walk(&specs[robot], frequency, payload);
        let finished = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        progress(finished, total);
        (robot, k, frequency, payload, walk)
    });
    let mut robots: Vec<Walks> = probes
        .into_iter()
        .map(|probe| Walks {
            model_name: probe.session.model.name().to_string(),
            session: probe.session,
            body_length: settings.body_length,
            frequencies: settings.frequencies.clone(),
            payloads: settings.payloads.clone(),
            walks: Vec::new(),
            failed: Vec::new(),
            shown: None,
            compared: None,
        })
        .collect();
    for (robot, k, frequency, payload, result) in results {
        let walks = &mut robots[robot];
        match result {
            Ok((walk, trajectory)) => {
                if k == 0 {
                    walks.shown = Some((walk.clone(), trajectory));
                }
                walks.walks.push(walk);
            }
            Err(error) => walks
                .failed
                .push(format!("{frequency} Hz, {:.2} g: {error}", payload * 1e3)),
        }
    }
    let compared = (robots.len() > 1).then(|| Box::new(robots.remove(1)));
    let mut walks = robots.remove(0);
    walks.compared = compared;
    Ok(walks)
}

/// The session of one grid point and the indices the measurements read.
struct Opened {
    session: Session,
    /// The base's first velocity speed (`BASE.vx`): every body moves with it, so its diagonal
    /// entry of `M` is the total mass.
    base_velocity: usize,
    quaternion: usize,
    position: usize,
    power: usize,
    /// Per leg: the contact's normal force and the foot's x.
    legs: Vec<(usize, usize)>,
}

fn open(spec: &Spec, frequency: f64, payload: f64) -> Result<Opened, Error> {
    let mut sets = spec.model.set.clone();
    sets.push(format!("{}={payload} kg", spec.payload));
    let session = Session::open(&spec.model.path, &sets, &spec.drives(frequency)?)?;
    let base_velocity = session.index_of(NameKind::Speed, &format!("{}.vx", spec.base), None)?;
    let quaternion = match session.model.unit_quaternions() {
        [index] => *index,
        found => {
            return Err(key_error(format!(
                "key `base`: the robot must have exactly one unit quaternion (its floating \
                 base's), found {}",
                found.len()
            )))
        }
    };
    let position = session.output_index(&format!("{}.x", spec.position))?;
    let power = session.output_index(&spec.drive_power)?;
    let legs = spec
        .legs
        .iter()
        .map(|leg| {
            Ok((
                session.output_index(&format!("{}.normal_force", leg.contact))?,
                session.output_index(&format!("{}.x", leg.foot))?,
            ))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    Ok(Opened {
        session,
        base_velocity,
        quaternion,
        position,
        power,
        legs,
    })
}

/// One walk: simulate from rest, then average over the measured cycles.
pub fn walk(spec: &Spec, frequency: f64, payload: f64) -> Result<(Walk, Trajectory), Error> {
    let opened = open(spec, frequency, payload)?;
    let session = &opened.session;
    let state = session.assemble(&spec.model.independent)?;
    let model = &session.model;
    let nu = model.nu();
    let mut mass = vec![0.0; nu * nu];
    model.mass_matrix(0.0, &state.q, &vec![0.0; model.ninputs()], &mut mass);
    let total_mass = mass[opened.base_velocity * (nu + 1)];
    let period = 1.0 / frequency;
    let options = SimOptions {
        t_end: (spec.settle_cycles + spec.cycles) * period,
        output_interval: period / spec.samples_per_cycle as f64,
        method: {
            let (rtol, atol, h_max) = (spec.rtol, spec.rtol * 1e-3, f64::INFINITY);
            match spec.method {
                WalkMethod::Dopri5 => Method::Dopri5 { rtol, atol, h_max },
                WalkMethod::RosenbrockW => Method::RosenbrockW { rtol, atol, h_max },
            }
        },
        ..SimOptions::default()
    };
    let trajectory = session.simulate(&state, &options, &mut |_| {})?;
    let run = measure(
        &opened,
        &trajectory,
        spec.settle_cycles * period,
        spec.cycles,
    );
    let walk = Walk {
        frequency,
        payload,
        robot_mass: total_mass - payload,
        run,
    };
    Ok((walk, trajectory))
}

/// Roll, pitch and yaw (rad) of the unit quaternion `e` (scalar first; body to Newtonian),
/// the Z-Y-X (yaw, pitch, roll) sequence.
pub fn roll_pitch_yaw(e: &[f64]) -> (f64, f64, f64) {
    let (e0, e1, e2, e3) = (e[0], e[1], e[2], e[3]);
    let roll = f64::atan2(2.0 * (e0 * e1 + e2 * e3), 1.0 - 2.0 * (e1 * e1 + e2 * e2));
    let pitch = (2.0 * (e0 * e2 - e3 * e1)).clamp(-1.0, 1.0).asin();
    let yaw = f64::atan2(2.0 * (e0 * e3 + e1 * e2), 1.0 - 2.0 * (e2 * e2 + e3 * e3));
    (roll, pitch, yaw)
}

/// The averages over the samples from `from` (s) on, `cycles` cycles.
fn measure(opened: &Opened, trajectory: &Trajectory, from: f64, cycles: f64) -> Run {
    let start = trajectory
        .times
        .iter()
        .position(|&t| t >= from - 1e-12)
        .unwrap_or(0);
    let samples = start..trajectory.len();
    let duration = trajectory.times[trajectory.len() - 1] - trajectory.times[start];
    let output = |k: usize, index: usize| trajectory.outputs[k][index];
    let (first, last) = (start, trajectory.len() - 1);
    let position = opened.position;
    let attitude: Vec<(f64, f64, f64)> = samples
        .clone()
        .map(|k| {
            let q = &trajectory.q[k];
            roll_pitch_yaw(&q[opened.quaternion..opened.quaternion + 4])
        })
        .collect();
    let heights: Vec<f64> = samples
        .clone()
        .map(|k| output(k, position + 2) - output(0, position + 2))
        .collect();
    let (height, height_range) = mean_range(&heights);
    let pitch: Vec<f64> = attitude.iter().map(|a| a.1).collect();
    let roll: Vec<f64> = attitude.iter().map(|a| a.0).collect();
    let (pitch, pitch_range) = mean_range(&pitch);
    let (roll, roll_range) = mean_range(&roll);
    let yaw_change = attitude[attitude.len() - 1].2 - attitude[0].2;
    // Slip: the foot's travel in the floor plane between samples where it presses on the
    // floor at both ends.
    let mut slip = 0.0;
    for &(normal, foot) in &opened.legs {
        for k in start + 1..trajectory.len() {
            if output(k - 1, normal) > 0.0 && output(k, normal) > 0.0 {
                let dx = output(k, foot) - output(k - 1, foot);
                let dy = output(k, foot + 1) - output(k - 1, foot + 1);
                slip += dx.hypot(dy);
            }
        }
    }
    let airborne = samples
        .clone()
        .filter(|&k| {
            opened
                .legs
                .iter()
                .all(|&(normal, _)| output(k, normal) <= 0.0)
        })
        .count() as f64
        / (last - first + 1) as f64;
    // Mean drive power by the trapezoidal rule.
    let mut work = 0.0;
    for k in start + 1..trajectory.len() {
        let dt = trajectory.times[k] - trajectory.times[k - 1];
        work += 0.5 * dt * (output(k, opened.power) + output(k - 1, opened.power));
    }
    Run {
        speed: (output(last, position) - output(first, position)) / duration,
        sideways: (output(last, position + 1) - output(first, position + 1)) / duration,
        height,
        height_range,
        pitch,
        pitch_range,
        roll,
        roll_range,
        yaw_change,
        slip_per_cycle: slip / (opened.legs.len() as f64 * cycles),
        airborne,
        drive_power: work / duration,
        steps: trajectory.stats.accepted_steps,
    }
}

/// Mean and peak-to-peak of `values`.
fn mean_range(values: &[f64]) -> (f64, f64) {
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    (mean, peak_to_peak(values))
}
