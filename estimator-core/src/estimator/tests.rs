//! The estimator's own tests: rejection leaves the state untouched, reinit equals new, gaps and
//! rotation faults.

use super::*;
use crate::gap_fill::DELAY;
use crate::synthetic::Signal;
use crate::units::{rad_to_arcsec, RAD_PER_DEG};
use crate::Field;
use std::vec::Vec;

const X_ARCSEC: [f64; 4] = [200.0, -150.0, 300.0, -250.0];

/// Sway plus eq (2)'s oscillation at time `t`: one-way 480 s rotation, 40 deg latitude, roll sway
/// of `roll_sway_deg` and 6 s, 1 deg pitch sway of 9 s, no low-frequency error, no noise. The
/// oscillation is `synthetic`'s f64 eq (2), independent of the core's f32 rows.
fn sample(t: f64, roll_sway_deg: f64) -> Sample {
    let mut signal = Signal::new(X_ARCSEC, 40.0);
    signal.rotation_phase_rad = 0.3;
    signal.platform_phase_rad = 1.1;
    signal.heading_rad = 10.0 * RAD_PER_DEG;
    signal.roll_sway_deg = roll_sway_deg;
    signal.pitch_sway_phase_rad = 0.0;
    signal.low_frequency_deg = 0.0;
    signal.sample(t)
}

fn errors_arcsec(est: &Estimator) -> [f64; 4] {
    let e = est.estimate().unwrap();
    core::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - X_ARCSEC[i])
}

#[test]
fn bad_samples_are_rejected_by_reason_and_change_nothing_else() {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    for k in 0..1000 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    let good = sample(1000.0, 3.0);
    let mut bad = std::vec::Vec::new();
    let mut nan_roll = good;
    nan_roll.attitude.roll_rad = Real::NAN;
    bad.push((nan_roll, SampleError::NonFinite(Field::Roll)));
    let mut inf_time = good;
    inf_time.time_s = f64::INFINITY;
    bad.push((inf_time, SampleError::NonFinite(Field::Time)));
    let mut inf_rot = good;
    inf_rot.rotation_rad = Real::NEG_INFINITY;
    bad.push((inf_rot, SampleError::NonFinite(Field::Rotation)));
    bad.push((
        Sample::from_degrees(1000.0, 1.0, 1.0, 90.0, 1.0, 1.0, 1.0),
        SampleError::LatitudeOutOfRange,
    ));
    bad.push((
        Sample::from_degrees(1000.0, 1.0, 1.0, -95.0, 1.0, 1.0, 1.0),
        SampleError::LatitudeOutOfRange,
    ));
    bad.push((
        Sample::from_degrees(1000.0, 1.0, 1.0, 40.0, 1.0, 120.0, 1.0),
        SampleError::AngleOutOfRange(Field::Roll),
    ));
    let mut huge_platform = good;
    huge_platform.platform_rad = 1e6;
    bad.push((huge_platform, SampleError::AngleOutOfRange(Field::Platform)));
    let mut back = good;
    back.time_s = 998.0;
    bad.push((back, SampleError::TimeNotIncreasing));
    let mut same = good;
    same.time_s = 999.0;
    bad.push((same, SampleError::TimeNotIncreasing));
    let mut close = good;
    close.time_s = 999.3;
    bad.push((close, SampleError::IrregularTimeStep));
    for (s, expected) in bad {
        let before = est.clone();
        assert_eq!(est.step(&s), Err(expected));
        let counted = est.run.rejected.of(expected.reason());
        assert_eq!(counted, before.run.rejected.of(expected.reason()) + 1);
        let mut restored = est.clone();
        restored.run.rejected = before.run.rejected;
        assert!(restored == before, "state changed by {expected:?}");
    }
    assert_eq!(est.rejected().total(), 10);
    assert!(est.step(&good).is_ok());
}

/// Runs 8000 s, dropping sample `k` where `drop(k)`; returns the estimate errors of a plain and
/// of the gappy run, the gappy run's counters and its 1-sigma.
fn gappy_run(
    config: Config,
    drop: impl Fn(u32) -> bool,
) -> ([f64; 4], [f64; 4], Counters, [f64; 4]) {
    let mut plain: Estimator = Estimator::new(Config::default()).unwrap();
    let mut gappy: Estimator = Estimator::new(config).unwrap();
    for k in 0..8000u32 {
        let s = sample(k as f64, 3.0);
        plain.step(&s).unwrap();
        if !drop(k) {
            let out = gappy.step(&s).unwrap();
            assert!(
                k < 2000 || matches!(out.status, Status::Estimating | Status::Converged),
                "{k}: {:?}",
                out.status
            );
        }
    }
    let sigma = gappy
        .estimate()
        .unwrap()
        .sigma_rad
        .map(|s| rad_to_arcsec(s as f64));
    (
        errors_arcsec(&plain),
        errors_arcsec(&gappy),
        gappy.counters(),
        sigma,
    )
}

/// One or two samples lost every ~15 min: filled, the window never restarts, and the estimates
/// move by what the interpolation errors carry. The 10-point interpolation of a 3 deg, 6 s
/// roll is 0.4 % (43 arcsec) off for one lost sample, 2 % for two; each filled sample's error
/// enters the filter's average over ~7500 updates once (it passes through 480 windows of
/// 1/480 weight), 0.006 arcsec for one, 0.03 for two, times 2 / cos L = 2.6 on x3, x4: with 8
/// single and 3 double gaps (and one unfilled pair), up to about 0.3 arcsec if they all add up.
/// (Restarting the window instead cost nothing here, but never estimates through frequent loss.)
#[test]
fn short_gaps_are_filled_and_cost_little_accuracy() {
    let (a, b, counters, _) = gappy_run(Config::default(), |k| k % 907 == 5 || k % 1814 == 6);
    assert_eq!(counters.window_restarts, 0);
    // 14 lost, of which the two at 5 and 6 s fall in the first 9 samples, from which the
    // sample interval is learned (nothing is estimated from those).
    assert_eq!(counters.filled, 12);
    for i in 0..4 {
        assert!(
            (a[i] - b[i]).abs() < 0.3,
            "x{}: plain {:.3}, gappy {:.3}",
            i + 1,
            a[i],
            b[i]
        );
    }
}

/// A sample lost every 97 s: the window never holds a gap, estimation never stops, and the
/// accuracy stays within a few tenths of an arcsec of the plain run, inside the 1-sigma.
#[test]
fn frequent_drops_cost_accuracy_never_the_estimate() {
    let (a, b, counters, sigma) = gappy_run(Config::default(), |k| k % 97 == 5);
    assert_eq!(counters.window_restarts, 0);
    for i in 0..4 {
        assert!(
            (a[i] - b[i]).abs() < 0.3,
            "x{}: plain {:.3}, gappy {:.3}",
            i + 1,
            a[i],
            b[i]
        );
        assert!(
            b[i].abs() < 3.0 * sigma[i],
            "x{}: error {:.3} vs 1-sigma {:.3}",
            i + 1,
            b[i],
            sigma[i]
        );
    }
}

/// With filling switched off, a lost row is left out of the sums with the taper around it: the
/// window does not restart and nothing is filled.
#[test]
fn without_filling_a_lost_row_is_left_out() {
    let none = Config {
        max_filled_gap_samples: 0,
        ..Config::default()
    };
    let mut est: Estimator = Estimator::new(none).unwrap();
    for k in 0..3000u32 {
        if k != 2500 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
    }
    assert_eq!(
        (est.counters().window_restarts, est.counters().filled),
        (0, 0)
    );
    for (i, e) in errors_arcsec(&est).iter().enumerate() {
        assert!(e.abs() < 1.0, "x{}: {e:.3}", i + 1);
    }
}

/// Runs of 10 lost rows every 120 s (8 % of rows) and of 40 every 1000 s: left out with the taper,
/// never a restart, the estimates never stop, and within a few tenths of an arcsec of the plain
/// run.
#[test]
fn runs_of_lost_rows_shorter_than_an_eighth_of_a_period_are_left_out() {
    let (a, b, counters, sigma) = gappy_run(Config::default(), |k| {
        k % 120 < 10 || (k % 1000 >= 700 && k % 1000 < 740)
    });
    assert_eq!(counters.window_restarts, 0);
    for i in 0..4 {
        assert!(
            (a[i] - b[i]).abs() < 0.3,
            "x{}: plain {:.3}, gappy {:.3}",
            i + 1,
            a[i],
            b[i]
        );
        assert!(
            b[i].abs() < 3.0 * sigma[i],
            "x{}: error {:.3} vs 1-sigma {:.3}",
            i + 1,
            b[i],
            sigma[i]
        );
    }
}

#[test]
fn a_long_gap_restarts_the_window_and_holds_the_estimates() {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    for k in 0..2000u32 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    // 300 s missing: more than an eighth of the period, the window restarts once the samples
    // before the gap, still in the filler's delay line, have gone through it.
    let mut k = 2300u32;
    est.step(&sample(k as f64, 3.0)).unwrap();
    while est.counters().window_restarts == 0 {
        k += 1;
        est.step(&sample(k as f64, 3.0)).unwrap();
        assert!(
            k <= 2300 + DELAY,
            "the gap reaches the window within the delay"
        );
    }
    let held = est.estimate().unwrap();
    while est.step(&sample((k + 1) as f64, 3.0)).unwrap().status == Status::Holding {
        k += 1;
        assert_eq!(
            est.estimate().unwrap(),
            held,
            "estimates moved while holding"
        );
    }
    assert_eq!(
        k + 1,
        2300 + 479 + DELAY,
        "refilled after one window and the filler's delay"
    );
    for t in (k + 2)..6000 {
        est.step(&sample(t as f64, 3.0)).unwrap();
    }
    for (i, e) in errors_arcsec(&est).iter().enumerate() {
        assert!(e.abs() < 1.0, "x{}: {e:.3}", i + 1);
    }
}

#[test]
fn sway_gate_waits_for_enough_roll() {
    let config = Config {
        sway_gate_rad: (3.0 * RAD_PER_DEG) as Real,
        ..Config::default()
    };
    let mut est: Estimator = Estimator::new(config).unwrap();
    for k in 0..1000u32 {
        let out = est.step(&sample(k as f64, 2.0)).unwrap();
        assert_eq!(out.status, Status::WaitingForSway);
        assert!(out.estimate.is_none());
    }
    let mut opened_at = None;
    for k in 1000..4000u32 {
        let out = est.step(&sample(k as f64, 4.0)).unwrap();
        if opened_at.is_none() && out.status != Status::WaitingForSway {
            opened_at = Some(k);
        }
    }
    let opened_at = opened_at.unwrap();
    assert!(
        opened_at > 1000 && opened_at < 1100,
        "gate opened at {opened_at}"
    );
    for (i, e) in errors_arcsec(&est).iter().enumerate() {
        assert!(e.abs() < 1.5, "x{}: {e:.3}", i + 1);
    }
}

/// `reinit` (behind `reset` and checkpoint restore) and `new` give the same estimator, for every
/// method, from a used estimator of the same or another method.
#[test]
fn reinit_equals_new() {
    use crate::config::Method;
    let methods = [Method::Windowed, Method::Paper, Method::Traditional];
    for from in methods {
        for to in methods {
            let mut est: Estimator = Estimator::new(Config::with_method(from)).unwrap();
            for k in 0..700 {
                est.step(&sample(k as f64, 3.0)).unwrap();
            }
            let config = Config {
                rotation_period_s: Some(300.0),
                sway_gate_rad: 0.01,
                ..Config::with_method(to)
            };
            est.reinit(config).unwrap();
            assert!(est == Estimator::new(config).unwrap(), "{from:?} -> {to:?}");
        }
    }
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    for k in 0..700 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    let before = est.clone();
    let bad = Config {
        rotation_period_s: Some(4000.0),
        ..Config::default()
    };
    assert_eq!(
        est.reinit(bad),
        Err(ConfigError::RotationPeriod { value_s: 4000.0 })
    );
    assert!(
        est == before,
        "a refused configuration changed the estimator"
    );
}

#[test]
fn init_in_equals_new_and_refuses_what_new_refuses() {
    use crate::config::Method;
    use core::mem::MaybeUninit;
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        let config = Config {
            rotation_period_s: Some(300.0),
            sway_gate_rad: 0.01,
            ..Config::with_method(method)
        };
        let mut slot: std::boxed::Box<MaybeUninit<Estimator>> =
            std::boxed::Box::new(MaybeUninit::uninit());
        let est = Estimator::init_in(&mut slot, config).unwrap();
        assert!(*est == Estimator::new(config).unwrap(), "{method:?}");
        // And it runs as one.
        for k in 0..700 {
            est.step(&sample(k as f64, 3.0)).unwrap();
        }
    }
    let mut slot: std::boxed::Box<MaybeUninit<Estimator>> =
        std::boxed::Box::new(MaybeUninit::uninit());
    let bad = Config {
        rotation_period_s: Some(4000.0),
        ..Config::default()
    };
    assert_eq!(
        Estimator::init_in(&mut slot, bad).err(),
        Some(ConfigError::RotationPeriod { value_s: 4000.0 })
    );
}

#[test]
fn reset_forgets_all_but_the_configuration_and_rejections() {
    let config = Config {
        rotation_period_s: Some(300.0),
        ..Config::default()
    };
    let mut est: Estimator = Estimator::new(config).unwrap();
    for k in 0..700 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    // A repeated time stamp.
    assert!(est.step(&sample(699.0, 3.0)).is_err());
    let rejected = est.rejected();
    est.reset();
    let mut fresh: Estimator = Estimator::new(config).unwrap();
    fresh.run.rejected = rejected;
    assert!(est == fresh);
}

#[test]
fn covariance_stays_symmetric_positive_definite_over_two_days() {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    for k in 0..172_800u32 {
        est.step(&sample(k as f64, 3.0)).unwrap();
        if k % 3600 == 0 || k == 172_799 {
            let w = est.windowed().expect("default is windowed");
            if w.updates() > 0 {
                assert!(w.filter().covariance_is_spd(), "not SPD at {k} s");
            }
        }
    }
    for (i, e) in errors_arcsec(&est).iter().enumerate() {
        assert!(e.abs() < 0.5, "x{}: {e:.3}", i + 1);
    }
}

/// One row of [`stepped_run`]: time, status, and the estimate's errors against the truth.
type SteppedRow = (f64, Status, Option<[f64; 4]>);

/// A 16,000 s log of the paper's sway with 5 arcsec of noise, whose errors step at 12,000 s by
/// `step_arcsec`; per row the estimator's status and, once there is one, the estimate's errors
/// against the errors in force. Returns the rows and the estimator at the end.
fn stepped_run(config: Config, step_arcsec: [f64; 4]) -> (Vec<SteppedRow>, Estimator) {
    let after: [f64; 4] = core::array::from_fn(|i| X_ARCSEC[i] + step_arcsec[i]);
    let mut signal = Signal::new(X_ARCSEC, 40.0).with_seed(11);
    signal.noise_arcsec = 5.0;
    let mut est: Estimator = Estimator::new(config).unwrap();
    let mut rows = Vec::new();
    for k in 0..16_000u32 {
        let t = f64::from(k);
        if k == 12_000 {
            signal.x_arcsec = after;
        }
        let out = est.step(&signal.sample(t)).unwrap();
        let errors = out.estimate.map(|e| {
            core::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - signal.x_arcsec[i])
        });
        rows.push((t, out.status, errors));
    }
    (rows, est)
}

#[test]
fn a_step_of_the_errors_is_declared_reported_and_learned_again() {
    let step = [0.0, 40.0, -25.0, 0.0];
    let (rows, est) = stepped_run(Config::default(), step);
    let change = est.error_change().expect("a change declared");
    // Declared within 3.5 periods, x2 and x3 learned again (other errors may be too: they are
    // learned from the same block).
    assert!(
        change.detected_s > 12_000.0 && change.detected_s <= 12_000.0 + 3.5 * 480.0,
        "{change:?}"
    );
    assert!(change.relearned[1] && change.relearned[2], "{change:?}");
    assert!(
        change.seen_since_s > 12_000.0 - 480.0 && change.seen_since_s < change.detected_s,
        "{change:?}"
    );
    // Said so in the status, from the detection, once; then estimating again.
    let changed: Vec<f64> = rows
        .iter()
        .filter(|r| r.1 == Status::ErrorsChanged)
        .map(|r| r.0)
        .collect();
    assert_eq!(changed.first(), Some(&change.detected_s));
    assert!(
        changed.windows(2).all(|w| w[1] == w[0] + 1.0),
        "one run of errors_changed: {changed:?}"
    );
    assert!(
        matches!(
            rows.last().unwrap().1,
            Status::Estimating | Status::Converged
        ),
        "{:?}",
        rows.last()
    );
    // Every error within 10 arcsec of the new values from 2,000 s after the step on, within 1 at
    // the end; before the step, nothing was declared.
    for (t, _, e) in rows.iter().filter(|r| r.0 >= 14_000.0) {
        assert!(e.unwrap().iter().all(|v| v.abs() < 10.0), "{t}: {e:?}");
    }
    assert!(
        rows.last()
            .unwrap()
            .2
            .unwrap()
            .iter()
            .all(|v| v.abs() < 1.0),
        "{:?}",
        rows.last()
    );
    assert!(rows
        .iter()
        .all(|r| r.0 >= 12_000.0 || r.1 != Status::ErrorsChanged));
    // Latched: long after the `errors_changed` rows, every output still says that a change was
    // declared, and when.
    let health = est.health();
    assert_eq!(health.changes_detected, 1);
    assert_eq!(health.last_change_s, Some(change.detected_s));
    assert_eq!(health.window_restarts, 0);
    assert!(health.residual_rad.is_some() && health.noise_scale.is_some());

    // Detection off: nothing declared, and 2,000 s after the step x2 is still off by more than
    // 10 arcsec (the filter's memory is the whole log).
    let off = Config {
        change_detection_step_rad: 0.0,
        ..Config::default()
    };
    let (rows, est) = stepped_run(off, step);
    assert_eq!(est.error_change(), None);
    assert_eq!(
        (est.health().changes_detected, est.health().last_change_s),
        (0, None)
    );
    assert!(rows.iter().all(|r| r.1 != Status::ErrorsChanged));
    let at_14000 = rows[14_000].2.unwrap();
    assert!(at_14000[1].abs() > 10.0, "{at_14000:?}");
}

#[test]
fn clock_steps_are_counted() {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    for k in 0..200 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    assert_eq!(est.counters().clock_steps, 0);
    // A step back of 5 s (more than two intervals) and a jump forwards off the grid (a whole
    // number of intervals forwards is a gap, not a step of the clock), seen at the second stamp
    // off the grid (one stamp off may be jitter).
    est.step(&sample(194.0, 3.0)).unwrap();
    for k in 195..300 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    est.step(&sample(3900.5, 3.0)).unwrap();
    assert_eq!(est.counters().clock_steps, 1);
    est.step(&sample(3901.5, 3.0)).unwrap();
    assert_eq!(est.counters().clock_steps, 2);
}

/// Compensation between steps: before the first estimate it has none to apply; from then on, a
/// sample compensated after its step comes back exactly as the step corrected it, bit for bit,
/// and a sample at a time between the grid's (as a 100 Hz feed gives) has the oscillation of
/// eq (2) removed to within the estimate's error; a bad sample is refused by its field and
/// nothing changes.
#[test]
fn compensate_applies_the_current_estimate_without_stepping() {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let first = sample(0.0, 3.0);
    assert_eq!(est.compensate(&first), Err(CompensateError::NoEstimate));
    let mut compensated = 0;
    for k in 0..3000 {
        let s = sample(k as f64, 3.0);
        let out = est.step(&s).unwrap();
        let before = est.clone();
        match (out.estimate, est.compensate(&s)) {
            (None, Err(CompensateError::NoEstimate)) => {}
            (Some(_), Ok(a)) => {
                compensated += 1;
                assert_eq!(a.heading_rad.to_bits(), out.corrected.heading_rad.to_bits());
                assert_eq!(a.roll_rad.to_bits(), out.corrected.roll_rad.to_bits());
                assert_eq!(a.pitch_rad.to_bits(), out.corrected.pitch_rad.to_bits());
            }
            (e, c) => panic!("at {k} s: estimate {e:?}, compensate {c:?}"),
        }
        assert!(est == before, "compensate changed the estimator at {k} s");
    }
    assert!(compensated > 2000, "{compensated} samples compensated");
    // Between the grid's samples: 100 samples in the next second, without their sway (the
    // attitude is eq (2)'s oscillation alone): what remains is the estimate's error's share.
    let error_sum_rad =
        errors_arcsec(&est).iter().map(|e| e.abs()).sum::<f64>() / crate::units::ARCSEC_PER_RAD;
    for i in 0..100 {
        let t = 2999.0 + i as f64 * 0.01;
        let mut s = sample(t, 0.0);
        let sway = {
            let mut zero = Signal::new([0.0; 4], 40.0);
            zero.rotation_phase_rad = 0.3;
            zero.platform_phase_rad = 1.1;
            zero.heading_rad = 10.0 * RAD_PER_DEG;
            zero.roll_sway_deg = 0.0;
            zero.pitch_sway_phase_rad = 0.0;
            zero.low_frequency_deg = 0.0;
            zero.sample(t)
        };
        s.attitude.roll_rad -= sway.attitude.roll_rad;
        s.attitude.pitch_rad -= sway.attitude.pitch_rad;
        let a = est.compensate(&s).unwrap();
        // Eq (2)'s rows times the estimate's errors: each entry of a row is at most 1 in size.
        let bound = error_sum_rad as Real + 1e-9;
        assert!(a.roll_rad.abs() <= bound, "roll {} at {t} s", a.roll_rad);
        assert!(a.pitch_rad.abs() <= bound, "pitch {} at {t} s", a.pitch_rad);
    }
    let before = est.clone();
    let mut bad = sample(3000.0, 3.0);
    bad.attitude.pitch_rad = Real::NAN;
    assert_eq!(
        est.compensate(&bad),
        Err(CompensateError::Rejected(SampleError::NonFinite(
            Field::Pitch
        )))
    );
    assert!(est == before);
}

/// Known values: with a prior, the estimate (and the compensation) is there from the first
/// sample, the prior's own values and 1-sigma until the first measurement; the measurements then
/// take it to the truth, as without. A prior out of its bounds is refused.
#[test]
fn a_prior_is_reported_from_the_first_sample_and_learned_past() {
    let off_arcsec = [8.0, -6.0, 5.0, -7.0];
    let prior = crate::Prior {
        x_rad: core::array::from_fn(|i| {
            ((X_ARCSEC[i] + off_arcsec[i]) / crate::units::ARCSEC_PER_RAD) as Real
        }),
        sigma_rad: [(10.0 / crate::units::ARCSEC_PER_RAD) as Real; 4],
    };
    let config = Config {
        prior: Some(prior),
        ..Config::default()
    };
    let mut est: Estimator = Estimator::new(config).unwrap();
    let out = est.step(&sample(0.0, 3.0)).unwrap();
    let e = out.estimate.expect("the prior from the first sample");
    assert_eq!((e.x_rad, e.sigma_rad), (prior.x_rad, prior.sigma_rad));
    assert!(est.compensate(&sample(0.5, 3.0)).is_ok());
    // Without a prior: nothing until the first measurement.
    let mut fresh: Estimator = Estimator::new(Config::default()).unwrap();
    assert!(fresh.step(&sample(0.0, 3.0)).unwrap().estimate.is_none());
    for k in 1..3000 {
        let s = sample(k as f64, 3.0);
        let out = est.step(&s).unwrap();
        assert!(out.estimate.is_some(), "no estimate at {k} s");
        fresh.step(&s).unwrap();
    }
    let with = errors_arcsec(&est);
    let without = errors_arcsec(&fresh);
    for i in 0..4 {
        assert!(with[i].abs() < 1.0, "x{} {} arcsec off", i + 1, with[i]);
        assert!(
            without[i].abs() < 1.0,
            "x{} {} arcsec off without",
            i + 1,
            without[i]
        );
    }
    // Bounds: each 1-sigma positive and within the configuration's prior; each value within a
    // radian.
    let mut bad = config;
    bad.prior = Some(crate::Prior {
        sigma_rad: [
            prior.sigma_rad[0],
            0.0,
            prior.sigma_rad[2],
            prior.sigma_rad[3],
        ],
        ..prior
    });
    assert!(matches!(
        Estimator::<720>::new(bad),
        Err(ConfigError::Parameter {
            name: "prior.sigma_rad[1]",
            ..
        })
    ));
    bad.prior = Some(crate::Prior {
        sigma_rad: [2.0 * config.prior_sigma_rad; 4],
        ..prior
    });
    assert!(Estimator::<720>::new(bad).is_err());
    bad.prior = Some(crate::Prior {
        x_rad: [0.0, 0.0, 1.5, 0.0],
        ..prior
    });
    assert!(matches!(
        Estimator::<720>::new(bad),
        Err(ConfigError::Parameter {
            name: "prior.x_rad[2]",
            ..
        })
    ));
}

/// A rotation angle measured 0.2 s before the attitude (a 480 s rotation: 0.15 deg behind):
/// with the latency configured the estimate is that of a log without the lag within 0.1 arcsec;
/// left unset, it is off by more (the rotation terms' phase error times the errors' size). A
/// latency out of its bounds is refused.
#[test]
fn a_rotation_angle_that_lags_is_carried_forward() {
    const LAG_S: f64 = 0.2;
    let run = |lag_s: f64, latency_s: f64| {
        let config = Config {
            angle_latency_s: latency_s,
            ..Config::default()
        };
        let mut est: Estimator = Estimator::new(config).unwrap();
        for k in 0..6000 {
            let t = k as f64;
            let mut s = sample(t, 3.0);
            s.rotation_rad = sample(t - lag_s, 3.0).rotation_rad;
            est.step(&s).unwrap();
        }
        errors_arcsec(&est)
    };
    let exact = run(0.0, 0.0);
    let set = run(LAG_S, LAG_S);
    let unset = run(LAG_S, 0.0);
    let worst = |a: [f64; 4], b: [f64; 4]| (0..4).fold(0.0f64, |m, i| m.max((a[i] - b[i]).abs()));
    assert!(worst(set, exact) < 0.1, "set: {set:?} against {exact:?}");
    // 0.15 deg of phase on errors of 150-300 arcsec: about 0.4-0.8 arcsec.
    assert!(
        worst(unset, exact) > 0.3,
        "unset: {unset:?} against {exact:?}"
    );
    for bad in [-0.1, 1.5, f64::NAN] {
        let config = Config {
            angle_latency_s: bad,
            ..Config::default()
        };
        assert!(
            matches!(
                Estimator::<720>::new(config),
                Err(ConfigError::Parameter {
                    name: "angle_latency_s",
                    ..
                })
            ),
            "{bad}"
        );
    }
}

/// The prior and the latency are part of the configuration a checkpoint keeps.
#[test]
fn a_checkpoint_keeps_the_prior_and_the_latency() {
    let config = Config {
        prior: Some(crate::Prior {
            x_rad: [1e-4, -2e-4, 3e-4, -4e-4],
            sigma_rad: [1e-5, 2e-5, 3e-5, 4e-5],
        }),
        angle_latency_s: 0.25,
        ..Config::default()
    };
    let mut est: Estimator = Estimator::new(config).unwrap();
    for k in 0..700 {
        est.step(&sample(k as f64, 3.0)).unwrap();
    }
    let mut image = std::vec![0u8; crate::checkpoint::CHECKPOINT_LEN];
    est.checkpoint(&mut image).unwrap();
    let back: Estimator = Estimator::from_checkpoint(&image).unwrap();
    assert_eq!(back.config(), &config);
}
