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

/// `M` (upper triangle), `F` and the outputs as s-expressions.
pub fn equations_text(compiled: &Compiled) -> String {
    let eqs = &compiled.equations;
    let names: Vec<&str> = compiled
        .model
        .coordinates
        .iter()
        .map(|(_, c)| c.name.as_str())
        .collect();
    let mut text = format!(
        "// M(q) u̇ = F for model `{}`; u = q̇ for q = [{}]\n",
        compiled.model.name,
        names.join(", ")
    );
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
    text
}

/// The register instructions of each tape program.
pub fn tape_text(compiled: &Compiled) -> String {
    let tape = compiled.tape();
    let mut text = format!(
        "// tape of model `{}`; {}",
        compiled.model.name,
        operation_counts(&tape)
    );
    for (name, program) in [
        ("mass_matrix", &tape.mass_matrix),
        ("forcing", &tape.forcing),
        ("outputs", &tape.outputs),
    ] {
        text.push_str(&format!("\n{name}:\n"));
        for (i, op) in program.ops.iter().enumerate() {
            text.push_str(&format!("  r{i} = {op:?}\n"));
        }
        let results: Vec<String> = program.results.iter().map(|r| format!("r{r}")).collect();
        text.push_str(&format!("  results = [{}]\n", results.join(", ")));
    }
    text
}
