//! Checkpoint and restore on the project's own scenarios (host_sim::sim::scenario), as after a power cut
//! right after a save: for each scenario and method, checkpoint at spread-out and random cut
//! points, restore into a fresh estimator of another method, continue to the end. The restored
//! estimator writes the very image it came from, reports the checkpoint's estimate from its first
//! output on, rejects exactly the rows the uninterrupted run rejects and never loses its estimate;
//! at the end its errors are within the uninterrupted run's 1-sigma of that run's (a restart
//! costs a period of updates while the window refills; cuts in the first periods cost most), for
//! our method and the traditional baseline (not for the paper's method as published: see below).
//! The sea scenario
//! moves the latitude and turns the heading; with rotation jitter on it also trips the rotation
//! monitor.

use estimator_core::units::rad_to_arcsec;
use estimator_core::{Config, Estimator, Method, Output, SampleError};
use host_sim::replay::sample_of;
use host_sim::sim::scenario::{generate, ScenarioKind, ScenarioParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn image(est: &Estimator) -> Vec<u8> {
    let mut buf = vec![0u8; estimator_core::checkpoint::CHECKPOINT_LEN];
    est.checkpoint(&mut buf).unwrap();
    buf
}

fn check(kind: ScenarioKind, method: Method, jitter_deg: f64, cuts: usize) {
    let mut params = ScenarioParams::new(kind, 7);
    params.duration_s = params.duration_s.min(4.0 * 3600.0);
    params.mismatch.rotation_jitter_deg = jitter_deg;
    let samples: Vec<_> = generate(&params).rows.iter().map(sample_of).collect();
    let n = samples.len();
    let config = Config::with_method(method);
    let mut reference = Estimator::new(config).unwrap();
    let mut outputs: Vec<Result<Output, SampleError>> = Vec::with_capacity(n);
    let mut images = Vec::new();
    // Cut points: first, last-but-one, evenly spread, and random (ChaCha8, seeded per method).
    let mut rng = ChaCha8Rng::seed_from_u64(0x2545_F491_4F6C_DD1D ^ (method as u64) << 7);
    let mut cut_points: Vec<usize> = vec![0, n - 2];
    cut_points.extend((1..cuts / 2).map(|i| i * n / (cuts / 2)));
    for _ in 0..cuts / 2 {
        cut_points.push(rng.gen_range(0..n - 1));
    }
    cut_points.sort_unstable();
    let mut next_cut = cut_points.iter().peekable();
    for (k, s) in samples.iter().enumerate() {
        outputs.push(reference.step(s));
        while next_cut.peek() == Some(&&k) {
            images.push((k, image(&reference)));
            next_cut.next();
        }
    }
    let faults = outputs
        .iter()
        .filter(
            |o| matches!(o, Ok(o) if matches!(o.status, estimator_core::Status::RotationFault(_))),
        )
        .count();
    let reference_end = reference.estimate().unwrap();
    let other = if method == Method::Traditional {
        Method::Windowed
    } else {
        Method::Traditional
    };
    let mut worst = 0.0f64;
    for (cut, img) in &images {
        let mut resumed = Estimator::new(Config::with_method(other)).unwrap();
        resumed.restore(img).unwrap();
        assert_eq!(
            image(&resumed),
            *img,
            "{kind:?} {method:?}: cut {cut}: restored, it writes another image"
        );
        let at_cut = match &outputs[*cut] {
            Ok(o) => o.estimate,
            Err(_) => resumed.estimate(),
        };
        assert_eq!(
            resumed.estimate().map(|e| e.x_rad),
            at_cut.map(|e| e.x_rad),
            "{kind:?} {method:?}: cut {cut}"
        );
        let mut had = at_cut.is_some();
        for k in cut + 1..n {
            match (resumed.step(&samples[k]), &outputs[k]) {
                (Ok(o), Ok(_)) => {
                    assert!(
                        !had || o.estimate.is_some(),
                        "{kind:?} {method:?}: cut {cut}: row {k} lost the estimate"
                    );
                    had |= o.estimate.is_some();
                }
                (Err(a), Err(b)) => assert_eq!(
                    a.reason(),
                    b.reason(),
                    "{kind:?} {method:?}: cut {cut}: row {k}"
                ),
                (a, b) => panic!("{kind:?} {method:?}: cut {cut}: row {k}: {a:?}, uncut {b:?}"),
            }
        }
        let end = resumed.estimate().unwrap();
        for i in 0..4 {
            let d = rad_to_arcsec(f64::from(end.x_rad[i] - reference_end.x_rad[i])).abs();
            let sigma = rad_to_arcsec(f64::from(reference_end.sigma_rad[i]));
            worst = worst.max(d / sigma);
            // The paper's method as published is left out of the bound: its estimate depends on
            // its whole history (a filter without process noise whose states stay nearly collinear
            // for hours), so that a restart, like any gap of a few rows early on, moves its end by
            // up to hundreds of arcsec (it ends 85-93 arcsec off on the paper scenario uncut).
            assert!(
                method == Method::Paper || d <= sigma,
                "{kind:?} {method:?}: cut {cut}: x{} ends {d} arcsec from the uncut run, whose 1-sigma is {sigma}",
                i + 1
            );
        }
    }
    println!("{kind:?} {method:?}: worst end difference {worst:.3} of the uncut run's 1-sigma");
    println!("{kind:?} {method:?} jitter {jitter_deg}: {n} samples, {} cuts, {faults} rotation-fault steps", images.len());
}

#[test]
fn paper_scenario_restarts_for_every_method() {
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        check(ScenarioKind::Paper, method, 0.0, 12);
    }
}

#[test]
fn sea_scenario_with_rotation_jitter_restarts() {
    check(ScenarioKind::Sea, Method::Windowed, 0.0, 12);
    check(ScenarioKind::Sea, Method::Windowed, 0.1, 12);
}

#[test]
fn turntable_scenario_restarts() {
    check(ScenarioKind::Turntable, Method::Windowed, 0.0, 8);
}
