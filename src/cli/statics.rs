//! `mech statics MODEL [--fixture OUTPUT=[x,y,z]]`: the static equilibrium under the
//! inputs and loads, the loop reactions and the forces of fixtures.
//!
//! Consumes: [`ModelArgs`] and fixture strings. Produces: a table on stdout and, with
//! `--out`, the equilibrium as CSV: the coordinates `q_NAME`, the loop reactions
//! `lambda_ROW` and the fixture forces `FIXTURE.force_x` ….

use super::Error;
use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use mech_runtime::{Fixture, Model};

use super::args::ModelArgs;
use crate::output;

#[derive(Args, Clone, Debug)]
pub struct StaticsArgs {
    #[command(flatten)]
    pub common: ModelArgs,
    /// Hold a point at a place: `--fixture 'foot=[1 mm, 2 mm, 0]'` where `foot` is a
    /// `position(...)` output of the model (Newtonian components; repeatable). Append
    /// `:xz` to hold only some components.
    #[arg(long = "fixture", value_name = "OUTPUT=[x, y, z][:COMPONENTS]")]
    pub fixtures: Vec<String>,
    /// CSV file for the equilibrium: coordinates, loop reactions and fixture forces.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `foot=[1 mm, 2 mm, 0]:xz` → a fixture on the position output `foot`.
fn parse_fixture(model: &dyn Model, text: &str) -> Result<Fixture, String> {
    let (name, rest) = text
        .split_once('=')
        .ok_or_else(|| format!("--fixture `{text}`: expected OUTPUT=[x, y, z]"))?;
    let name = name.trim();
    let (vector, components) = match rest.rsplit_once(':') {
        Some((vector, components)) if !components.contains(']') => (vector, components.trim()),
        _ => (rest, "xyz"),
    };
    let components: Vec<usize> = components
        .chars()
        .map(|c| {
            "xyz"
                .find(c)
                .ok_or_else(|| format!("--fixture {name}: `{c}` is not a component; use x, y, z"))
        })
        .collect::<Result<_, _>>()?;
    let mut outputs = [0; 3];
    for (axis, slot) in ["x", "y", "z"].iter().zip(outputs.iter_mut()) {
        *slot = model.output_index(&format!("{name}.{axis}")).ok_or_else(|| {
            format!("--fixture: the model has no position output `{name}`; declare `output {name} = position(body.point);`")
        })?;
    }
    let inner = vector
        .trim()
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| {
            format!(
                "--fixture {name}: expected a position `[x, y, z]` with units, e.g. `[1 mm, 0, 0]`"
            )
        })?;
    let values: Vec<f64> = inner
        .split(',')
        .map(|part| {
            let (value, dimension) = mech_codegen::front::units::parse_quantity(part.trim())
                .map_err(|e| format!("--fixture {name}: {e}"))?;
            if dimension != mech_codegen::ir::Dimension::LENGTH
                && !(dimension == mech_codegen::ir::Dimension::NONE && value == 0.0)
            {
                return Err(format!(
                    "--fixture {name}: `{}` is not a length",
                    part.trim()
                ));
            }
            Ok(value)
        })
        .collect::<Result<_, _>>()?;
    let target: [f64; 3] = values
        .try_into()
        .map_err(|_| format!("--fixture {name}: give three components"))?;
    Ok(Fixture {
        name: name.to_string(),
        outputs,
        target,
        components,
    })
}

pub fn run(args: &StaticsArgs) -> Result<(), Error> {
    let reads = args.common.check_outputs(&[args.out.as_deref()], None)?;
    let (session, inputs) = args.common.open("statics")?;
    let model = &session.model;
    let fixtures: Vec<Fixture> = args
        .fixtures
        .iter()
        .map(|f| parse_fixture(model, f).map_err(Error::Usage))
        .collect::<Result<_, _>>()?;
    let (equilibrium, _) = session.equilibrium(&args.common.independent, &inputs, &fixtures)?;
    let mut text = format!(
        "static equilibrium of `{}` in {} Newton iteration(s): max |F + Jᵀλ| = {:.1e}, max |φ| = {:.1e}\n",
        model.name(),
        equilibrium.iterations,
        equilibrium.force_residual,
        equilibrium.constraint_residual
    );
    let _ = writeln!(text, "\n{:<20} {:>18}", "coordinate", "q");
    for i in 0..model.nq() {
        let _ = writeln!(
            text,
            "{:<20} {:>18.10e}",
            model.coordinate_name(i),
            equilibrium.q[i]
        );
    }
    if model.nc() > 0 {
        let _ = writeln!(text, "\n{:<20} {:>18}", "loop row", "λ (reaction)");
        for (i, lambda) in equilibrium.loop_multipliers.iter().enumerate() {
            let _ = writeln!(text, "{:<20} {:>18.6e}", model.constraint_name(i), lambda);
        }
    }
    for (fixture, force) in fixtures.iter().zip(&equilibrium.fixture_forces) {
        let _ = writeln!(
            text,
            "\nforce of fixture `{}` on the model [N]: x {:.6e}, y {:.6e}, z {:.6e} (|F| = {:.6e})",
            fixture.name,
            force[0],
            force[1],
            force[2],
            (force[0] * force[0] + force[1] * force[1] + force[2] * force[2]).sqrt()
        );
    }
    print!("{text}");
    if let Some(out) = &args.out {
        let mut header: Vec<String> = (0..model.nq())
            .map(|i| format!("q_{}", model.coordinate_name(i)))
            .collect();
        let mut row = equilibrium.q.clone();
        for (i, lambda) in equilibrium.loop_multipliers.iter().enumerate() {
            header.push(format!("lambda_{}", model.constraint_name(i)));
            row.push(*lambda);
        }
        for (fixture, force) in fixtures.iter().zip(&equilibrium.fixture_forces) {
            for (axis, value) in ["x", "y", "z"].iter().zip(force) {
                header.push(format!("{}.force_{axis}", fixture.name));
                row.push(*value);
            }
        }
        output::write_all(&[output::File::csv(out, &header, &[row])?], &reads)?;
        println!("written to {}", out.display());
    }
    Ok(())
}
