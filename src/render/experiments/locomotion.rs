//! Rendering of `kind = "locomotion"` experiment results: the walks' table, the paper's
//! facts beside the model's, speed against payload (Fig. 9), the CSV of every walk and of
//! one walk's motion (for `mech animate`).
//!
//! Consumes: the kind's spec and what its `compute` returns. Produces: an [`Outcome`] and
//! the files it lists.

use super::shared::csv;
use crate::experiments::locomotion::{compute, Spec, Walk, WalkMethod, Walks};
use crate::experiments::Error;
use crate::output::CsvTable;
use crate::render::plot;
use crate::render::report::Outcome;
use crate::render::run::trajectory_table;
use crate::render::table::Table;
use mech_runtime::Model;
use std::path::Path;

/// The payload the paper's HAMR-VI carries (Sec. V-C), kg.
const PAPER_PAYLOAD: f64 = 2.9e-3;
/// How much more HAMR-VI carries than HAMR-V2.0 (Sec. V-C: a 114 % increase), kg.
const PAPER_PAYLOAD_GAIN: f64 = 1.6e-3;

/// A walk advances if it gains at least this much per cycle (m): a tenth of a millimetre,
/// well above what the body's sway leaves over whole cycles.
const ADVANCE_PER_CYCLE: f64 = 0.1e-3;

pub fn run(
    spec: &Spec,
    dir: &Path,
    progress: super::shared::Progress<'_>,
) -> Result<Outcome, Error> {
    let walks = compute(spec, progress)?;
    let mut outcome = Outcome::with_method(method_text(spec, &walks));
    // The robot, then the one it is compared with (named apart in files and values).
    let robots: Vec<(&Walks, String)> = std::iter::once((&walks, String::new()))
        .chain(
            walks
                .compared
                .as_deref()
                .map(|other| (other, format!("{}_", other.model_name))),
        )
        .collect();
    for (robot, _) in &robots {
        outcome.tables.push(walks_table(robot));
    }
    outcome.tables.push(facts_table(&walks));
    for (robot, prefix) in &robots {
        let rows: Vec<Vec<f64>> = robot
            .walks
            .iter()
            .map(|w| row(w, robot.body_length))
            .collect();
        let file = match prefix.is_empty() {
            true => "locomotion.csv".to_string(),
            false => format!("locomotion_{}.csv", robot.model_name),
        };
        csv(&mut outcome, dir, &file, &HEADER, &rows)?;
        for walk in &robot.walks {
            let key = format!("{}Hz_{}mg", walk.frequency, (walk.payload * 1e6).round());
            outcome
                .values
                .insert(format!("{prefix}speed_{key}"), walk.run.speed);
            outcome
                .values
                .insert(format!("{prefix}airborne_{key}"), walk.run.airborne);
        }
    }
    shown_walk(&mut outcome, dir, &walks)?;
    speed_payload_plot(&mut outcome, dir, &robots)?;
    for (robot, _) in &robots {
        outcome.notes.extend(observations(robot, robots.len() > 1));
        if !robot.failed.is_empty() {
            outcome.notes.push(format!(
                "Did not simulate ({}): {}",
                robot.model_name,
                robot.failed.join("; ")
            ));
        }
    }
    Ok(outcome)
}

/// The walk shown in full, if one ran: its trajectory as a CSV table and, from it, the 3D
/// page that `mech animate` would make of that table.
fn shown_walk(outcome: &mut Outcome, dir: &Path, walks: &Walks) -> Result<(), Error> {
    let Some((walk, trajectory)) = &walks.shown else {
        return Ok(());
    };
    let (header, rows) = trajectory_table(&walks.session.model, trajectory);
    let names: Vec<&str> = header.iter().map(String::as_str).collect();
    let file = format!("walk_{}Hz.csv", walk.frequency);
    csv(outcome, dir, &file, &names, &rows)?;
    // The same walk in 3D (as `mech animate` plays the CSV).
    let table = CsvTable {
        columns: (0..header.len())
            .map(|j| rows.iter().map(|row| row[j]).collect())
            .collect(),
        lines: (2..).take(rows.len()).collect(),
        header,
    };
    let model = &walks.session.model;
    let values: Vec<f64> = (0..model.nparams()).map(|i| model.param(i)).collect();
    let motion = crate::animation::animate(&walks.session.compiled, &values, &table)
        .map_err(Error::Animation)?;
    let page = crate::render::animation::page(&motion);
    let path = dir.join(format!("walk_{}Hz.html", walk.frequency));
    outcome.add_file(crate::output::File::new(path, page));
    Ok(())
}

/// Forward speed against payload (Fig. 9): one colour per frequency, the compared robot's
/// curves dashed in its frequency's colour.
fn speed_payload_plot(
    outcome: &mut Outcome,
    dir: &Path,
    robots: &[(&Walks, String)],
) -> Result<(), Error> {
    let mut curves: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut styles = Vec::new();
    for (index, (robot, _)) in robots.iter().enumerate() {
        for (color, &f) in robot.frequencies.iter().enumerate() {
            let points: Vec<&Walk> = robot.walks.iter().filter(|w| w.frequency == f).collect();
            let payloads: Vec<f64> = points.iter().map(|w| w.payload * 1e3).collect();
            let speeds: Vec<f64> = points.iter().map(|w| w.run.speed * 1e3).collect();
            let label = match robots.len() {
                1 => format!("{f} Hz"),
                _ => format!("{f} Hz, {}", robot.model_name),
            };
            if !payloads.is_empty() {
                curves.push((label, payloads, speeds));
                styles.push(plot::CurveStyle {
                    color,
                    dashed: index > 0,
                });
            }
        }
    }
    if !curves.is_empty() {
        let names: Vec<&str> = robots.iter().map(|(r, _)| r.model_name.as_str()).collect();
        let title = format!(
            "{}: forward speed against payload (Fig. 9)",
            names.join(" and ")
        );
        let plot = plot::XyPlot {
            styles: Some(&styles),
            ..plot::XyPlot::new(&title, "payload [g]", "forward speed [mm/s]", &curves)
        }
        .render(&dir.join("speed_payload.svg"))?;
        outcome.add_plot(plot);
    }
    Ok(())
}

const HEADER: [&str; 15] = [
    "frequency_hz",
    "payload_g",
    "speed_mm_s",
    "speed_bl_s",
    "per_cycle_mm",
    "sideways_mm_s",
    "height_mm",
    "height_pp_mm",
    "pitch_pp_deg",
    "roll_pp_deg",
    "yaw_change_deg",
    "slip_mm_per_cycle",
    "airborne",
    "cost_of_transport",
    "steps",
];

fn row(walk: &Walk, body_length: f64) -> Vec<f64> {
    let run = &walk.run;
    vec![
        walk.frequency,
        walk.payload * 1e3,
        run.speed * 1e3,
        run.speed / body_length,
        walk.per_cycle() * 1e3,
        run.sideways * 1e3,
        run.height * 1e3,
        run.height_range * 1e3,
        run.pitch_range.to_degrees(),
        run.roll_range.to_degrees(),
        run.yaw_change.to_degrees(),
        run.slip_per_cycle * 1e3,
        run.airborne,
        walk.cost_of_transport(),
        run.steps as f64,
    ]
}

fn walks_table(walks: &Walks) -> Table {
    let title = format!(
        "Walks of `{}`: averages over the measured cycles",
        walks.model_name
    );
    let mut table = Table::new(
        &title,
        &[
            "f [Hz]",
            "payload [g]",
            "speed [mm/s]",
            "[BL/s]",
            "[mm/cycle]",
            "sideways [mm/s]",
            "height [mm] (p-p)",
            "pitch p-p [°]",
            "roll p-p [°]",
            "yaw change [°]",
            "slip [mm/cycle]",
            "airborne",
            "CoT",
        ],
    );
    for walk in &walks.walks {
        let cells = row(walk, walks.body_length);
        let cost = walk.cost_of_transport();
        table.row(vec![
            format!("{}", walk.frequency),
            format!("{:.2}", cells[1]),
            format!("{:.2}", cells[2]),
            format!("{:.3}", cells[3]),
            format!("{:.3}", cells[4]),
            format!("{:+.2}", cells[5]),
            format!("{:+.3} ({:.3})", cells[6], cells[7]),
            format!("{:.2}", cells[8]),
            format!("{:.2}", cells[9]),
            format!("{:+.2}", cells[10]),
            format!("{:.3}", cells[11]),
            format!("{:.0} %", 100.0 * cells[12]),
            if cost.is_finite() {
                format!("{cost:.1}")
            } else {
                "–".into()
            },
        ]);
    }
    table
}

/// The largest payload of the grid at which the walk at `frequency` advances, if any.
fn largest_advancing(walks: &Walks, frequency: f64) -> Option<f64> {
    walks
        .walks
        .iter()
        .filter(|w| w.frequency == frequency && w.per_cycle() >= ADVANCE_PER_CYCLE)
        .map(|w| w.payload)
        .reduce(f64::max)
}

fn facts_table(walks: &Walks) -> Table {
    let mut table = Table::new(
        "The paper's facts (Sec. V-C) beside the model",
        &["fact", "paper", "model"],
    );
    let paper = [
        format!("{:.1} g (1–10 Hz)", PAPER_PAYLOAD * 1e3),
        format!(
            "{:.1} g (HAMR-V2.0 carries {:.1} g less)",
            (PAPER_PAYLOAD - PAPER_PAYLOAD_GAIN) * 1e3,
            PAPER_PAYLOAD_GAIN * 1e3
        ),
    ];
    let robots = std::iter::once(walks).chain(walks.compared.as_deref());
    for (robot, paper) in robots.zip(paper) {
        let fact = match walks.compared {
            Some(_) => format!("largest payload carried forwards, `{}`", robot.model_name),
            None => "largest payload carried forwards".into(),
        };
        for &f in &robot.frequencies {
            let top = grid_top(robot);
            let model = match largest_advancing(robot, f) {
                Some(m) if m >= top => {
                    format!("≥ {:.2} g at {f} Hz (the grid's largest)", m * 1e3)
                }
                Some(m) => format!("{:.2} g at {f} Hz", m * 1e3),
                None => format!("none of the grid at {f} Hz"),
            };
            table.row(vec![fact.clone(), paper.clone(), model]);
        }
    }
    if let Some(walk) = walks
        .walks
        .iter()
        .find(|w| w.frequency == 10.0 && w.payload == 0.0)
    {
        table.row(vec![
            "unloaded trot at 10 Hz".into(),
            "the body bounces and forward progress stops".into(),
            format!(
                "airborne {:.0} % of the time, body height p-p {:.3} mm, {:.3} mm/cycle",
                100.0 * walk.run.airborne,
                walk.run.height_range * 1e3,
                walk.per_cycle() * 1e3
            ),
        ]);
    }
    if let Some(other) = walks.compared.as_deref() {
        table.row(vec![
            format!("`{}` faster than `{}`", walks.model_name, other.model_name),
            "at every frequency and payload except unloaded and lightly loaded at 10 Hz".into(),
            faster_at(walks, other),
        ]);
    }
    table
}

/// Where the walks of `one` are faster than those of `other` at the same grid point.
fn faster_at(one: &Walks, other: &Walks) -> String {
    let pairs: Vec<(&Walk, &Walk)> = one
        .walks
        .iter()
        .filter_map(|a| {
            let b = other
                .walks
                .iter()
                .find(|b| b.frequency == a.frequency && b.payload == a.payload)?;
            Some((a, b))
        })
        .collect();
    let slower: Vec<String> = pairs
        .iter()
        .filter(|(a, b)| a.run.speed <= b.run.speed)
        .map(|(a, _)| format!("{} Hz with {:.2} g", a.frequency, a.payload * 1e3))
        .collect();
    let faster = pairs.len() - slower.len();
    match slower.is_empty() {
        true => format!("at all {} grid points", pairs.len()),
        false => format!(
            "at {faster} of {} grid points; not at {}",
            pairs.len(),
            slower.join(", ")
        ),
    }
}

fn grid_top(walks: &Walks) -> f64 {
    walks.payloads.iter().fold(0.0, |a: f64, &b| a.max(b))
}

fn observations(walks: &Walks, named: bool) -> Vec<String> {
    let robot = match named {
        true => format!(" `{}`", walks.model_name),
        false => String::new(),
    };
    let mut notes = Vec::new();
    for &f in &walks.frequencies {
        let speeds: Vec<String> = walks
            .walks
            .iter()
            .filter(|w| w.frequency == f)
            .map(|w| format!("{:.2} g: {:.1} mm/s", w.payload * 1e3, w.run.speed * 1e3))
            .collect();
        if !speeds.is_empty() {
            notes.push(format!("Model{robot} at {f} Hz: {}.", speeds.join(", ")));
        }
    }
    notes
}

fn method_text(spec: &Spec, walks: &Walks) -> String {
    format!(
        "The whole robot (`{}`, {}) from rest on the floor, driven by a {} gait: each leg's \
         swing drive {} sin(2πft + φ) with its leg's phase φ, the lift drive {} from it, the \
         legs wired the other way given half a cycle more. {} settle cycle(s), then averages \
         over {} cycle(s), {} samples per cycle ({}, rtol {:e}). Speed is the base's \
         forward (+x) travel over the measured cycles; height, pitch and roll are the base's \
         (mean and peak to peak); slip is the feet's travel on the floor while pressing on \
         it; airborne is the share of samples with no foot on the floor; the cost of \
         transport is the drives' mean mechanical power over weight times speed (the \
         electrical input is larger by the actuators' efficiency). A walk advances if it \
         gains at least {} mm per cycle. Body length {} mm.",
        walks.model_name,
        spec.model.path.display(),
        spec.gait,
        spec.amplitude,
        spec.lift_phase,
        spec.settle_cycles,
        spec.cycles,
        spec.samples_per_cycle,
        match spec.method {
            WalkMethod::Dopri5 => "DOPRI5",
            WalkMethod::RosenbrockW => "the W-method ROS34PW2, implicit in the feet's friction",
        },
        spec.rtol,
        ADVANCE_PER_CYCLE * 1e3,
        walks.body_length * 1e3,
    )
}
