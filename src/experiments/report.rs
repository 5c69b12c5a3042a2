//! `mech experiment FILE` and `mech report`: run experiment files (in parallel), print their
//! tables, and write a self-contained HTML report (plots inline as SVG) and a Markdown one.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;

use super::table::escape_html;
use super::{load, parallel, stem, threads, Experiment, Outcome};
use crate::output;

#[derive(Args, Clone, Debug)]
pub struct ExperimentArgs {
    /// The experiment file (TOML), e.g. `experiments/hamr_vi_trajectory.toml`.
    pub file: PathBuf,
    /// Folder for the CSV files and plots (a subfolder named after the file is used).
    #[arg(long, default_value = "out/experiments")]
    pub out_dir: PathBuf,
}

#[derive(Args, Clone, Debug)]
pub struct ReportArgs {
    /// Folder of experiment files (every `*.toml` in it is run).
    #[arg(long, default_value = "experiments")]
    pub experiments: PathBuf,
    /// Output folder: `report.html`, `report.md`, and one subfolder per experiment.
    #[arg(long, default_value = "out/report")]
    pub out_dir: PathBuf,
}

/// The terminal text of an outcome: method, tables, notes, files.
pub fn outcome_text(outcome: &Outcome) -> String {
    let mut text = format!(
        "== {} ({})\n{}\n\n",
        outcome.title, outcome.name, outcome.method
    );
    for table in &outcome.tables {
        text += &table.text();
        text += "\n";
    }
    for note in &outcome.notes {
        let _ = writeln!(text, "- {note}");
    }
    for file in outcome.files.iter().chain(&outcome.plots) {
        let _ = writeln!(text, "written: {}", file.display());
    }
    text
}

pub fn experiment_command(args: &ExperimentArgs) -> Result<(), String> {
    let outcome = super::run_file(&args.file, &args.out_dir)?;
    print!("{}", outcome_text(&outcome));
    Ok(())
}

/// The experiment files of a folder, sorted by name.
pub fn experiment_files(folder: &Path) -> Result<Vec<PathBuf>, String> {
    let entries = std::fs::read_dir(folder).map_err(|e| {
        format!(
            "cannot read the experiments folder `{}`: {e}",
            folder.display()
        )
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(format!(
            "no `*.toml` experiment files in `{}`",
            folder.display()
        ));
    }
    Ok(files)
}

/// Runs every file (parsed first, so a bad file fails before anything runs), the costly
/// ones first, on all cores; `progress` is called after each one finishes.
pub fn run_all(
    files: &[PathBuf],
    out_dir: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Outcome>, String> {
    let experiments: Vec<(usize, String, Experiment)> = files
        .iter()
        .enumerate()
        .map(|(k, f)| Ok((k, stem(f), load(f)?)))
        .collect::<Result<_, String>>()?;
    let mut jobs = experiments;
    jobs.sort_by(|a, b| b.2.cost().total_cmp(&a.2.cost()));
    let results = parallel(jobs, threads(), |(k, name, experiment)| {
        let result = experiment
            .run(&name, &out_dir.join(&name))
            .map_err(|e| format!("experiment `{}`: {e}", files[k].display()));
        progress(&name);
        (k, result)
    });
    let mut results: Vec<(usize, Result<Outcome, String>)> = results;
    results.sort_by_key(|(k, _)| *k);
    results.into_iter().map(|(_, r)| r).collect()
}

pub fn report_command(args: &ReportArgs) -> Result<(), String> {
    let start = Instant::now();
    let files = experiment_files(&args.experiments)?;
    let bar = indicatif::ProgressBar::new(files.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "experiments {bar:40} {pos}/{len} {msg} [{elapsed}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.tick();
    let outcomes = run_all(&files, &args.out_dir, &|name| {
        bar.inc(1);
        bar.set_message(format!("done: {name}"));
    });
    bar.finish_and_clear();
    let mut outcomes = outcomes?;
    // In the order of their titles ("1. …", "2. …").
    outcomes.sort_by(|a, b| a.title.cmp(&b.title));
    for outcome in &outcomes {
        println!("{}", outcome_text(outcome));
    }
    let elapsed = start.elapsed().as_secs_f64();
    let (html, markdown) = (
        args.out_dir.join("report.html"),
        args.out_dir.join("report.md"),
    );
    output::write_atomic(
        &html,
        render_html(&outcomes, &args.out_dir, elapsed)?.as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    output::write_atomic(
        &markdown,
        render_markdown(&outcomes, &args.out_dir, elapsed).as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    println!(
        "{} experiments in {elapsed:.1} s; report written to {} and {}",
        outcomes.len(),
        html.display(),
        markdown.display()
    );
    Ok(())
}

const INTRO: &str = "Model predictions of the bundled HAMR leg models (models/hamr_vi.mech, \
models/hamr_v2.mech) for the experiments of Doshi et al., \"Model Driven Design for \
Flexure-Based Microrobots\" (Secs. V and VI, Figs. 6, 8, 10, Table IV), beside the paper's \
measured values where it gives numbers. No parameter is tuned to the paper's measurements; \
every model value comes from the model files (their sources are documented there).";

fn relative(path: &Path, base: &Path) -> String {
    path.strip_prefix(base)
        .unwrap_or(path)
        .display()
        .to_string()
}

/// The Markdown report: tables, notes, links to the plots and CSV files.
pub fn render_markdown(outcomes: &[Outcome], base: &Path, seconds: f64) -> String {
    let mut text = format!("# HAMR experiments: model against the paper\n\n{INTRO}\n\nGenerated by `mech report` in {seconds:.1} s.\n\n");
    for outcome in outcomes {
        let _ = write!(
            text,
            "## {}\n\n`experiments/{}.toml`. {}\n\n",
            outcome.title, outcome.name, outcome.method
        );
        for table in &outcome.tables {
            text += &table.markdown();
            text += "\n";
        }
        for plot in &outcome.plots {
            let _ = writeln!(
                text,
                "![{}]({})\n",
                relative(plot, base),
                relative(plot, base)
            );
        }
        for note in &outcome.notes {
            let _ = writeln!(text, "- {note}");
        }
        if !outcome.notes.is_empty() {
            text += "\n";
        }
        let files: Vec<String> = outcome
            .files
            .iter()
            .map(|f| format!("`{}`", relative(f, base)))
            .collect();
        let _ = writeln!(text, "Data: {}\n", files.join(", "));
    }
    text
}

/// The HTML report, self-contained: the SVG plots are inlined.
pub fn render_html(outcomes: &[Outcome], base: &Path, seconds: f64) -> Result<String, String> {
    render_page(
        "HAMR experiments: model against the paper",
        INTRO,
        &format!("Generated by <code>mech report</code> in {seconds:.1} s."),
        outcomes,
        base,
    )
}

/// A self-contained HTML page in the report's style: `title`, an `intro` paragraph (text),
/// a `footer` line (HTML), and one section per outcome with its tables, inlined plots, notes
/// and files (paths shown relative to `base`).
pub fn render_page(
    title: &str,
    intro: &str,
    footer: &str,
    outcomes: &[Outcome],
    base: &Path,
) -> Result<String, String> {
    let mut body = String::new();
    let mut toc = String::new();
    for outcome in outcomes {
        let _ = writeln!(
            toc,
            "<li><a href=\"#{}\">{}</a></li>",
            outcome.name,
            escape_html(&outcome.title)
        );
        let _ = writeln!(
            body,
            "<section id=\"{}\">\n<h2>{}</h2>\n<p class=\"file\"><code>{}</code></p>\n<p>{}</p>",
            outcome.name,
            escape_html(&outcome.title),
            escape_html(
                &outcome
                    .source
                    .clone()
                    .unwrap_or_else(|| format!("experiments/{}.toml", outcome.name))
            ),
            escape_html(&outcome.method)
        );
        for table in &outcome.tables {
            body += &table.html();
        }
        for plot in &outcome.plots {
            let svg = std::fs::read_to_string(plot)
                .map_err(|e| format!("cannot read plot {}: {e}", plot.display()))?;
            let svg = match svg.find("<svg") {
                Some(start) => &svg[start..],
                None => svg.as_str(),
            };
            let _ = writeln!(
                body,
                "<figure>{svg}<figcaption>{}</figcaption></figure>",
                escape_html(&relative(plot, base))
            );
        }
        if !outcome.notes.is_empty() {
            body += "<ul class=\"notes\">\n";
            for note in &outcome.notes {
                let _ = writeln!(body, "<li>{}</li>", escape_html(note));
            }
            body += "</ul>\n";
        }
        let files: Vec<String> = outcome
            .files
            .iter()
            .map(|f| format!("<code>{}</code>", escape_html(&relative(f, base))))
            .collect();
        let _ = writeln!(
            body,
            "<p class=\"file\">Data: {}</p>\n</section>",
            files.join(", ")
        );
    }
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{title}</title>\n<style>\n{STYLE}\n</style>\n</head>\n<body>\n<h1>{title}</h1>\n<p>{}</p>\n<p>{footer}</p>\n<ol class=\"toc\">\n{toc}</ol>\n{body}</body>\n</html>\n",
        escape_html(intro),
        title = escape_html(title)
    ))
}

const STYLE: &str = "body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em; color: #222; line-height: 1.45; }
h1 { font-size: 1.7em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.92em; }
caption { text-align: left; font-weight: bold; padding-bottom: 0.3em; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th { background: #eef; } td:first-child, th:first-child { text-align: left; }
figure { margin: 1em 0; } figure svg { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption, .file { color: #666; font-size: 0.85em; }
ul.notes li { margin: 0.3em 0; }";
