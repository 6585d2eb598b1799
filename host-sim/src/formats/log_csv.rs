//! The attitude log (input) and the truth file of generated logs; formats in `docs/log-format.md`.
//!
//! # Reading
//! With the `csv` crate: the header names the columns, which are matched **by name** (any order;
//! other columns ignored; case, spaces for underscores, spaces around names and values, a UTF-8
//! byte-order mark and `\r\n` line ends tolerated: `Time S` is `time_s`). The separator is the one
//! of `,`, `;` and tab that splits the header line into the most fields. Lines starting with `#` and
//! blank lines are skipped. A gzip stream is decompressed on the fly (recognised by its magic
//! bytes); `-` is standard input. `nan`, `inf` and `-inf` (any case) parse to non-finite values and
//! are passed through: the core rejects such samples and counts them.
//!
//! The time is one column of [`TimeColumn::ALL`] (`time_s`, `time_ms` or `time_utc`; the first
//! present is used), read by [`TimeColumn::parse`]: seconds, milliseconds or ISO 8601 / RFC 3339.
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

use crate::formats::time_stamps::TimeColumn;
use crate::sim::scenario::{Row, ScenarioParams};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender};
use std::sync::Arc;

/// The attitude log's header as `generate` writes it.
pub const HEADER: &str =
    "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg";
/// The columns a log must have (in any order); the time may also be `time_ms` or `time_utc`
/// ([`TimeColumn`]).
pub const COLUMNS: [&str; 7] = [
    "time_s",
    "rotation_deg",
    "platform_deg",
    "latitude_deg",
    "heading_deg",
    "roll_deg",
    "pitch_deg",
];
/// The separators a log may use; the one that splits the header into the most fields is used.
pub const SEPARATORS: [u8; 3] = [b',', b';', b'\t'];
/// The name that stands for standard input (and, for outputs, standard output).
pub const STDIO: &str = "-";

/// A file that cannot be read as expected. `line` is 1-based; 0 for errors of the whole file
/// (cannot open, cannot write).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}:{line}: {message}")]
pub struct LogError {
    /// The file's path, as displayed.
    pub path: String,
    /// The line, 1-based; 0 for the whole file.
    pub line: usize,
    /// What is wrong.
    pub message: String,
    /// Only this row is unreadable; the rows after it can still be read.
    pub row: bool,
}

impl LogError {
    /// An error of the whole file: nothing after it can be read.
    pub fn new(path: &Path, line: usize, message: impl Into<String>) -> LogError {
        LogError {
            path: path.display().to_string(),
            line,
            message: message.into(),
            row: false,
        }
    }

    /// An unreadable row.
    pub fn unreadable_row(path: &Path, line: usize, message: impl Into<String>) -> LogError {
        LogError {
            row: true,
            ..LogError::new(path, line, message)
        }
    }
}

/// One parsed data line: its 1-based line number in the file, and the row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLine {
    /// Line number in the file, 1-based.
    pub line: usize,
    /// The row.
    pub row: Row,
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
    let head = buffered
        .fill_buf()
        .map_err(|e| LogError::new(path, 0, format!("cannot read: {e}")))?;
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
        self.ahead
            .extend(memchr::memchr_iter(b'\n', &buf[..n]).map(|i| offset + i as u64));
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

/// How many bytes at most are looked at for the header line, to choose the separator.
const HEADER_SCAN_BYTES: usize = 1 << 16;

/// Reads the start of `reader` up to the first line that is neither blank nor a comment (or
/// [`HEADER_SCAN_BYTES`], or the end), and picks the separator from that line ([`separator_of`]).
/// Returns the separator and the bytes read, which go back in front of the rest.
fn scan_header<R: Read>(reader: &mut R) -> std::io::Result<(u8, Vec<u8>)> {
    let mut head = Vec::new();
    let mut chunk = [0u8; 4096];
    loop {
        if let Some(line) = header_line(&head) {
            return Ok((separator_of(line), head));
        }
        if head.len() >= HEADER_SCAN_BYTES {
            return Ok((b',', head));
        }
        let n = match reader.read(&mut chunk) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if n == 0 {
            // The whole input is shorter: its last line may be the header, without a line end.
            let line = head
                .split(|b| *b == b'\n')
                .map(trim_line)
                .find(|l| is_content(l))
                .unwrap_or(&[]);
            return Ok((separator_of(line), head));
        }
        head.extend_from_slice(&chunk[..n]);
    }
}

/// A line without its byte-order mark, `\r` and surrounding spaces.
fn trim_line(line: &[u8]) -> &[u8] {
    let line = line.strip_prefix("\u{feff}".as_bytes()).unwrap_or(line);
    line.trim_ascii()
}

/// Whether a (trimmed) line carries data: not blank, not a `#` comment.
fn is_content(line: &[u8]) -> bool {
    !line.is_empty() && line[0] != b'#'
}

/// The first complete line of `head` that carries data, if `head` holds one.
fn header_line(head: &[u8]) -> Option<&[u8]> {
    let mut lines = head.split(|b| *b == b'\n');
    // The last piece has no line end yet: it may be incomplete.
    let complete = head.iter().filter(|b| **b == b'\n').count();
    lines
        .by_ref()
        .take(complete)
        .map(trim_line)
        .find(|l| is_content(l))
}

/// The separator of [`SEPARATORS`] that occurs most often in `line` outside double quotes (`,` on
/// a tie or when none occurs).
pub fn separator_of(line: &[u8]) -> u8 {
    let mut counts = [0usize; SEPARATORS.len()];
    let mut quoted = false;
    for &b in line {
        if b == b'"' {
            quoted = !quoted;
        } else if !quoted {
            if let Some(i) = SEPARATORS.iter().position(|s| *s == b) {
                counts[i] += 1;
            }
        }
    }
    let best =
        (0..SEPARATORS.len()).fold(0, |best, i| if counts[i] > counts[best] { i } else { best });
    SEPARATORS[best]
}

/// A header name as it is matched: trimmed, without a byte-order mark, lower case, every run of
/// spaces and underscores one underscore (`Time S`, `TIME_S` and `time  s` are `time_s`).
pub fn normalize_column_name(name: &str) -> String {
    let name = name.trim_start_matches('\u{feff}').trim().to_lowercase();
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        if c == ' ' || c == '_' {
            if !out.ends_with('_') {
                out.push('_');
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// Where the seven values of a row are: the time column and its kind, then the six angles'
/// columns in [`COLUMNS`] order; and the names as the header writes them.
#[derive(Clone, Debug)]
struct Layout {
    time: TimeColumn,
    index: [usize; 7],
    names: [String; 7],
}

impl Layout {
    /// Finds every column in a header (see [`normalize_column_name`]).
    fn of(header: &[String]) -> Result<Layout, String> {
        let normalized: Vec<String> = header.iter().map(|n| normalize_column_name(n)).collect();
        let find = |want: &str| -> Result<Option<usize>, String> {
            let mut found = normalized
                .iter()
                .enumerate()
                .filter(|(_, n)| *n == want)
                .map(|(i, _)| i);
            match (found.next(), found.next()) {
                (Some(_), Some(_)) => Err(format!("column {want:?} appears twice in the header")),
                (first, _) => Ok(first),
            }
        };
        let mut time = None;
        for column in TimeColumn::ALL {
            if let Some(i) = find(column.name())? {
                time.get_or_insert((column, i));
            }
        }
        let missing = |want: &str| {
            let times: Vec<String> = TimeColumn::ALL
                .iter()
                .skip(1)
                .map(|c| format!("{:?}", c.name()))
                .collect();
            let or_time = if want == COLUMNS[0] {
                format!(" (or {})", times.join(", "))
            } else {
                String::new()
            };
            let header: Vec<&str> = header
                .iter()
                .map(|n| n.trim_start_matches('\u{feff}'))
                .collect();
            format!(
                "no column {want:?}{or_time} in the header {:?} (needs {})",
                header.join(","),
                COLUMNS.join(",")
            )
        };
        let Some((time, time_index)) = time else {
            return Err(missing(COLUMNS[0]));
        };
        let mut index = [time_index; 7];
        for (k, want) in COLUMNS.iter().enumerate().skip(1) {
            index[k] = find(want)?.ok_or_else(|| missing(want))?;
        }
        let names = index.map(|i| header[i].trim_start_matches('\u{feff}').trim().to_string());
        Ok(Layout { time, index, names })
    }
}

/// Streams the rows of an attitude log.
pub struct LogReader<R: Read> {
    path: PathBuf,
    csv: csv::Reader<LineCounter<std::io::Chain<std::io::Cursor<Vec<u8>>, R>>>,
    layout: Option<Layout>,
    record: csv::ByteRecord,
    separator: u8,
    /// Why the start of the log could not be read (told at the first row).
    scan_error: Option<std::io::Error>,
    failed: bool,
    gzip: bool,
}

impl LogReader<Box<dyn Read + Send>> {
    /// Opens a log file (or standard input for `-`; gzip decompressed).
    pub fn open(path: &Path) -> Result<Self, LogError> {
        let (input, gzip) = open_input_gz(path)?;
        Ok(LogReader {
            gzip,
            ..LogReader::new(path, input)
        })
    }
}

impl<R: Read> LogReader<R> {
    /// Reads a log from any reader; `path` names it in errors.
    pub fn new(path: &Path, mut reader: R) -> Self {
        let (separator, head, scan_error) = match scan_header(&mut reader) {
            Ok((separator, head)) => (separator, head, None),
            Err(e) => (b',', Vec::new(), Some(e)),
        };
        let csv = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .delimiter(separator)
            .comment(Some(b'#'))
            .buffer_capacity(1 << 16)
            .from_reader(LineCounter {
                inner: std::io::Cursor::new(head).chain(reader),
                offset: 0,
                ahead: Default::default(),
                passed: 0,
            });
        LogReader {
            path: path.to_path_buf(),
            csv,
            layout: None,
            record: csv::ByteRecord::new(),
            separator,
            scan_error,
            failed: false,
            gzip: false,
        }
    }

    /// Bytes of (decompressed) log read so far.
    pub fn bytes_read(&self) -> u64 {
        self.csv.position().byte()
    }

    /// Whether the log was opened from a gzip file.
    pub fn is_gzip(&self) -> bool {
        self.gzip
    }

    /// The separator found in the header line.
    pub fn separator(&self) -> u8 {
        self.separator
    }

    /// The time column used, once the header is read.
    pub fn time_column(&self) -> Option<TimeColumn> {
        self.layout.as_ref().map(|l| l.time)
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

    /// The current record as a row, or why it is unreadable.
    fn parse_row(&self, layout: &Layout) -> Result<Row, String> {
        let missing: Vec<&str> = COLUMNS
            .iter()
            .zip(&layout.index)
            .filter(|(_, i)| **i >= self.record.len())
            .map(|(c, _)| *c)
            .collect();
        if !missing.is_empty() {
            return Err(format!(
                "short row: {} fields, no {}",
                self.record.len(),
                missing.join(", ")
            ));
        }
        let cell = |k: usize| {
            String::from_utf8_lossy(self.record.get(layout.index[k]).unwrap_or_default())
        };
        let time_s = layout
            .time
            .parse(&cell(0))
            .map_err(|m| format!("{}: {m}", layout.names[0]))?;
        let mut v = [0.0; 6];
        for (k, slot) in v.iter_mut().enumerate() {
            let text = cell(k + 1);
            *slot = text.parse().map_err(|_| {
                let name = &layout.names[k + 1];
                if text.is_empty() {
                    format!("{name}: blank cell")
                } else if text.replace(',', ".").parse::<f64>().is_ok() {
                    format!("{name}: not a number: {text:?} (a decimal comma? numbers need a decimal point)")
                } else {
                    format!("{name}: not a number: {text:?}")
                }
            })?;
        }
        Ok(Row {
            time_s,
            rotation_deg: v[0],
            platform_deg: v[1],
            latitude_deg: v[2],
            heading_deg: v[3],
            roll_deg: v[4],
            pitch_deg: v[5],
        })
    }
}

/// A log's rows as they are read, and how far into the file the reading is (for progress).
pub trait LogLines: Iterator<Item = Result<LogLine, LogError>> {
    /// Bytes of the file read so far.
    fn bytes_read(&self) -> u64;
}

impl<R: Read> LogLines for LogReader<R> {
    fn bytes_read(&self) -> u64 {
        LogReader::bytes_read(self)
    }
}

impl<R: Read> Iterator for LogReader<R> {
    type Item = Result<LogLine, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        if let Some(e) = self.scan_error.take() {
            return self.fail(LogError::new(&self.path, 1, format!("cannot read: {e}")));
        }
        loop {
            match self.csv.read_byte_record(&mut self.record) {
                Ok(true) => {}
                Ok(false) if self.layout.is_none() => {
                    let line = self.line();
                    return self.fail(LogError::new(
                        &self.path,
                        line,
                        format!("no header, expected the columns {HEADER:?}"),
                    ));
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
            let Some(layout) = &self.layout else {
                let header: Vec<String> = self
                    .record
                    .iter()
                    .map(|f| String::from_utf8_lossy(f).into_owned())
                    .collect();
                match Layout::of(&header) {
                    Ok(layout) => self.layout = Some(layout),
                    Err(m) => {
                        let line = self.line();
                        return self.fail(LogError::new(
                            &self.path,
                            line,
                            format!("bad header: {m}"),
                        ));
                    }
                }
                continue;
            };
            let parsed = self.parse_row(layout);
            let line = self.line();
            return Some(match parsed {
                Ok(row) => Ok(LogLine { line, row }),
                Err(message) => Err(LogError::unreadable_row(&self.path, line, message)),
            });
        }
    }
}

/// Rows parsed ahead by [`read_ahead`]'s thread, per batch: a consumer that stops at the end of
/// a batch of this many items (or of a divisor of it) never waits on rows the reader has not yet
/// handed over.
pub const READ_AHEAD_BATCH: usize = 4096;
/// Batches that may wait in [`read_ahead`]'s channel.
pub const READ_AHEAD_DEPTH: usize = 4;

/// One item of a log, as [`LogReader`] gives it.
type LogItem = Result<LogLine, LogError>;

/// Runs `reader` on a thread of its own, a few batches of rows ahead of `consume`, which gets the
/// same items in the same order: parsing the CSV and the work done with its rows then share two
/// cores. At most [`READ_AHEAD_DEPTH`] batches of [`READ_AHEAD_BATCH`] rows wait at any time, so
/// memory does not grow with the log.
///
/// However `consume` ends (it read every item, returned early, or panicked), the reader ends too,
/// and this function does not wait on it longer than it must. When `consume` stops before the end
/// of the log, the channel is hung up and the reader told to stop, which it does before its next
/// row (at once if it is waiting to hand over a batch); it is not waited for, as it may be blocked
/// in a read that returns only when its writer writes or closes (standard input): it ends then, or
/// with the process. When `consume` read every item, the reader has hung up and is joined: a panic
/// in it is raised here, so that a log is never taken for complete because its reader died.
pub fn read_ahead<R, T>(
    reader: LogReader<R>,
    consume: impl FnOnce(&mut dyn Iterator<Item = LogItem>) -> T,
) -> T
where
    R: Read + Send + 'static,
{
    let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<LogItem>>(READ_AHEAD_DEPTH);
    let stop = Arc::new(AtomicBool::new(false));
    let reader_stop = stop.clone();
    let handle = std::thread::spawn(move || read_batches(reader, &tx, &reader_stop));
    let mut items = Batches {
        rx,
        batch: Vec::new().into_iter(),
        stop,
        ended: false,
    };
    let result = consume(&mut items);
    let ended = items.ended;
    // Hangs up and tells the reader to stop (also done when `consume` panics: `items` is dropped
    // then too).
    drop(items);
    if ended {
        if let Err(panic) = handle.join() {
            std::panic::resume_unwind(panic);
        }
    }
    result
}

/// [`read_ahead`]'s thread: batches of rows into `tx` until the end of the log, a hang-up, or
/// `stop`.
fn read_batches<R: Read>(
    mut reader: LogReader<R>,
    tx: &SyncSender<Vec<LogItem>>,
    stop: &AtomicBool,
) {
    loop {
        let mut batch = Vec::with_capacity(READ_AHEAD_BATCH);
        let mut end = false;
        while batch.len() < READ_AHEAD_BATCH {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            match reader.next() {
                Some(item) => batch.push(item),
                None => {
                    end = true;
                    break;
                }
            }
        }
        // A send fails as soon as the consumer hangs up, even one waiting on a full channel.
        if !batch.is_empty() && tx.send(batch).is_err() {
            return;
        }
        if end {
            return;
        }
    }
}

/// The consumer's end of [`read_ahead`]: the items of the batches in order. Dropping it hangs up
/// and tells the reader to stop.
struct Batches {
    rx: Receiver<Vec<LogItem>>,
    batch: std::vec::IntoIter<LogItem>,
    stop: Arc<AtomicBool>,
    /// The reader hung up: every item was received.
    ended: bool,
}

impl Iterator for Batches {
    type Item = LogItem;

    fn next(&mut self) -> Option<LogItem> {
        loop {
            if let Some(item) = self.batch.next() {
                return Some(item);
            }
            if self.ended {
                return None;
            }
            match self.rx.recv() {
                Ok(batch) => self.batch = batch.into_iter(),
                Err(_) => self.ended = true,
            }
        }
    }
}

impl Drop for Batches {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
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
        RowFilter {
            strict,
            ..RowFilter::default()
        }
    }

    /// The row of a reader's item: `Ok(None)` for an unreadable row that is skipped; errors for a
    /// fatal error, or for any unreadable row when strict. `warn` is told each skipped row (up to
    /// [`RowFilter::KEPT`]).
    pub fn admit(
        &mut self,
        item: Result<LogLine, LogError>,
        warn: &mut dyn FnMut(&LogError),
    ) -> Result<Option<LogLine>, LogError> {
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
    let name = log_path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    let stem = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
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
            r.time_s,
            r.rotation_deg,
            r.platform_deg,
            r.latitude_deg,
            r.heading_deg,
            r.roll_deg,
            r.pitch_deg
        )?;
    }
    w.flush()
}

/// Writes rows as an attitude log file (through a temporary file beside it, renamed when complete:
/// [`crate::formats::output_file`]).
pub fn write_log<I>(path: &Path, rows: I) -> anyhow::Result<()>
where
    I: IntoIterator,
    I::Item: std::borrow::Borrow<Row>,
{
    let mut out = crate::formats::output_file::OutputFile::create(path)?;
    write_log_to(&mut out, rows)
        .map_err(|e| LogError::new(path, 0, format!("cannot write: {e}")))?;
    out.commit()
}

/// The truth file of a generated log: the installation errors and every scenario parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Installation errors x1..x4 at t = 0, arcsec (they drift only under a model mismatch).
    pub x_arcsec: [f64; 4],
    /// Every parameter of the scenario, written at the top level.
    #[serde(flatten)]
    pub params: ScenarioParams,
}

impl Truth {
    /// The truth file of the log `params` generates.
    pub fn new(params: &ScenarioParams) -> Truth {
        Truth {
            x_arcsec: params.errors_arcsec,
            params: params.clone(),
        }
    }
}

/// `<dir>/<stem>.truth.json` beside the log `<dir>/<stem>.csv` (or `.csv.gz`).
pub fn truth_path(log_path: &Path) -> PathBuf {
    let stem = log_stem(log_path);
    let name = format!(
        "{}.truth.json",
        stem.file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    stem.with_file_name(name)
}

/// Writes the truth file (through a temporary file beside it).
pub fn write_truth(path: &Path, truth: &Truth) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(truth)
        .map_err(|e| LogError::new(path, 0, format!("cannot encode: {e}")))?;
    crate::formats::output_file::write_bytes(path, (text + "\n").as_bytes())
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
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| LogError::new(path, e.line(), e.to_string()))?;
    let x = value
        .get("x_arcsec")
        .ok_or_else(|| LogError::new(path, 0, "no \"x_arcsec\": [x1, x2, x3, x4] (arcsec)"))?;
    let x_arcsec: [f64; 4] = serde_json::from_value(x.clone())
        .map_err(|e| LogError::new(path, 0, format!("x_arcsec: {e}")))?;
    let (params, params_error) = match value.get("scenario") {
        None => (None, None),
        Some(_) => match ScenarioParams::deserialize(&value) {
            Ok(p) => (Some(p), None),
            Err(e) => (None, Some(e.to_string())),
        },
    };
    Ok(Some(TruthFile {
        x_arcsec,
        params,
        params_error,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scenario::{generate, ScenarioKind};

    fn parse(text: &str) -> Vec<Result<LogLine, LogError>> {
        LogReader::new(Path::new("t.csv"), text.as_bytes()).collect()
    }

    fn rows(text: &str) -> Vec<LogLine> {
        parse(text)
            .into_iter()
            .collect::<Result<Vec<_>, _>>()
            .unwrap()
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
        let plain = rows(&format!(
            "{HEADER}\n0,1,2,40,4,5,6\n1,1.75,2,40,4,5.5,6.5\n"
        ));
        let shuffled = rows(" pitch_deg , speed_kn,roll_deg,heading_deg,latitude_deg,platform_deg,rotation_deg,time_s,flags\n6,12.5,5,4,40,2,1,0,ok\n6.5,12.5,5.5,4,40,2,1.75,1,\n");
        assert_eq!(plain, shuffled);
    }

    #[test]
    fn header_names_in_any_case_with_spaces_and_any_separator_read_the_same() {
        let plain = rows(&format!(
            "{HEADER}\n0,1,2,40,4,5,6\n1,1.75,2,40,4,5.5,6.5\n"
        ));
        let variants = [
            "TIME_S,Rotation_Deg,PLATFORM DEG,Latitude Deg,heading  deg,Roll_deg, pitch_DEG \n0,1,2,40,4,5,6\n1,1.75,2,40,4,5.5,6.5\n",
            "# a ; comment, with \t separators\nTime S;Rotation Deg;Platform Deg;Latitude Deg;Heading Deg;Roll Deg;Pitch Deg\n0;1;2;40;4;5;6\n1;1.75;2;40;4;5.5;6.5\n",
            "time_s\trotation_deg\tplatform_deg\tlatitude_deg\theading_deg\troll_deg\tpitch_deg\n0\t1\t2\t40\t4\t5\t6\n1\t1.75\t2\t40\t4\t5.5\t6.5\n",
        ];
        let values = |lines: Vec<LogLine>| lines.into_iter().map(|l| l.row).collect::<Vec<_>>();
        for text in variants {
            assert_eq!(values(rows(text)), values(plain.clone()), "{text}");
        }
        assert_eq!(separator_of(b"a;b;c,d"), b';');
        assert_eq!(
            separator_of(b"\"a;b\",c"),
            b',',
            "separators inside quotes do not count"
        );
        assert_eq!(normalize_column_name("\u{feff} Time__ S "), "time_s");
        let twice = parse("time_s,Roll Deg,roll_deg,rotation_deg,platform_deg,latitude_deg,heading_deg,pitch_deg\n");
        assert!(
            twice[0]
                .as_ref()
                .unwrap_err()
                .to_string()
                .contains("\"roll_deg\" appears twice"),
            "{:?}",
            twice[0]
        );
    }

    #[test]
    fn time_in_milliseconds_or_utc_reads_as_seconds() {
        let plain = rows(&format!(
            "{HEADER}\n1700000000,1,2,40,4,5,6\n1700000001.5,1.75,2,40,4,5.5,6.5\n"
        ));
        let ms = rows("time_ms,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n1700000000000,1,2,40,4,5,6\n1700000001500,1.75,2,40,4,5.5,6.5\n");
        let utc = rows("Time UTC;rotation_deg;platform_deg;latitude_deg;heading_deg;roll_deg;pitch_deg\n2023-11-14T22:13:20Z;1;2;40;4;5;6\n2023-11-14 22:13:21.5;1.75;2;40;4;5.5;6.5\n");
        let iso_in_seconds = rows(&format!("{HEADER}\n2023-11-14T22:13:20Z,1,2,40,4,5,6\n2023-11-15T00:13:21.500+02:00,1.75,2,40,4,5.5,6.5\n"));
        assert_eq!(ms, plain);
        assert_eq!(utc, plain);
        assert_eq!(iso_in_seconds, plain);
        let mut reader = LogReader::new(Path::new("t.csv"), "time_utc,time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n2023-11-14T22:13:20Z,5,1,2,40,4,5,6\n".as_bytes());
        assert_eq!(
            reader.next().unwrap().unwrap().row.time_s,
            5.0,
            "time_s is used before time_utc"
        );
        assert_eq!(reader.time_column(), Some(TimeColumn::Seconds));
        let missing =
            parse("time,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n");
        let e = missing[0].as_ref().unwrap_err().to_string();
        assert!(
            e.contains("no column \"time_s\" (or \"time_ms\", \"time_utc\")"),
            "{e}"
        );
    }

    #[test]
    fn a_decimal_comma_is_named_as_the_likely_cause() {
        let items = parse("time_s;rotation_deg;platform_deg;latitude_deg;heading_deg;roll_deg;pitch_deg\n0;1;2;40;4;0,5;6\n");
        let e = items[0].as_ref().unwrap_err();
        assert!(e.row);
        assert_eq!(e.to_string(), "t.csv:2: roll_deg: not a number: \"0,5\" (a decimal comma? numbers need a decimal point)");
    }

    #[test]
    fn a_bad_row_is_an_error_of_that_row_and_the_next_rows_are_read() {
        let text = format!(
            "{HEADER}\n0,1,2,40,4,5,6\n1,1,x2,40,4,5,6\n2,1,2,40,,5,6\n3,1,2,40,4,5,6\n4,1,2,40"
        );
        let items = parse(&text);
        assert_eq!(items.len(), 5);
        assert!(items[0].is_ok() && items[3].is_ok());
        let bad = items[1].as_ref().unwrap_err();
        assert!(bad.row);
        assert_eq!(
            bad.to_string(),
            "t.csv:3: platform_deg: not a number: \"x2\""
        );
        let blank = items[2].as_ref().unwrap_err();
        assert_eq!(blank.to_string(), "t.csv:4: heading_deg: blank cell");
        let truncated = items[4].as_ref().unwrap_err();
        assert!(truncated.row);
        assert_eq!(
            truncated.to_string(),
            "t.csv:6: short row: 4 fields, no heading_deg, roll_deg, pitch_deg"
        );
    }

    #[test]
    fn header_errors_are_fatal() {
        let items = parse("time_s,rotation_deg\n0,1\n");
        assert_eq!(items.len(), 1);
        let e = items[0].as_ref().unwrap_err();
        assert!(!e.row);
        assert!(
            e.to_string()
                .starts_with("t.csv:1: bad header: no column \"platform_deg\""),
            "{e}"
        );
        let twice = parse(&format!("{HEADER},roll_deg\n"));
        assert!(twice[0]
            .as_ref()
            .unwrap_err()
            .to_string()
            .contains("\"roll_deg\" appears twice"));
        let empty = parse("# only\n");
        let e = empty[0].as_ref().unwrap_err();
        assert!(
            e.to_string().starts_with("t.csv:") && e.to_string().contains("no header"),
            "{e}"
        );
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
        let err = parse(&text)
            .into_iter()
            .map(|i| strict.admit(i, &mut |_| {}))
            .find_map(Result::err)
            .unwrap();
        assert_eq!(err.line, 3);
    }

    #[test]
    fn written_log_reads_back_bit_identical_plain_and_gzip() {
        let mut p = crate::sim::scenario::ScenarioParams::new(ScenarioKind::Sea, 3);
        p.duration_s = 300.0;
        let g = generate(&p);
        let mut buf = Vec::new();
        write_log_to(&mut buf, &g.rows).unwrap();
        let back = LogReader::new(Path::new("g.csv"), buf.as_slice())
            .collect::<Result<Vec<_>, _>>()
            .unwrap();
        assert_eq!(back.len(), g.rows.len());
        for (a, b) in back.iter().zip(&g.rows) {
            assert_eq!(a.row, *b);
        }
        let dir = std::env::temp_dir().join(format!("host-sim-log-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gz = dir.join("g.csv.gz");
        let mut enc =
            flate2::write::GzEncoder::new(File::create(&gz).unwrap(), flate2::Compression::fast());
        enc.write_all(&buf).unwrap();
        enc.finish().unwrap();
        let unzipped = read_log(&gz).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(unzipped, back);
    }

    #[test]
    fn truth_round_trips_with_params_and_needs_only_x_arcsec() {
        let p = crate::sim::scenario::ScenarioParams::new(ScenarioKind::Paper, 9);
        let truth = Truth::new(&p);
        let text = serde_json::to_string(&truth).unwrap();
        assert!(
            text.starts_with("{\"x_arcsec\":[200.0,-150.0,300.0,-250.0],"),
            "{text}"
        );
        let dir = std::env::temp_dir().join(format!("host-sim-truth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let full = dir.join("full.truth.json");
        write_truth(&full, &truth).unwrap();
        let minimal = dir.join("min.truth.json");
        std::fs::write(&minimal, "{\"x_arcsec\": [1, -2, 3.5, 0]}").unwrap();
        let broken = dir.join("broken.truth.json");
        std::fs::write(&broken, "{\"x\": 1}").unwrap();
        let (full, minimal, broken, missing) = (
            read_truth(&full),
            read_truth(&minimal),
            read_truth(&broken),
            read_truth(&dir.join("none.json")),
        );
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(
            full.unwrap().unwrap(),
            TruthFile {
                x_arcsec: truth.x_arcsec,
                params: Some(p),
                params_error: None
            }
        );
        assert_eq!(
            minimal.unwrap().unwrap(),
            TruthFile {
                x_arcsec: [1.0, -2.0, 3.5, 0.0],
                params: None,
                params_error: None
            }
        );
        assert!(broken.unwrap_err().to_string().contains("x_arcsec"));
        assert_eq!(missing.unwrap(), None);
    }

    /// A log of `rows` rows at 1 s, every `bad`-th row (if any) unreadable.
    fn long_log(rows: usize, bad: Option<usize>) -> Vec<u8> {
        let mut text = format!("{HEADER}\n");
        for k in 0..rows {
            if bad.is_some_and(|b| k % b == b - 1) {
                text.push_str(&format!("{k},1,x,40,4,5,6\n"));
            } else {
                text.push_str(&format!("{k},1,2,40,4,5,6\n"));
            }
        }
        text.into_bytes()
    }

    /// Bytes that count what is read of them and, at their end, wait until `release` hangs up
    /// (standard input from a writer that neither writes nor closes).
    struct Watched {
        bytes: std::io::Cursor<Vec<u8>>,
        read: Arc<std::sync::atomic::AtomicU64>,
        release: Option<Receiver<()>>,
        /// Panic at the end instead.
        panic_at_end: bool,
    }

    impl Read for Watched {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = self.bytes.read(buf)?;
            if n == 0 {
                assert!(!self.panic_at_end, "the reader fails");
                if let Some(release) = &self.release {
                    let _ = release.recv();
                }
            }
            self.read.fetch_add(n as u64, Ordering::Relaxed);
            Ok(n)
        }
    }

    fn watched(bytes: Vec<u8>) -> (Watched, Arc<std::sync::atomic::AtomicU64>) {
        let read = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let w = Watched {
            bytes: std::io::Cursor::new(bytes),
            read: read.clone(),
            release: None,
            panic_at_end: false,
        };
        (w, read)
    }

    /// `f` on a thread of its own; fails the test if it has not returned within 20 s (a hang).
    fn within_20_s<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(f());
        });
        rx.recv_timeout(std::time::Duration::from_secs(20))
            .expect("did not return within 20 s")
    }

    #[test]
    fn read_ahead_hands_on_every_item_in_order() {
        let bytes = long_log(20_000, Some(997));
        let plain: Vec<_> = LogReader::new(Path::new("t.csv"), bytes.as_slice()).collect();
        let (input, _) = watched(bytes);
        let ahead = within_20_s(|| {
            read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                items.collect::<Vec<_>>()
            })
        });
        assert_eq!(plain.len(), 20_000);
        assert_eq!(ahead, plain);
    }

    #[test]
    fn a_consumer_stopping_early_stops_the_reader_with_the_channel_full() {
        // Far more rows than the channel holds: the reader waits on a full channel when the
        // consumer stops at its first row.
        let bytes = long_log(300_000, None);
        let total = bytes.len() as u64;
        let (input, read) = watched(bytes);
        let first = within_20_s(|| {
            read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                items.next().map(|i| i.map(|l| l.line))
            })
        });
        assert_eq!(first, Some(Ok(2)));
        // The reader stops where it was: what it has read no longer grows.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        let mut last = u64::MAX;
        loop {
            let now = read.load(Ordering::Relaxed);
            if now == last {
                break;
            }
            assert!(
                std::time::Instant::now() < deadline,
                "the reader goes on: {now} bytes"
            );
            last = now;
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        assert!(last < total / 2, "read {last} of {total} bytes");
    }

    #[test]
    fn a_consumer_stopping_early_does_not_wait_on_a_reader_blocked_in_a_read() {
        let (release, wait) = std::sync::mpsc::channel::<()>();
        let (mut input, _) = watched(long_log(10_000, None));
        input.release = Some(wait);
        // The first batch comes, then the reader waits for input that does not come.
        let taken = within_20_s(|| {
            read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                items.take(10).count()
            })
        });
        assert_eq!(taken, 10);
        drop(release);
    }

    #[test]
    fn a_reader_that_dies_is_not_taken_for_the_end_of_the_log() {
        let (mut input, _) = watched(long_log(10_000, None));
        input.panic_at_end = true;
        let outcome = within_20_s(|| {
            std::panic::catch_unwind(|| {
                read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                    items.count()
                })
            })
        });
        assert!(outcome.is_err(), "{outcome:?}");
    }

    #[test]
    fn companion_files_drop_csv_and_gz() {
        assert_eq!(
            truth_path(Path::new("/a/b/log.csv")),
            PathBuf::from("/a/b/log.truth.json")
        );
        assert_eq!(
            truth_path(Path::new("/a/b/log.csv.gz")),
            PathBuf::from("/a/b/log.truth.json")
        );
        assert_eq!(
            log_stem(Path::new("x/trial.csv.gz")),
            PathBuf::from("x/trial")
        );
    }
}
