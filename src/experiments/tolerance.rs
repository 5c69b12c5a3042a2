//! Experiment 7, a tolerance study in the report: a `mech sweep` study file (e.g. HAMR-V2.0
//! against HAMR-VI under the same fabrication tolerances) run as one of the experiments.
//!
//! Consumes: a [`Spec`] naming the study file and, optionally, a sample count in place of
//! its own. Produces: the prepared study and its table ([`crate::sweep`]).

use std::path::PathBuf;

use serde::Deserialize;

use super::Error;
use crate::parallel::threads;
use crate::sweep::{self, Study, Table};

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// The study file (`mech sweep`'s TOML), relative to the current directory.
    pub study: PathBuf,
    /// Monte-Carlo samples in place of the study's own.
    pub samples: Option<usize>,
}

impl Spec {
    pub fn check(&self) -> Result<(), Error> {
        if let Some(samples) = self.samples {
            sweep::check_count("samples", None, samples.min(i64::MAX as usize) as i64)
                .map_err(|e| Error::Sweep(Box::new(e)))?;
        }
        Ok(())
    }
}

/// Loads the study and runs every sample on all cores.
pub fn compute(spec: &Spec) -> Result<(Study, Table), Error> {
    let wrap = |e| Error::Sweep(Box::new(e));
    let mut study = sweep::load(&spec.study).map_err(wrap)?;
    if let Some(samples) = spec.samples {
        study = study.with_samples(samples).map_err(wrap)?;
    }
    let table = study.run_all(threads(), &|| {}).map_err(wrap)?;
    Ok((study, table))
}
