//! Experiment 7 rendered: the study's outcome ([`crate::render::sweep`]) with, per output of
//! a study of robots, the coefficients of variation side by side.

use std::path::Path;

use crate::experiments::tolerance::{compute, Spec};
use crate::experiments::Error;
use crate::render::report::Outcome;

pub fn run(spec: &Spec, dir: &Path) -> Result<Outcome, Error> {
    let (study, table) = compute(spec)?;
    let mut outcome = crate::render::sweep::render(&study, &table, dir)
        .map_err(|e| Error::SweepRender(Box::new(e)))?;
    // Per output of a study of robots, each robot's coefficient of variation side by side.
    for feature in &study.features {
        let name = feature.name();
        let cvs: Vec<String> = table
            .outputs
            .iter()
            .zip(table.summaries())
            .filter(|(column, _)| column.ends_with(&format!("/{name}")))
            .map(|(column, s)| {
                format!(
                    "{} {:.2} %",
                    column.split('/').next().unwrap_or(column),
                    100.0 * s.cv()
                )
            })
            .collect();
        if cvs.len() > 1 {
            outcome
                .notes
                .push(format!("cv of {name}: {}.", cvs.join(", ")));
        }
    }
    Ok(outcome)
}
