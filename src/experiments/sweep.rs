use std::path::Path;

use serde::Deserialize;

use super::Outcome;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    pub title: String,
}

impl Spec {
    pub fn check(&self) -> Result<(), String> {
        Ok(())
    }
}

pub fn run(_spec: &Spec, _dir: &Path) -> Result<Outcome, String> {
    Err("kind = \"ratio_sweep\" is not implemented yet".into())
}
