//! The front end: `.mech` text → [`ir::Model`].
//!
//! Consumes: a [`SourceFile`] (path as shown in diagnostics, and text).
//! Produces: an [`ir::Model`] satisfying the invariants in `ir/mod.rs`, or [`Errors`]:
//! - [`parse`]: pest grammar (`mech.pest`) → typed [`ast::File`] with byte spans; at most one
//!   syntax error (pest does not recover).
//! - [`lower`]: names, units, dimensions and the joint tree → IR; collects every error of the
//!   phase.
//! - [`load`]: both, with the model name defaulting to the file stem.
//!
//! The language is documented in `docs/mech-language.md`; error codes are `E01xx` syntax,
//! `E02xx` names, `E03xx` dimensions, `E04xx` structure, `E05xx` physical plausibility
//! (`ir::plausible`).

pub mod ast;
mod lower;

/// "Did you mean …?": the candidate closest to a misspelt name (also used for data files).
mod parse;

pub(crate) use parse::DECLARATION_KEYWORDS;
pub mod units;

#[cfg(test)]
mod tests;

use std::sync::Arc;

use crate::diag::{Errors, SourceFile};
use crate::ir;

/// Parses a file into its syntax tree (the only place that sees pest pairs).
pub fn parse(file: &SourceFile) -> Result<ast::File, Errors> {
    parse::parse_file(file)
        .map_err(|diagnostic| Errors::new(Arc::new(file.clone()), vec![diagnostic]))
}

/// Resolves names, units, dimensions and the joint tree; reports every error found.
/// Without a `model NAME;` line, the model is named after the file stem of `file.path`.
pub fn lower(file: &Arc<SourceFile>, ast: &ast::File) -> Result<ir::Model, Errors> {
    lower::lower(file, ast)
}

/// Parses and lowers a file.
pub fn load(file: Arc<SourceFile>) -> Result<ir::Model, Errors> {
    let ast = parse::parse_file(&file)
        .map_err(|diagnostic| Errors::new(file.clone(), vec![diagnostic]))?;
    lower(&file, &ast)
}
