//! Embeds two generated models and runs them with mech-runtime alone: a double pendulum
//! (a tree: the fixed-size functions, a simulation) and a four-bar linkage (a closed loop:
//! assembly, constrained accelerations, a simulation checked for loop closure and energy).

pub mod double_pendulum {
    mech_runtime::include_model!("double_pendulum");
}

pub mod four_bar {
    mech_runtime::include_model!("four_bar");
}

use double_pendulum::DoublePendulum;
use four_bar::FourBar;
use mech_runtime::{AssemblyOptions, ConstrainedSolver, Model, RuntimeError, SVector, SimOptions};

fn main() -> Result<(), RuntimeError> {
    double_pendulum()?;
    four_bar()
}

fn double_pendulum() -> Result<(), RuntimeError> {
    let mut model = DoublePendulum::new();
    model.params.m2 = 0.015; // parameters are plain fields (SI units), settable at run time

    // The fixed-size functions: M(q) and F(t, q, u, inputs) on nalgebra types, no
    // allocation. `initial_q()` is an associated function, like `DoublePendulum::NQ`: the
    // q0 written in the model does not depend on the parameters.
    let q = DoublePendulum::initial_q();
    let u = DoublePendulum::initial_u();
    let inputs = SVector::<f64, 0>::zeros();
    let mass = model.mass_matrix_fixed(0.0, &q, &inputs);
    let forcing = model.forcing_fixed(0.0, &q, &u, &inputs);
    println!("double pendulum: M(q0) = {mass}F(q0, u0) = {forcing}");

    // The runtime's integrator, through the `Model` trait (slices).
    let options = SimOptions {
        t_end: 1.0,
        output_interval: 0.25,
        ..SimOptions::default()
    };
    let signals = mech_runtime::default_signals(&model);
    let run = mech_runtime::simulate(
        &model,
        q.as_slice(),
        u.as_slice(),
        &signals,
        &options,
        &mut |_| {},
    )?;
    let energy = model.output_index("energy").expect("declared in the model");
    for (t, y) in run.times.iter().zip(&run.outputs) {
        println!("t = {t:.2} s  kinetic energy = {:.6e} J", y[energy]);
    }
    Ok(())
}

fn four_bar() -> Result<(), RuntimeError> {
    let model = FourBar::new();
    let (mut q, mut u) = (vec![0.0; model.nq()], vec![0.0; model.nu()]);
    model.initial_state(&mut q, &mut u);

    // The q0, u0 written in the model only roughly close the loop: hold the crank's angle
    // and speed, solve φ(q) = 0 and J u = 0 for the other coordinates.
    let crank = model
        .coordinate_index("crank_angle")
        .expect("declared in the model");
    mech_runtime::assemble(&model, 0.0, &mut q, &[crank], &AssemblyOptions::default())?;
    mech_runtime::assemble_speeds(&model, 0.0, &q, &mut u, &[crank])?;
    println!("four-bar: assembled q = {q:.6?}, u = {u:.6?}");

    // Constrained accelerations: M u̇ = F + Jᵀλ with J u̇ = −J̇u; λ are the loop's forces.
    let mut solver = ConstrainedSolver::for_model(&model);
    let mut udot = vec![0.0; model.nu()];
    solver.accelerations(&model, 0.0, &q, &u, &[], &mut udot)?;
    println!("u̇ = {udot:.6?}, λ = {:.6?} N", solver.multipliers());

    // Two seconds undamped, in full coordinates: the state is projected back onto the loop
    // after every step (`SimOptions::constraint_tolerance`).
    let options = SimOptions {
        t_end: 2.0,
        output_interval: 0.01,
        ..SimOptions::default()
    };
    let signals = mech_runtime::default_signals(&model);
    let run = mech_runtime::simulate(&model, &q, &u, &signals, &options, &mut |_| {})?;

    let mut phi = vec![0.0; model.nc()];
    let mut worst_phi = 0.0_f64;
    for q in &run.q {
        model.constraints(0.0, q, &mut phi);
        worst_phi = phi.iter().fold(worst_phi, |worst, v| worst.max(v.abs()));
    }
    let ke = model.output_index("ke").expect("declared in the model");
    let pe = model.output_index("pe").expect("declared in the model");
    let energies: Vec<f64> = run.outputs.iter().map(|y| y[ke] + y[pe]).collect();
    let drift = energies
        .iter()
        .map(|e| (e - energies[0]).abs())
        .fold(0.0, f64::max);
    println!(
        "four-bar over {} s: max |φ| = {worst_phi:.1e} m",
        options.t_end
    );
    println!("energy {:.6} J, drift {drift:.1e} J", energies[0]);
    assert!(
        worst_phi < 1e-9,
        "the loop opened: max |φ| = {worst_phi:e} m"
    );
    assert!(
        drift < 1e-6 * energies[0].abs(),
        "energy drifted by {drift:e} J"
    );
    Ok(())
}
