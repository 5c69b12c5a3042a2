//! The progress bars of long commands (`mech sweep`, `mech report`, `mech experiment`,
//! `mech simulate`, `mech linearize`), on stderr.

/// A progress bar drawn with `template` (indicatif's syntax) on stderr.
pub(super) fn progress_bar(length: u64, template: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(length);
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}
