//! Files written and read by the command line: a run's outputs written all or none, and
//! simple numeric CSV tables.
//!
//! Consumes: the [`File`]s a run rendered in memory (plots, reports, CSV of numbers) with the
//! files it read, and CSV files named on the command line (`--input x=csv(...)`). Produces:
//! the run's files, either all written or none changed (never half-written, never over one of
//! the run's inputs), and `(times, values)` columns read back from CSV, or a [`CsvError`]
//! that names file, line and column. Writing fails with a [`WriteError`] that names the file.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A file rendered in memory. A run renders all its files first and writes them together
/// with [`write_all`], so a failure half-way (a bad plot path, a fit that does not converge)
/// leaves every earlier output as it was.
#[derive(Debug, Clone, PartialEq)]
pub struct File {
    pub path: PathBuf,
    pub bytes: Vec<u8>,
}

/// A file's name without its extension (`experiments/bode.toml` → `bode`), or `fallback`
/// for a path that has none: outputs and keys are named after the files they come from.
pub fn file_stem(path: &Path, fallback: &str) -> String {
    path.file_stem()
        .map_or(fallback.into(), |s| s.to_string_lossy().into_owned())
}

impl File {
    pub fn new(path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) -> File {
        File {
            path: path.into(),
            bytes: bytes.into(),
        }
    }

    /// A numeric table as CSV: one header row, then one row per entry of `rows`. Numbers are
    /// printed in the shortest form that reads back to the same `f64` (`1e-7`, `0.1`, `NaN`,
    /// `inf`). Every row must have one value per header field.
    pub fn csv(path: impl Into<PathBuf>, header: &[String], rows: &[Vec<f64>]) -> io::Result<File> {
        let path = path.into();
        if let Some((i, row)) = rows
            .iter()
            .enumerate()
            .find(|(_, row)| row.len() != header.len())
        {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "cannot write `{}`: row {} has {} values but the header has {} columns",
                    path.display(),
                    i + 1,
                    row.len(),
                    header.len()
                ),
            ));
        }
        let mut writer = csv::Writer::from_writer(Vec::new());
        let to_io = |e: csv::Error| io::Error::other(e.to_string());
        writer.write_record(header).map_err(to_io)?;
        for row in rows {
            writer
                .write_record(row.iter().map(|v| format!("{v:?}")))
                .map_err(to_io)?;
        }
        let bytes = writer
            .into_inner()
            .map_err(|e| io::Error::other(e.to_string()))?;
        Ok(File { path, bytes })
    }
}

/// Why the files of a run were not written; no file was changed unless the message says so.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// An output would replace a file the same run reads.
    #[error(
        "refusing to write `{}`: it is {what} `{}` of this run; choose another output name",
        .output.display(),
        .input.display()
    )]
    OverwritesInput {
        output: PathBuf,
        input: PathBuf,
        /// "the input", "the model", …
        what: &'static str,
    },
    /// Two outputs of the run name the same file (`--plot` equal to `--out`).
    #[error(
        "refusing to write `{}` twice in one run (as `{}` and as `{}`); give the outputs different names",
        .path.display(),
        .first.display(),
        .second.display()
    )]
    Twice {
        path: PathBuf,
        first: PathBuf,
        second: PathBuf,
    },
    #[error("{0}")]
    Io(#[from] io::Error),
}

/// A file a run reads, which none of its outputs may replace.
#[derive(Clone, Debug)]
pub struct Read {
    pub path: PathBuf,
    /// What the file is to the run, for the message: "the model", "the data file", ….
    pub what: &'static str,
}

/// Refuses outputs that would replace one of `reads` or that name one file twice, before a
/// run starts its work (so a long run does not fail at its end). [`write_all`] checks again.
pub fn check_outputs<'a>(
    outputs: impl IntoIterator<Item = &'a Path>,
    reads: &[Read],
) -> Result<(), WriteError> {
    let reads: Vec<(PathBuf, &Read)> = reads.iter().map(|r| (identity(&r.path), r)).collect();
    let mut seen: Vec<(PathBuf, &Path)> = Vec::new();
    for output in outputs {
        let id = identity(output);
        if let Some((_, read)) = reads.iter().find(|(r, _)| *r == id) {
            return Err(WriteError::OverwritesInput {
                output: output.to_path_buf(),
                input: read.path.clone(),
                what: read.what,
            });
        }
        if let Some((_, first)) = seen.iter().find(|(s, _)| *s == id) {
            return Err(WriteError::Twice {
                path: id,
                first: first.to_path_buf(),
                second: output.to_path_buf(),
            });
        }
        seen.push((id, output));
    }
    Ok(())
}

/// Writes `files` all or none. Each goes to a new temporary file beside its target (missing
/// folders are created), flushed to disk; only when every one is complete are they renamed
/// into place, one after another (a rename is atomic; the window between renames is that of
/// a few system calls). On an error, or SIGINT/SIGTERM/SIGHUP, the temporary files are
/// removed and the targets keep their old contents. An existing target's permissions are
/// kept. Refuses, before writing anything, an output that is one of `reads` or a file named
/// twice.
pub fn write_all(files: &[File], reads: &[Read]) -> Result<(), WriteError> {
    check_outputs(files.iter().map(|f| f.path.as_path()), reads)?;
    install_cleanup();
    let mut staged: Vec<(PathBuf, &Path)> = Vec::new();
    let result = files.iter().try_for_each(|file| {
        staged.push((stage(file)?, &file.path));
        Ok::<(), io::Error>(())
    });
    if let Err(error) = result {
        remove_staged(staged.iter().map(|(temp, _)| temp));
        return Err(error.into());
    }
    for (k, (temp, target)) in staged.iter().enumerate() {
        if let Err(error) = fs::rename(temp, target) {
            remove_staged(staged[k..].iter().map(|(temp, _)| temp));
            let replaced: Vec<String> = staged[..k]
                .iter()
                .map(|(_, t)| format!("`{}`", t.display()))
                .collect();
            let note = if replaced.is_empty() {
                String::new()
            } else {
                format!(" (already replaced: {})", replaced.join(", "))
            };
            return Err(WriteError::Io(io::Error::new(
                error.kind(),
                format!("cannot write `{}`: {error}{note}", target.display()),
            )));
        }
        forget_staged(temp);
    }
    // Make the renames durable (best effort: not every platform can sync a directory).
    for (_, target) in &staged {
        if let Ok(dir_handle) = fs::File::open(folder_of(target)) {
            let _ = dir_handle.sync_all();
        }
    }
    Ok(())
}

/// The folder a file goes into (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// Where `path` really is, for comparing paths: the canonical path of the file, or of its
/// folder joined with its name when the file does not exist yet.
fn identity(path: &Path) -> PathBuf {
    if let Ok(canonical) = fs::canonicalize(path) {
        return canonical;
    }
    match (fs::canonicalize(folder_of(path)), path.file_name()) {
        (Ok(folder), Some(name)) => folder.join(name),
        _ => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

/// Writes `file` to a new temporary file beside its target and returns that file's path
/// (registered for removal on a signal).
fn stage(file: &File) -> io::Result<PathBuf> {
    let context = |error: io::Error, what: &str, path: &Path| {
        io::Error::new(
            error.kind(),
            format!("cannot {what} `{}`: {error}", path.display()),
        )
    };
    let path = &file.path;
    let file_name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot write `{}`: it does not name a file", path.display()),
        )
    })?;
    let dir = folder_of(path);
    fs::create_dir_all(dir).map_err(|e| context(e, "create directory", dir))?;
    let (temp_path, mut handle) = create_temp_file(dir, file_name)
        .map_err(|e| context(e, "create a temporary file in", dir))?;
    let result = (|| {
        handle.write_all(&file.bytes)?;
        if let Ok(metadata) = fs::metadata(path) {
            handle.set_permissions(metadata.permissions())?;
        }
        handle.sync_all()
    })();
    match result {
        Ok(()) => Ok(temp_path),
        Err(error) => {
            remove_staged([&temp_path]);
            Err(context(error, "write", path))
        }
    }
}

/// Temporary files not yet renamed into place: what a signal handler removes.
static STAGED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn remove_staged<'a>(temps: impl IntoIterator<Item = &'a PathBuf>) {
    for temp in temps {
        let _ = fs::remove_file(temp);
        forget_staged(temp);
    }
}

fn forget_staged(temp: &Path) {
    if let Ok(mut staged) = STAGED.lock() {
        staged.retain(|t| t != temp);
    }
}

/// On SIGINT, SIGTERM or SIGHUP: remove the temporary files of a write in progress and exit
/// with 130 (the shell's code for an interrupt). Installed once, on the first write.
fn install_cleanup() {
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    INSTALLED.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if let Ok(staged) = STAGED.lock() {
                for temp in staged.iter() {
                    let _ = fs::remove_file(temp);
                }
            }
            std::process::exit(130);
        });
    });
}

/// Creates `dir/.NAME.tmp-PID-N` with a fresh `N`, never reusing an existing file, and
/// registers it for removal on a signal.
fn create_temp_file(dir: &Path, file_name: &std::ffi::OsStr) -> io::Result<(PathBuf, fs::File)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut name = std::ffi::OsString::from(".");
        name.push(file_name);
        name.push(format!(".tmp-{}-{n}", std::process::id()));
        let temp_path = dir.join(name);
        // Registered before it exists: a signal between creation and registration would
        // otherwise leave it behind.
        if let Ok(mut staged) = STAGED.lock() {
            staged.push(temp_path.clone());
        }
        match fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp_path)
        {
            Ok(file) => return Ok((temp_path, file)),
            Err(e) => {
                forget_staged(&temp_path);
                if e.kind() != io::ErrorKind::AlreadyExists {
                    return Err(e);
                }
            }
        }
    }
}

/// Why `bytes` are not a UTF-8 text file, in words for the user (with the line where that
/// is known), or `None` if they are one. Data files saved as UTF-16 ("Unicode text" in some
/// spreadsheets), Latin-1 or a binary format are otherwise misread as rows of the wrong
/// length.
pub fn encoding_problem(bytes: &[u8]) -> Option<String> {
    const HINT: &str = "save it as CSV in UTF-8";
    if bytes.starts_with(b"\xFF\xFE") || bytes.starts_with(b"\xFE\xFF") {
        return Some(format!(
            "it is UTF-16 text (it starts with a UTF-16 byte-order mark); {HINT}"
        ));
    }
    let line_of = |offset: usize| 1 + bytes[..offset].iter().filter(|&&b| b == b'\n').count();
    if let Some(offset) = bytes.iter().position(|&b| b == 0) {
        return Some(format!(
            "line {}: it holds NUL bytes: binary data or UTF-16 text, not a text file; {HINT}",
            line_of(offset)
        ));
    }
    std::str::from_utf8(bytes).err().map(|error| {
        format!(
            "line {}: it is not valid UTF-8 (Latin-1 or another encoding?); {HINT}",
            line_of(error.valid_up_to())
        )
    })
}

/// A numeric CSV table: the header and the values column by column.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvTable {
    /// Column names, trimmed, in file order (the first is time).
    pub header: Vec<String>,
    /// `columns[j][i]` is the value in data row `i`, column `j`.
    pub columns: Vec<Vec<f64>>,
    /// `lines[i]` is the file line (1-based) of data row `i`: comment lines are skipped, so
    /// messages about a value need this rather than the row index.
    pub lines: Vec<u64>,
}

impl CsvTable {
    /// Index of the column named `name` (exact match after trimming).
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name.trim())
    }
}

/// Why a CSV file named on the command line cannot be read as a numeric table; every message
/// names the file, and the line and column where there is one.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub kind: CsvErrorKind,
}

/// What is wrong with a CSV file, for [`CsvError`].
#[derive(Debug, Clone, PartialEq)]
pub enum CsvErrorKind {
    /// The file cannot be opened or read, or is not CSV.
    Read {
        /// The operating system's or the CSV reader's reason.
        reason: String,
    },
    /// The bytes are not UTF-8 text ([`encoding_problem`]'s words).
    NotText { problem: String },
    /// The first line names no column.
    NoHeader,
    /// A row whose number of fields differs from the header's.
    RaggedRow {
        line: u64,
        fields: usize,
        columns: usize,
    },
    /// A field that does not parse as a number.
    NotANumber {
        line: u64,
        /// 1-based.
        column: usize,
        /// The column's name in the header.
        name: String,
        /// The field as written.
        field: String,
    },
    /// A header and nothing else.
    NoDataRows,
    /// The column asked for is not in the header.
    MissingColumn {
        column: String,
        /// The header's columns.
        columns: Vec<String>,
    },
}

impl CsvError {
    fn new(path: &Path, kind: CsvErrorKind) -> CsvError {
        CsvError {
            path: path.to_path_buf(),
            kind,
        }
    }

    /// A failure of the `csv` reader: I/O, or anything else it reports (the text was
    /// checked to be UTF-8 before).
    fn reading(path: &Path, error: &csv::Error) -> CsvError {
        let kind = match error.kind() {
            csv::ErrorKind::Io(e) => CsvErrorKind::Read {
                reason: e.to_string(),
            },
            _ => CsvErrorKind::Read {
                reason: error.to_string(),
            },
        };
        CsvError::new(path, kind)
    }
}

impl std::fmt::Display for CsvError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let file = self.path.display();
        match &self.kind {
            CsvErrorKind::Read { reason } => write!(f, "cannot read `{file}`: {reason}"),
            CsvErrorKind::NotText { problem } => write!(f, "cannot read `{file}`: {problem}"),
            CsvErrorKind::NoHeader => write!(
                f,
                "`{file}` has no header row: the first line must name the columns, e.g. `t,voltage`"
            ),
            CsvErrorKind::RaggedRow {
                line,
                fields,
                columns,
            } => write!(
                f,
                "`{file}`, line {line}: {fields} fields, but the header has {columns} columns"
            ),
            CsvErrorKind::NotANumber {
                line,
                column,
                name,
                field,
            } => write!(
                f,
                "`{file}`, line {line}, column {column} (`{name}`): `{field}` is not a number"
            ),
            CsvErrorKind::NoDataRows => write!(f, "`{file}` has a header but no data rows"),
            CsvErrorKind::MissingColumn { column, columns } => write!(
                f,
                "`{file}` has no column `{column}`; its columns are {}",
                quoted_list(columns)
            ),
        }
    }
}

impl std::error::Error for CsvError {}

/// Reads a CSV file of numbers with a header row. Fields are trimmed; lines starting with `#`
/// are comments; `NaN` and `inf` are accepted as numbers. Every row must have as many fields as
/// the header, and there must be at least one column and one data row.
pub fn read_csv_table(path: &Path) -> Result<CsvTable, CsvError> {
    let bytes = fs::read(path).map_err(|e| {
        let reason = e.to_string();
        CsvError::new(path, CsvErrorKind::Read { reason })
    })?;
    parse_csv_table(path, &bytes)
}

/// Parses CSV `bytes` as [`read_csv_table`] does; `path` only names the file in messages.
pub fn parse_csv_table(path: &Path, bytes: &[u8]) -> Result<CsvTable, CsvError> {
    let reading = |e: csv::Error| CsvError::reading(path, &e);
    if let Some(problem) = encoding_problem(bytes) {
        return Err(CsvError::new(path, CsvErrorKind::NotText { problem }));
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bytes);
    let header: Vec<String> = reader
        .headers()
        .map_err(reading)?
        .iter()
        .map(str::to_string)
        .collect();
    if header.is_empty() || header.iter().all(String::is_empty) {
        return Err(CsvError::new(path, CsvErrorKind::NoHeader));
    }
    let mut columns = vec![Vec::new(); header.len()];
    let mut lines = Vec::new();
    let mut record = csv::StringRecord::new();
    while reader.read_record(&mut record).map_err(reading)? {
        let line = record.position().map_or(0, |p| p.line());
        lines.push(line);
        if record.len() != header.len() {
            let kind = CsvErrorKind::RaggedRow {
                line,
                fields: record.len(),
                columns: header.len(),
            };
            return Err(CsvError::new(path, kind));
        }
        for (j, field) in record.iter().enumerate() {
            let value: f64 = field.parse().map_err(|_| {
                let kind = CsvErrorKind::NotANumber {
                    line,
                    column: j + 1,
                    name: header[j].clone(),
                    field: field.to_string(),
                };
                CsvError::new(path, kind)
            })?;
            columns[j].push(value);
        }
    }
    if columns[0].is_empty() {
        return Err(CsvError::new(path, CsvErrorKind::NoDataRows));
    }
    Ok(CsvTable {
        header,
        columns,
        lines,
    })
}

/// Reads one column of a CSV file (see [`read_csv_table`]) together with the first column,
/// which is time whatever its name: returns `(times, values)`.
pub fn read_csv_column(path: &Path, column: &str) -> Result<(Vec<f64>, Vec<f64>), CsvError> {
    let mut table = read_csv_table(path)?;
    let Some(index) = table.column_index(column) else {
        let kind = CsvErrorKind::MissingColumn {
            column: column.to_string(),
            columns: table.header,
        };
        return Err(CsvError::new(path, kind));
    };
    let values = table.columns[index].clone();
    let times = table.columns.swap_remove(0);
    Ok((times, values))
}

/// `` `a`, `b`, `c` ``.
pub(crate) fn quoted_list(names: &[impl AsRef<str>]) -> String {
    names
        .iter()
        .map(|n| format!("`{}`", n.as_ref()))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh empty directory under the system temp dir (removed when dropped).
    struct TempDir(PathBuf);
    impl TempDir {
        fn new(tag: &str) -> TempDir {
            static N: AtomicU64 = AtomicU64::new(0);
            let n = N.fetch_add(1, Ordering::Relaxed);
            let dir = std::env::temp_dir()
                .join(format!("mech-output-test-{tag}-{}-{n}", std::process::id()));
            let _ = fs::remove_dir_all(&dir);
            fs::create_dir_all(&dir).unwrap();
            TempDir(dir)
        }
    }
    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    /// One file written alone.
    fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
        write_all(&[File::new(path, bytes)], &[])
    }

    fn write_csv(path: &Path, header: &[String], rows: &[Vec<f64>]) -> io::Result<()> {
        let file = File::csv(path, header, rows)?;
        write_all(&[file], &[]).map_err(|e| io::Error::other(e.to_string()))
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn write_atomic_creates_replaces_and_leaves_no_temp_files() {
        let dir = TempDir::new("atomic");
        let path = dir.0.join("sub/dir/out.txt");
        write_atomic(&path, b"first").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"first");
        write_atomic(&path, b"second, longer").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second, longer");
        assert_eq!(entries(&dir.0.join("sub/dir")), vec!["out.txt"]);
    }

    #[test]
    fn write_atomic_failure_leaves_target_unchanged() {
        let dir = TempDir::new("fail");
        // The "directory" is a regular file: neither it nor a temp file inside can be created.
        let blocker = dir.0.join("blocker");
        fs::write(&blocker, b"keep").unwrap();
        let error = write_atomic(&blocker.join("out.txt"), b"x").unwrap_err();
        assert!(error.to_string().contains("blocker"), "{error}");
        assert_eq!(fs::read(&blocker).unwrap(), b"keep");

        // Renaming onto a non-empty directory fails: the directory is untouched, no temp left.
        let target = dir.0.join("target");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("inner"), b"inner").unwrap();
        let error = write_atomic(&target, b"x").unwrap_err();
        assert!(error.to_string().contains("target"), "{error}");
        assert_eq!(fs::read(target.join("inner")).unwrap(), b"inner");
        assert_eq!(entries(&dir.0), vec!["blocker", "target"]);
    }

    #[cfg(unix)]
    #[test]
    fn write_atomic_into_readonly_directory_fails_cleanly() {
        use std::os::unix::fs::PermissionsExt;
        let dir = TempDir::new("readonly");
        let path = dir.0.join("out.txt");
        write_atomic(&path, b"old").unwrap();
        fs::set_permissions(&dir.0, fs::Permissions::from_mode(0o555)).unwrap();
        let result = write_atomic(&path, b"new");
        fs::set_permissions(&dir.0, fs::Permissions::from_mode(0o755)).unwrap();
        // Root ignores directory permissions; then the write simply succeeds.
        match result {
            Err(error) => {
                assert_eq!(fs::read(&path).unwrap(), b"old");
                assert!(
                    error.to_string().contains(&*dir.0.to_string_lossy()),
                    "{error}"
                );
            }
            Ok(()) => assert_eq!(fs::read(&path).unwrap(), b"new"),
        }
        assert_eq!(entries(&dir.0), vec!["out.txt"]);
    }

    #[test]
    fn a_failure_in_any_file_of_a_run_changes_none() {
        let dir = TempDir::new("all-or-none");
        let (csv, plot) = (dir.0.join("run.csv"), dir.0.join("blocker/run.svg"));
        fs::write(&csv, b"old run").unwrap();
        // `blocker` is a file, so no folder of that name can be made for the plot.
        fs::write(dir.0.join("blocker"), b"keep").unwrap();
        let files = [File::new(&csv, "new run"), File::new(&plot, "<svg/>")];
        let error = write_all(&files, &[]).unwrap_err();
        assert!(error.to_string().contains("blocker"), "{error}");
        assert_eq!(fs::read(&csv).unwrap(), b"old run");
        assert_eq!(entries(&dir.0), vec!["blocker", "run.csv"]);
    }

    #[test]
    fn outputs_over_an_input_or_named_twice_are_refused_before_writing() {
        let dir = TempDir::new("guard");
        let model = dir.0.join("model.mech");
        fs::write(&model, b"model m;").unwrap();
        let reads = [Read {
            path: model.clone(),
            what: "the model",
        }];
        // The same file by another spelling.
        let same = dir.0.join(".").join("model.mech");
        let error = write_all(&[File::new(&same, "x")], &reads).unwrap_err();
        assert!(
            matches!(
                error,
                WriteError::OverwritesInput {
                    what: "the model",
                    ..
                }
            ),
            "{error}"
        );
        assert!(error.to_string().contains("it is the model"), "{error}");
        assert_eq!(fs::read(&model).unwrap(), b"model m;");

        let out = dir.0.join("out.csv");
        let twice = [
            File::new(&out, "a"),
            File::new(dir.0.join("sub/../out.csv"), "b"),
        ];
        fs::create_dir(dir.0.join("sub")).unwrap();
        let error = write_all(&twice, &reads).unwrap_err();
        assert!(matches!(error, WriteError::Twice { .. }), "{error}");
        assert_eq!(entries(&dir.0), vec!["model.mech", "sub"]);
    }

    #[test]
    fn csv_round_trip_is_exact() {
        let dir = TempDir::new("roundtrip");
        let path = dir.0.join("data.csv");
        let header = vec!["t".to_string(), "q, rad".to_string(), "u".to_string()];
        let rows = vec![
            vec![0.0, 0.1, -1e-300],
            vec![1.0 / 3.0, std::f64::consts::PI, 6.02e23],
            vec![2.0, f64::NAN, f64::INFINITY],
        ];
        write_csv(&path, &header, &rows).unwrap();
        let table = read_csv_table(&path).unwrap();
        assert_eq!(table.header, header);
        for (j, column) in table.columns.iter().enumerate() {
            for (i, &value) in column.iter().enumerate() {
                let expected = rows[i][j];
                assert!(
                    value.to_bits() == expected.to_bits() || (value.is_nan() && expected.is_nan()),
                    "row {i} column {j}: {value} != {expected}"
                );
            }
        }
        let (t, u) = read_csv_column(&path, "u").unwrap();
        assert_eq!(t, vec![0.0, 1.0 / 3.0, 2.0]);
        assert_eq!(u[1], 6.02e23);
    }

    #[test]
    fn write_csv_rejects_ragged_rows() {
        let dir = TempDir::new("ragged-write");
        let path = dir.0.join("data.csv");
        let error = write_csv(&path, &["t".into(), "x".into()], &[vec![0.0]]).unwrap_err();
        assert!(error.to_string().contains("row 1 has 1 values"), "{error}");
        assert!(!path.exists());
    }

    #[test]
    fn reads_trimmed_fields_and_comments() {
        let dir = TempDir::new("read");
        let path = dir.0.join("in.csv");
        fs::write(&path, "# a comment\ntime , voltage\n0, 1.5\n 0.5 ,2e-3\n").unwrap();
        let (t, v) = read_csv_column(&path, "voltage").unwrap();
        assert_eq!(t, vec![0.0, 0.5]);
        assert_eq!(v, vec![1.5, 2e-3]);
    }

    #[test]
    fn read_errors_name_file_line_and_column() {
        let dir = TempDir::new("errors");
        let path = dir.0.join("in.csv");
        let name = path.display().to_string();

        fs::write(&path, "t,v\n0,1\n1,abc\n").unwrap();
        let error = read_csv_column(&path, "v").unwrap_err();
        assert_eq!(error.path, path);
        assert_eq!(
            error.kind,
            CsvErrorKind::NotANumber {
                line: 3,
                column: 2,
                name: "v".to_string(),
                field: "abc".to_string()
            }
        );
        assert_eq!(
            error.to_string(),
            format!("`{name}`, line 3, column 2 (`v`): `abc` is not a number")
        );

        // `NAME` stands for the file's path in the expected messages.
        for (contents, column, expected) in [
            (
                "t,v\n0,1\n1,2,3\n",
                "v",
                "`NAME`, line 3: 3 fields, but the header has 2 columns",
            ),
            (
                "t,v\n0,1\n",
                "w",
                "`NAME` has no column `w`; its columns are `t`, `v`",
            ),
            ("t,v\n", "v", "`NAME` has a header but no data rows"),
        ] {
            fs::write(&path, contents).unwrap();
            let error = read_csv_column(&path, column).unwrap_err().to_string();
            assert_eq!(error, expected.replace("NAME", &name));
        }

        fs::write(&path, "").unwrap();
        let error = read_csv_column(&path, "v").unwrap_err().to_string();
        assert!(error.contains("has no header row"), "{error}");

        let missing = dir.0.join("missing.csv");
        let error = read_csv_column(&missing, "v").unwrap_err().to_string();
        assert!(
            error.starts_with(&format!("cannot read `{}`", missing.display())),
            "{error}"
        );
    }
}
