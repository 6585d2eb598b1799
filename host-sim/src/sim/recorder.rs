//! The data recorder between the RINS and the log: lost rows, outages and loose time stamps.
//!
//! The generator ([`crate::sim::scenario`]) produces one row per sample instant `t_k = k *
//! sample_interval_s`; the recorder decides which of them reach the log and with what time stamp:
//!
//! - each row is dropped independently with probability `drop_fraction`;
//! - rows whose instant falls inside an outage `[start, start + outage_duration_s)` are missing;
//! - with `gap_every_s > 0`, `gap_rows` rows in a row are missing every `gap_every_s` seconds: the
//!   rows of instants `t` with `t mod gap_every_s` (measured from the log's start) below
//!   `gap_rows` sample intervals, the first gap starting one `gap_every_s` into the log (a
//!   recorder that loses a block of rows at a fixed cadence, e.g. while it writes a file);
//! - the stamp is `t_k + time_offset_s + j_k`, `j_k` uniform in `[-time_jitter_s,
//!   time_jitter_s]`: the data are those of the true instant `t_k`, only the stamp is loose. The
//!   stamp is rounded to the microsecond (a recorder's resolution), so it is written as a short
//!   decimal (`1700000123.02`, not `1700000123.0200002`; `0.3`, not `0.30000000000000004`; whole
//!   seconds, as at the default 1 s interval, are left exactly as they were); the jitter is kept
//!   below half an interval, so the stamps stay in order and each names its instant unambiguously
//!   ([`Recording::sample_time_s`]).
//!
//! The recorder draws from its own random stream (from the scenario's seed), two numbers per
//! instant whether or not the row is kept: switching loss or jitter on changes neither the sway
//! and noise of a seed nor which rows another setting keeps. Outage start times are drawn once,
//! from a third stream ([`draw_outage_starts_s`]), and recorded in the truth file with the rest.

use crate::sim::scenario::Row;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Length of one outage, s.
pub const OUTAGE_S: f64 = 60.0;
/// Largest |time offset| accepted, s: stamps must keep a microsecond resolution in an `f64`.
pub const MAX_TIME_OFFSET_S: f64 = 4.0e9;

/// What the recorder did to a generated log. All zero (the default): every row, stamped with its
/// instant.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Recording {
    /// Probability that a row is dropped, independently of the others.
    pub drop_fraction: f64,
    /// Start times of the outages (rows missing), s from the log's start (before the offset).
    pub outage_starts_s: Vec<f64>,
    /// Length of each outage, s.
    pub outage_duration_s: f64,
    /// Added to every time stamp, s (e.g. 1.7e9 for Unix time).
    pub time_offset_s: f64,
    /// Half-width of the uniform time-stamp jitter, s.
    pub time_jitter_s: f64,
    /// Period of the regular gaps, s (0: none).
    pub gap_every_s: f64,
    /// Rows lost in a row at each regular gap.
    pub gap_rows: u32,
}

impl Recording {
    /// Checks the settings for rows every `interval_s`.
    pub fn check(&self, interval_s: f64) -> Result<(), RecorderError> {
        if !(self.drop_fraction.is_finite() && (0.0..1.0).contains(&self.drop_fraction)) {
            return Err(RecorderError::DropFraction(self.drop_fraction));
        }
        if !(self.time_offset_s.is_finite() && self.time_offset_s.abs() <= MAX_TIME_OFFSET_S) {
            return Err(RecorderError::TimeOffset {
                value_s: self.time_offset_s,
            });
        }
        if !(self.time_jitter_s.is_finite()
            && self.time_jitter_s >= 0.0
            && self.time_jitter_s < interval_s / 2.0)
        {
            return Err(RecorderError::TimeJitter {
                value_s: self.time_jitter_s,
                limit_s: interval_s / 2.0,
            });
        }
        let gap_s = f64::from(self.gap_rows) * interval_s;
        if !(self.gap_every_s.is_finite() && self.gap_every_s >= 0.0)
            || (self.gap_every_s > 0.0 && gap_s >= self.gap_every_s)
        {
            return Err(RecorderError::RegularGaps {
                every_s: self.gap_every_s,
                rows: self.gap_rows,
                interval_s,
            });
        }
        Ok(())
    }

    /// Whether a sample instant falls inside an outage.
    pub fn in_outage(&self, t_s: f64) -> bool {
        self.outage_starts_s
            .iter()
            .any(|&s| t_s >= s && t_s < s + self.outage_duration_s)
    }

    /// Whether the row of sample `k` (instant `k * interval_s`) falls in a regular gap.
    pub fn in_regular_gap(&self, k: u64, interval_s: f64) -> bool {
        if self.gap_every_s.is_nan() || self.gap_every_s <= 0.0 || self.gap_rows == 0 {
            return false;
        }
        // Whole rows from the start of the gap period the instant is in (no drift from summing).
        let t_s = k as f64 * interval_s;
        let periods = (t_s / self.gap_every_s).floor();
        let row_in_period = ((t_s - periods * self.gap_every_s) / interval_s + 1e-6).floor();
        periods >= 1.0 && row_in_period < f64::from(self.gap_rows)
    }

    /// The sample instant a recorded stamp belongs to, s from the log's start (exactly the
    /// generator's `k * interval_s`); `None` when the stamp is not within the jitter of an instant.
    pub fn sample_time_s(&self, stamp_s: f64, interval_s: f64) -> Option<f64> {
        let rel = stamp_s - self.time_offset_s;
        let k = (rel / interval_s).round();
        // Stamps are rounded to 1 us, and an offset of up to 4e9 s costs up to 0.5 us more.
        let tolerance_s = self.time_jitter_s + 2e-6;
        (k >= 0.0 && (rel - k * interval_s).abs() <= tolerance_s).then_some(k * interval_s)
    }
}

/// Why recorder settings cannot make a log; each names the command-line option to change.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum RecorderError {
    /// The fraction of rows dropped is not in `[0, 1)`.
    #[error("--drop-fraction must be in [0, 1), got {0}")]
    DropFraction(f64),
    /// The time offset is beyond [`MAX_TIME_OFFSET_S`].
    #[error("--time-offset must be within +-{MAX_TIME_OFFSET_S} s, got {value_s}")]
    TimeOffset {
        /// The time offset, s.
        value_s: f64,
    },
    /// The jitter is negative, or not below half the sample interval (`limit_s`), so that stamps
    /// could leave their order.
    #[error("--time-jitter must be >= 0 and below half the sample interval ({limit_s} s) so stamps stay in order, got {value_s}")]
    TimeJitter {
        /// The jitter's half-width, s.
        value_s: f64,
        /// Half the sample interval, s: the jitter must stay below it.
        limit_s: f64,
    },
    /// The outages (each [`OUTAGE_S`], `gap_s` apart) do not fit in the log.
    #[error("--outages: {count} outages of {OUTAGE_S} s (and {gap_s} s between them) do not fit in {duration_s} s")]
    OutagesDoNotFit {
        /// Outages asked for.
        count: usize,
        /// Shortest time between two outages, s: two sample intervals.
        gap_s: f64,
        /// Length of the log, s.
        duration_s: f64,
    },
    /// The regular gaps' period is negative or not finite, or their rows do not leave a row
    /// between two gaps.
    #[error("--gap-every must be >= 0 s and longer than --gap-rows rows ({rows} x {interval_s} s), got {every_s}")]
    RegularGaps {
        /// Period of the regular gaps, s.
        every_s: f64,
        /// Rows lost in a row at each gap.
        rows: u32,
        /// Sample interval, s.
        interval_s: f64,
    },
}

/// What the recorder is asked to do, before the outages are placed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RecorderSettings {
    /// Probability that a row is dropped, independently of the others.
    pub drop_fraction: f64,
    /// Number of outages of [`OUTAGE_S`].
    pub outages: usize,
    /// Added to every time stamp, s.
    pub time_offset_s: f64,
    /// Half-width of the uniform time-stamp jitter, s.
    pub time_jitter_s: f64,
    /// Period of the regular gaps, s (0: none).
    pub gap_every_s: f64,
    /// Rows lost in a row at each regular gap.
    pub gap_rows: u32,
}

impl RecorderSettings {
    /// The recording of a log of `duration_s` with rows every `interval_s`, outage start times
    /// drawn from `seed`; checked.
    pub fn recording(
        &self,
        seed: u64,
        duration_s: f64,
        interval_s: f64,
    ) -> Result<Recording, RecorderError> {
        let r = Recording {
            drop_fraction: self.drop_fraction,
            outage_starts_s: draw_outage_starts_s(seed, self.outages, duration_s, interval_s)?,
            outage_duration_s: if self.outages > 0 { OUTAGE_S } else { 0.0 },
            time_offset_s: self.time_offset_s,
            time_jitter_s: self.time_jitter_s,
            gap_every_s: self.gap_every_s,
            gap_rows: self.gap_rows,
        };
        r.check(interval_s)?;
        Ok(r)
    }
}

/// Rounds a time to the microsecond.
fn round_to_us(t_s: f64) -> f64 {
    (t_s * 1e6).round() / 1e6
}

/// Applies a [`Recording`] to generated rows, one at a time, in order.
pub struct Recorder<'a> {
    recording: &'a Recording,
    rng: ChaCha8Rng,
    /// The sample interval of the rows, s.
    interval_s: f64,
    /// The number of the next row (rows come one per sample instant, in order).
    row: u64,
}

impl<'a> Recorder<'a> {
    /// The recorder of a scenario with `seed` and rows every `interval_s`.
    pub fn new(recording: &'a Recording, seed: u64, interval_s: f64) -> Recorder<'a> {
        Recorder {
            recording,
            rng: ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0xD6E8_FEB8_6659_FD93) ^ 0x2EC0_2DE2),
            interval_s,
            row: 0,
        }
    }

    /// The row as logged (`row.time_s` is its sample instant; rows come one per instant, in
    /// order, from the first), or `None` when it is lost.
    pub fn record(&mut self, row: &Row) -> Option<Row> {
        let r = self.recording;
        let drop_draw: f64 = self.rng.gen();
        let jitter_draw: f64 = self.rng.gen();
        let k = self.row;
        self.row += 1;
        if drop_draw < r.drop_fraction
            || r.in_outage(row.time_s)
            || r.in_regular_gap(k, self.interval_s)
        {
            return None;
        }
        let jitter_s = r.time_jitter_s * (2.0 * jitter_draw - 1.0);
        Some(Row {
            time_s: round_to_us(row.time_s + r.time_offset_s + jitter_s),
            ..*row
        })
    }
}

/// The rows of a generated log (one every `interval_s`, from the first) as the recorder logs them.
pub fn recorded_rows(recording: &Recording, seed: u64, interval_s: f64, rows: &[Row]) -> Vec<Row> {
    let mut rec = Recorder::new(recording, seed, interval_s);
    rows.iter().filter_map(|r| rec.record(r)).collect()
}

/// Start times of `count` outages of [`OUTAGE_S`] in a log of `duration_s`, s, rounded to the
/// millisecond, ascending: uniformly placed, not overlapping, at least two sample intervals apart
/// (at least one row between two outages). Deterministic for a seed.
pub fn draw_outage_starts_s(
    seed: u64,
    count: usize,
    duration_s: f64,
    interval_s: f64,
) -> Result<Vec<f64>, RecorderError> {
    if count == 0 {
        return Ok(Vec::new());
    }
    let gap_s = 2.0 * interval_s;
    let free_s = duration_s - count as f64 * OUTAGE_S - (count - 1) as f64 * gap_s;
    if free_s.is_nan() || free_s < 0.0 {
        return Err(RecorderError::OutagesDoNotFit {
            count,
            gap_s,
            duration_s,
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0xA24B_AED4_963E_E407) ^ 0x0007_A6E5);
    // Uniform non-overlapping placement: sorted uniform points in the free time, each then
    // pushed right by the outages (and gaps) before it.
    let mut points: Vec<f64> = (0..count).map(|_| rng.gen::<f64>() * free_s).collect();
    points.sort_by(f64::total_cmp);
    Ok(points
        .iter()
        .enumerate()
        .map(|(i, p)| ((p + i as f64 * (OUTAGE_S + gap_s)) * 1e3).floor() / 1e3)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(t: f64) -> Row {
        Row {
            time_s: t,
            rotation_deg: 1.0,
            platform_deg: 2.0,
            latitude_deg: 3.0,
            heading_deg: 4.0,
            roll_deg: 5.0,
            pitch_deg: 6.0,
        }
    }

    #[test]
    fn default_recording_keeps_every_row_at_its_instant() {
        let rec = Recording::default();
        let rows: Vec<Row> = (0..100).map(|k| row(k as f64)).collect();
        assert_eq!(recorded_rows(&rec, 5, 1.0, &rows), rows);
        // At 0.1 s, stamps are short decimals that name their instant exactly.
        let rows: Vec<Row> = (0..100).map(|k| row(k as f64 * 0.1)).collect();
        let out = recorded_rows(&rec, 5, 0.1, &rows);
        assert_eq!(out[3].time_s.to_string(), "0.3");
        for (a, b) in out.iter().zip(&rows) {
            assert!((a.time_s - b.time_s).abs() < 1e-12);
            assert_eq!(rec.sample_time_s(a.time_s, 0.1), Some(b.time_s));
            assert_eq!(
                Row {
                    time_s: b.time_s,
                    ..*a
                },
                *b
            );
        }
    }

    #[test]
    fn stamps_are_offset_jittered_within_bounds_and_map_back() {
        let rec = Recording {
            time_offset_s: 1.7e9,
            time_jitter_s: 0.02,
            ..Recording::default()
        };
        let rows: Vec<Row> = (0..2000).map(|k| row(k as f64 * 0.1)).collect();
        let out = recorded_rows(&rec, 1, 0.1, &rows);
        assert_eq!(out.len(), rows.len());
        let mut largest = 0.0f64;
        for (a, b) in out.iter().zip(&rows) {
            let d = a.time_s - 1.7e9 - b.time_s;
            assert!(d.abs() <= 0.02 + 1e-6, "{} {}", a.time_s, b.time_s);
            largest = largest.max(d.abs());
            assert_eq!(rec.sample_time_s(a.time_s, 0.1), Some(b.time_s));
            assert_eq!(a.roll_deg, b.roll_deg);
            // A microsecond grid: at most 16 significant digits.
            assert!(a.time_s.to_string().len() <= 17, "{}", a.time_s);
        }
        assert!(largest > 0.015, "jitter spans its range: {largest}");
        assert!(out.windows(2).all(|w| w[1].time_s > w[0].time_s));
        assert_eq!(rec.sample_time_s(1.7e9 + 0.05, 0.1), None);
        assert_eq!(
            round_to_us(1_700_000_123.0 + 0.02).to_string(),
            "1700000123.02"
        );
    }

    #[test]
    fn regular_gaps_lose_their_rows_at_their_cadence_and_nothing_else() {
        // 4 rows every 60 s at 1 s, and 10 rows every 120 s at 0.5 s (5 s of rows).
        for (every_s, rows_lost, interval_s) in [(60.0, 4u32, 1.0), (120.0, 10, 0.5)] {
            let rec = Recording {
                gap_every_s: every_s,
                gap_rows: rows_lost,
                ..Recording::default()
            };
            assert_eq!(rec.check(interval_s), Ok(()));
            let n = (1000.0 / interval_s) as usize;
            let rows: Vec<Row> = (0..n).map(|k| row(k as f64 * interval_s)).collect();
            let kept: Vec<f64> = recorded_rows(&rec, 3, interval_s, &rows)
                .iter()
                .map(|r| r.time_s)
                .collect();
            let lost: Vec<f64> = rows
                .iter()
                .map(|r| r.time_s)
                .filter(|t| !kept.contains(t))
                .collect();
            let gaps = (1000.0 / every_s).ceil() as usize - 1;
            assert_eq!(lost.len(), gaps * rows_lost as usize, "{every_s} s");
            for (g, run) in lost.chunks(rows_lost as usize).enumerate() {
                let start = (g + 1) as f64 * every_s;
                let expected: Vec<f64> = (0..rows_lost)
                    .map(|j| start + f64::from(j) * interval_s)
                    .collect();
                assert_eq!(run, &expected[..], "gap {g} of every {every_s} s");
            }
        }
        let bad = Recording {
            gap_every_s: 10.0,
            gap_rows: 10,
            ..Recording::default()
        };
        assert_eq!(
            bad.check(1.0),
            Err(RecorderError::RegularGaps {
                every_s: 10.0,
                rows: 10,
                interval_s: 1.0
            })
        );
        assert!(Recording {
            gap_every_s: -1.0,
            gap_rows: 1,
            ..Recording::default()
        }
        .check(1.0)
        .is_err());
    }

    #[test]
    fn outages_do_not_overlap_and_fit() {
        for seed in 0..50 {
            let s = draw_outage_starts_s(seed, 5, 1000.0, 1.0).unwrap();
            assert_eq!(s.len(), 5);
            assert!(s[0] >= 0.0 && s[4] + OUTAGE_S <= 1000.0, "{s:?}");
            assert!(
                s.windows(2).all(|w| w[1] - w[0] >= OUTAGE_S + 2.0 - 1e-3),
                "{s:?}"
            );
        }
        assert_eq!(
            draw_outage_starts_s(3, 2, 500.0, 1.0),
            draw_outage_starts_s(3, 2, 500.0, 1.0)
        );
        assert_ne!(
            draw_outage_starts_s(3, 2, 500.0, 1.0),
            draw_outage_starts_s(4, 2, 500.0, 1.0)
        );
        assert_eq!(
            draw_outage_starts_s(1, 3, 180.0, 1.0),
            Err(RecorderError::OutagesDoNotFit {
                count: 3,
                gap_s: 2.0,
                duration_s: 180.0
            })
        );
        assert_eq!(draw_outage_starts_s(1, 0, 10.0, 1.0), Ok(vec![]));
    }

    #[test]
    fn check_rejects_bad_settings() {
        let ok = Recording {
            drop_fraction: 0.05,
            time_offset_s: -1.7e9,
            time_jitter_s: 0.4,
            ..Recording::default()
        };
        assert_eq!(ok.check(1.0), Ok(()));
        for bad in [
            Recording {
                drop_fraction: 1.0,
                ..ok.clone()
            },
            Recording {
                drop_fraction: f64::NAN,
                ..ok.clone()
            },
            Recording {
                time_offset_s: 5e9,
                ..ok.clone()
            },
            Recording {
                time_jitter_s: 0.5,
                ..ok.clone()
            },
            Recording {
                time_jitter_s: -0.1,
                ..ok.clone()
            },
        ] {
            assert!(bad.check(1.0).is_err(), "{bad:?}");
        }
        assert_eq!(
            Recording {
                drop_fraction: 1.0,
                ..ok.clone()
            }
            .check(1.0),
            Err(RecorderError::DropFraction(1.0))
        );
        assert_eq!(
            Recording {
                time_jitter_s: 0.5,
                ..ok.clone()
            }
            .check(1.0),
            Err(RecorderError::TimeJitter {
                value_s: 0.5,
                limit_s: 0.5
            })
        );
        {}
    }
}
