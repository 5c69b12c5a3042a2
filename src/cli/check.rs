//! `mech check MODEL`: validate a model and print its coordinates, bodies and degrees of
//! freedom (the mobility at the assembled q0 for models with loops).
//!
//! Consumes: the model path. Produces: text on stdout.

use super::Error;
use std::path::PathBuf;

use clap::Args;
use mech_codegen::ir::{Dimension, Model};

use crate::session::{self, Session};

#[derive(Args, Clone, Debug)]
pub struct CheckArgs {
    /// The `.mech` file.
    pub model: PathBuf,
}

pub fn run(args: &CheckArgs) -> Result<(), Error> {
    let path = args.model.as_path();
    let session = Session::open(path, &[], &[])?;
    let compiled = &session.compiled;
    let model = &compiled.model;
    println!("model `{}` ({})", model.name, path.display());
    if model.loops.is_empty() && model.velocity_constraints.is_empty() {
        println!(
            "  {} bodies, {} joints, {} degrees of freedom",
            model.bodies.len(),
            model.joints.len(),
            model.nu()
        );
    } else {
        let state = session.assemble(&[])?;
        let mobility = state
            .mobility
            .as_ref()
            .map(ToString::to_string)
            .unwrap_or_default();
        let velocity = match model.velocity_constraints.len() {
            0 => String::new(),
            1 => ", 1 velocity constraint".to_string(),
            n => format!(", {n} velocity constraints"),
        };
        println!(
            "  {} bodies, {} joints, {} loops{velocity}; at the assembled q0: {mobility}",
            model.bodies.len(),
            model.joints.len(),
            model.loops.len()
        );
        // The singular values that decide the rank, and any warning about them.
        let report = session::assembly_report(&session.model, &state);
        for line in report.lines().skip(1).take_while(|line| !line.is_empty()) {
            println!("  {line}");
        }
    }
    print_coordinates(model);
    print_chosen_speeds(model);
    print_bodies(model);
    let list = |title: &str, items: Vec<String>| {
        if !items.is_empty() {
            println!("\n{title}: {}", items.join(", "));
        }
    };
    list(
        "parameters",
        model
            .params
            .iter()
            .map(|(_, p)| match p.dimension == Dimension::NONE {
                // A plain number, or an angle in rad.
                true => format!("{} = {}", p.name, p.value),
                false => format!("{} = {} {}", p.name, p.value, p.dimension),
            })
            .collect(),
    );
    list(
        "inputs",
        model
            .inputs
            .iter()
            .map(|(_, i)| format!("{} [{}]", i.name, i.dimension))
            .collect(),
    );
    list("outputs", compiled.equations.output_names.clone());
    Ok(())
}

/// Each joint's coordinates (and quaternion or Euler angles) with their initial values, then
/// the speeds chosen by `speed` declarations, if any.
fn print_coordinates(model: &Model) {
    match (model.speeds.is_empty(), model.has_kinematic_rates()) {
        (false, _) => println!("\ncoordinates (q, with q̇ = W(q) u of the chosen speeds below):"),
        (true, false) => println!("\ncoordinates (q, with u = q̇):"),
        (true, true) => println!(
            "\ncoordinates (q, with u = q̇ except for quaternions, Euler angles and free joints' \
             positions: q̇ = W(q) u):"
        ),
    }
    for (_, joint) in model.joints.iter() {
        for &c in &joint.coordinates {
            let coordinate = &model.coordinates[c];
            let unit = if coordinate.dimension == Dimension::NONE {
                "rad"
            } else {
                "m"
            };
            println!(
                "  {:<16} {:?} joint `{}`, q0 = {} {unit}, u0 = {} {unit}/s",
                coordinate.name,
                joint.kind,
                joint.name,
                coordinate.initial,
                coordinate.initial_speed
            );
        }
        if let Some(quaternion) = joint.quaternion.map(|e| &model.quaternions[e]) {
            let [wx, wy, wz] = quaternion.initial_angular_velocity;
            println!(
                "  {:<16} {:?} joint `{}`: unit quaternion ({}), q0 = (1, 0, 0, 0); \
                 speeds {} (angular velocity in the child frame), u0 = [{wx}, {wy}, {wz}] rad/s",
                quaternion.name,
                joint.kind,
                joint.name,
                quaternion.coordinate_names().join(", "),
                quaternion.speed_names().join(", "),
            );
        }
        let translation = model
            .translations
            .iter()
            .find(|(_, t)| t.name == joint.name);
        if let Some((_, translation)) = translation {
            let [vx, vy, vz] = translation.initial_velocity;
            println!(
                "  {:<16} {:?} joint `{}`: position ({}) in the joint frame, q0 = 0 m; \
                 speeds {} (velocity in the child frame), u0 = [{vx}, {vy}, {vz}] m/s",
                translation.name,
                joint.kind,
                joint.name,
                translation.coordinate_names().join(", "),
                translation.speed_names().join(", "),
            );
        }
        let euler = model
            .euler_angles
            .iter()
            .find(|(_, a)| a.name == joint.name);
        if let Some((_, angles)) = euler {
            let [wx, wy, wz] = angles.initial_angular_velocity;
            println!(
                "  {:<16} {:?} joint `{}`: Euler angles {} ({}), q0 = {:?} rad; \
                 speeds {} (angular velocity in the child frame), u0 = [{wx}, {wy}, {wz}] rad/s",
                angles.name,
                joint.kind,
                joint.name,
                angles.sequence_name(),
                angles.coordinate_names().join(", "),
                angles.initial_angles,
                angles.speed_names().join(", "),
            );
        }
    }
}

/// The speeds chosen by `speed` declarations (`u = Y(q) q̇`), with their initial values.
fn print_chosen_speeds(model: &Model) {
    if model.speeds.is_empty() {
        return;
    }
    println!("\nspeeds (chosen by `speed`: u = Y(q) q̇, mech derives q̇ = W(q) u with W = Y⁻¹):");
    let described = mech_codegen::kane::describe_speeds(model);
    for (speed, description) in model.speeds.iter().zip(described) {
        println!("  {description}, u0 = {}", speed.initial);
    }
}

/// Each body and the joint that attaches it to its parent.
fn print_bodies(model: &Model) {
    println!("\nbodies:");
    for (_, body) in model.bodies.iter() {
        let parent = model
            .joints
            .iter()
            .find(|(_, j)| model.bodies[j.child].name == body.name);
        let attached = parent.map_or("?".to_string(), |(_, joint)| {
            let parent_name = joint
                .parent
                .map_or("newtonian", |b| model.bodies[b].name.as_str());
            format!(
                "child of `{parent_name}` by {:?} joint `{}`",
                joint.kind, joint.name
            )
        });
        println!("  {:<16} {attached}", body.name);
    }
}
