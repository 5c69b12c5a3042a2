//! Rendering: data in, bytes for people and files out — plots (SVG/PNG), tables (text,
//! Markdown, HTML), the experiment report and the diagnosis page. Shared by `mech report`,
//! `mech experiment`, `mech fit` and `mech diagnose`; analyses never call it.

pub mod diagnosis;
pub mod plot;
pub mod report;
pub mod table;
