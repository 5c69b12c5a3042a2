//! `--compare OTHER.urdf`: the inertial data of the links two URDF files share by name,
//! compared; a disagreement is a warning with both files' numbers (the published HAMR files
//! give the leg `FLL4` two different inertias, one of them physically wrong).
//!
//! Consumes: two read [`Robot`]s. Produces: warnings spanned in the imported file; the other
//! file is named with its line.

use std::sync::Arc;

use super::read::{Inertial, Num, Robot};
use crate::diag::{Diagnostic, SourceFile};

/// Two values agree when they differ by at most this fraction of the larger of the group
/// (mass; the centre of mass's coordinates; the inertia's entries): the files write 4 to 6
/// significant digits.
const AGREE: f64 = 1e-6;

/// One warning per shared link whose mass, centre of mass or inertia differ.
pub fn compare(
    robot: &Robot,
    other: &Robot,
    other_file: &Arc<SourceFile>,
    units: &super::options::Units,
) -> Vec<Diagnostic> {
    let mut warnings = Vec::new();
    for link in &robot.links {
        let Some(theirs) = other.links.iter().find(|l| l.name.text == link.name.text) else {
            continue;
        };
        let (Some(a), Some(b)) = (&link.inertial, &theirs.inertial) else {
            continue;
        };
        let (length, mass) = (&units.length, &units.mass);
        let mut differences = Vec::new();
        if !agree(std::slice::from_ref(&a.mass), std::slice::from_ref(&b.mass)) {
            differences.push(format!(
                "mass {} vs {} {mass}",
                a.mass.literal, b.mass.literal
            ));
        }
        if !agree(&a.origin.xyz, &b.origin.xyz) || !agree(&a.origin.rpy, &b.origin.rpy) {
            differences.push(format!(
                "centre of mass {} vs {} {length}",
                list(&a.origin.xyz),
                list(&b.origin.xyz)
            ));
        }
        if !agree(&a.inertia, &b.inertia) {
            differences.push(format!(
                "inertia [ixx, iyy, izz, ixy, iyz, ixz] {} vs {} {mass}*{length}^2{}",
                list(&a.inertia),
                list(&b.inertia),
                products_flipped(a, b)
            ));
        }
        if differences.is_empty() {
            continue;
        }
        let line = other_file.line_col(theirs.span.start).0;
        let other_name = other_file
            .path
            .rsplit('/')
            .next()
            .unwrap_or(&other_file.path);
        let mut warning = Diagnostic::warning(
            "U0611",
            format!(
                "link `{}`'s inertial data differ from `{other_name}` (line {line})",
                link.name.text
            ),
        )
        .with_label(a.span, "this file's (imported)");
        for difference in differences {
            warning = warning.with_note(difference);
        }
        warnings.push(warning.with_help(
            "the import keeps this file's values; decide which is right (a centre of mass outside the link, the sign of the products) and edit the body",
        ));
    }
    warnings
}

fn agree(a: &[Num], b: &[Num]) -> bool {
    let scale = a.iter().chain(b).fold(0.0_f64, |m, n| m.max(n.value.abs()));
    a.iter()
        .zip(b)
        .all(|(x, y)| (x.value - y.value).abs() <= AGREE * scale)
}

fn list(numbers: &[Num]) -> String {
    let items: Vec<&str> = numbers.iter().map(|n| n.literal.as_str()).collect();
    format!("[{}]", items.join(", "))
}

/// `" (the three products have opposite signs)"` when they do.
fn products_flipped(a: &Inertial, b: &Inertial) -> &'static str {
    let opposite = (3..6).all(|i| a.inertia[i].value * b.inertia[i].value < 0.0);
    if opposite {
        "; the three products of inertia have opposite signs"
    } else {
        ""
    }
}
