//! The estimates CSV (output), one row per input row; format in `docs/log-format.md`.
//!
//! Header [`HEADER`]. Fixed, deterministic formatting so that the replay path and the firmware
//! stream path write byte-identical files from the same [`Output`]s:
//! - `time_s`: 6 decimals;
//! - `x*_arcsec`, `sigma*_arcsec`: 4 decimals, empty while there is no estimate;
//! - `status`: [`estimator_core::Status::name`], or `rejected_<reason>` with
//!   [`RejectReason::name`](estimator_core::RejectReason::name) for an input row the core rejected;
//! - `*_corrected_deg`: 9 decimals (heading in [-180, 180]); empty on a rejected row.
//!
//! A rejected row carries the estimate held on board at that moment: a rejected sample leaves the
//! estimator untouched, so that is the estimate of the last [`Output`], which the writer remembers.

use crate::log_csv::LogError;
use estimator_core::units::{rad_to_arcsec, RAD_PER_DEG};
use estimator_core::{Estimate, Output, SampleError};
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

/// The estimates CSV header.
pub const HEADER: &str = "time_s,x1_arcsec,x2_arcsec,x3_arcsec,x4_arcsec,sigma1_arcsec,sigma2_arcsec,sigma3_arcsec,sigma4_arcsec,status,heading_corrected_deg,roll_corrected_deg,pitch_corrected_deg";
const COLUMNS: usize = 13;
/// Prefix of the status of a rejected row.
pub const REJECTED_PREFIX: &str = "rejected_";

/// Writes the estimates CSV, one line per step, as the steps come (nothing is held but the last
/// estimate and one line's buffer).
pub struct EstimatesWriter<W: Write> {
    out: W,
    held: Option<Estimate>,
    line: String,
}

/// Appends `format!("{value:.decimals}")`, byte for byte, for `decimals <= 9`.
///
/// The standard formatter's exact mode falls back to big-number arithmetic for most of the values
/// this file holds, which made formatting most of the replay's time. Here: a finite `f64` is
/// exactly `m * 2^e`; for `e < 0` the scaled value `m * 10^decimals / 2^-e` is computed exactly in
/// `u128` (`m < 2^53`, `10^9 < 2^30`) and rounded half to even on the exact remainder, which is
/// what the standard formatter does (pinned by `fixed_formatting_equals_the_standard_formatter`).
/// Anything else (integers beyond 2^53, tiny, non-finite values) goes to the standard formatter.
fn push_fixed(line: &mut String, value: f64, decimals: usize) {
    use std::fmt::Write as _;
    const POW10: [u128; 10] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000, 100_000_000, 1_000_000_000];
    let bits = value.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    let (mantissa, shift) = if exponent == 0 { (fraction, 1074) } else { (fraction | (1u64 << 52), 1075 - exponent) };
    if decimals > 9 || exponent == 0x7ff || !(1..=110).contains(&shift) {
        let _ = write!(line, "{value:.decimals$}");
        return;
    }
    let scaled = mantissa as u128 * POW10[decimals];
    let mut q = scaled >> shift;
    let rem = scaled - (q << shift);
    let half = 1u128 << (shift - 1);
    if rem > half || (rem == half && q & 1 == 1) {
        q += 1;
    }
    let Ok(q) = u64::try_from(q) else {
        let _ = write!(line, "{value:.decimals$}");
        return;
    };
    if value.is_sign_negative() {
        line.push('-');
    }
    let unit = POW10[decimals] as u64;
    push_digits(line, q / unit, 1);
    if decimals > 0 {
        line.push('.');
        push_digits(line, q % unit, decimals);
    }
}

/// Appends `n` in decimal, zero-padded to at least `width` digits.
fn push_digits(line: &mut String, mut n: u64, width: usize) {
    let mut digits = [b'0'; 20];
    let mut start = digits.len();
    while n > 0 || digits.len() - start < width {
        start -= 1;
        digits[start] = b'0' + (n % 10) as u8;
        n /= 10;
    }
    line.extend(digits[start..].iter().map(|&d| d as char));
}

fn push_estimate(line: &mut String, estimate: Option<&Estimate>) {
    match estimate {
        Some(e) => {
            for v in e.x_rad.iter().chain(e.sigma_rad.iter()) {
                line.push(',');
                push_fixed(line, rad_to_arcsec(*v as f64), 4);
            }
        }
        None => line.push_str(",,,,,,,,"),
    }
}

/// `{:.6}` of a time, byte for byte. Whole seconds (nearly every log row) are written as an
/// integer and `.000000`.
fn push_time(line: &mut String, time_s: f64) {
    if time_s.fract() == 0.0 && time_s.abs() < 9.0e15 && !(time_s == 0.0 && time_s.is_sign_negative()) {
        if time_s < 0.0 {
            line.push('-');
        }
        push_digits(line, time_s.abs() as u64, 1);
        line.push_str(".000000");
    } else {
        push_fixed(line, time_s, 6);
    }
}

fn push_output(line: &mut String, out: &Output) {
    push_time(line, out.time_s);
    push_estimate(line, out.estimate.as_ref());
    let c = &out.corrected;
    let deg = |rad: estimator_core::Real| rad as f64 / RAD_PER_DEG;
    line.push(',');
    line.push_str(out.status.name());
    for v in [c.heading_rad, c.roll_rad, c.pitch_rad] {
        line.push(',');
        push_fixed(line, deg(v), 9);
    }
}

fn push_rejected(line: &mut String, time_s: f64, reason: &SampleError, held: Option<&Estimate>) {
    push_time(line, time_s);
    push_estimate(line, held);
    line.push(',');
    line.push_str(REJECTED_PREFIX);
    line.push_str(reason.reason().name());
    line.push_str(",,,");
}

/// One row for a step's output (no newline).
pub fn format_output(out: &Output) -> String {
    let mut line = String::new();
    push_output(&mut line, out);
    line
}

/// One row for a rejected input row (no newline): its time, the held estimate, the reason.
pub fn format_rejected(time_s: f64, reason: &SampleError, held: Option<&Estimate>) -> String {
    let mut line = String::new();
    push_rejected(&mut line, time_s, reason, held);
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
        push_output(&mut self.line, out);
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }

    /// Writes the row of a rejected sample.
    pub fn write_rejected(&mut self, time_s: f64, reason: &SampleError) -> std::io::Result<()> {
        self.line.clear();
        push_rejected(&mut self.line, time_s, reason, self.held.as_ref());
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
    fn times_are_written_as_the_float_formatter_writes_them() {
        for t in [0.0, -0.0, 1.0, 172_799.0, -3.0, 0.5, 1e-7, 123_456.000_000_4, 8.9e15, 9.1e15, 1e300, f64::NAN, f64::INFINITY] {
            let mut fast = String::new();
            push_time(&mut fast, t);
            assert_eq!(fast, format!("{t:.6}"), "{t}");
        }
    }

    #[test]
    fn fixed_formatting_equals_the_standard_formatter() {
        // xorshift64*: the same values on every run.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            state.wrapping_mul(0x2545_F491_4F6C_DD1D)
        };
        let mut values = vec![0.0, -0.0, 0.5, 1.5, 2.5, -2.5, 0.125, 0.375, 1e-5, -1e-5, 0.00005, 0.00015, 1e300, -1e-300, 5e-324, f64::NAN, f64::INFINITY, 9.007_199_254_740_993e15];
        for _ in 0..100_000 {
            let r = next();
            // Random bit patterns between 2^-64 and 2^64, arcsec-like and degree-like values.
            values.push(f64::from_bits((r & 0x800f_ffff_ffff_ffff) | ((1023 - 64 + (r >> 52) % 128) << 52)));
            values.push(((r >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2000.0);
            values.push(((r >> 40) as f32 / (1u32 << 24) as f32 - 0.5) as f64 * 57.295_779_513_082_32);
            // Exact ties at each number of decimals: k + 1/2 units of the last place.
            let k = (r >> 44) as f64;
            values.push((k + 0.5) / 16.0);
        }
        let mut fast = String::new();
        for v in values {
            for decimals in [0, 4, 6, 9] {
                fast.clear();
                push_fixed(&mut fast, v, decimals);
                assert_eq!(fast, format!("{v:.decimals$}"), "{v:e} to {decimals} decimals");
            }
        }
    }

    #[test]
    fn reader_errors_name_the_line() {
        let text = format!("{HEADER}\n0.0,,,,,,,,,warming_up,1,2\n");
        let err = read_estimates_from(Path::new("e.csv"), text.as_bytes()).unwrap_err();
        assert!(err.to_string().starts_with("e.csv:2: short row"), "{err}");
    }
}
