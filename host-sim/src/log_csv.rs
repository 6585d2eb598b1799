//! The attitude log (input) and the truth file of generated logs; formats in `docs/log-format.md`.
//!
//! # Reading
//! Header exactly [`HEADER`] (surrounding whitespace and a trailing `\r` tolerated); blank lines and
//! lines starting with `#` are skipped; every other line has exactly seven numbers, decimal or
//! scientific. `nan`, `inf` and `-inf` (any case) parse to non-finite values and are passed through:
//! the core rejects such samples and counts them. A bad header, a field that is not a number, or a
//! short or long row is a [`LogError`], displayed on one line as `FILE:LINE: message`.
//!
//! # Writing
//! Numbers are written with Rust's `Display` for `f64`, the shortest decimal that parses back to the
//! same `f64`: a generated log read back gives bit-identical rows.

use crate::scenario::{Row, ScenarioParams};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The attitude log's header.
pub const HEADER: &str = "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg";
/// Number of columns of the attitude log.
pub const COLUMNS: usize = 7;

/// A file that cannot be read as expected. `line` is 1-based; 0 for errors of the whole file
/// (cannot open, cannot write).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}:{line}: {message}")]
pub struct LogError {
    pub path: String,
    pub line: usize,
    pub message: String,
}

impl LogError {
    pub fn new(path: &Path, line: usize, message: impl Into<String>) -> LogError {
        LogError { path: path.display().to_string(), line, message: message.into() }
    }
}

/// One parsed data line: its 1-based line number in the file, and the row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLine {
    pub line: usize,
    pub row: Row,
}

/// Splits a CSV data line into exactly `expected` numbers (non-finite values allowed).
/// The message names the column of a bad field.
pub fn parse_numbers<const N: usize>(text: &str, header: &str) -> Result<[f64; N], String> {
    let fields: Vec<&str> = text.split(',').collect();
    if fields.len() != N {
        let kind = if fields.len() < N { "short" } else { "long" };
        return Err(format!("{kind} row: {} fields, expected {N} ({header})", fields.len()));
    }
    let names: Vec<&str> = header.split(',').collect();
    let mut out = [0.0; N];
    for (i, field) in fields.iter().enumerate() {
        let f = field.trim();
        out[i] = f.parse::<f64>().map_err(|_| {
            let name = names.get(i).copied().unwrap_or("?");
            format!("{name}: not a number: {f:?}")
        })?;
    }
    Ok(out)
}

/// Whether a line carries no data: blank or a `#` comment.
pub fn is_comment(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

/// Checks a header line against `expected` (whitespace, a `\r` and a UTF-8 BOM around it ignored).
pub fn check_header(path: &Path, line_no: usize, line: &str, expected: &str) -> Result<(), LogError> {
    let got = line.trim_start_matches('\u{feff}').trim();
    if got != expected {
        return Err(LogError::new(path, line_no, format!("bad header {got:?}, expected {expected:?}")));
    }
    Ok(())
}

/// Streams the rows of an attitude log.
pub struct LogReader<R: BufRead> {
    path: PathBuf,
    lines: std::io::Lines<R>,
    line_no: usize,
    header_seen: bool,
    failed: bool,
}

impl LogReader<BufReader<File>> {
    /// Opens a log file.
    pub fn open(path: &Path) -> Result<Self, LogError> {
        let file = File::open(path).map_err(|e| LogError::new(path, 0, format!("cannot open: {e}")))?;
        Ok(LogReader::new(path, BufReader::new(file)))
    }
}

impl<R: BufRead> LogReader<R> {
    /// Reads a log from any buffered reader; `path` names it in errors.
    pub fn new(path: &Path, reader: R) -> Self {
        LogReader { path: path.to_path_buf(), lines: reader.lines(), line_no: 0, header_seen: false, failed: false }
    }
}

impl<R: BufRead> Iterator for LogReader<R> {
    type Item = Result<LogLine, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        loop {
            let line = match self.lines.next() {
                None if !self.header_seen => {
                    self.failed = true;
                    return Some(Err(LogError::new(&self.path, self.line_no + 1, format!("no header, expected {HEADER:?}"))));
                }
                None => return None,
                Some(Err(e)) => {
                    self.failed = true;
                    return Some(Err(LogError::new(&self.path, self.line_no + 1, format!("cannot read: {e}"))));
                }
                Some(Ok(l)) => l,
            };
            self.line_no += 1;
            if is_comment(&line) {
                continue;
            }
            if !self.header_seen {
                if let Err(e) = check_header(&self.path, self.line_no, &line, HEADER) {
                    self.failed = true;
                    return Some(Err(e));
                }
                self.header_seen = true;
                continue;
            }
            return Some(match parse_numbers::<COLUMNS>(&line, HEADER) {
                Ok([time_s, rotation_deg, platform_deg, latitude_deg, heading_deg, roll_deg, pitch_deg]) => Ok(LogLine {
                    line: self.line_no,
                    row: Row { time_s, rotation_deg, platform_deg, latitude_deg, heading_deg, roll_deg, pitch_deg },
                }),
                Err(message) => {
                    self.failed = true;
                    Err(LogError::new(&self.path, self.line_no, message))
                }
            });
        }
    }
}

/// Reads a whole attitude log.
pub fn read_log(path: &Path) -> Result<Vec<LogLine>, LogError> {
    LogReader::open(path)?.collect()
}

/// Writes rows as an attitude log (lossless, see the module doc).
pub fn write_log_to<W: Write>(mut w: W, rows: &[Row]) -> std::io::Result<()> {
    writeln!(w, "{HEADER}")?;
    for r in rows {
        writeln!(
            w,
            "{},{},{},{},{},{},{}",
            r.time_s, r.rotation_deg, r.platform_deg, r.latitude_deg, r.heading_deg, r.roll_deg, r.pitch_deg
        )?;
    }
    w.flush()
}

/// Writes rows as an attitude log file.
pub fn write_log(path: &Path, rows: &[Row]) -> Result<(), LogError> {
    let file = File::create(path).map_err(|e| LogError::new(path, 0, format!("cannot create: {e}")))?;
    write_log_to(BufWriter::new(file), rows).map_err(|e| LogError::new(path, 0, format!("cannot write: {e}")))
}

/// The truth file of a generated log: the installation errors and every scenario parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Installation errors x1..x4 at t = 0, arcsec (they drift only under a model mismatch).
    pub x_arcsec: [f64; 4],
    #[serde(flatten)]
    pub params: ScenarioParams,
}

impl Truth {
    pub fn new(params: &ScenarioParams) -> Truth {
        Truth { x_arcsec: params.errors_arcsec, params: params.clone() }
    }
}

/// `<dir>/<stem>.truth.json` beside the log `<dir>/<stem>.csv`.
pub fn truth_path(log_path: &Path) -> PathBuf {
    let stem = log_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    log_path.with_file_name(format!("{stem}.truth.json"))
}

/// Writes the truth file.
pub fn write_truth(path: &Path, truth: &Truth) -> Result<(), LogError> {
    let text = serde_json::to_string_pretty(truth).map_err(|e| LogError::new(path, 0, format!("cannot encode: {e}")))?;
    std::fs::write(path, text + "\n").map_err(|e| LogError::new(path, 0, format!("cannot write: {e}")))
}

/// Reads a truth file; `Ok(None)` when it does not exist.
pub fn read_truth(path: &Path) -> Result<Option<Truth>, LogError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(LogError::new(path, 0, format!("cannot read: {e}"))),
    };
    serde_json::from_str(&text).map(Some).map_err(|e| LogError::new(path, e.line(), e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{generate, ScenarioKind};

    fn parse(text: &str) -> Result<Vec<LogLine>, LogError> {
        LogReader::new(Path::new("t.csv"), text.as_bytes()).collect()
    }

    #[test]
    fn reads_comments_scientific_and_non_finite() {
        let text = format!("# a comment\n\n{HEADER}\r\n0,1e1,2.5E-1,40,30,nan,-inf\n# x\n1, 2 ,3,4,5,6,7\n");
        let rows = parse(&text).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].line, 4);
        assert_eq!(rows[0].row.rotation_deg, 10.0);
        assert_eq!(rows[0].row.platform_deg, 0.25);
        assert!(rows[0].row.roll_deg.is_nan());
        assert_eq!(rows[0].row.pitch_deg, f64::NEG_INFINITY);
        assert_eq!(rows[1].line, 6);
        assert_eq!(rows[1].row.rotation_deg, 2.0);
    }

    #[test]
    fn errors_name_file_and_line() {
        let bad_header = parse("time_s,rotation_deg\n0,1\n").unwrap_err();
        assert_eq!(bad_header.line, 1);
        assert!(bad_header.to_string().starts_with("t.csv:1: bad header"), "{bad_header}");
        let non_number = parse(&format!("{HEADER}\n0,1,2,3,4,5,6\n1,1,x2,3,4,5,6\n")).unwrap_err();
        assert_eq!(non_number.to_string(), "t.csv:3: platform_deg: not a number: \"x2\"");
        let short = parse(&format!("{HEADER}\n0,1,2,3,4,5\n")).unwrap_err();
        assert!(short.to_string().starts_with("t.csv:2: short row: 6 fields"), "{short}");
        let long = parse(&format!("{HEADER}\n0,1,2,3,4,5,6,7\n")).unwrap_err();
        assert!(long.to_string().starts_with("t.csv:2: long row: 8 fields"), "{long}");
        let empty = parse("# only\n").unwrap_err();
        assert!(empty.to_string().starts_with("t.csv:2: no header"), "{empty}");
        assert!(!empty.to_string().contains('\n'));
    }

    #[test]
    fn written_log_reads_back_bit_identical() {
        let mut p = crate::scenario::ScenarioParams::new(ScenarioKind::Sea, 3);
        p.duration_s = 300.0;
        let g = generate(&p);
        let mut buf = Vec::new();
        write_log_to(&mut buf, &g.rows).unwrap();
        let back = LogReader::new(Path::new("g.csv"), buf.as_slice()).collect::<Result<Vec<_>, _>>().unwrap();
        assert_eq!(back.len(), g.rows.len());
        for (a, b) in back.iter().zip(&g.rows) {
            assert_eq!(a.row, *b);
        }
    }

    #[test]
    fn truth_round_trips_with_params() {
        let p = crate::scenario::ScenarioParams::new(ScenarioKind::Paper, 9);
        let truth = Truth::new(&p);
        let text = serde_json::to_string(&truth).unwrap();
        assert!(text.starts_with("{\"x_arcsec\":[200.0,-150.0,300.0,-250.0],"), "{text}");
        let back: Truth = serde_json::from_str(&text).unwrap();
        assert_eq!(back, truth);
        assert_eq!(truth_path(Path::new("/a/b/log.csv")), PathBuf::from("/a/b/log.truth.json"));
    }
}
