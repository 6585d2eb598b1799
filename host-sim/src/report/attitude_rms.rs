//! The attitude error of eq (2) before and after compensation: what is left of the oscillation
//! in one row ([`residual_arcsec`]) and its RMS over rows ([`AttitudeRms`]).

use crate::sim::scenario::{Row, RowTruth};

/// RMS of the attitude error of eq (2) before and after compensation, arcsec, per axis
/// (heading, roll, pitch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeRms {
    /// Start of the span, s: the rows from this time on are taken.
    pub from_s: f64,
    /// Time of the last row taken, s (`from_s` when none was).
    pub to_s: f64,
    /// Rows taken.
    pub rows: usize,
    /// RMS of the oscillation eq (2) put in, before compensation, arcsec.
    pub before_arcsec: [f64; 3],
    /// RMS of what is left of it after compensation, arcsec.
    pub after_arcsec: [f64; 3],
}

/// Attitude error left after compensation of one accepted row, arcsec (heading, roll, pitch):
/// oscillation put in minus oscillation removed.
pub fn residual_arcsec(
    row: &Row,
    corrected: &estimator_core::Attitude,
    truth: &RowTruth,
) -> [f64; 3] {
    let raw = [row.heading_deg, row.roll_deg, row.pitch_deg];
    let cor = [
        corrected.heading_rad as f64,
        corrected.roll_rad as f64,
        corrected.pitch_rad as f64,
    ]
    .map(|r| r.to_degrees());
    core::array::from_fn(|a| {
        let mut removed_deg = raw[a] - cor[a];
        if a == 0 {
            removed_deg = estimator_core::units::wrap_deg(removed_deg);
        }
        (truth.oscillation_deg[a] - removed_deg) * 3600.0
    })
}

/// Accumulates [`AttitudeRms`] over rows with `time_s >= from_s`.
#[derive(Clone, Debug)]
pub struct RmsAccumulator {
    from_s: f64,
    to_s: f64,
    rows: usize,
    before: [f64; 3],
    after: [f64; 3],
}

impl RmsAccumulator {
    /// An accumulator of the rows from `from_s` on, s.
    pub fn new(from_s: f64) -> Self {
        RmsAccumulator {
            from_s,
            to_s: from_s,
            rows: 0,
            before: [0.0; 3],
            after: [0.0; 3],
        }
    }

    /// Takes one accepted row: its time, s, the attitude error left after compensation
    /// ([`residual_arcsec`]) and its truth. A row before `from_s` is left out.
    pub fn add(&mut self, time_s: f64, residual_arcsec: &[f64; 3], truth: &RowTruth) {
        if time_s.is_nan() || time_s < self.from_s {
            return;
        }
        self.rows += 1;
        self.to_s = time_s;
        #[allow(clippy::needless_range_loop)]
        for a in 0..3 {
            let b = truth.oscillation_deg[a] * 3600.0;
            self.before[a] += b * b;
            self.after[a] += residual_arcsec[a] * residual_arcsec[a];
        }
    }

    /// The RMS over the rows taken.
    pub fn finish(&self) -> AttitudeRms {
        let n = self.rows.max(1) as f64;
        AttitudeRms {
            from_s: self.from_s,
            to_s: self.to_s,
            rows: self.rows,
            before_arcsec: self.before.map(|s| (s / n).sqrt()),
            after_arcsec: self.after.map(|s| (s / n).sqrt()),
        }
    }
}

/// The oscillation eq (2) puts into the attitude of `row` for installation errors `x_arcsec`,
/// deg (heading, roll, pitch), from the core's rows ([`estimator_core::installation::Angles`]).
pub fn oscillation_deg(row: &Row, x_arcsec: &[f64; 4]) -> [f64; 3] {
    use estimator_core::installation::Angles;
    use estimator_core::units::{arcsec_to_rad, wrap_deg, RAD_PER_DEG};
    use estimator_core::Real;
    let rad = |deg: f64| (wrap_deg(deg) * RAD_PER_DEG) as Real;
    let lat = row.latitude_deg * RAD_PER_DEG;
    let angles = Angles::new(
        rad(row.rotation_deg),
        rad(row.platform_deg),
        (lat.sin() as Real, lat.cos() as Real),
    );
    let d = angles.oscillation(&x_arcsec.map(|x| arcsec_to_rad(x) as Real));
    [d.heading_rad, d.roll_rad, d.pitch_rad].map(|r| r as f64 / RAD_PER_DEG)
}
