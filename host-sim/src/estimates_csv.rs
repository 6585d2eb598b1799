//! The estimates CSV (output), one row per input row; format in `docs/log-format.md`.
//!
//! The rows are formatted by [`estimator_core::estimates_csv`], the same code the C library's
//! `rins_format_row` runs, so that the replay path, the firmware stream path and a C program
//! write byte-identical files from the same [`Output`]s. A rejected row carries the estimate held
//! on board at that moment: a rejected sample leaves the estimator untouched, so that is the
//! estimate of the last [`Output`], which the writer remembers.

use crate::log_csv::LogError;
use estimator_core::estimates_csv::{write_output, write_rejected};
use estimator_core::{Estimate, Output, SampleError};
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

pub use estimator_core::estimates_csv::{HEADER, REJECTED_PREFIX};
const COLUMNS: usize = 13;

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
        Ok(EstimatesWriter { out, held: None, line: String::with_capacity(256) })
    }

    /// Writes the row of one step: pass `step`'s result as it is, with the input row's time.
    pub fn write_step(&mut self, time_s: f64, result: &Result<Output, SampleError>) -> std::io::Result<()> {
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
    pub time_s: f64,
    pub x_arcsec: Option<[f64; 4]>,
    pub sigma_arcsec: Option<[f64; 4]>,
    pub status: String,
    /// Heading, roll, pitch corrected, deg; `None` on a rejected row.
    pub corrected_deg: Option<[f64; 3]>,
}

impl EstimateRow {
    pub fn is_rejected(&self) -> bool {
        self.status.starts_with(REJECTED_PREFIX)
    }
}

fn parse_group<const N: usize>(fields: &[&str], names: &[&str]) -> Result<Option<[f64; N]>, String> {
    if fields.iter().all(|f| f.trim().is_empty()) {
        return Ok(None);
    }
    let mut out = [0.0; N];
    for i in 0..N {
        let f = fields[i].trim();
        out[i] = f.parse().map_err(|_| format!("{}: not a number: {f:?}", names[i]))?;
    }
    Ok(Some(out))
}

fn parse_row(line: &str) -> Result<EstimateRow, String> {
    let fields: Vec<&str> = line.split(',').collect();
    if fields.len() != COLUMNS {
        let kind = if fields.len() < COLUMNS { "short" } else { "long" };
        return Err(format!("{kind} row: {} fields, expected {COLUMNS}", fields.len()));
    }
    let names: Vec<&str> = HEADER.split(',').collect();
    let time_s = fields[0].trim().parse().map_err(|_| format!("time_s: not a number: {:?}", fields[0]))?;
    Ok(EstimateRow {
        time_s,
        x_arcsec: parse_group(&fields[1..5], &names[1..5])?,
        sigma_arcsec: parse_group(&fields[5..9], &names[5..9])?,
        status: fields[9].trim().to_string(),
        corrected_deg: parse_group(&fields[10..13], &names[10..13])?,
    })
}

/// Whether a line carries no data: blank or a `#` comment.
fn is_comment(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

/// Checks a header line (whitespace, a `\r` and a UTF-8 BOM around it ignored).
fn check_header(path: &Path, line_no: usize, line: &str) -> Result<(), LogError> {
    let got = line.trim_start_matches('\u{feff}').trim();
    if got != HEADER {
        return Err(LogError::new(path, line_no, format!("bad header {got:?}, expected {HEADER:?}")));
    }
    Ok(())
}

/// Reads an estimates CSV from a buffered reader; `path` names it in errors.
pub fn read_estimates_from<R: BufRead>(path: &Path, reader: R) -> Result<Vec<EstimateRow>, LogError> {
    let mut rows = Vec::new();
    let mut header_seen = false;
    let mut line_no = 0;
    for line in reader.lines() {
        line_no += 1;
        let line = line.map_err(|e| LogError::new(path, line_no, format!("cannot read: {e}")))?;
        if is_comment(&line) {
            continue;
        }
        if !header_seen {
            check_header(path, line_no, &line)?;
            header_seen = true;
            continue;
        }
        rows.push(parse_row(line.trim_end()).map_err(|m| LogError::new(path, line_no, m))?);
    }
    if !header_seen {
        return Err(LogError::new(path, line_no + 1, format!("no header, expected {HEADER:?}")));
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
            status: if estimate.is_some() { Status::Estimating } else { Status::WarmingUp },
            estimate,
            corrected: Attitude { heading_rad: 0.5, roll_rad: -0.01, pitch_rad: 0.02 },
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
        w.write_step(2.0, &Err(SampleError::NonFinite(Field::Roll))).unwrap();
        let bytes = w.finish().unwrap();
        let text = String::from_utf8(bytes.clone()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], HEADER);
        assert_eq!(lines[1], "0.000000,,,,,,,,,warming_up,28.647889757,-0.572957782,1.145915565");
        assert!(lines[2].starts_with("1.000000,200.0000,-150.0000,300.0000,-250.0000,1.0000,2.0000,3.0000,4.0000,estimating,"), "{}", lines[2]);
        assert!(lines[3].starts_with("2.000000,200.0000,") && lines[3].ends_with(",rejected_non_finite,,,"), "{}", lines[3]);
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
    }
}
