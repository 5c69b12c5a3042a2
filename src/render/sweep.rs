//! A sweep's table rendered: the CSV of every sample, the summary and sensitivity tables,
//! the failed samples, a histogram per output and a scatter plot of each output against each
//! parameter — as an [`Outcome`], printed by `mech sweep` and listed by `mech report`.
//!
//! Consumes: a [`Study`] and its [`Table`]. Produces: an [`Outcome`] with its files in
//! memory (written by the command, all or none).

use std::path::Path;

use super::plot::{significant, ErrorPoint, Measured, PlotError, XyPlot};
use super::report::Outcome;
use super::table::Table as TextTable;
use crate::output::File;
use crate::sweep::stats::percentile;
use crate::sweep::{Study, Table};

/// Failed samples listed by name in the text (all are in `failures.csv`).
const FAILURES_SHOWN: usize = 5;

/// Parameters shown per output in the printed ranking (all are in `ranking.csv`).
const RANKED_SHOWN: usize = 5;

/// Why a sweep's outcome could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error("cannot write `{path}`: {message}")]
    Csv {
        path: std::path::PathBuf,
        message: String,
    },
}

/// `value` in `unit` for a table cell (4 significant digits).
fn cell(value: f64, unit: &str) -> String {
    match unit.is_empty() {
        true => significant(value, 4),
        false => format!("{} {unit}", significant(value, 4)),
    }
}

/// A column's name for files: `/` (between robot and output) and spaces made `_`.
fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The outcome of a study: tables, notes and the files under `dir`.
pub fn render(study: &Study, table: &Table, dir: &Path) -> Result<Outcome, Error> {
    let mut outcome = Outcome {
        title: study.title.clone().unwrap_or_else(|| "sweep".into()),
        method: method(study),
        notes: study.notes.clone(),
        ..Outcome::default()
    };
    outcome.tables.push(summary_table(table));
    outcome.tables.push(ranking_table(table));
    failures(table, dir, &mut outcome)?;
    outcome.add_file(samples_csv(table, &dir.join("samples.csv"))?);
    outcome.add_file(ranking_csv(table, &dir.join("ranking.csv"))?);
    for (k, name) in table.outputs.iter().enumerate() {
        let column = table.output_column(k);
        let summary = crate::sweep::stats::summary(&column);
        outcome.values.insert(format!("{name}.mean"), summary.mean);
        outcome.values.insert(format!("{name}.sd"), summary.sd);
        outcome.values.insert(format!("{name}.cv"), summary.cv());
        if summary.count == 0 {
            continue;
        }
        let label = axis_label(name, &table.output_units[k]);
        let path = dir.join(format!("hist_{}.svg", file_name(name)));
        outcome.add_plot(histogram(&path, name, &label, &column)?);
        for (p, parameter) in table.parameters.iter().enumerate() {
            let path = dir.join(format!(
                "scatter_{}_{}.png",
                file_name(name),
                file_name(parameter)
            ));
            let x_label = axis_label(parameter, &table.parameter_units[p]);
            let xs = table.parameter_column(p);
            outcome.add_file(scatter(&path, &x_label, &label, &xs, &column)?);
        }
    }
    outcome
        .values
        .insert("failed".into(), table.failed() as f64);
    Ok(outcome)
}

fn axis_label(name: &str, unit: &str) -> String {
    match unit.is_empty() {
        true => name.to_string(),
        false => format!("{name} [{unit}]"),
    }
}

/// How the samples were made: the count, the seed or grid, each parameter's source.
fn method(study: &Study) -> String {
    use crate::sweep::sample::{Dist, Source};
    let parameters: Vec<String> = study
        .parameters
        .iter()
        .map(|p| {
            let unit = match p.relative {
                true => " × the model's value".to_string(),
                false => match p.unit.is_empty() {
                    true => String::new(),
                    false => format!(" {}", p.unit),
                },
            };
            let g = |x: f64| significant(x, 4);
            let source = match &p.source {
                Source::Draw(Dist::Normal { mean, sd }) => {
                    format!("normal({}, sd {})", g(*mean), g(*sd))
                }
                Source::Draw(Dist::Uniform { low, high }) => {
                    format!("uniform({}, {})", g(*low), g(*high))
                }
                Source::Draw(Dist::TruncatedNormal {
                    mean,
                    sd,
                    low,
                    high,
                }) => format!(
                    "normal({}, sd {}) truncated to [{}, {}]",
                    g(*mean),
                    g(*sd),
                    g(*low),
                    g(*high)
                ),
                Source::Grid(values) => format!(
                    "{} values from {} to {}",
                    values.len(),
                    g(values[0]),
                    g(values[values.len() - 1])
                ),
            };
            format!("`{}` {source}{unit}", p.name)
        })
        .collect();
    let grid = study
        .parameters
        .iter()
        .all(|p| matches!(p.source, Source::Grid(_)));
    let kind = match grid {
        true => format!("{} grid points", study.samples),
        false => format!(
            "{} Monte-Carlo samples (seed {})",
            study.samples, study.seed
        ),
    };
    format!("{kind}; {}.", parameters.join("; "))
}

fn summary_table(table: &Table) -> TextTable {
    let mut text = TextTable::new(
        "Outputs over the samples",
        &["output", "n", "mean", "sd", "cv", "p5", "p50", "p95"],
    );
    for (k, (name, s)) in table.outputs.iter().zip(table.summaries()).enumerate() {
        let unit = &table.output_units[k];
        text.row(vec![
            name.clone(),
            s.count.to_string(),
            cell(s.mean, unit),
            cell(s.sd, unit),
            format!("{:.2} %", 100.0 * s.cv()),
            cell(s.p5, unit),
            cell(s.p50, unit),
            cell(s.p95, unit),
        ]);
    }
    text
}

/// Per output, the [`RANKED_SHOWN`] parameters of largest |Spearman ρ|, largest first.
fn ranking_table(table: &Table) -> TextTable {
    let mut text = TextTable::new(
        &format!(
            "Sensitivity: Spearman rank correlation, the {RANKED_SHOWN} largest |rho| per output \
             (all in ranking.csv)"
        ),
        &["output", "parameter", "rho"],
    );
    for row in table.ranking() {
        for c in row.into_iter().take(RANKED_SHOWN) {
            text.row(vec![
                table.outputs[c.output].clone(),
                table.parameters[c.parameter].clone(),
                format!("{:+.3}", c.rho),
            ]);
        }
    }
    text
}

/// The failed samples: counted in a note (the first few named), all in `failures.csv`.
fn failures(table: &Table, dir: &Path, outcome: &mut Outcome) -> Result<(), Error> {
    let failed: Vec<_> = table
        .rows
        .iter()
        .flat_map(|r| r.failures.iter().map(move |f| (r.index, f)))
        .collect();
    let samples = table.failed();
    outcome.notes.push(format!(
        "{samples} of {} samples failed (their outputs are left out of the statistics).",
        table.rows.len()
    ));
    for (index, failure) in failed.iter().take(FAILURES_SHOWN) {
        let robot = failure
            .robot
            .as_deref()
            .map(|r| format!(" {r}"))
            .unwrap_or_default();
        outcome
            .notes
            .push(format!("sample {index}{robot}: {}", failure.error));
    }
    if failed.is_empty() {
        return Ok(());
    }
    let records = failed.iter().map(|(index, failure)| {
        let robot = failure.robot.clone().unwrap_or_default();
        [index.to_string(), robot, failure.error.to_string()]
    });
    let path = dir.join("failures.csv");
    outcome.add_file(text_csv(&path, ["sample", "robot", "error"], records)?);
    Ok(())
}

/// Every (output, parameter) pair's Spearman ρ, by output, largest |ρ| first.
fn ranking_csv(table: &Table, path: &Path) -> Result<File, Error> {
    let records = table.ranking().into_iter().flatten().map(|c| {
        [
            table.outputs[c.output].clone(),
            table.parameters[c.parameter].clone(),
            format!("{:?}", c.rho),
        ]
    });
    text_csv(path, ["output", "parameter", "rho"], records)
}

/// A CSV file of text records under a header.
fn text_csv(
    path: &Path,
    header: [&str; 3],
    records: impl Iterator<Item = [String; 3]>,
) -> Result<File, Error> {
    let error = |e: &dyn std::fmt::Display| Error::Csv {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(header).map_err(|e| error(&e))?;
    for record in records {
        writer.write_record(&record).map_err(|e| error(&e))?;
    }
    let bytes = writer.into_inner().map_err(|e| error(&e))?;
    Ok(File::new(path, bytes))
}

/// Every sample: its index, parameter values, outputs (SI; NaN where failed), and `failed`.
pub fn samples_csv(table: &Table, path: &Path) -> Result<File, Error> {
    let mut header = vec!["sample".to_string()];
    header.extend(table.parameters.iter().cloned());
    header.extend(table.outputs.iter().cloned());
    header.push("failed".into());
    let rows: Vec<Vec<f64>> = table
        .rows
        .iter()
        .map(|r| {
            let mut row = vec![r.index as f64];
            row.extend(&r.parameters);
            row.extend(&r.outputs);
            row.push(if r.failures.is_empty() { 0.0 } else { 1.0 });
            row
        })
        .collect();
    File::csv(path, &header, &rows).map_err(|e| Error::Csv {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// A histogram of the finite values of `column` as its outline (a step curve): √n bins,
/// between 5 and 40, over the 0.5–99.5 % range of the values.
fn histogram(path: &Path, name: &str, label: &str, column: &[f64]) -> Result<File, PlotError> {
    let mut values: Vec<f64> = column.iter().copied().filter(|v| v.is_finite()).collect();
    values.sort_by(f64::total_cmp);
    let bins = ((values.len() as f64).sqrt() as usize).clamp(5, 40);
    let (low, high) = (percentile(&values, 0.5), percentile(&values, 99.5));
    let width = match high > low {
        true => (high - low) / bins as f64,
        false => low.abs().max(1e-300) * 1e-3,
    };
    let mut counts = vec![0usize; bins];
    for v in &values {
        let bin = ((v - low) / width).floor();
        if (0.0..bins as f64).contains(&bin) {
            counts[bin as usize] += 1;
        } else if *v == low + width * bins as f64 {
            counts[bins - 1] += 1;
        }
    }
    let (mut xs, mut ys) = (vec![low], vec![0.0]);
    for (k, &count) in counts.iter().enumerate() {
        let (left, right) = (low + width * k as f64, low + width * (k + 1) as f64);
        xs.extend([left, right]);
        ys.extend([count as f64, count as f64]);
    }
    xs.push(low + width * bins as f64);
    ys.push(0.0);
    let title = format!("{name}: {} samples", values.len());
    let curves = [(String::new(), xs, ys)];
    XyPlot::new(&title, label, "samples per bin", &curves).render(path)
}

/// Output against parameter, one marker per sample.
fn scatter(
    path: &Path,
    x_label: &str,
    y_label: &str,
    xs: &[f64],
    ys: &[f64],
) -> Result<File, PlotError> {
    let points = xs
        .iter()
        .zip(ys)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(&x, &y)| ErrorPoint {
            x,
            y,
            ..ErrorPoint::default()
        })
        .collect();
    let measured = [Measured {
        name: String::new(),
        color: 0,
        points,
    }];
    let title = format!("{y_label} against {x_label}");
    XyPlot {
        measured: &measured,
        ..XyPlot::new(&title, x_label, y_label, &[])
    }
    .render(path)
}
