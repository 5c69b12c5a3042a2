//! Human-readable listings of derived equations and tapes (`mech derive --emit ...`).
//!
//! Consumes: a [`Compiled`] model. Produces: text with one equation or instruction per line
//! and the operation counts of each generated function.

use mech_codegen::Compiled;

/// `operations: mass_matrix N, forcing N, outputs N (total N)`.
pub fn operation_counts(tape: &mech_codegen::Tape) -> String {
    let (m, f, y) = (
        tape.mass_matrix.operation_count(),
        tape.forcing.operation_count(),
        tape.outputs.operation_count(),
    );
    format!(
        "operations: mass_matrix {m}, forcing {f}, outputs {y} (total {})\n",
        m + f + y
    )
}

/// Largest printout [`equations_text`] makes, in expression nodes (a few bytes each: an
/// 8-link chain prints about 2 MB, a 16-link one would print 560 MB).
pub const MAX_PRINTED_NODES: u64 = 10_000_000;

/// The equations are too large to print as trees.
#[derive(Debug, thiserror::Error)]
#[error(
    "the equations of `{model}` would print as {} expression nodes, more than {limit}: \
     printed as trees they repeat every shared subexpression at each of its uses; \
     `--emit tape` or `--emit rust` write each one once",
    if *nodes == u64::MAX { "over 1.8e19".to_string() } else { nodes.to_string() }
)]
pub struct TooLarge {
    pub model: String,
    /// [`mech_codegen::sym::ExprPool::printed_size`] of everything printed (saturated at
    /// `u64::MAX`).
    pub nodes: u64,
    pub limit: u64,
}

/// `M` (upper triangle), `F` and the outputs as s-expressions; [`TooLarge`] rather than a
/// printout of more than [`MAX_PRINTED_NODES`] nodes, measured before any is written.
pub fn equations_text(compiled: &Compiled) -> Result<String, TooLarge> {
    let eqs = &compiled.equations;
    let upper = (0..eqs.nu).flat_map(|r| (r..eqs.nu).map(move |s| r + eqs.nu * s));
    let rates = eqs.kinematic_rates.as_deref().unwrap_or_default();
    let roots: Vec<_> = upper
        .map(|i| eqs.mass_matrix[i])
        .chain(eqs.forcing.iter().copied())
        .chain(eqs.outputs.iter().copied())
        .chain(rates.iter().copied())
        .collect();
    let nodes = eqs.pool.printed_size(&roots);
    if nodes > MAX_PRINTED_NODES {
        return Err(TooLarge {
            model: compiled.model.name.clone(),
            nodes,
            limit: MAX_PRINTED_NODES,
        });
    }
    let model = &compiled.model;
    let q = model.coordinate_names().join(", ");
    let mut text = match eqs.kinematic_rates {
        None => format!(
            "// M(q) u̇ = F for model `{}`; u = q̇ for q = [{q}]\n",
            model.name
        ),
        Some(_) => format!(
            "// M(q) u̇ = F and q̇ = W(q) u for model `{}`; q = [{q}], u = [{}]\n",
            model.name,
            model.speed_names().join(", ")
        ),
    };
    text.push_str(&format!("// {}", operation_counts(&compiled.tape())));
    for r in 0..eqs.nu {
        for s in r..eqs.nu {
            text.push_str(&format!(
                "M[{r},{s}] = {}\n",
                eqs.pool.sexpr(eqs.mass_matrix[r + eqs.nu * s])
            ));
        }
    }
    for (r, &f) in eqs.forcing.iter().enumerate() {
        text.push_str(&format!("F[{r}] = {}\n", eqs.pool.sexpr(f)));
    }
    for (name, &y) in eqs.output_names.iter().zip(&eqs.outputs) {
        text.push_str(&format!("{name} = {}\n", eqs.pool.sexpr(y)));
    }
    for (i, &rate) in rates.iter().enumerate() {
        text.push_str(&format!("qdot[{i}] = {}\n", eqs.pool.sexpr(rate)));
    }
    // Velocity constraints `A(q) u = 0`: the nonzero entries of `A` (the last rows of `J`)
    // and the bias `Ȧu`, by row name.
    let rows = &eqs.constraints;
    let nc = rows.residual.len();
    let speeds = model.speed_names();
    for k in nc - rows.velocity_rows..nc {
        let name = &rows.names[k];
        for (j, speed) in speeds.iter().enumerate() {
            let entry = rows.jacobian[k + nc * j];
            if !eqs.pool.is_zero(entry) {
                text.push_str(&format!("A[{name},{speed}] = {}\n", eqs.pool.sexpr(entry)));
            }
        }
        text.push_str(&format!(
            "Adot_u[{name}] = {}\n",
            eqs.pool.sexpr(rows.bias[k])
        ));
    }
    Ok(text)
}

/// The register instructions of each tape program.
pub fn tape_text(compiled: &Compiled) -> String {
    let tape = compiled.tape();
    let mut text = format!(
        "// tape of model `{}`; {}",
        compiled.model.name,
        operation_counts(&tape)
    );
    let programs = [
        ("mass_matrix", Some(&tape.mass_matrix)),
        ("forcing", Some(&tape.forcing)),
        ("outputs", Some(&tape.outputs)),
        ("kinematic_rates", tape.kinematic_rates.as_ref()),
    ];
    for (name, program) in programs
        .into_iter()
        .filter_map(|(name, program)| Some((name, program?)))
    {
        text.push_str(&format!("\n{name}:\n"));
        for (i, op) in program.ops.iter().enumerate() {
            text.push_str(&format!("  r{i} = {op:?}\n"));
        }
        let results: Vec<String> = program.results.iter().map(|r| format!("r{r}")).collect();
        text.push_str(&format!("  results = [{}]\n", results.join(", ")));
    }
    text
}
