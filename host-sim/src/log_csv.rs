//! The attitude log (input) and the truth file of generated logs; formats in `docs/log-format.md`.
//!
//! # Reading
//! With the `csv` crate and serde: the header names the columns, which are matched **by name**
//! (any order; other columns ignored; spaces around names and values, a UTF-8 byte-order mark and
//! `\r\n` line ends tolerated). Lines starting with `#` and blank lines are skipped. A gzip stream
//! is decompressed on the fly (recognised by its magic bytes); `-` is standard input. `nan`, `inf`
//! and `-inf` (any case) parse to non-finite values and are passed through: the core rejects such
//! samples and counts them.
//!
//! A header without one of the seven columns is a fatal [`LogError`]. A row that cannot be read (a
//! cell that is not a number, a blank cell, a missing cell) is a [`LogError`] with
//! [`LogError::row`] set: the reader goes on with the next row, and the caller decides whether to
//! skip it ([`RowFilter`]) or refuse the log (`--strict`). Errors display on one line as
//! `FILE:LINE: message`.
//!
//! # Writing
//! Numbers are written with Rust's `Display` for `f64`, the shortest decimal that parses back to the
//! same `f64`: a generated log read back gives bit-identical rows.

use crate::scenario::{Row, ScenarioParams};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// The attitude log's header as `generate` writes it.
pub const HEADER: &str = "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg";
/// The columns a log must have (in any order).
pub const COLUMNS: [&str; 7] = ["time_s", "rotation_deg", "platform_deg", "latitude_deg", "heading_deg", "roll_deg", "pitch_deg"];
/// The name that stands for standard input (and, for outputs, standard output).
pub const STDIO: &str = "-";

/// A file that cannot be read as expected. `line` is 1-based; 0 for errors of the whole file
/// (cannot open, cannot write).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}:{line}: {message}")]
pub struct LogError {
    pub path: String,
    pub line: usize,
    pub message: String,
    /// Only this row is unreadable; the rows after it can still be read.
    pub row: bool,
}

impl LogError {
    /// An error of the whole file: nothing after it can be read.
    pub fn new(path: &Path, line: usize, message: impl Into<String>) -> LogError {
        LogError { path: path.display().to_string(), line, message: message.into(), row: false }
    }

    /// An unreadable row.
    pub fn unreadable_row(path: &Path, line: usize, message: impl Into<String>) -> LogError {
        LogError { row: true, ..LogError::new(path, line, message) }
    }
}

/// One parsed data line: its 1-based line number in the file, and the row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLine {
    pub line: usize,
    pub row: Row,
}

/// One row as serde reads it, by column name.
#[derive(Deserialize)]
struct RowRecord {
    time_s: f64,
    rotation_deg: f64,
    platform_deg: f64,
    latitude_deg: f64,
    heading_deg: f64,
    roll_deg: f64,
    pitch_deg: f64,
}

/// Whether `path` names standard input / output.
pub fn is_stdio(path: &Path) -> bool {
    path.as_os_str() == STDIO
}

/// Opens a log for reading: a file, or standard input for `-`; gzip is decompressed on the fly.
pub fn open_input(path: &Path) -> Result<Box<dyn Read + Send>, LogError> {
    open_input_gz(path).map(|(r, _)| r)
}

/// [`open_input`], and whether the log is gzip.
fn open_input_gz(path: &Path) -> Result<(Box<dyn Read + Send>, bool), LogError> {
    let raw: Box<dyn Read + Send> = if is_stdio(path) {
        Box::new(std::io::stdin())
    } else {
        Box::new(File::open(path).map_err(|e| LogError::new(path, 0, format!("cannot open: {e}")))?)
    };
    let mut buffered = BufReader::with_capacity(1 << 16, raw);
    let head = buffered.fill_buf().map_err(|e| LogError::new(path, 0, format!("cannot read: {e}")))?;
    Ok(if head.starts_with(&[0x1f, 0x8b]) {
        (Box::new(flate2::read::MultiGzDecoder::new(buffered)), true)
    } else {
        (Box::new(buffered), false)
    })
}

/// Counts the line ends that pass through it, so that a record's line number can be told from
/// its byte offset (the `csv` crate's own line count skips comment and blank lines). Holds the
/// offsets of the line ends read ahead of the parser: at most one buffer's worth.
struct LineCounter<R> {
    inner: R,
    offset: u64,
    ahead: std::collections::VecDeque<u64>,
    passed: usize,
}

impl<R: Read> Read for LineCounter<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let offset = self.offset;
        self.ahead.extend(memchr::memchr_iter(b'\n', &buf[..n]).map(|i| offset + i as u64));
        self.offset += n as u64;
        Ok(n)
    }
}

impl<R> LineCounter<R> {
    /// 1-based line of a record whose parse ended at byte `end` (just after the first byte of its
    /// terminator, `\n` or the `\r` of `\r\n`, or at the end of the input).
    fn line_of_record_ending_at(&mut self, end: u64) -> usize {
        while self.ahead.front().is_some_and(|&at| at + 1 < end) {
            self.ahead.pop_front();
            self.passed += 1;
        }
        self.passed + 1
    }
}

/// Streams the rows of an attitude log.
pub struct LogReader<R: Read> {
    path: PathBuf,
    csv: csv::Reader<LineCounter<R>>,
    headers: Option<csv::ByteRecord>,
    record: csv::ByteRecord,
    failed: bool,
    gzip: bool,
}

impl LogReader<Box<dyn Read + Send>> {
    /// Opens a log file (or standard input for `-`; gzip decompressed).
    pub fn open(path: &Path) -> Result<Self, LogError> {
        let (input, gzip) = open_input_gz(path)?;
        Ok(LogReader { gzip, ..LogReader::new(path, input) })
    }
}

impl<R: Read> LogReader<R> {
    /// Reads a log from any reader; `path` names it in errors.
    pub fn new(path: &Path, reader: R) -> Self {
        let csv = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .buffer_capacity(1 << 16)
            .from_reader(LineCounter { inner: reader, offset: 0, ahead: Default::default(), passed: 0 });
        LogReader { path: path.to_path_buf(), csv, headers: None, record: csv::ByteRecord::new(), failed: false, gzip: false }
    }

    /// Bytes of (decompressed) log read so far.
    pub fn bytes_read(&self) -> u64 {
        self.csv.position().byte()
    }

    /// Whether the log was opened from a gzip file.
    pub fn is_gzip(&self) -> bool {
        self.gzip
    }

    fn fail(&mut self, e: LogError) -> Option<Result<LogLine, LogError>> {
        self.failed = true;
        Some(Err(e))
    }

    /// Line of the record just read.
    fn line(&mut self) -> usize {
        let end = self.csv.position().byte();
        self.csv.get_mut().line_of_record_ending_at(end)
    }

    /// Checks the header: every column of [`COLUMNS`] exactly once.
    fn check_header(&self) -> Result<(), String> {
        let names: Vec<String> = self.record.iter().map(|f| String::from_utf8_lossy(f).trim_start_matches('\u{feff}').to_string()).collect();
        for want in COLUMNS {
            match names.iter().filter(|n| *n == want).count() {
                1 => {}
                0 => return Err(format!("no column {want:?} in the header {:?} (needs {})", names.join(","), COLUMNS.join(","))),
                _ => return Err(format!("column {want:?} appears twice in the header")),
            }
        }
        Ok(())
    }

    /// Why the current record cannot be read as a row.
    fn row_error(&self, e: &csv::DeserializeError) -> String {
        let headers = self.headers.as_ref();
        let named = e.field().and_then(|i| Some((headers?.get(i as usize)?, self.record.get(i as usize)?)));
        match (e.kind(), named) {
            (csv::DeserializeErrorKind::ParseFloat(_), Some((name, value))) => {
                let (name, value) = (String::from_utf8_lossy(name), String::from_utf8_lossy(value));
                if value.is_empty() {
                    format!("{name}: blank cell")
                } else {
                    format!("{name}: not a number: {value:?}")
                }
            }
            _ => {
                let missing: Vec<&str> = COLUMNS
                    .iter()
                    .copied()
                    .filter(|c| headers.and_then(|h| h.iter().position(|n| n == c.as_bytes())).is_none_or(|i| i >= self.record.len()))
                    .collect();
                if missing.is_empty() {
                    e.to_string()
                } else {
                    format!("short row: {} fields, no {}", self.record.len(), missing.join(", "))
                }
            }
        }
    }
}

impl<R: Read> Iterator for LogReader<R> {
    type Item = Result<LogLine, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        loop {
            match self.csv.read_byte_record(&mut self.record) {
                Ok(true) => {}
                Ok(false) if self.headers.is_none() => {
                    let line = self.line();
                    return self.fail(LogError::new(&self.path, line, format!("no header, expected the columns {HEADER:?}")));
                }
                Ok(false) => return None,
                Err(e) => {
                    let line = self.line();
                    return self.fail(LogError::new(&self.path, line, format!("cannot read: {e}")));
                }
            }
            // Blank lines (or only spaces) carry nothing.
            if self.record.len() == 1 && self.record.get(0).is_some_and(|f| f.is_empty()) {
                continue;
            }
            let Some(headers) = &self.headers else {
                if let Err(m) = self.check_header() {
                    let line = self.line();
                    return self.fail(LogError::new(&self.path, line, format!("bad header: {m}")));
                }
                let mut names = self.record.clone();
                // A byte-order mark before the first name.
                if let Some(first) = names.get(0) {
                    if let Some(stripped) = first.strip_prefix("\u{feff}".as_bytes()) {
                        let mut fixed = csv::ByteRecord::new();
                        fixed.push_field(stripped);
                        names.iter().skip(1).for_each(|f| fixed.push_field(f));
                        names = fixed;
                    }
                }
                self.headers = Some(names);
                continue;
            };
            let parsed = self.record.deserialize::<RowRecord>(Some(headers));
            let line = self.line();
            return Some(match parsed {
                Ok(r) => Ok(LogLine {
                    line,
                    row: Row {
                        time_s: r.time_s,
                        rotation_deg: r.rotation_deg,
                        platform_deg: r.platform_deg,
                        latitude_deg: r.latitude_deg,
                        heading_deg: r.heading_deg,
                        roll_deg: r.roll_deg,
                        pitch_deg: r.pitch_deg,
                    },
                }),
                Err(e) => {
                    let message = match e.kind() {
                        csv::ErrorKind::Deserialize { err, .. } => self.row_error(err),
                        _ => e.to_string(),
                    };
                    Err(LogError::unreadable_row(&self.path, line, message))
                }
            });
        }
    }
}

/// Rows parsed ahead by [`read_ahead`]'s thread, per batch.
const READ_AHEAD_BATCH: usize = 4096;

/// Runs `reader` on a thread of its own, a few batches of rows ahead of `consume`, which gets the
/// same items in the same order: parsing the CSV and the work done with its rows then share two
/// cores. At most 4 batches of [`READ_AHEAD_BATCH`] rows wait at any time, so memory does not grow
/// with the log. If `consume` returns early, the reader stops at its next batch.
pub fn read_ahead<R, T>(reader: LogReader<R>, consume: impl FnOnce(&mut dyn Iterator<Item = Result<LogLine, LogError>>) -> T) -> T
where
    R: Read + Send,
{
    let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Result<LogLine, LogError>>>(4);
    std::thread::scope(|scope| {
        scope.spawn(move || {
            let mut reader = reader;
            loop {
                let batch: Vec<_> = reader.by_ref().take(READ_AHEAD_BATCH).collect();
                if batch.is_empty() || tx.send(batch).is_err() {
                    break;
                }
            }
        });
        let mut items = rx.iter().flatten();
        let result = consume(&mut items);
        // Hang up before the reader thread is joined, so that it stops if `consume` stopped early.
        drop(items);
        result
    })
}

/// Reads a whole attitude log; any unreadable row is an error.
pub fn read_log(path: &Path) -> Result<Vec<LogLine>, LogError> {
    LogReader::open(path)?.collect()
}

/// Unreadable rows met so far: skipped and counted, or (strict) refused.
#[derive(Clone, Debug, Default)]
pub struct RowFilter {
    strict: bool,
    /// Rows skipped.
    pub skipped: u64,
    /// The first [`RowFilter::KEPT`] of them.
    pub first: Vec<LogError>,
}

impl RowFilter {
    /// How many unreadable rows are kept to report.
    pub const KEPT: usize = 10;

    /// `strict`: the first unreadable row refuses the log.
    pub fn new(strict: bool) -> RowFilter {
        RowFilter { strict, ..RowFilter::default() }
    }

    /// The row of a reader's item: `Ok(None)` for an unreadable row that is skipped; errors for a
    /// fatal error, or for any unreadable row when strict. `warn` is told each skipped row (up to
    /// [`RowFilter::KEPT`]).
    pub fn admit(&mut self, item: Result<LogLine, LogError>, warn: &mut dyn FnMut(&LogError)) -> Result<Option<LogLine>, LogError> {
        match item {
            Ok(line) => Ok(Some(line)),
            Err(e) if e.row && !self.strict => {
                self.skipped += 1;
                if self.first.len() < Self::KEPT {
                    warn(&e);
                    self.first.push(e);
                }
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }
}

/// The name a log's companion files are made from: `dir/trial.csv` and `dir/trial.csv.gz` both
/// give `dir/trial`.
pub fn log_stem(log_path: &Path) -> PathBuf {
    let name = log_path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    let stem = Path::new(name).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    log_path.with_file_name(stem)
}

/// Writes rows (a slice, or an iterator: streamed) as an attitude log (lossless, see the module doc).
pub fn write_log_to<W: Write, I>(mut w: W, rows: I) -> std::io::Result<()>
where
    I: IntoIterator,
    I::Item: std::borrow::Borrow<Row>,
{
    writeln!(w, "{HEADER}")?;
    for r in rows {
        let r: &Row = std::borrow::Borrow::borrow(&r);
        writeln!(
            w,
            "{},{},{},{},{},{},{}",
            r.time_s, r.rotation_deg, r.platform_deg, r.latitude_deg, r.heading_deg, r.roll_deg, r.pitch_deg
        )?;
    }
    w.flush()
}

/// Writes rows as an attitude log file.
pub fn write_log<I>(path: &Path, rows: I) -> Result<(), LogError>
where
    I: IntoIterator,
    I::Item: std::borrow::Borrow<Row>,
{
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

/// `<dir>/<stem>.truth.json` beside the log `<dir>/<stem>.csv` (or `.csv.gz`).
pub fn truth_path(log_path: &Path) -> PathBuf {
    let stem = log_stem(log_path);
    let name = format!("{}.truth.json", stem.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default());
    stem.with_file_name(name)
}

/// Writes the truth file.
pub fn write_truth(path: &Path, truth: &Truth) -> Result<(), LogError> {
    let text = serde_json::to_string_pretty(truth).map_err(|e| LogError::new(path, 0, format!("cannot encode: {e}")))?;
    std::fs::write(path, text + "\n").map_err(|e| LogError::new(path, 0, format!("cannot write: {e}")))
}

/// A truth file as read: the errors, and the scenario when `generate` wrote it.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthFile {
    /// Installation errors x1..x4, arcsec.
    pub x_arcsec: [f64; 4],
    /// The scenario's parameters, when the file carries them.
    pub params: Option<ScenarioParams>,
    /// Why the scenario's parameters (the file has a `scenario` field) could not be read.
    pub params_error: Option<String>,
}

/// Reads a truth file; `Ok(None)` when it does not exist. Only `x_arcsec` is required.
pub fn read_truth(path: &Path) -> Result<Option<TruthFile>, LogError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(LogError::new(path, 0, format!("cannot read: {e}"))),
    };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| LogError::new(path, e.line(), e.to_string()))?;
    let x = value.get("x_arcsec").ok_or_else(|| LogError::new(path, 0, "no \"x_arcsec\": [x1, x2, x3, x4] (arcsec)"))?;
    let x_arcsec: [f64; 4] = serde_json::from_value(x.clone()).map_err(|e| LogError::new(path, 0, format!("x_arcsec: {e}")))?;
    let (params, params_error) = match value.get("scenario") {
        None => (None, None),
        Some(_) => match ScenarioParams::deserialize(&value) {
            Ok(p) => (Some(p), None),
            Err(e) => (None, Some(e.to_string())),
        },
    };
    Ok(Some(TruthFile { x_arcsec, params, params_error }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{generate, ScenarioKind};

    fn parse(text: &str) -> Vec<Result<LogLine, LogError>> {
        LogReader::new(Path::new("t.csv"), text.as_bytes()).collect()
    }

    fn rows(text: &str) -> Vec<LogLine> {
        parse(text).into_iter().collect::<Result<Vec<_>, _>>().unwrap()
    }

    #[test]
    fn reads_comments_scientific_and_non_finite() {
        let text = format!("# a comment\n\n\u{feff}{HEADER}\r\n0,1e1,2.5E-1,40,30,nan,-inf\r\n# x\n1, 2 ,3,4,5,6,7\n   \n");
        let rows = rows(&text);
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
    fn columns_are_matched_by_name_in_any_order_extra_ones_ignored() {
        let plain = rows(&format!("{HEADER}\n0,1,2,40,4,5,6\n1,1.75,2,40,4,5.5,6.5\n"));
        let shuffled = rows(" pitch_deg , speed_kn,roll_deg,heading_deg,latitude_deg,platform_deg,rotation_deg,time_s,flags\n6,12.5,5,4,40,2,1,0,ok\n6.5,12.5,5.5,4,40,2,1.75,1,\n");
        assert_eq!(plain, shuffled);
    }

    #[test]
    fn a_bad_row_is_an_error_of_that_row_and_the_next_rows_are_read() {
        let text = format!("{HEADER}\n0,1,2,40,4,5,6\n1,1,x2,40,4,5,6\n2,1,2,40,,5,6\n3,1,2,40,4,5,6\n4,1,2,40");
        let items = parse(&text);
        assert_eq!(items.len(), 5);
        assert!(items[0].is_ok() && items[3].is_ok());
        let bad = items[1].as_ref().unwrap_err();
        assert!(bad.row);
        assert_eq!(bad.to_string(), "t.csv:3: platform_deg: not a number: \"x2\"");
        let blank = items[2].as_ref().unwrap_err();
        assert_eq!(blank.to_string(), "t.csv:4: heading_deg: blank cell");
        let truncated = items[4].as_ref().unwrap_err();
        assert!(truncated.row);
        assert_eq!(truncated.to_string(), "t.csv:6: short row: 4 fields, no heading_deg, roll_deg, pitch_deg");
    }

    #[test]
    fn header_errors_are_fatal() {
        let items = parse("time_s,rotation_deg\n0,1\n");
        assert_eq!(items.len(), 1);
        let e = items[0].as_ref().unwrap_err();
        assert!(!e.row);
        assert!(e.to_string().starts_with("t.csv:1: bad header: no column \"platform_deg\""), "{e}");
        let twice = parse(&format!("{HEADER},roll_deg\n"));
        assert!(twice[0].as_ref().unwrap_err().to_string().contains("\"roll_deg\" appears twice"));
        let empty = parse("# only\n");
        let e = empty[0].as_ref().unwrap_err();
        assert!(e.to_string().starts_with("t.csv:") && e.to_string().contains("no header"), "{e}");
        assert!(!e.to_string().contains('\n'));
    }

    #[test]
    fn strict_filter_refuses_a_bad_row_lenient_skips_and_counts() {
        let text = format!("{HEADER}\n0,1,2,40,4,5,6\n1,1,x2,40,4,5,6\n2,1,2,40,4,5,6\n");
        let mut lenient = RowFilter::new(false);
        let mut warned = Vec::new();
        let kept: Vec<LogLine> = parse(&text)
            .into_iter()
            .filter_map(|i| lenient.admit(i, &mut |e| warned.push(e.line)).unwrap())
            .collect();
        assert_eq!(kept.len(), 2);
        assert_eq!((lenient.skipped, warned), (1, vec![3]));
        let mut strict = RowFilter::new(true);
        let err = parse(&text).into_iter().map(|i| strict.admit(i, &mut |_| {})).find_map(Result::err).unwrap();
        assert_eq!(err.line, 3);
    }

    #[test]
    fn written_log_reads_back_bit_identical_plain_and_gzip() {
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
        let dir = std::env::temp_dir().join(format!("host-sim-log-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gz = dir.join("g.csv.gz");
        let mut enc = flate2::write::GzEncoder::new(File::create(&gz).unwrap(), flate2::Compression::fast());
        enc.write_all(&buf).unwrap();
        enc.finish().unwrap();
        let unzipped = read_log(&gz).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(unzipped, back);
    }

    #[test]
    fn truth_round_trips_with_params_and_needs_only_x_arcsec() {
        let p = crate::scenario::ScenarioParams::new(ScenarioKind::Paper, 9);
        let truth = Truth::new(&p);
        let text = serde_json::to_string(&truth).unwrap();
        assert!(text.starts_with("{\"x_arcsec\":[200.0,-150.0,300.0,-250.0],"), "{text}");
        let dir = std::env::temp_dir().join(format!("host-sim-truth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let full = dir.join("full.truth.json");
        write_truth(&full, &truth).unwrap();
        let minimal = dir.join("min.truth.json");
        std::fs::write(&minimal, "{\"x_arcsec\": [1, -2, 3.5, 0]}").unwrap();
        let broken = dir.join("broken.truth.json");
        std::fs::write(&broken, "{\"x\": 1}").unwrap();
        let (full, minimal, broken, missing) =
            (read_truth(&full), read_truth(&minimal), read_truth(&broken), read_truth(&dir.join("none.json")));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(full.unwrap().unwrap(), TruthFile { x_arcsec: truth.x_arcsec, params: Some(p), params_error: None });
        assert_eq!(minimal.unwrap().unwrap(), TruthFile { x_arcsec: [1.0, -2.0, 3.5, 0.0], params: None, params_error: None });
        assert!(broken.unwrap_err().to_string().contains("x_arcsec"));
        assert_eq!(missing.unwrap(), None);
    }

    #[test]
    fn companion_files_drop_csv_and_gz() {
        assert_eq!(truth_path(Path::new("/a/b/log.csv")), PathBuf::from("/a/b/log.truth.json"));
        assert_eq!(truth_path(Path::new("/a/b/log.csv.gz")), PathBuf::from("/a/b/log.truth.json"));
        assert_eq!(log_stem(Path::new("x/trial.csv.gz")), PathBuf::from("x/trial"));
    }
}
