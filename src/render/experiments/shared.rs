//! What the kinds' renderers share: the progress callback of a long experiment, a table of
//! numbers rendered as a CSV file of the outcome, a model value against the paper's in
//! percent. Apart from `mod.rs`, which runs the kinds, so that no kind depends on the code
//! that dispatches to it.

use std::path::Path;

use crate::experiments::Error;
use crate::render::report::Outcome;

/// Told `(done, total)` as the parts of one experiment finish (the walks of a locomotion
/// grid); kinds that run as one piece do not call it.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// Renders a CSV under `dir` into the outcome.
pub(super) fn csv(
    outcome: &mut Outcome,
    dir: &Path,
    file: &str,
    header: &[&str],
    rows: &[Vec<f64>],
) -> Result<(), Error> {
    let path = dir.join(file);
    let header: Vec<String> = header.iter().map(|s| s.to_string()).collect();
    let file = crate::output::File::csv(&path, &header, rows).map_err(|e| Error::Write {
        path: path.clone(),
        message: e.to_string(),
    })?;
    outcome.add_file(file);
    Ok(())
}

/// `a` relative to `b` in percent, `+12 %`.
pub(super) fn percent_diff(model: f64, paper: f64) -> String {
    if paper == 0.0 {
        return "–".into();
    }
    format!("{:+.0} %", 100.0 * (model / paper - 1.0))
}
