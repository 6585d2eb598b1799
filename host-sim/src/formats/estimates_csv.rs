//! The estimates CSV (output), one row per input row; format in `docs/log-format.md`.
//!
//! The rows are formatted by [`estimator_core::estimates_csv`], the same code the C library's
//! `rins_format_row` runs, so that the replay path, the firmware stream path and a C program
//! write byte-identical files from the same [`Output`]s. A rejected row carries the estimate held
//! on board at that moment: a rejected sample leaves the estimator untouched, so that is the
//! estimate of the last [`Output`], which the writer remembers.

use crate::formats::log_csv::LogError;
use estimator_core::estimates_csv::{write_output, write_rejected};
use estimator_core::{Estimate, Output, SampleError};
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

pub use estimator_core::estimates_csv::{HEADER, REJECTED_PREFIX};

/// Writes the estimates CSV, one line per step, as the steps come (nothing is held but the last
/// estimate and one line's buffer).
pub struct EstimatesWriter<W: Write> {
    out: W,
    held: Option<Estimate>,
    line: String,
}

/// One row for a step's output (no newline).
pub fn format_output(out: &Output) -> String {
    let mut line = String::new();
    // Writing into a `String` cannot fail.
    let _ = write_output(&mut line, out);
    line
}

/// One row for a rejected input row (no newline): its time, the held estimate, the reason.
pub fn format_rejected(time_s: f64, reason: &SampleError, held: Option<&Estimate>) -> String {
    let mut line = String::new();
    let _ = write_rejected(&mut line, time_s, reason.reason(), held);
    line
}

impl<W: Write> EstimatesWriter<W> {
    /// Writes the header.
    pub fn new(mut out: W) -> std::io::Result<Self> {
        writeln!(out, "{HEADER}")?;
        Ok(EstimatesWriter {
            out,
            held: None,
            line: String::with_capacity(256),
        })
    }

    /// Writes the row of one step: pass `step`'s result as it is, with the input row's time.
    pub fn write_step(
        &mut self,
        time_s: f64,
        result: &Result<Output, SampleError>,
    ) -> std::io::Result<()> {
        match result {
            Ok(out) => self.write_output(out),
            Err(reason) => self.write_rejected(time_s, reason),
        }
    }

    /// Writes the row of an accepted sample.
    pub fn write_output(&mut self, out: &Output) -> std::io::Result<()> {
        self.held = out.estimate;
        self.line.clear();
        let _ = write_output(&mut self.line, out);
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    /// Writes the row of a rejected sample.
    pub fn write_rejected(&mut self, time_s: f64, reason: &SampleError) -> std::io::Result<()> {
        self.line.clear();
        let _ = write_rejected(&mut self.line, time_s, reason.reason(), self.held.as_ref());
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    /// Flushes and returns the inner writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// One parsed row of the estimates CSV.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimateRow {
    /// The input row's time, s.
    pub time_s: f64,
    /// The estimates of x1..x4, arcsec; `None` while there is no estimate.
    pub x_arcsec: Option<[f64; 4]>,
    /// Their 1-sigma, arcsec; `None` while there is no estimate.
    pub sigma_arcsec: Option<[f64; 4]>,
    /// The status's name, or `rejected_<reason>` for a rejected row.
    pub status: String,
    /// Heading, roll, pitch corrected, deg; `None` on a rejected row.
    pub corrected_deg: Option<[f64; 3]>,
}

impl EstimateRow {
    /// Whether the estimator rejected the row.
    pub fn is_rejected(&self) -> bool {
        self.status.starts_with(REJECTED_PREFIX)
    }
}

/// One row as the `csv` crate reads it, columns by the names of [`HEADER`]; an empty field is
/// `None`.
#[derive(serde::Deserialize)]
struct RawRow {
    time_s: f64,
    x1_arcsec: Option<f64>,
    x2_arcsec: Option<f64>,
    x3_arcsec: Option<f64>,
    x4_arcsec: Option<f64>,
    sigma1_arcsec: Option<f64>,
    sigma2_arcsec: Option<f64>,
    sigma3_arcsec: Option<f64>,
    sigma4_arcsec: Option<f64>,
    status: String,
    heading_corrected_deg: Option<f64>,
    roll_corrected_deg: Option<f64>,
    pitch_corrected_deg: Option<f64>,
}

/// A group of columns written together (an estimate, its 1-sigma, the corrected attitude): all
/// present or all empty; one empty among numbers is an error naming its column.
fn group<const N: usize>(
    values: [Option<f64>; N],
    names: [&str; N],
) -> Result<Option<[f64; N]>, String> {
    if values.iter().all(Option::is_none) {
        return Ok(None);
    }
    let mut out = [0.0; N];
    for ((slot, value), name) in out.iter_mut().zip(values).zip(names) {
        *slot = value.ok_or_else(|| format!("{name}: empty while the rest of its group is not"))?;
    }
    Ok(Some(out))
}

impl TryFrom<RawRow> for EstimateRow {
    type Error = String;

    fn try_from(r: RawRow) -> Result<EstimateRow, String> {
        Ok(EstimateRow {
            time_s: r.time_s,
            x_arcsec: group(
                [r.x1_arcsec, r.x2_arcsec, r.x3_arcsec, r.x4_arcsec],
                ["x1_arcsec", "x2_arcsec", "x3_arcsec", "x4_arcsec"],
            )?,
            sigma_arcsec: group(
                [
                    r.sigma1_arcsec,
                    r.sigma2_arcsec,
                    r.sigma3_arcsec,
                    r.sigma4_arcsec,
                ],
                [
                    "sigma1_arcsec",
                    "sigma2_arcsec",
                    "sigma3_arcsec",
                    "sigma4_arcsec",
                ],
            )?,
            status: r.status,
            corrected_deg: group(
                [
                    r.heading_corrected_deg,
                    r.roll_corrected_deg,
                    r.pitch_corrected_deg,
                ],
                [
                    "heading_corrected_deg",
                    "roll_corrected_deg",
                    "pitch_corrected_deg",
                ],
            )?,
        })
    }
}

/// What the `csv` crate's error says, as one line (the line number is given separately).
fn describe(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => {
            let kind = if len < expected_len { "short" } else { "long" };
            format!("{kind} row: {len} fields, expected {expected_len}")
        }
        csv::ErrorKind::Deserialize { err, .. } => match err.field() {
            Some(i) => format!(
                "{}: {}",
                HEADER.split(',').nth(i as usize).unwrap_or("?"),
                err.kind()
            ),
            None => err.kind().to_string(),
        },
        csv::ErrorKind::Io(io) => format!("cannot read: {io}"),
        csv::ErrorKind::Utf8 { .. } => "not UTF-8".to_string(),
        _ => e.to_string(),
    }
}

/// Reads an estimates CSV (the `csv` crate, rows deserialized by column name) from a buffered
/// reader; `path` names it in errors. Blank lines and `#` comment lines are skipped; whitespace
/// around fields, a `\r` and a UTF-8 byte-order mark are ignored; the header must be [`HEADER`].
pub fn read_estimates_from<R: BufRead>(
    path: &Path,
    reader: R,
) -> Result<Vec<EstimateRow>, LogError> {
    let mut csv = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(reader);
    let line_of = |e: &csv::Error| e.position().map_or(0, |p| p.line() as usize);
    let header = csv
        .byte_headers()
        .map_err(|e| LogError::new(path, line_of(&e), describe(&e)))?
        .clone();
    if header.is_empty() {
        return Err(LogError::new(
            path,
            1,
            format!("no header, expected {HEADER:?}"),
        ));
    }
    let got = header
        .iter()
        .map(String::from_utf8_lossy)
        .collect::<Vec<_>>()
        .join(",");
    if got != HEADER {
        let line = header.position().map_or(1, |p| p.line() as usize);
        return Err(LogError::new(
            path,
            line,
            format!("bad header {got:?}, expected {HEADER:?}"),
        ));
    }
    let names = csv::StringRecord::from_byte_record_lossy(header);
    let mut rows = Vec::new();
    let mut record = csv::StringRecord::new();
    loop {
        match csv.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {
                let line = record.position().map_or(0, |p| p.line() as usize);
                let raw: RawRow = record
                    .deserialize(Some(&names))
                    .map_err(|e| LogError::new(path, line, describe(&e)))?;
                rows.push(EstimateRow::try_from(raw).map_err(|m| LogError::new(path, line, m))?);
            }
            Err(e) => return Err(LogError::new(path, line_of(&e), describe(&e))),
        }
    }
    Ok(rows)
}

/// Reads an estimates CSV file.
pub fn read_estimates(path: &Path) -> Result<Vec<EstimateRow>, LogError> {
    let file = File::open(path).map_err(|e| LogError::new(path, 0, format!("cannot open: {e}")))?;
    read_estimates_from(path, BufReader::new(file))
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::units::arcsec_to_rad;
    use estimator_core::{Attitude, Field, Real, Status};

    fn output(time_s: f64, estimate: Option<Estimate>) -> Output {
        Output {
            time_s,
            status: if estimate.is_some() {
                Status::Estimating
            } else {
                Status::WarmingUp
            },
            estimate,
            corrected: Attitude {
                heading_rad: 0.5,
                roll_rad: -0.01,
                pitch_rad: 0.02,
            },
            health: estimator_core::Health::NONE,
        }
    }

    #[test]
    fn writes_and_reads_back() {
        let e = Estimate {
            x_rad: [200.0, -150.0, 300.0, -250.0].map(|a| arcsec_to_rad(a) as Real),
            sigma_rad: [1.0, 2.0, 3.0, 4.0].map(|a| arcsec_to_rad(a) as Real),
        };
        let mut w = EstimatesWriter::new(Vec::new()).unwrap();
        w.write_step(0.0, &Ok(output(0.0, None))).unwrap();
        w.write_step(1.0, &Ok(output(1.0, Some(e)))).unwrap();
        w.write_step(2.0, &Err(SampleError::NonFinite(Field::Roll)))
            .unwrap();
        let bytes = w.finish().unwrap();
        let text = String::from_utf8(bytes.clone()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], HEADER);
        assert_eq!(
            lines[1],
            "0.000000,,,,,,,,,warming_up,28.647889757,-0.572957782,1.145915565,0,,0,0,0.000,,,,"
        );
        assert!(lines[2].starts_with("1.000000,200.0000,-150.0000,300.0000,-250.0000,1.0000,2.0000,3.0000,4.0000,estimating,"), "{}", lines[2]);
        assert!(
            lines[3].starts_with("2.000000,200.0000,")
                && lines[3].ends_with(",rejected_non_finite,,,,,,,,,,,,"),
            "{}",
            lines[3]
        );
        let rows = read_estimates_from(Path::new("e.csv"), bytes.as_slice()).unwrap();
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[0].x_arcsec, None);
        assert_eq!(rows[1].x_arcsec, Some([200.0, -150.0, 300.0, -250.0]));
        assert_eq!(rows[1].sigma_arcsec, Some([1.0, 2.0, 3.0, 4.0]));
        assert!(rows[2].is_rejected());
        assert_eq!(rows[2].corrected_deg, None);
        assert_eq!(rows[2].x_arcsec, rows[1].x_arcsec);
    }

    #[test]
    fn reader_errors_name_the_line() {
        let text = format!("{HEADER}\n0.0,,,,,,,,,warming_up,1,2\n");
        let err = read_estimates_from(Path::new("e.csv"), text.as_bytes()).unwrap_err();
        assert!(err.to_string().starts_with("e.csv:2: short row"), "{err}");
        let text = format!("{HEADER}\n0.0,1,2,3,,,,,,estimating,1,2,3,0,,0,0,0.000,,,,\n");
        let err = read_estimates_from(Path::new("e.csv"), text.as_bytes()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "e.csv:2: x4_arcsec: empty while the rest of its group is not"
        );
        let text = format!("{HEADER}\n0.0,1,2,3,x,,,,,estimating,1,2,3,0,,0,0,0.000,,,,\n");
        let err = read_estimates_from(Path::new("e.csv"), text.as_bytes()).unwrap_err();
        assert!(err.to_string().starts_with("e.csv:2: x4_arcsec: "), "{err}");
        let err = read_estimates_from(Path::new("e.csv"), "time_s,x1\n".as_bytes()).unwrap_err();
        assert!(err.to_string().starts_with("e.csv:1: bad header"), "{err}");
        let err = read_estimates_from(Path::new("e.csv"), "".as_bytes()).unwrap_err();
        assert!(err.to_string().starts_with("e.csv:1: no header"), "{err}");
    }

    #[test]
    fn comments_blank_lines_byte_order_mark_and_carriage_returns_are_read_past() {
        let text = format!("\u{feff}# written by a test\n\n{HEADER}\r\n# a comment\n0.000000,,,,,,,,,warming_up,28.6,-0.5,1.1,0,,0,0,0.000,,,,\r\n\n");
        let rows = read_estimates_from(Path::new("e.csv"), text.as_bytes()).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].status, "warming_up");
        assert_eq!(rows[0].corrected_deg, Some([28.6, -0.5, 1.1]));
    }
}
