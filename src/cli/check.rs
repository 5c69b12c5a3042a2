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

/// Each joint's coordinates (and quaternion, Euler angles or free position) with their initial
/// values, then
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
        let joint_part =
            |name: &str, what: String, q0: String, speeds: String, u0: ([f64; 3], &str)| {
                let ([x, y, z], unit) = u0;
                println!(
                    "  {name:<16} {:?} joint `{}`: {what}, q0 = {q0}; speeds {speeds}, \
                 u0 = [{x}, {y}, {z}] {unit}",
                    joint.kind, joint.name,
                );
            };
        let in_child = |names: [String; 3], what: &str| {
            format!("{} ({what} in the child frame)", names.join(", "))
        };
        if let Some(quaternion) = joint.quaternion.map(|e| &model.quaternions[e]) {
            joint_part(
                &quaternion.name,
                format!(
                    "unit quaternion ({})",
                    quaternion.coordinate_names().join(", ")
                ),
                "(1, 0, 0, 0)".into(),
                in_child(quaternion.speed_names(), "angular velocity"),
                (quaternion.initial_angular_velocity, "rad/s"),
            );
        }
        let same_name = |name: &str| name == joint.name;
        if let Some((_, angles)) = model.euler_angles.iter().find(|(_, a)| same_name(&a.name)) {
            joint_part(
                &angles.name,
                format!(
                    "Euler angles {} ({})",
                    angles.sequence_name(),
                    angles.coordinate_names().join(", ")
                ),
                format!("{:?} rad", angles.initial_angles),
                in_child(angles.speed_names(), "angular velocity"),
                (angles.initial_angular_velocity, "rad/s"),
            );
        }
        if let Some((_, position)) = model.translations.iter().find(|(_, t)| same_name(&t.name)) {
            joint_part(
                &position.name,
                format!(
                    "position ({}) in the joint frame",
                    position.coordinate_names().join(", ")
                ),
                "0 m".into(),
                in_child(position.speed_names(), "velocity"),
                (position.initial_velocity, "m/s"),
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
