//! Namespaces, redefinition errors and "did you mean" suggestions.
//!
//! Consumes: declared identifiers and the names looked up.
//! Produces: `E0210` redefinition and `E0212` reserved-name diagnostics, and help texts that
//! list the candidates and suggest the closest one.

use std::collections::BTreeMap;

use crate::diag::{closest, Diagnostic, Span};
use crate::front::ast::Ident;

/// Names declared in one namespace, with where they were declared (first declaration wins).
#[derive(Default)]
pub struct Namespace {
    names: BTreeMap<String, Span>,
    order: Vec<String>,
}

impl Namespace {
    /// Declares `name`; on a clash returns the redefinition error.
    pub fn declare(&mut self, name: &Ident, what: &str) -> Result<(), Diagnostic> {
        if let Some(&previous) = self.names.get(&name.name) {
            return Err(redefinition(name, previous, what));
        }
        self.names.insert(name.name.clone(), name.span);
        self.order.push(name.name.clone());
        Ok(())
    }
    /// Names in declaration order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.order.iter().map(String::as_str)
    }
}

pub fn redefinition(name: &Ident, previous: Span, what: &str) -> Diagnostic {
    Diagnostic::error(
        "E0210",
        format!("{what} `{}` is defined more than once", name.name),
    )
    .with_label(name.span, "defined again here")
    .with_label(previous, "first defined here")
    .with_help("rename one of them")
}

pub fn reserved(name: &Ident, meaning: &str) -> Diagnostic {
    Diagnostic::error("E0212", format!("`{}` is a reserved name", name.name))
        .with_label(
            name.span,
            format!("`{}` already means {meaning}", name.name),
        )
        .with_help("choose another name")
}

/// The label of an unknown name where the declarations are the model's own.
pub const NOT_DECLARED: &str = "not declared in this model";

/// An "unknown X" error, the name `label`led (e.g. [`NOT_DECLARED`]), with the candidates
/// as a note and the closest one as help; `plural` introduces the list ("bodies in scope",
/// "joint kinds").
pub fn unknown(
    code: &'static str,
    what: &str,
    plural: &str,
    name: &str,
    span: Span,
    candidates: &[&str],
    label: &str,
) -> Diagnostic {
    let mut diagnostic =
        Diagnostic::error(code, format!("unknown {what} `{name}`")).with_label(span, label);
    diagnostic = match candidates.len() {
        0 => diagnostic.with_note(format!("{plural}: none")),
        _ => diagnostic.with_note(format!("{plural}: {}", list(candidates))),
    };
    match closest(name, candidates) {
        Some(best) => diagnostic.with_help(format!("did you mean `{best}`?")),
        None => diagnostic,
    }
}

/// E0208: `kind` is not a known `joint` or `loop` kind (`of`), with the name used here as help
/// where `synonym` is it: what other tools call a `thing` (`joint`, `closure`) of that kind.
pub fn unknown_kind(
    of: &str,
    thing: &str,
    kind: &Ident,
    known: &[&str],
    synonym: Option<&str>,
) -> Diagnostic {
    let diagnostic = unknown(
        "E0208",
        &format!("{of} kind"),
        &format!("{of} kinds"),
        &kind.name,
        kind.span,
        known,
        &format!("not a {of} kind"),
    );
    match synonym {
        Some(synonym) => diagnostic.with_help(format!(
            "a {} {thing} is called `{synonym}` here",
            kind.name
        )),
        None => diagnostic,
    }
}

/// Up to 12 names, comma separated.
pub fn list(names: &[&str]) -> String {
    const SHOWN: usize = 12;
    let mut text = names
        .iter()
        .take(SHOWN)
        .copied()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        text.push_str(&format!(", ... ({} more)", names.len() - SHOWN));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_close_names_only() {
        assert_eq!(
            closest("forearm2", &["upper_arm", "forearm"]),
            Some("forearm")
        );
        assert_eq!(closest("xyz", &["upper_arm", "forearm"]), None);
        assert_eq!(closest("MN", &["mN", "kN"]), Some("mN"));
        assert_eq!(crate::diag::edit_distance("kitten", "sitting"), 3);
    }
}
