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

mod header;

use crate::formats::time_stamps::TimeColumn;
use crate::sim::scenario::Row;
use header::{scan_header, Layout};
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};

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

    /// `unreadable rows skipped: N (lines A, B, ...; --strict refuses such a log)`, the lines of
    /// the first few; `None` when no row was skipped.
    pub fn describe_skipped(&self) -> Option<String> {
        if self.skipped == 0 {
            return None;
        }
        let lines: Vec<String> = self.first.iter().map(|e| e.line.to_string()).collect();
        let more = if self.skipped as usize > lines.len() {
            ", ..."
        } else {
            ""
        };
        Some(format!(
            "unreadable rows skipped: {} (lines {}{more}; --strict refuses such a log)",
            self.skipped,
            lines.join(", ")
        ))
    }
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

#[cfg(test)]
mod tests {
    use super::header::{normalize_column_name, separator_of};
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
}
