//! Rendering: data in, bytes for people and files out — plots (SVG/PNG), tables (text,
//! Markdown, HTML), the experiment report and the diagnosis page. Shared by `mech report`,
//! `mech experiment`, `mech fit` and `mech diagnose`; analyses never call it.

use std::fmt;
use std::path::PathBuf;

pub mod animation;
pub mod diagnosis;
pub mod experiments;
pub mod flexure_fit;
pub mod plot;
pub mod report;
pub mod run;
pub mod sweep;
pub mod table;
pub mod terminal;

pub use plot::PlotError;

/// Why a page or its figures could not be made: a plot, or a file read (a plot to inline)
/// or written.
#[derive(Debug)]
pub enum Error {
    Plot(PlotError),
    /// A plot to inline in a page could not be read.
    ReadPlot {
        path: PathBuf,
        message: String,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Plot(error) => write!(f, "{error}"),
            Error::ReadPlot { path, message } => {
                write!(f, "cannot read plot {}: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for Error {}

impl From<PlotError> for Error {
    fn from(error: PlotError) -> Error {
        Error::Plot(error)
    }
}
