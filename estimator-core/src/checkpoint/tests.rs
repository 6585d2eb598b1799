//! Layout, CRC and field validation, on states tampered with inside the crate. The end-to-end
//! properties (bit-identical continuation from every phase, every bit flip refused) are in
//! `tests/checkpoint_roundtrip.rs`.

use super::wire::Writer;
use super::*;
use crate::config::Bound;
use crate::config::{Config, Method};
use crate::estimator::Estimator;
use crate::rotation_pattern::RotationFault;
use crate::methods::{MethodState, Windowed};
use crate::sample::Sample;
use crate::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S};
use std::vec;
use std::vec::Vec;

type Est = Estimator<64>;

#[test]
fn crc32_matches_the_standard_check_value() {
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(crc32(b""), 0);
}

#[test]
fn default_image_is_23384_bytes_with_f32() {
    #[cfg(not(feature = "f64"))]
    assert_eq!(CHECKPOINT_LEN, 23_384);
    #[cfg(feature = "f64")]
    assert_eq!(CHECKPOINT_LEN, 24_416);
    assert_eq!(Estimator::<720>::CHECKPOINT_LEN, CHECKPOINT_LEN);
    assert_eq!(CHECKPOINT_LEN % 4, 0);
}

/// A 1 Hz log: a one-way rotation of 120 s (two samples a bin in a ring of 64), 2 deg of roll
/// sway, eq (2) for known errors; every 97th sample lost (filled) from sample 300 on.
fn log(n: u32) -> Vec<Sample> {
    let x = [200.0, -150.0, 300.0, -250.0].map(arcsec_to_rad);
    (0..n)
        .filter(|k| k % 97 != 50 || *k < 300)
        .map(|k| {
            let t = f64::from(k);
            let rho = 0.3 + 2.0 * core::f64::consts::PI * t / 120.0;
            let s = 1.1 + EARTH_RATE_RAD_PER_S * t;
            let lat = 0.7f64;
            let roll = 0.035 * (t * 1.047).sin() - x[0] * lat.sin() * (rho - s).cos() + x[2] * lat.cos() * rho.sin();
            let pitch = 0.01 * (t * 0.698).sin() + x[0] * (rho - s).sin() - x[1] * (rho - s).cos();
            let deg = |r: f64| r.to_degrees();
            Sample::from_degrees(t, deg(rho), deg(s), deg(lat), 20.0, deg(roll), deg(pitch))
        })
        .collect()
}

fn running(method: Method) -> Est {
    let mut est = Est::new(Config::with_method(method)).unwrap();
    for s in log(700) {
        est.step(&s).unwrap();
    }
    assert!(est.estimate().is_some(), "{method:?}");
    est
}

fn image_of<const CAP: usize>(est: &Estimator<CAP>) -> Vec<u8> {
    let mut buf = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
    assert_eq!(est.checkpoint(&mut buf), Ok(buf.len()));
    buf
}

fn reseal(buf: &mut [u8]) {
    let n = buf.len();
    let crc = crc32(&buf[..n - CRC_LEN]);
    buf[n - CRC_LEN..].copy_from_slice(&crc.to_le_bytes());
}

/// Restores an image into a running estimator: the error, and the estimator must not change.
fn refused(buf: &[u8], expected: CheckpointError) {
    let mut target = running(Method::Windowed);
    let before = target.clone();
    assert_eq!(target.restore(buf), Err(expected));
    assert_eq!(target, before);
}

/// Writes an estimator whose state was tampered with (the CRC is then valid) and checks that
/// restoring it is refused with `expected`.
fn rejects(tampered: &Est, expected: CheckpointError) {
    refused(&image_of(tampered), expected);
}

/// Offset in `image` of the correlation window whose length, head, fill count and bin are
/// `indices` (u32 each, the first thing written of a window); there must be exactly one.
fn window_at(image: &[u8], indices: [u32; 4]) -> usize {
    let pattern: Vec<u8> = indices.iter().flat_map(|v| v.to_le_bytes()).collect();
    let hits: Vec<usize> = (METHOD_OFFSET..image.len() - 16).filter(|&i| image[i..i + 16] == pattern[..]).collect();
    assert_eq!(hits.len(), 1, "{hits:?}");
    hits[0]
}

/// From a correlation window's start to its first ring slot: indices, sums, the bin being filled.
const WINDOW_RING_OFFSET: usize = 4 * 4 + (4 + crate::correlation::SUMS * 8 + 4) + (4 + 11 * R + 4);
/// Bytes of one ring slot.
const ENTRY_LEN: usize = 30;

fn accepts(state: &Est) {
    assert_eq!(Est::from_checkpoint(&image_of(state)).as_ref(), Ok(state));
}

/// The methods of this build.
const METHODS: &[Method] = if cfg!(feature = "paper-method") {
    &[Method::Windowed, Method::Paper, Method::Traditional]
} else {
    &[Method::Windowed, Method::Traditional]
};

#[test]
fn every_part_ends_where_the_layout_says_and_every_method_round_trips() {
    for &method in METHODS {
        let est = running(method);
        let mut buf = vec![0u8; Est::CHECKPOINT_LEN];
        let mut w = Writer::new(&mut buf, HEADER_LEN);
        let mut end = HEADER_LEN;
        config::write(&mut w, &est.config);
        end += config::LEN;
        assert_eq!(w.pos(), end);
        running::write(&mut w, &est);
        end += running::LEN;
        assert_eq!(w.pos(), end);
        time_grid::write(&mut w, &est.grid);
        end += time_grid::LEN;
        assert_eq!(w.pos(), end);
        rotation::write(&mut w, &est.rotation);
        end += rotation::LEN;
        assert_eq!(w.pos(), end);
        gap_fill::write(&mut w, &est.filler);
        end += gap_fill::LEN;
        assert_eq!(w.pos(), end);
        assert_eq!(end, METHOD_OFFSET);
        let mut w = Writer::new(&mut buf, METHOD_OFFSET);
        methods::write(&mut w, &est.method);
        assert_eq!(w.pos(), METHOD_OFFSET + methods::len(method, 64), "{method:?}");
        assert!(w.pos() <= Est::CHECKPOINT_LEN - CRC_LEN);

        let image = image_of(&est);
        assert_eq!(crc32(&image[..image.len() - 4]), u32::from_le_bytes(image[image.len() - 4..].try_into().unwrap()));
        let back = Est::from_checkpoint(&image).unwrap();
        assert_eq!(back, est, "{method:?}");
    }
    // The windowed method is the longest for any ring of more than 16 entries.
    assert_eq!(method_len(64), methods::len(Method::Windowed, 64));
    assert_eq!(method_len(960), methods::len(Method::Windowed, 960));
}

#[test]
fn a_running_state_has_bins_and_filled_gaps_to_carry() {
    // What the tampering below reaches: bins of 2 samples over the 120 s period, a fill-error
    // estimate, features, a timing pass.
    let est = running(Method::Windowed);
    let MethodState::Windowed(m) = &est.method else { panic!() };
    assert_eq!((m.window.bin, m.window.len), (2, 60));
    assert!(est.filler.error_samples > 0 && est.counters.filled > 0);
    assert!(est.rotation.features.is_some() && est.rotation.timing_pass.is_some());
}

fn with_windowed(base: &Est, f: impl Fn(&mut Windowed<64>)) -> Est {
    let mut e = base.clone();
    if let MethodState::Windowed(m) = &mut e.method {
        f(m);
    }
    e
}

#[test]
fn tampered_filters_and_windows_are_refused_with_a_typed_error() {
    use CheckpointError::*;
    let base = running(Method::Windowed);
    rejects(&with_windowed(&base, |m| m.kf.x[2] = Real::NAN), InvalidValue(Part::KalmanState));
    rejects(&with_windowed(&base, |m| m.kf.p[(3, 3)] = Real::INFINITY), InvalidValue(Part::KalmanCovariance));
    rejects(&with_windowed(&base, |m| m.kf.p[(0, 1)] += 1e-12), NotPositiveDefinite(Part::KalmanCovariance));
    rejects(&with_windowed(&base, |m| m.kf.p[(2, 2)] = -m.kf.p[(2, 2)]), NotPositiveDefinite(Part::KalmanCovariance));
    rejects(&with_windowed(&base, |m| m.gains[3] = -0.5), InvalidValue(Part::Residuals));
    rejects(&with_windowed(&base, |m| m.gains[1] = Real::NAN), InvalidValue(Part::Residuals));
    // A zero gain (a window whose reference does not move) is a state the estimator can be in.
    accepts(&with_windowed(&base, |m| m.gains[3] = 0.0));

    rejects(&with_windowed(&base, |m| m.window.sums.sums[3] += 1), Inconsistent(Part::WindowSums));
    rejects(&with_windowed(&base, |m| m.window.sums.count += 1), Inconsistent(Part::WindowSums));
    rejects(&with_windowed(&base, |m| m.window.sums.fill_weight += 1), Inconsistent(Part::WindowSums));
    rejects(
        &with_windowed(&base, |m| {
            if let Some(e) = m.window.ring.iter_mut().nth(7) {
                e.fill_weight += 1;
            }
        }),
        Inconsistent(Part::WindowSums),
    );
    rejects(&with_windowed(&base, |m| m.window.len -= 1), Inconsistent(Part::WindowIndices));
    rejects(&with_windowed(&base, |m| m.window.bin = 3), Inconsistent(Part::WindowIndices));
    rejects(
        &with_windowed(&base, |m| {
            let Some(e) = m.window.ring.iter_mut().nth(5) else { return };
            let mut q = e.sample;
            m.window.sums.subtract(&q, 0);
            q.roll = i32::MAX;
            m.window.sums.add(&q, 0);
            e.sample = q;
        }),
        InvalidValue(Part::WindowEntries),
    );

    // The ring's indices and spare slots, in the image: the window of 60 entries is full, written
    // from slot 0 (head 0), in a ring of 64.
    let image = image_of(&base);
    let at = window_at(&image, [60, 0, 60, 2]);
    let entry = |k: usize| at + WINDOW_RING_OFFSET + k * ENTRY_LEN;
    let tampered = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut b = image.clone();
        f(&mut b);
        reseal(&mut b);
        b
    };
    let put_u32 = |b: &mut Vec<u8>, pos: usize, v: u32| b[pos..pos + 4].copy_from_slice(&v.to_le_bytes());
    refused(&tampered(&|b| put_u32(b, at + 4, 60)), Inconsistent(Part::WindowIndices));
    refused(
        &tampered(&|b| {
            put_u32(b, at + 4, 11);
            put_u32(b, at + 8, 10);
        }),
        Inconsistent(Part::WindowIndices),
    );
    // A spare slot out of range is refused; one in range (a stale entry, as an older writer left
    // them) is ignored.
    refused(&tampered(&|b| b[entry(63) + 16..entry(63) + 18].copy_from_slice(&16_385i16.to_le_bytes())), InvalidValue(Part::WindowEntries));
    assert_eq!(Est::from_checkpoint(&tampered(&|b| put_u32(b, entry(63), 12345))).as_ref(), Ok(&base));
    // A ring stored rotated (oldest entry in slot 17, as an older writer left it) is the same window.
    let rotated = tampered(&|b| {
        let ring: Vec<u8> = b[entry(0)..entry(60)].to_vec();
        for k in 0..60 {
            let from = (k + 60 - 17) % 60;
            b[entry(k)..entry(k + 1)].copy_from_slice(&ring[from * ENTRY_LEN..(from + 1) * ENTRY_LEN]);
        }
        put_u32(b, at + 4, 17);
    });
    assert_eq!(Est::from_checkpoint(&rotated).as_ref(), Ok(&base));

    // The bin being filled.
    rejects(&with_windowed(&base, |m| m.window.partial.count = 2), Inconsistent(Part::Bin));
    rejects(
        &with_windowed(&base, |m| {
            m.window.partial = Default::default();
            m.window.partial.roll_rad = 1e-3;
        }),
        UnusedNotZero(Part::Bin),
    );
    rejects(
        &with_windowed(&base, |m| {
            m.window.partial.count = 1;
            m.window.partial.pitch_rad = Real::NAN;
        }),
        InvalidValue(Part::Bin),
    );
    rejects(
        &with_windowed(&base, |m| {
            m.window.partial.count = 1;
            m.window.partial.fill_weight = 70_000;
        }),
        InvalidValue(Part::Bin),
    );
}

/// Regression, fuzz target `checkpoint_restore` (crash-daa82956...): an image of a paper-method
/// estimator whose first filter's b2 state had its top byte flipped (finite, ~1e300 in f64) was
/// accepted; the next update moved x1 beyond f32 range and the output was infinite/NaN. Finite but
/// absurd states, variances and residuals are refused.
#[test]
fn regression_fuzz_huge_finite_states_are_refused() {
    use CheckpointError::*;
    let base = running(Method::Windowed);
    rejects(&with_windowed(&base, |m| m.kf.x[0] = 1e30), InvalidValue(Part::KalmanState));
    rejects(&with_windowed(&base, |m| m.kf.p[(1, 1)] = 1e30), InvalidValue(Part::KalmanCovariance));
    rejects(&with_windowed(&base, |m| m.residual_mean[2] = 1e30), InvalidValue(Part::Residuals));
    rejects(&with_windowed(&base, |m| m.gains[0] = 1e30), InvalidValue(Part::Residuals));
    #[cfg(feature = "paper-method")]
    {
        let paper = |f: &dyn Fn(&mut crate::methods::Paper<64>)| {
            let mut e = running(Method::Paper);
            if let MethodState::Paper(m) = &mut e.method {
                f(m);
            }
            e
        };
        rejects(&paper(&|m| m.kf[0].x[2] = 1e300), InvalidValue(Part::KalmanState));
        rejects(&paper(&|m| m.kf[1].p[(0, 0)] = 1e200), InvalidValue(Part::KalmanCovariance));
    }
}

#[test]
fn tampered_configuration_grid_and_estimator_are_refused_with_a_typed_error() {
    use crate::config::ConfigError;
    use CheckpointError::*;
    let base = running(Method::Windowed);
    let with = |f: &dyn Fn(&mut Est)| {
        let mut e = base.clone();
        f(&mut e);
        e
    };
    let param = |name: &'static str, value: f64, bound: Bound| InvalidConfig(ConfigError::Parameter { name, value, bound });
    rejects(&with(&|e| e.config.measurement_sigma_rad = -1.0), param("measurement_sigma_rad", -1.0, Bound::Positive));
    rejects(&with(&|e| e.config.max_filled_gap_samples = 4), param("max_filled_gap_samples", 4.0, Bound::AtMost(3.0)));
    // Regressions, fuzz target `checkpoint_restore`: a flipped exponent made the traditional
    // random walk 1e26 rad/sqrt(s), whose square is infinite in f32; a sigma whose square
    // underflows; a flipped top byte of the gap bridged (filled, now) made one step work for minutes.
    let huge = 2.0 * Real::MAX.sqrt();
    let bound = Bound::AtMost(1.0 / libm::sqrt(crate::config::SAMPLE_INTERVAL_RANGE_S.1));
    rejects(&with(&|e| e.config.traditional_drift_rad_per_sqrt_s = huge), param("traditional_drift_rad_per_sqrt_s", huge as f64, bound));
    let tiny = (if R == 4 { 1e-30 } else { 1e-200 }) as Real;
    rejects(&with(&|e| e.config.measurement_sigma_rad = tiny), param("measurement_sigma_rad", tiny as f64, Bound::SquareUnderflows));
    rejects(&with(&|e| e.config.max_filled_gap_samples = 0x6c00_0000), param("max_filled_gap_samples", f64::from(0x6c00_0000u32), Bound::AtMost(3.0)));
    rejects(&with(&|e| e.config.rotation_period_s = Some(10.0)), InvalidConfig(ConfigError::RotationPeriod { value_s: 10.0 }));
    rejects(&with(&|e| e.config.sample_interval_s = Some(f64::NAN)), InvalidConfig(ConfigError::SampleInterval { value_s: f64::NAN }));

    rejects(&with(&|e| e.grid.interval_s = Some(-1.0)), InvalidValue(Part::TimeGrid));
    rejects(&with(&|e| e.grid.last_stamp_s = Some(f64::INFINITY)), InvalidValue(Part::TimeGrid));
    rejects(&with(&|e| e.grid.learning_steps[3] = f64::NAN), InvalidValue(Part::TimeGrid));
    rejects(&with(&|e| e.grid.learned = 9), InvalidValue(Part::TimeGrid));
    rejects(&with(&|e| e.grid.pinned = true), Inconsistent(Part::TimeGrid));

    rejects(&with(&|e| e.latitude_trig.0 = 1.6), InvalidValue(Part::Latitude));
    rejects(&with(&|e| e.sway.mean_square_rad2 = Real::NAN), InvalidValue(Part::SwayMonitor));
    rejects(&with(&|e| e.sway.mean_square_rad2 = -1e-3), InvalidValue(Part::SwayMonitor));
    rejects(&with(&|e| e.fault = Some((RotationFault::Stopped, f64::NAN))), InvalidValue(Part::Fault));
    accepts(&with(&|e| e.fault = Some((RotationFault::Stopped, -1.0))));
    accepts(&with(&|e| e.fault = Some((RotationFault::Reversed, 12.0))));
}

#[test]
fn tampered_rotation_monitor_and_delay_line_are_refused_with_a_typed_error() {
    use CheckpointError::*;
    let base = running(Method::Windowed);
    let with = |f: &dyn Fn(&mut Est)| {
        let mut e = base.clone();
        f(&mut e);
        e
    };
    rejects(&with(&|e| e.rotation.timing_pass = Some((8, 0))), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.timing_pass = Some((1, 2))), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.level_side[2] = 2), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.period_samples = Some(1)), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.short_steps = 5), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.levels_rad = Some(Real::NAN)), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.previous = Some((3, 7.0))), InvalidValue(Part::RotationMonitor));
    rejects(&with(&|e| e.rotation.pinned = true), Inconsistent(Part::RotationMonitor));
    rejects(
        &with(&|e| {
            if let Some(f) = &mut e.rotation.features {
                f.direction = 3;
            }
        }),
        InvalidValue(Part::Features),
    );
    // The window must match the period (the window is configured for 120 samples).
    rejects(&with(&|e| e.rotation.period_samples = Some(122)), Inconsistent(Part::WindowIndices));

    let newest = base.filler.newest.unwrap();
    let k = newest as usize % gap_fill_slots();
    rejects(&with(&|e| e.filler.slots[k].as_mut().unwrap().index += 1), Inconsistent(Part::DelayLine));
    rejects(&with(&|e| e.filler.slots[k] = None), Inconsistent(Part::DelayLine));
    rejects(&with(&|e| e.filler.slots[k].as_mut().unwrap().roll_rad = Real::NAN), InvalidValue(Part::DelayLine));
    rejects(&with(&|e| e.filler.slots[k].as_mut().unwrap().angles.cos_rho = 1.5), InvalidValue(Part::DelayLine));
    rejects(&with(&|e| e.filler.slots[k].as_mut().unwrap().fill_weight = 1), InvalidValue(Part::DelayLine));
    rejects(&with(&|e| e.filler.next = newest.wrapping_sub(5)), Inconsistent(Part::DelayLine));
    rejects(&with(&|e| e.filler.newest = None), Inconsistent(Part::DelayLine));
    rejects(&with(&|e| e.filler.roll_error_rad2 = -1e-9), InvalidValue(Part::FillError));
    rejects(&with(&|e| e.filler.error_samples = 257), InvalidValue(Part::FillError));
}

fn gap_fill_slots() -> usize {
    crate::gap_fill::SLOTS
}

#[cfg(feature = "paper-method")]
#[test]
fn tampered_paper_states_are_refused() {
    use CheckpointError::*;
    let paper = |f: &dyn Fn(&mut crate::methods::Paper<64>)| {
        let mut e = running(Method::Paper);
        if let MethodState::Paper(m) = &mut e.method {
            f(m);
        }
        e
    };
    rejects(&paper(&|m| m.kf[2].p[(1, 2)] = 2.0 * m.kf[2].p[(1, 2)] + 1.0), NotPositiveDefinite(Part::KalmanCovariance));
    rejects(&paper(&|m| m.start_time_s = f64::NAN), InvalidValue(Part::PaperStartTime));
    rejects(&paper(&|m| m.integrals[1] = i64::MAX), InvalidValue(Part::PaperIntegrals));
    rejects(&paper(&|m| m.window.sums[0] += 1), Inconsistent(Part::WindowSums));
    rejects(&paper(&|m| m.window.len = 60), Inconsistent(Part::WindowIndices));
}

#[test]
fn tampered_traditional_state_is_refused() {
    let mut e = running(Method::Traditional);
    if let MethodState::Traditional(m) = &mut e.method {
        m.kf.x[1] = Real::INFINITY;
    }
    rejects(&e, CheckpointError::InvalidValue(Part::KalmanState));
}

#[test]
fn bad_flags_codes_unused_bytes_and_padding_are_refused() {
    use CheckpointError::*;
    let est = running(Method::Traditional);
    let good = image_of(&est);
    let edit = |at: usize, v: u8| {
        let mut b = good.clone();
        b[at] = v;
        reseal(&mut b);
        b
    };
    let running_at = HEADER_LEN + config::LEN;
    // Padding after the traditional method's state.
    refused(&edit(good.len() - 10, 1), UnusedNotZero(Part::Padding));
    // An absent pinned period with a non-zero value.
    assert_eq!(good[HEADER_LEN], 0);
    refused(&edit(HEADER_LEN + 3, 1), UnusedNotZero(Part::Config));
    // The feed interval's presence flag (after the grid index) set to 2.
    refused(&edit(running_at + 4, 2), InvalidValue(Part::Estimator));
    // Status and fault codes.
    refused(&edit(running_at + 14 + R, 10), InvalidValue(Part::Status));
    refused(&edit(running_at + 15 + R, 4), InvalidValue(Part::Fault));
    refused(&edit(running_at + 15 + R, 0x10), InvalidValue(Part::Fault));
    // No fault, but a time for it.
    refused(&edit(running_at + 16 + R, 1), UnusedNotZero(Part::Fault));
    // Unknown method code.
    refused(&edit(7, 9), UnknownMethod(9));

    // And the genuine image restores into an estimator of another method, method and all.
    let mut target = running(Method::Windowed);
    target.restore(&good).unwrap();
    assert_eq!(target, est);
}

#[test]
fn errors_say_what_to_do_with_an_old_image() {
    use std::string::ToString;
    let old = CheckpointError::Version { found: 2, expected: VERSION }.to_string();
    assert!(old.contains("older firmware") && old.contains("discarded"), "{old}");
    let new = CheckpointError::Version { found: VERSION + 1, expected: VERSION }.to_string();
    assert!(new.contains("newer firmware"), "{new}");
    let e: &dyn core::error::Error = &CheckpointError::Inconsistent(Part::WindowSums);
    assert_eq!(e.to_string(), "checkpoint window running sums: inconsistent values");
}
