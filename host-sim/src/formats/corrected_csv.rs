//! The corrected-attitude CSV (output of `stream --nav-rate --corrected-out FILE`): one row per
//! navigation-rate sample, the sample's heading, roll and pitch as the firmware compensated them;
//! format in `docs/log-format.md`.
//!
//! The angles are written as the estimates CSV writes its corrected angles (degrees, 9 decimals:
//! `format!("{:.9}")` of the radians over [`RAD_PER_DEG`], which is what
//! [`estimator_core::estimates_csv`] writes byte for byte), the time with 6 decimals, so that a
//! file written from the host core's [`estimator_core::Estimator::compensate`] of the same samples
//! is the same byte for byte.

use estimator_core::units::RAD_PER_DEG;
use estimator_core::{Real, RejectReason};
use std::io::Write;

pub use estimator_core::estimates_csv::REJECTED_PREFIX;

/// The corrected-attitude CSV header (no line end).
pub const HEADER: &str =
    "time_s,heading_corrected_deg,roll_corrected_deg,pitch_corrected_deg,status";
/// The status of a sample compensated with an estimate.
pub const COMPENSATED: &str = "compensated";
/// The status of a sample answered before the firmware had an estimate: no corrected angles.
pub const NO_ESTIMATE: &str = "no_estimate";

/// One row (no line end): the sample's time and its corrected heading, roll and pitch, rad
/// (`None` while there is no estimate: empty cells).
pub fn format_corrected(time_s: f64, corrected_rad: Option<[Real; 3]>) -> String {
    match corrected_rad {
        Some(angles) => {
            let [h, r, p] = angles.map(|v| f64::from(v) / RAD_PER_DEG);
            format!("{time_s:.6},{h:.9},{r:.9},{p:.9},{COMPENSATED}")
        }
        None => format!("{time_s:.6},,,,{NO_ESTIMATE}"),
    }
}

/// One row (no line end) for a sample the firmware refused: its time and the reason.
pub fn format_refused(time_s: f64, reason: RejectReason) -> String {
    format!("{time_s:.6},,,,{REJECTED_PREFIX}{}", reason.name())
}

/// Writes the corrected-attitude CSV, a row at a time.
pub struct CorrectedWriter<W: Write> {
    out: W,
}

impl<W: Write> CorrectedWriter<W> {
    /// Writes the header.
    pub fn new(mut out: W) -> std::io::Result<Self> {
        writeln!(out, "{HEADER}")?;
        Ok(CorrectedWriter { out })
    }

    /// The row of a sample the firmware answered ([`format_corrected`]).
    pub fn write_corrected(
        &mut self,
        time_s: f64,
        corrected_rad: Option<[Real; 3]>,
    ) -> std::io::Result<()> {
        writeln!(self.out, "{}", format_corrected(time_s, corrected_rad))
    }

    /// The row of a sample the firmware refused ([`format_refused`]).
    pub fn write_refused(&mut self, time_s: f64, reason: RejectReason) -> std::io::Result<()> {
        writeln!(self.out, "{}", format_refused(time_s, reason))
    }

    /// Flushes and returns the inner writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::estimates_csv::write_output;
    use estimator_core::{Attitude, Health, Output, Status};

    #[test]
    fn the_angles_are_written_as_the_estimates_csv_writes_them() {
        let corrected = [0.5 as Real, -0.01, 0.02];
        let out = Output {
            time_s: 12.34,
            estimate: None,
            status: Status::WarmingUp,
            corrected: Attitude {
                heading_rad: corrected[0],
                roll_rad: corrected[1],
                pitch_rad: corrected[2],
            },
            health: Health::NONE,
        };
        let mut estimates_row = String::new();
        write_output(&mut estimates_row, &out).unwrap();
        let cells: Vec<&str> = estimates_row.split(',').collect();
        let row = format_corrected(12.34, Some(corrected));
        let mine: Vec<&str> = row.split(',').collect();
        assert_eq!(mine[0], cells[0]);
        assert_eq!(mine[1..4], cells[10..13]);
        assert_eq!(mine[4], "compensated");
        assert_eq!(format_corrected(3.0, None), "3.000000,,,,no_estimate");
        assert_eq!(
            format_refused(3.0, RejectReason::TimeNotIncreasing),
            "3.000000,,,,rejected_time_not_increasing"
        );
    }

    #[test]
    fn the_writer_writes_the_header_and_a_row_a_sample() {
        let mut w = CorrectedWriter::new(Vec::new()).unwrap();
        w.write_corrected(0.01, None).unwrap();
        w.write_refused(0.01, RejectReason::TimeNotIncreasing)
            .unwrap();
        let text = String::from_utf8(w.finish().unwrap()).unwrap();
        assert_eq!(
            text,
            format!(
                "{HEADER}\n0.010000,,,,no_estimate\n0.010000,,,,rejected_time_not_increasing\n"
            )
        );
    }
}
