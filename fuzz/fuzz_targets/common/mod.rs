//! Shared by the fuzz targets: a healthy sample source and the output checks.
#![allow(dead_code)]

use estimator_core::{Attitude, Estimator, Output, Real, Sample};
use std::f64::consts::PI;

/// Ring capacity of the fuzzed estimators (small, so windows fill and the filter runs quickly).
pub const CAP: usize = 32;

/// A healthy sample at time `t` for a rotation of `period` samples at latitude `lat_rad`, with the
/// given roll and pitch offsets (rad) and rotation angle `rho` (rad).
pub fn healthy(t: f64, rho: f64, lat_rad: f64, roll_off: f64, pitch_off: f64) -> Sample {
    let s = 0.9 + 7.292115e-5 * t;
    let wrap = |a: f64| (a + PI).rem_euclid(2.0 * PI) - PI;
    let x = [7e-4, -5e-4, 1e-3, -3e-4];
    let roll = 0.05 * (2.0 * PI * t / 6.0).sin() - x[0] * lat_rad.sin() * (rho - s).cos()
        + x[2] * lat_rad.cos() * rho.sin()
        + roll_off;
    let pitch = 0.02 * (2.0 * PI * t / 9.0).sin() + x[0] * (rho - s).sin() - x[1] * (rho - s).cos() + pitch_off;
    Sample {
        time_s: t,
        rotation_rad: wrap(rho) as Real,
        platform_rad: wrap(s) as Real,
        latitude_rad: lat_rad as Real,
        attitude: Attitude { heading_rad: 0.4, roll_rad: roll.clamp(-1.5, 1.5) as Real, pitch_rad: pitch.clamp(-1.5, 1.5) as Real },
    }
}

/// Panics (a fuzzer finding) if any number in an output is not finite.
pub fn assert_finite(o: &Output) {
    let mut ok = o.time_s.is_finite()
        && o.corrected.heading_rad.is_finite()
        && o.corrected.roll_rad.is_finite()
        && o.corrected.pitch_rad.is_finite();
    if let Some(e) = o.estimate {
        ok &= e.x_rad.iter().chain(e.sigma_rad.iter()).all(|v| v.is_finite());
    }
    assert!(ok, "non-finite output {o:?}");
}

/// Panics if the state does not survive a checkpoint round trip (restore validates every value
/// finite, every covariance SPD, every running sum equal to its window).
pub fn assert_state_valid(est: &Estimator<CAP>) {
    let mut buf = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
    est.checkpoint(&mut buf).expect("checkpoint");
    match Estimator::<CAP>::from_checkpoint(&buf) {
        Ok(back) => assert!(back == *est, "round trip changed the state"),
        Err(e) => panic!("state does not validate: {e:?}"),
    }
}
