//! Logs stamped on receipt: every stamp jittered independently by up to +-0.45 of the interval
//! (`host-sim generate --time-jitter`). Each stamp still names its slot on the grid, so the
//! estimates are those of the same log with exact stamps, the interval learned or pinned, with no
//! window restart and no clock step.

use estimator_core::{Config, Counters, Estimator};
use host_sim::replay::sample_of;
use host_sim::report::accuracy::errors_arcsec;
use host_sim::sim::recorder::{Recorder, RecorderSettings};
use host_sim::sim::samples::Samples;
use host_sim::sim::scenario::{ScenarioKind, ScenarioParams};

/// The estimates (arcsec) at `at_s` and at the end of a sea log of `duration_s` with rows every
/// `interval_s` stamped with `jitter_s` of jitter, and the counters at the end.
fn replay(
    interval_s: f64,
    duration_s: f64,
    jitter_s: f64,
    pinned: bool,
    at_s: f64,
) -> ([[f64; 4]; 2], Counters) {
    let seed = 1;
    let mut p = ScenarioParams::new(ScenarioKind::Sea, seed);
    p.duration_s = duration_s;
    p.sample_interval_s = interval_s;
    p.recording = RecorderSettings {
        time_jitter_s: jitter_s,
        ..RecorderSettings::default()
    }
    .recording(seed, duration_s, interval_s)
    .unwrap();
    let config = Config {
        sample_interval_s: pinned.then_some(interval_s),
        ..Config::default()
    };
    let mut est: Estimator = Estimator::new(config).unwrap();
    let mut recorder = Recorder::new(&p.recording, seed, interval_s);
    let mut at = None;
    for (row, _) in Samples::new(&p) {
        let logged = recorder.record(&row).expect("no row lost");
        est.step(&sample_of(&logged))
            .expect("every jittered stamp is accepted");
        if at.is_none() && row.time_s >= at_s {
            at = est.estimate();
        }
    }
    let x = |e: Option<estimator_core::Estimate>| {
        errors_arcsec(Some(&e.expect("an estimate")), &[0.0; 4]).expect("an estimate")
    };
    ([x(at), x(est.estimate())], est.counters())
}

fn assert_as_exact(interval_s: f64, duration_s: f64, jitter_s: f64, at_s: f64) {
    for pinned in [false, true] {
        let (exact, _) = replay(interval_s, duration_s, 0.0, pinned, at_s);
        let (jittered, counters) = replay(interval_s, duration_s, jitter_s, pinned, at_s);
        assert_eq!(
            (counters.window_restarts, counters.clock_steps),
            (0, 0),
            "{interval_s} s, +-{jitter_s} s, pinned {pinned}: {counters:?}"
        );
        for (k, when) in [at_s, duration_s].iter().enumerate() {
            for i in 0..4 {
                let d = (jittered[k][i] - exact[k][i]).abs();
                assert!(
                    d < 0.1,
                    "{interval_s} s, +-{jitter_s} s, pinned {pinned}: x{} at {when} s {} arcsec, exact stamps {}",
                    i + 1,
                    jittered[k][i],
                    exact[k][i]
                );
            }
        }
    }
}

#[test]
fn a_1_hz_sea_log_jittered_by_045_s_estimates_as_with_exact_stamps() {
    assert_as_exact(1.0, 20_000.0, 0.45, 10_000.0);
}

#[test]
fn a_10_hz_sea_log_jittered_by_0045_s_estimates_as_with_exact_stamps() {
    assert_as_exact(0.1, 5_000.0, 0.045, 2_500.0);
}

/// A 10 Hz sea log (a period of 480 s needs bins of 8 samples in the 720-entry window) gives its
/// first estimate 1.25 periods after its first row, as a 1 Hz log does, with exact stamps and
/// stamps jittered by +-0.045 s: the window bins its samples as the expected period needs while
/// the period is learned, and keeps them when it comes. The first estimate is within 10 arcsec
/// and within 3 sigma of the truth.
#[test]
fn a_10_hz_log_gives_its_first_estimate_at_125_periods_as_at_1_hz() {
    let (interval_s, period_s) = (0.1, 480.0);
    for jitter_s in [0.0, 0.045] {
        let seed = 2;
        let mut p = ScenarioParams::new(ScenarioKind::Sea, seed);
        p.duration_s = 700.0;
        p.sample_interval_s = interval_s;
        p.recording = RecorderSettings {
            time_jitter_s: jitter_s,
            ..RecorderSettings::default()
        }
        .recording(seed, p.duration_s, interval_s)
        .unwrap();
        let mut est: Estimator = Estimator::new(Config::default()).unwrap();
        let mut recorder = Recorder::new(&p.recording, seed, interval_s);
        let mut first = None;
        for (row, truth) in Samples::new(&p) {
            let logged = recorder.record(&row).expect("no row lost");
            let out = est.step(&sample_of(&logged)).expect("accepted");
            if let (None, Some(e)) = (first, out.estimate) {
                first = Some((row.time_s, e, truth.errors_arcsec));
            }
        }
        let (at_s, e, x) = first.expect("an estimate within 700 s");
        assert!(
            at_s <= 1.25 * period_s + 1.0,
            "+-{jitter_s} s: first estimate at {at_s} s"
        );
        let errors = errors_arcsec(Some(&e), &x).expect("an estimate");
        for i in 0..4 {
            let sigma = estimator_core::units::rad_to_arcsec(f64::from(e.sigma_rad[i]));
            assert!(
                errors[i].abs() < 10.0 && errors[i].abs() < 3.0 * sigma,
                "+-{jitter_s} s: x{} {} arcsec off at {at_s} s, 1-sigma {sigma}",
                i + 1,
                errors[i]
            );
        }
    }
}
