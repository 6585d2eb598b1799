//! Checkpoint and restore, end to end through the public API.
//!
//! - `restored_run_is_bit_identical_*`: run a scenario, checkpoint at a random step, restore into a
//!   fresh estimator (built with a *different* configuration, which the image replaces), continue:
//!   every later output is bit-identical to the uninterrupted run, and so is the final image.
//!   The scenario contains rejected samples, a long gap, a stopped rotation and a reversal, so the
//!   cut lands in every kind of state (warming up, holding, faulted, estimating).
//! - header, length, CRC and garbage: typed error, estimator untouched.
//!
//! The sample source is local (estimator-core cannot use host-sim): sinusoidal sway, eq (2)'s
//! oscillation for known errors, white noise from a 64-bit LCG.

mod common;

use common::oscillation;
use estimator_core::checkpoint::{CheckpointError, CHECKPOINT_LEN, VERSION};
use estimator_core::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
use estimator_core::{Config, Estimator, Method, Output, Real, Sample, SampleError};
use proptest::prelude::*;
use std::f64::consts::PI;

/// A deterministic log of `n` samples with a few faults in it. `period_samples`: rotation period.
fn scenario(n: usize, period_samples: usize, seed: u64) -> Vec<Sample> {
    let x = [120.0, -80.0, 250.0, -190.0].map(arcsec_to_rad);
    let lat = 35.0 * RAD_PER_DEG;
    let mut state = seed | 1;
    let mut noise = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0 * arcsec_to_rad(10.0)
    };
    let mut out = Vec::with_capacity(n);
    let mut rho = 0.4;
    let mut t = 0.0;
    let step = 2.0 * PI / period_samples as f64;
    for k in 0..n {
        // Faults at fixed fractions of the run.
        let phase = k * 20 / n;
        let increment = match phase {
            7 if k % 97 < 15 => 0.0,    // rotation stops for 15 samples
            12 if k % 211 == 0 => -step, // one reversed step
            _ => step,
        };
        rho += increment;
        t += if phase == 15 && k % 173 == 0 { 5.0 } else { 1.0 }; // a 4-sample gap
        let s = 1.3 + EARTH_RATE_RAD_PER_S * t;
        let d = oscillation(&x, rho, s, lat);
        let roll = 3.0 * RAD_PER_DEG * (2.0 * PI * t / 6.0).sin() + d[1] + noise();
        let pitch = 1.0 * RAD_PER_DEG * (2.0 * PI * t / 9.0 + 0.3).sin() + d[2] + noise();
        let mut sample = Sample::from_degrees(
            t,
            rho / RAD_PER_DEG,
            s / RAD_PER_DEG,
            lat / RAD_PER_DEG,
            (0.5 + d[0]) / RAD_PER_DEG,
            roll / RAD_PER_DEG,
            pitch / RAD_PER_DEG,
        );
        if k % 331 == 17 {
            sample.attitude.roll_rad = Real::NAN; // rejected, counted
        }
        if k % 509 == 100 {
            sample.time_s -= 3.0; // time going back: rejected
        }
        out.push(sample);
    }
    out
}

/// Every bit of a step's result (floats by their bit patterns).
fn fingerprint(r: &Result<Output, SampleError>) -> Vec<u64> {
    match r {
        Err(e) => vec![u64::MAX, e.reason_index() as u64],
        Ok(o) => {
            let mut v = vec![o.time_s.to_bits(), u64::from(o.status.code())];
            let mut push = |x: Real| v.push(x.to_bits() as u64);
            push(o.corrected.heading_rad);
            push(o.corrected.roll_rad);
            push(o.corrected.pitch_rad);
            match o.estimate {
                None => v.push(u64::MAX - 1),
                Some(e) => {
                    for i in 0..4 {
                        v.push(e.x_rad[i].to_bits() as u64);
                        v.push(e.sigma_rad[i].to_bits() as u64);
                    }
                }
            }
            v
        }
    }
}

fn image<const CAP: usize>(est: &Estimator<CAP>) -> Vec<u8> {
    let mut buf = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
    assert_eq!(est.checkpoint(&mut buf), Ok(buf.len()));
    buf
}

/// Runs `samples` uninterrupted and, separately, cut at `cut` (checkpoint after sample `cut`,
/// restore into a fresh estimator of another configuration, continue). Asserts bit-identity.
fn check_cut<const CAP: usize>(config: Config, samples: &[Sample], cut: usize) {
    let mut reference = Estimator::<CAP>::new(config).unwrap();
    let reference_out: Vec<_> = samples.iter().map(|s| fingerprint(&reference.step(s))).collect();

    let mut first = Estimator::<CAP>::new(config).unwrap();
    for s in &samples[..=cut] {
        first.step(s).ok();
    }
    let buf = image(&first);
    drop(first);
    // A fresh estimator with another method and period: the image must replace all of it.
    let other = Config {
        method: if config.method == Method::Paper { Method::Windowed } else { Method::Paper },
        rotation_period_samples: CAP.min(config.rotation_period_samples + 1).max(2),
        ..Config::default()
    };
    let mut resumed = Estimator::<CAP>::new(other).unwrap();
    resumed.restore(&buf).unwrap();
    assert_eq!(resumed.config(), &config);
    for (k, s) in samples.iter().enumerate().skip(cut + 1) {
        assert_eq!(fingerprint(&resumed.step(s)), reference_out[k], "cut {cut}: output {k} differs");
    }
    assert_eq!(image(&resumed), image(&reference), "cut {cut}: final state differs");
    assert_eq!(resumed.rejected(), reference.rejected());
    assert_eq!(resumed.counters(), reference.counters());
}

fn method(i: u8) -> Method {
    Method::from_code(i % 3).unwrap()
}

/// Cases per property: `n`, or `PROPTEST_CASES` from the environment for longer runs.
fn cases(n: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(n)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(96), ..ProptestConfig::default() })]

    /// Short rotation period (48 samples), 1200-sample scenario: every kind of state is visited
    /// many times, so random cuts land in all of them.
    #[test]
    fn restored_run_is_bit_identical_short_period(cut in 0usize..1199, m in 0u8..3, seed in any::<u64>()) {
        let config = Config { rotation_period_samples: 48, ..Config::with_method(method(m)) };
        let samples = scenario(1200, 48, seed);
        check_cut::<64>(config, &samples, cut);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(24), ..ProptestConfig::default() })]

    /// The default configuration (480-sample window, CAP 480), 2400 samples: five windows.
    #[test]
    fn restored_run_is_bit_identical_default_config(cut in 0usize..2399, m in 0u8..3, seed in any::<u64>()) {
        let samples = scenario(2400, 480, seed);
        check_cut::<480>(Config::with_method(method(m)), &samples, cut);
    }
}

/// A running estimator of each method and its image (built once: the flips below are cheap).
fn sources() -> &'static [(Estimator<480>, Vec<u8>); 3] {
    static SOURCES: std::sync::OnceLock<[(Estimator<480>, Vec<u8>); 3]> = std::sync::OnceLock::new();
    SOURCES.get_or_init(|| {
        let samples = scenario(700, 480, 3);
        std::array::from_fn(|m| {
            let mut est = Estimator::<480>::new(Config::with_method(method(m as u8))).unwrap();
            for s in &samples {
                est.step(s).ok();
            }
            let img = image(&est);
            (est, img)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(1024), ..ProptestConfig::default() })]

    /// Any single-bit flip anywhere in the image is refused (CRC-32 detects every single-bit
    /// error; a flip in the header fields checked first gives their error instead) and the
    /// running estimator does not change.
    #[test]
    fn any_bit_flip_is_refused_and_changes_nothing(byte in 0usize..CHECKPOINT_LEN, bit in 0u8..8, m in 0usize..3, t in 0usize..3) {
        let mut buf = sources()[m].1.clone();
        buf[byte] ^= 1 << bit;
        let mut target = sources()[t].0.clone();
        let before = target.clone();
        let result = target.restore(&buf);
        prop_assert!(result.is_err(), "flip at byte {byte} bit {bit} accepted");
        if byte >= 16 {
            prop_assert!(matches!(result, Err(CheckpointError::CrcMismatch { .. })), "{result:?}");
        }
        prop_assert_eq!(target, before);
    }

    /// Arbitrary bytes, and a valid image's truncations and garbage, never panic and are refused.
    #[test]
    fn garbage_and_truncations_are_refused(garbage in proptest::collection::vec(any::<u8>(), 0..15_000), cut in 0usize..CHECKPOINT_LEN) {
        let mut target = Estimator::<480>::new(Config::default()).unwrap();
        let before = target.clone();
        prop_assert!(target.restore(&garbage).is_err());
        let mut valid = image(&target);
        valid.truncate(cut);
        prop_assert!(target.restore(&valid).is_err());
        prop_assert_eq!(target, before);
    }
}

#[test]
fn default_image_size_is_documented_and_fits_four_flash_pages() {
    #[cfg(not(feature = "f64"))]
    assert_eq!(CHECKPOINT_LEN, 13_796);
    assert!(CHECKPOINT_LEN <= 4 * 4096);
    let est = Estimator::<480>::new(Config::default()).unwrap();
    let mut big = vec![0xAAu8; CHECKPOINT_LEN + 100];
    assert_eq!(est.checkpoint(&mut big), Ok(CHECKPOINT_LEN));
    // A longer buffer restores (trailing bytes are ignored).
    let mut other = Estimator::<480>::new(Config::with_method(Method::Traditional)).unwrap();
    other.restore(&big).unwrap();
    assert_eq!(other, est);
}

#[test]
fn too_small_buffer_is_refused_and_left_alone() {
    let est = Estimator::<480>::new(Config::default()).unwrap();
    let mut small = vec![0x55u8; CHECKPOINT_LEN - 1];
    assert_eq!(
        est.checkpoint(&mut small),
        Err(CheckpointError::BufferTooSmall { needed: CHECKPOINT_LEN, available: CHECKPOINT_LEN - 1 })
    );
    assert!(small.iter().all(|b| *b == 0x55));
}

#[test]
fn header_errors_are_typed() {
    let samples = scenario(900, 480, 11);
    let mut est = Estimator::<480>::new(Config::default()).unwrap();
    for s in &samples {
        est.step(s).ok();
    }
    let good = image(&est);
    let mut target = Estimator::<480>::new(Config::with_method(Method::Paper)).unwrap();
    let before = target.clone();

    let mut b = good.clone();
    b[0] = b'X';
    assert_eq!(target.restore(&b), Err(CheckpointError::BadMagic));
    let mut b = good.clone();
    // The previous format (version 1, before the rotation monitor's short mean) is refused.
    b[4..6].copy_from_slice(&(VERSION - 1).to_le_bytes());
    assert_eq!(target.restore(&b), Err(CheckpointError::UnsupportedVersion(VERSION - 1)));
    let mut b = good.clone();
    b[6] = 8 / (std::mem::size_of::<Real>() as u8 / 4); // the other float width
    assert_eq!(target.restore(&b), Err(CheckpointError::RealWidthMismatch(b[6])));
    let mut b = good.clone();
    b[12..16].copy_from_slice(&((CHECKPOINT_LEN - 4) as u32).to_le_bytes());
    assert_eq!(
        target.restore(&b),
        Err(CheckpointError::LengthMismatch { expected: CHECKPOINT_LEN, found: CHECKPOINT_LEN - 4 })
    );
    let mut b = good.clone();
    let n = b.len();
    b[n - 1] ^= 0x80;
    assert!(matches!(target.restore(&b), Err(CheckpointError::CrcMismatch { .. })));
    // An image of a smaller estimator.
    let small = Estimator::<64>::new(Config { rotation_period_samples: 48, ..Config::default() }).unwrap();
    let mut sb = vec![0u8; Estimator::<64>::CHECKPOINT_LEN];
    small.checkpoint(&mut sb).unwrap();
    assert_eq!(target.restore(&sb), Err(CheckpointError::CapacityMismatch(64)));
    assert_eq!(target, before);

    target.restore(&good).unwrap();
    assert_eq!(target, est);
}
