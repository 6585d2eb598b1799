//! Attitude at the navigation rate (100-200 Hz) averaged into bins of the estimator's grid.
//!
//! A navigation computer has its attitude and angles at 100 Hz or more; the estimator steps once
//! per grid interval (0.1 to 10 s, [`crate::config::SAMPLE_INTERVAL_RANGE_S`]). [`Binner`] takes
//! the samples as they come, at any rate, and hands back one averaged [`Sample`] per bin of
//! [`Binner::interval_s`] once the bin is complete, for [`crate::Estimator::step`]; every sample
//! can still be compensated on its own with [`crate::Estimator::compensate`].
//!
//! # Bins
//! Bin `k` holds the samples with `k T <= t < (k + 1) T`: aligned to multiples of `T` in the
//! stamps' own time, so the same log bins the same from any first row (a stamp within a millionth
//! of a bin below a boundary counts as on it, as a decimal stamp's writer meant). A bin is complete
//! when a sample of a later bin arrives ([`Binner::push`] returns it; [`Binner::finish`] the
//! last). An empty bin gives nothing: the estimator sees a lost sample. A sample that fails
//! [`Sample::check`], or is not later than the last accepted one, is refused with its
//! [`SampleError`] and changes nothing.
//!
//! # The average and its stamp
//! Each field is the mean of the bin's samples; rotation, platform and heading are unwrapped step
//! by step from the bin's first sample and the mean wrapped to [-pi, pi) again. The sums are `f64`
//! offsets from the bin's first sample (`f32` rounding would move a long bin's mean by arcsec).
//! Averaged over `T`, eq (2)'s oscillation of period `P` is the oscillation at the samples' mean
//! time scaled by `sinc(pi T / P)` (1 - 7e-6 at `T` = 1 s, `P` = 480 s), and the rotation angle is
//! averaged over the same samples, so the averaged sample obeys eq (2) whatever its stamp. It is
//! stamped at the bin's centre `(k + 1/2) T`: the centres lie exactly `T` apart whatever the
//! samples' rate, phase and losses, where a bin's mean time may lie up to half a bin off, beyond
//! the jitter the grid accepts ([`crate::time_grid`]).
//!
//! Fixed memory (a unit test bounds `size_of::<Binner>()`, no allocator); a push is a few
//! divisions, floors and additions in double precision. The derivations, and what the centre
//! costs: docs/interface.md, "Attitude at the navigation rate".

use crate::config::SAMPLE_INTERVAL_RANGE_S;
use crate::sample::{Attitude, Sample, SampleError};
use crate::Real;
use core::f64::consts::PI;

/// Bin intervals a [`Binner`] takes, s: the estimator's grid intervals.
pub const BIN_INTERVAL_RANGE_S: (f64, f64) = SAMPLE_INTERVAL_RANGE_S;

/// How far below a bin boundary, in bins, a stamp still counts as on it: a decimal stamp such as
/// `0.3` at a bin of `0.1` (`2.9999999999999996` bins in binary) opens bin 3, as its writer meant.
const BOUNDARY_SNAP_BINS: f64 = 1e-6;

/// A bin interval outside [`BIN_INTERVAL_RANGE_S`] (or not finite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinIntervalError {
    /// The interval given, s.
    pub value_s: f64,
}

impl core::fmt::Display for BinIntervalError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let (lo, hi) = BIN_INTERVAL_RANGE_S;
        write!(
            f,
            "bin_interval_s = {} must be from {lo} to {hi} s",
            self.value_s
        )
    }
}

impl core::error::Error for BinIntervalError {}

/// Wraps an angle to [-pi, pi) in `f64`.
fn wrap_pi_f64(angle_rad: f64) -> f64 {
    let two_pi = 2.0 * PI;
    let r = angle_rad - two_pi * libm::floor((angle_rad + PI) / two_pi);
    // `r` can round up to pi itself for inputs just below an odd multiple of pi.
    if r >= PI {
        r - two_pi
    } else {
        r
    }
}

/// The samples of the bin being filled: offsets from its first sample, summed in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bin {
    /// The bin's number `k` (an integer, held as `f64`: the stamps' range is the `f64`'s).
    index: f64,
    /// Samples in it.
    count: u32,
    /// The first sample's rotation, platform, heading, latitude, roll and pitch, rad.
    first_rad: [f64; 6],
    /// The last sample's wrapped angles (rotation, platform, heading), rad, as given.
    last_wrapped_rad: [f64; 3],
    /// The last sample's wrapped angles unwrapped, as offsets from the first sample's, rad.
    last_unwrapped_rad: [f64; 3],
    /// Sum of every sample's offset from the first sample (the three wrapped angles unwrapped,
    /// then latitude, roll and pitch), rad.
    sum_rad: [f64; 6],
}

/// The fields of a sample in the bin's order: rotation, platform, heading (they wrap), then
/// latitude, roll, pitch.
fn fields_rad(s: &Sample) -> [f64; 6] {
    [
        s.rotation_rad as f64,
        s.platform_rad as f64,
        s.attitude.heading_rad as f64,
        s.latitude_rad as f64,
        s.attitude.roll_rad as f64,
        s.attitude.pitch_rad as f64,
    ]
}

impl Bin {
    fn new(index: f64, s: &Sample) -> Bin {
        let first_rad = fields_rad(s);
        Bin {
            index,
            count: 1,
            first_rad,
            last_wrapped_rad: [first_rad[0], first_rad[1], first_rad[2]],
            last_unwrapped_rad: [0.0; 3],
            sum_rad: [0.0; 6],
        }
    }

    fn add(&mut self, s: &Sample) {
        let f = fields_rad(s);
        for (i, last) in self.last_wrapped_rad.iter_mut().enumerate() {
            let step = wrap_pi_f64(f[i] - *last);
            *last = f[i];
            self.last_unwrapped_rad[i] += step;
            self.sum_rad[i] += self.last_unwrapped_rad[i];
        }
        for i in 3..6 {
            self.sum_rad[i] += f[i] - self.first_rad[i];
        }
        self.count = self.count.saturating_add(1);
    }

    /// The bin's average, stamped at its centre.
    fn average(&self, interval_s: f64) -> Sample {
        let n = f64::from(self.count);
        let mean: [f64; 6] = core::array::from_fn(|i| self.first_rad[i] + self.sum_rad[i] / n);
        Sample {
            time_s: (self.index + 0.5) * interval_s,
            rotation_rad: wrap_pi_f64(mean[0]) as Real,
            platform_rad: wrap_pi_f64(mean[1]) as Real,
            latitude_rad: mean[3] as Real,
            attitude: Attitude {
                heading_rad: wrap_pi_f64(mean[2]) as Real,
                roll_rad: mean[4] as Real,
                pitch_rad: mean[5] as Real,
            },
        }
    }
}

/// Averages samples at any rate into bins of a fixed interval (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Binner {
    interval_s: f64,
    /// The last accepted sample's time, s.
    last_time_s: Option<f64>,
    /// The bin being filled.
    bin: Option<Bin>,
}

/// Bins of 1 s: the estimator's grid at its usual rate, one step a second.
pub const DEFAULT_BIN_INTERVAL_S: f64 = 1.0;

/// [`DEFAULT_BIN_INTERVAL_S`] lies within [`BIN_INTERVAL_RANGE_S`], which [`Binner::default`]
/// relies on.
const _: () = assert!(
    DEFAULT_BIN_INTERVAL_S >= BIN_INTERVAL_RANGE_S.0
        && DEFAULT_BIN_INTERVAL_S <= BIN_INTERVAL_RANGE_S.1
);

impl Default for Binner {
    /// An empty binner of [`DEFAULT_BIN_INTERVAL_S`] bins.
    fn default() -> Binner {
        Binner {
            interval_s: DEFAULT_BIN_INTERVAL_S,
            last_time_s: None,
            bin: None,
        }
    }
}

impl Binner {
    /// A binner of bins `bin_interval_s` long, within [`BIN_INTERVAL_RANGE_S`].
    pub fn new(bin_interval_s: f64) -> Result<Binner, BinIntervalError> {
        let (lo, hi) = BIN_INTERVAL_RANGE_S;
        if !(bin_interval_s >= lo && bin_interval_s <= hi) {
            return Err(BinIntervalError {
                value_s: bin_interval_s,
            });
        }
        Ok(Binner {
            interval_s: bin_interval_s,
            last_time_s: None,
            bin: None,
        })
    }

    /// The bin interval, s: the grid interval of the samples it hands back.
    pub fn interval_s(&self) -> f64 {
        self.interval_s
    }

    /// Samples in the bin being filled.
    pub fn pending(&self) -> u32 {
        self.bin.map_or(0, |b| b.count)
    }

    /// The number `k` of the bin a time falls in (an integer held as `f64`; see the module doc:
    /// `k T <= t < (k + 1) T`, a stamp within a millionth of a bin below a boundary counting as on
    /// it). A stream that resumes after a checkpoint taken at a bin's step sends the samples of
    /// later bins only: the bin of the checkpoint's stamp (the bin's centre) was stepped already.
    pub fn bin_of(&self, time_s: f64) -> f64 {
        libm::floor(time_s / self.interval_s + BOUNDARY_SNAP_BINS)
    }

    /// Takes one sample. Returns the average of the bin before it when the sample opens a later
    /// bin, `None` while the bin fills. A sample that fails [`Sample::check`] or whose time is not
    /// after the last accepted one is refused and changes nothing.
    pub fn push(&mut self, sample: &Sample) -> Result<Option<Sample>, SampleError> {
        sample.check()?;
        if self.last_time_s.is_some_and(|last| !(sample.time_s > last)) {
            return Err(SampleError::TimeNotIncreasing);
        }
        let index = self.bin_of(sample.time_s);
        self.last_time_s = Some(sample.time_s);
        match &mut self.bin {
            Some(bin) if bin.index == index => {
                bin.add(sample);
                Ok(None)
            }
            _ => {
                let done = self.bin.map(|b| b.average(self.interval_s));
                self.bin = Some(Bin::new(index, sample));
                Ok(done)
            }
        }
    }

    /// The average of the bin being filled, if it holds a sample (at the end of a log); the
    /// binner is then empty, and later samples must still come after the last one taken.
    pub fn finish(&mut self) -> Option<Sample> {
        self.bin.take().map(|b| b.average(self.interval_s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::rad_to_arcsec;

    fn sample(time_s: f64, rotation_rad: f64, roll_rad: f64) -> Sample {
        Sample {
            time_s,
            rotation_rad: rotation_rad as Real,
            platform_rad: 0.25,
            latitude_rad: 0.5,
            attitude: Attitude {
                heading_rad: -3.0,
                roll_rad: roll_rad as Real,
                pitch_rad: 0.01,
            },
        }
    }

    /// Pushes every sample, returning the bins completed.
    fn bins(
        binner: &mut Binner,
        samples: impl IntoIterator<Item = Sample>,
    ) -> std::vec::Vec<Sample> {
        samples
            .into_iter()
            .filter_map(|s| binner.push(&s).expect("a good sample"))
            .collect()
    }

    #[test]
    fn bin_of_is_the_bin_push_puts_a_sample_in() {
        let tenth = Binner::new(0.1).unwrap();
        assert_eq!(
            tenth.bin_of(0.3),
            3.0,
            "0.3 / 0.1 is just below 3 in binary"
        );
        let second = Binner::default();
        // A bin's centre (a checkpoint's stamp) lies in that bin; the next bin starts 0.5 s on.
        assert_eq!(second.bin_of(120.5), 120.0);
        assert_eq!(second.bin_of(120.999), 120.0);
        assert_eq!(second.bin_of(121.0), 121.0);
        assert_eq!(second.bin_of(-0.5), -1.0);
        let mut binner = Binner::default();
        let stepped = bins(
            &mut binner,
            [119.99, 120.5, 120.99, 121.0].map(|t| sample(t, 0.0, 0.0)),
        );
        assert_eq!(stepped.len(), 2);
        assert_eq!(second.bin_of(stepped[1].time_s), 120.0);
    }

    #[test]
    fn a_binner_is_small() {
        assert!(
            core::mem::size_of::<Binner>() < 200,
            "{}",
            core::mem::size_of::<Binner>()
        );
    }

    #[test]
    fn the_interval_must_be_a_grid_interval() {
        for bad in [0.0, 0.05, 10.5, f64::NAN, f64::INFINITY, -1.0] {
            let e = Binner::new(bad).unwrap_err();
            assert!(e.value_s.to_bits() == bad.to_bits());
        }
        assert_eq!(Binner::new(0.1).unwrap().interval_s(), 0.1);
        assert_eq!(Binner::new(10.0).unwrap().interval_s(), 10.0);
        assert_eq!(
            std::format!("{}", Binner::new(20.0).unwrap_err()),
            "bin_interval_s = 20 must be from 0.1 to 10 s"
        );
    }

    #[test]
    fn a_rotation_crossing_180_deg_averages_to_the_angle_in_the_middle() {
        // 0.75 deg/s (480 s a turn) at 200 Hz, through +180 deg = -180 deg in the bin [10, 11) s;
        // the heading turns the other way through -180 deg at 20 deg/s.
        let rate_rad_s = 0.75f64.to_radians();
        let heading_rate_rad_s = -20f64.to_radians();
        let at = |k: u32| {
            let t = 10.0 + f64::from(k) * 0.005;
            let rho = PI + rate_rad_s * (t - 10.5); // +180 deg at the bin's centre
            let mut s = sample(t, wrap_pi_f64(rho), 0.0);
            s.attitude.heading_rad = wrap_pi_f64(-PI + heading_rate_rad_s * (t - 10.5)) as Real;
            s.platform_rad = wrap_pi_f64(PI - 1e-4 + 2e-4 * (t - 10.0)) as Real;
            s
        };
        let mut binner = Binner::new(1.0).unwrap();
        let done = bins(&mut binner, (0..=200).map(at));
        assert_eq!(done.len(), 1, "the sample at 11 s completes bin 10");
        let b = done[0];
        assert_eq!(b.time_s, 10.5, "stamped at the bin's centre");
        // The samples' mean time is 10.4975 s: the mean angle is the angle then, 180 deg less
        // 0.0025 s at 0.75 deg/s, i.e. -180 deg + ...: near +-pi, not near 0.
        let expect_rho = wrap_pi_f64(PI + rate_rad_s * (10.4975 - 10.5));
        let off_arcsec = rad_to_arcsec(wrap_pi_f64(f64::from(b.rotation_rad) - expect_rho));
        assert!(
            off_arcsec.abs() < 0.1,
            "rotation off by {off_arcsec} arcsec"
        );
        let expect_heading = wrap_pi_f64(-PI + heading_rate_rad_s * (10.4975 - 10.5));
        let off_arcsec = rad_to_arcsec(wrap_pi_f64(
            f64::from(b.attitude.heading_rad) - expect_heading,
        ));
        assert!(off_arcsec.abs() < 0.1, "heading off by {off_arcsec} arcsec");
        let expect_platform = wrap_pi_f64(PI - 1e-4 + 2e-4 * 0.4975);
        let off_arcsec = rad_to_arcsec(wrap_pi_f64(f64::from(b.platform_rad) - expect_platform));
        assert!(
            off_arcsec.abs() < 0.1,
            "platform off by {off_arcsec} arcsec"
        );
        for angle in [b.rotation_rad, b.platform_rad, b.attitude.heading_rad] {
            assert!((-PI as Real..=PI as Real).contains(&angle), "{angle}");
        }
        assert_eq!(binner.pending(), 1, "the sample at 11 s waits in bin 11");
        assert_eq!(binner.finish().map(|s| s.time_s), Some(11.5));
        assert_eq!(binner.pending(), 0);
    }

    #[test]
    fn a_bin_of_a_200_hz_sinusoid_averages_to_its_analytic_mean() {
        // Roll = A sin(2 pi t / P + phi), N = 200 samples dt = 5 ms apart in each 1 s bin. The mean
        // of the N samples is the sinusoid at their mean time scaled by the Dirichlet kernel
        // sin(pi N dt / P) / (N sin(pi dt / P)) (docs/interface.md, "Attitude at the navigation
        // rate"), which tends to sinc(pi T / P).
        let amplitude_rad = 10f64.to_radians();
        let phase_rad = 0.3;
        let dt = 0.005;
        let n = 200u32;
        for period_s in [6.0, 11.0, 480.0] {
            let roll = |t: f64| amplitude_rad * (2.0 * PI * t / period_s + phase_rad).sin();
            let mut binner = Binner::new(1.0).unwrap();
            let samples = (0..n * 5).map(|k| {
                let t = 100.0 + f64::from(k) * dt;
                sample(t, 0.0, roll(t))
            });
            let done = bins(&mut binner, samples);
            assert_eq!(done.len(), 4);
            let x = PI * dt / period_s;
            let gain = (f64::from(n) * x).sin() / (f64::from(n) * x.sin());
            for (j, b) in done.iter().enumerate() {
                let mean_time_s = 100.0 + j as f64 + dt * f64::from(n - 1) / 2.0;
                let analytic = gain * roll(mean_time_s);
                let off_arcsec = rad_to_arcsec(f64::from(b.attitude.roll_rad) - analytic);
                assert!(
                    off_arcsec.abs() < 0.01,
                    "period {period_s} s, bin {j}: off by {off_arcsec} arcsec"
                );
                assert_eq!(b.time_s, 100.5 + j as f64);
            }
            // What the gain is: the 480 s terms keep 0.99999, the 6 s sway about 0.955.
            let sinc = (PI / period_s).sin() / (PI / period_s);
            assert!((gain - sinc).abs() < 1e-4, "{gain} against {sinc}");
            if period_s == 480.0 {
                assert!(gain > 0.99999 && gain < 1.0, "{gain}");
            }
            if period_s == 6.0 {
                assert!((gain - 0.955).abs() < 0.001, "{gain}");
            }
        }
    }

    #[test]
    fn bins_are_aligned_to_multiples_of_the_interval_and_empty_ones_give_nothing() {
        let mut binner = Binner::new(0.1).unwrap();
        // Decimal stamps at 100 Hz starting mid-bin (0.03 s), none from 0.15 to 0.34 s: bin 2 is
        // empty.
        let times = (3..50u32)
            .filter(|k| !(15..35).contains(k))
            .map(|k| f64::from(k) / 100.0);
        let done = bins(&mut binner, times.map(|t| sample(t, 0.0, 0.0)));
        let stamps: std::vec::Vec<f64> = done.iter().map(|s| s.time_s).collect();
        assert_eq!(stamps.len(), 3, "{stamps:?}");
        for (got, want) in stamps.iter().zip([0.05, 0.15, 0.35]) {
            assert!((got - want).abs() < 1e-12, "{stamps:?}");
        }
        assert_eq!(binner.pending(), 10, "0.40 to 0.49 s wait in bin 4");
        let last = binner.finish().unwrap().time_s;
        assert!((last - 0.45).abs() < 1e-12, "{last}");
        // 0.3 (2.9999999999999996 bins) opens bin 3: bin 2 holds 0.20 to 0.29 s, ten samples.
        let mut binner = Binner::new(0.1).unwrap();
        for k in 20..30u32 {
            assert_eq!(
                binner.push(&sample(f64::from(k) / 100.0, 0.0, 0.0)),
                Ok(None)
            );
        }
        assert_eq!(binner.pending(), 10);
        assert!(binner.push(&sample(0.3, 0.0, 0.0)).unwrap().is_some());
        assert_eq!(binner.pending(), 1);
    }

    #[test]
    fn bad_samples_are_refused_and_change_nothing() {
        let mut binner = Binner::new(1.0).unwrap();
        for k in 0..150u32 {
            binner
                .push(&sample(f64::from(k) * 0.005, 0.1, 0.01))
                .unwrap();
        }
        let before = binner;
        let last_s = 149.0 * 0.005;
        let mut nan_roll = sample(0.9, 0.1, 0.0);
        nan_roll.attitude.roll_rad = Real::NAN;
        let mut far_pitch = sample(0.9, 0.1, 0.0);
        far_pitch.attitude.pitch_rad = 2.0;
        let mut polar = sample(0.9, 0.1, 0.0);
        polar.latitude_rad = 1.6;
        let cases = [
            (
                sample(f64::NAN, 0.1, 0.0),
                SampleError::NonFinite(crate::Field::Time),
            ),
            (
                sample(f64::INFINITY, 0.1, 0.0),
                SampleError::NonFinite(crate::Field::Time),
            ),
            (sample(last_s, 0.1, 0.0), SampleError::TimeNotIncreasing),
            (sample(0.2, 0.1, 0.0), SampleError::TimeNotIncreasing),
            (sample(-1.0, 0.1, 0.0), SampleError::TimeNotIncreasing),
            (nan_roll, SampleError::NonFinite(crate::Field::Roll)),
            (far_pitch, SampleError::AngleOutOfRange(crate::Field::Pitch)),
            (polar, SampleError::LatitudeOutOfRange),
        ];
        for (bad, why) in cases {
            assert_eq!(binner.push(&bad), Err(why), "{bad:?}");
            assert_eq!(binner, before, "{bad:?} changed the binner");
        }
        // The bin goes on as if they never came: its average is that of the 150 good samples.
        let done = binner.push(&sample(1.0, 0.1, 0.0)).unwrap().unwrap();
        let off = rad_to_arcsec(f64::from(done.attitude.roll_rad) - 0.01);
        assert!(off.abs() < 0.01, "roll off by {off} arcsec");
        assert_eq!(done.time_s, 0.5);
    }
}
