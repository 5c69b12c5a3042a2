//! Profiling driver for the loop models (the `callgrind` counts quoted in docs/benchmarks.md):
//!
//! ```text
//! cargo build --release -p mech-bench --example profile_loops
//! valgrind --tool=callgrind target/release/examples/profile_loops udot 100000 four_bar
//! valgrind --tool=callgrind target/release/examples/profile_loops sim 200 four_bar   # DOP853; sim5: DOPRI5
//! target/release/examples/profile_loops dump 1 spherical_five_bar   # M, F, J, J̇u, u̇, λ as JSON
//! ```
use mech_bench::loops::{assembled, four_bar::FourBar, spherical_five_bar::SphericalFiveBar};
use mech_runtime::{ConstrainedSolver, Method, Model, SimOptions};
use std::hint::black_box;

fn run<M: Model>(model: &M, fixed: &[usize], what: &str, n: usize) {
    let (q, u, _) = assembled(model, fixed);
    let mut solver = ConstrainedSolver::for_model(model);
    let mut udot = vec![0.0; model.nq()];
    match what {
        "udot" => {
            for _ in 0..n {
                solver
                    .accelerations(model, 0.0, black_box(&q), black_box(&u), &[], &mut udot)
                    .unwrap();
                black_box(&udot);
            }
        }
        "sim" | "sim5" => {
            let method = if what == "sim" {
                Method::Dop853 {
                    rtol: 1e-9,
                    atol: 1e-9,
                    h_max: f64::INFINITY,
                }
            } else {
                Method::Dopri5 {
                    rtol: 1e-9,
                    atol: 1e-9,
                    h_max: f64::INFINITY,
                }
            };
            let options = SimOptions {
                t_end: 1.0,
                output_interval: 1.0,
                method,
                ..SimOptions::default()
            };
            let mut stats = None;
            for _ in 0..n {
                let t = mech_runtime::simulate(model, &q, &u, &[], &options, &mut |_| {}).unwrap();
                stats = Some((t.stats, t.q.last().unwrap()[0]));
            }
            eprintln!("{stats:?}");
        }
        "dump" => {
            let (n, nc) = (model.nq(), model.nc());
            let mut m = vec![0.0; n * n];
            let mut f = vec![0.0; n];
            let mut j = vec![0.0; nc * n];
            let mut b = vec![0.0; nc];
            model.mass_matrix(0.0, &q, &[], &mut m);
            model.forcing(0.0, &q, &u, &[], &mut f);
            model.constraint_jacobian(0.0, &q, &mut j);
            model.constraint_bias(0.0, &q, &u, &mut b);
            solver
                .accelerations(model, 0.0, &q, &u, &[], &mut udot)
                .unwrap();
            println!("{{\"M\":{m:?},\"F\":{f:?},\"J\":{j:?},\"b\":{b:?},\"udot\":{udot:?},\"lambda\":{:?}}}", solver.multipliers());
        }
        _ => panic!("usage: profile_loops udot|sim|sim5|dump N four_bar|spherical_five_bar"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[2].parse().unwrap();
    match args.get(3).map(String::as_str).unwrap_or("four_bar") {
        "four_bar" => run(&FourBar::new(), &[0], &args[1], n),
        _ => run(&SphericalFiveBar::new(), &[0, 1], &args[1], n),
    }
}
