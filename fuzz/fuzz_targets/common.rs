//! Shared by the fuzz targets: a healthy sample source and the output checks.
#![allow(dead_code)]

use estimator_core::synthetic::Signal;
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Estimator, Output, Real, Sample};

/// Ring capacity of the fuzzed estimators (small, so windows fill and the filter runs quickly).
pub const CAP: usize = 32;

/// A healthy sample at time `t` (s) and rotation angle `rho` (rad) at latitude `lat_rad`, with the
/// given roll and pitch offsets (rad) added and both clamped to +-1.5 rad: 0.05 rad roll and 0.02
/// rad pitch sway and eq (2)'s oscillation for fixed errors, from `estimator_core::synthetic`.
pub fn healthy(t: f64, rho: f64, lat_rad: f64, roll_off: f64, pitch_off: f64) -> Sample {
    let mut signal = Signal::new([7e-4, -5e-4, 1e-3, -3e-4].map(rad_to_arcsec), lat_rad.to_degrees());
    signal.platform_phase_rad = 0.9;
    signal.heading_rad = 0.4;
    signal.roll_sway_deg = 0.05f64.to_degrees();
    signal.pitch_sway_deg = 0.02f64.to_degrees();
    signal.pitch_sway_phase_rad = 0.0;
    signal.low_frequency_deg = 0.0;
    let mut sample = signal.sample_at(t, rho);
    let offset = |angle: Real, off: f64| (angle as f64 + off).clamp(-1.5, 1.5) as Real;
    sample.attitude.roll_rad = offset(sample.attitude.roll_rad, roll_off);
    sample.attitude.pitch_rad = offset(sample.attitude.pitch_rad, pitch_off);
    sample
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

/// Panics if what a restart keeps of the state does not survive a checkpoint round trip (restore
/// validates every value finite and in range, every covariance SPD): the restored estimator must
/// write the same image and report the same estimate.
pub fn assert_state_valid(est: &Estimator<CAP>) {
    let mut buf = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
    est.checkpoint(&mut buf).expect("checkpoint");
    match Estimator::<CAP>::from_checkpoint(&buf) {
        Ok(back) => {
            let mut again = vec![0u8; Estimator::<CAP>::CHECKPOINT_LEN];
            back.checkpoint(&mut again).expect("checkpoint");
            assert!(again == buf, "round trip changed the image");
            assert!(back.estimate().map(|e| e.x_rad) == est.estimate().map(|e| e.x_rad), "round trip changed the estimate");
        }
        Err(e) => panic!("state does not validate: {e:?}"),
    }
}
