//! The reported 1-sigma is honest and the default method never loses to the traditional baseline,
//! pinned on reduced sea Monte Carlo runs (the full study: `bash scripts/coverage-study.sh 20` and
//! `bash scripts/mismatch-study.sh 10`, figures in docs/uncertainty.md).
//!
//! Coverage = share of (run, error) pairs with |error| <= k x the reported 1-sigma. With a few
//! dozen pairs a 2-sigma coverage near 0.95 cannot be told from 1.0, so the "not too
//! pessimistic" side is pinned on the 1-sigma coverage instead: about 0.68 when honest, 0.9 for a
//! 1-sigma 1.6 times too large (2-sigma coverage 0.9995), about 0.95 for one twice too large, as
//! the method reported before it learned the noise.

use estimator_core::{Config, Method};
use host_sim::report::accuracy::Accuracy;
use host_sim::sim::scenario::{Mismatch, ScenarioKind};
use host_sim::study::compare::{compare_one, CompareRow};
use host_sim::study::monte_carlo::{quantile, run_all, sorted, Draw};

const TIMES_S: [f64; 2] = [5_000.0, 45_000.0];

fn sea(mismatch: Mismatch, duration_s: f64) -> Draw {
    let mut d = Draw::new(ScenarioKind::Sea, 1);
    d.mismatch = mismatch;
    d.duration_s = Some(duration_s);
    d
}

/// Share of (run, error) pairs within `k` sigma at report time `t`.
fn coverage(results: &[Accuracy], t: usize, k: f64) -> f64 {
    let within: usize = results.iter().map(|r| r.points[t].within_sigmas(k)).sum();
    within as f64 / (4 * results.len()) as f64
}

/// 95th percentile over runs of the largest |error| of the four at report time `t`, arcsec.
fn p95_max_error(results: &[Accuracy], t: usize) -> f64 {
    let v = sorted(results.iter().map(|r| {
        r.points[t].error_arcsec.map_or(f64::INFINITY, |e| {
            e.iter().fold(0.0, |m, x| f64::max(m, x.abs()))
        })
    }));
    quantile(&v, 0.95)
}

fn windowed_runs(draw: &Draw, runs: usize) -> Vec<Accuracy> {
    run_all(draw, Config::default(), runs, &TIMES_S, &|| {}).unwrap()
}

#[test]
fn clean_sea_one_sigma_is_neither_optimistic_nor_pessimistic() {
    let r = windowed_runs(&sea(Mismatch::default(), 45_001.0), 20);
    for (t, time) in TIMES_S.iter().enumerate() {
        let (c1, c2) = (coverage(&r, t, 1.0), coverage(&r, t, 2.0));
        println!(
            "clean, {time} s: within 1 sigma {c1:.3}, within 2 sigma {c2:.3}, p95 {:.3} arcsec",
            p95_max_error(&r, t)
        );
        assert!(
            c2 >= 0.9,
            "{time} s: only {c2:.3} of the errors within 2 sigma: the 1-sigma is too small"
        );
        assert!(
            c1 <= 0.9,
            "{time} s: {c1:.3} of the errors within 1 sigma: the 1-sigma is too large"
        );
    }
    // Accuracy as before the noise and drift were learned (sea p95 at most 0.5 arcsec by 5000 s).
    assert!(
        p95_max_error(&r, 0) <= 0.5,
        "p95 at 5000 s {:.3} arcsec",
        p95_max_error(&r, 0)
    );
}

#[test]
fn errors_drifting_20_arcsec_a_day_are_followed_within_2_arcsec_and_covered() {
    let mismatch = Mismatch {
        error_drift_arcsec_per_day: 20.0,
        ..Mismatch::default()
    };
    let r = windowed_runs(&sea(mismatch, 45_001.0), 10);
    let (c2, p95) = (coverage(&r, 1, 2.0), p95_max_error(&r, 1));
    println!("drift 20 arcsec/day, 45000 s: within 2 sigma {c2:.3}, p95 {p95:.3} arcsec");
    assert!(p95 <= 2.0, "p95 at 45000 s {p95:.3} arcsec");
    assert!(
        c2 >= 0.8,
        "only {c2:.3} of the errors within 2 sigma at 45000 s"
    );
}

fn line(mismatch: Mismatch, method: Method, seeds: usize) -> CompareRow {
    compare_one(&sea(mismatch, 45_001.0), Config::with_method(method), seeds).unwrap()
}

/// p95 over seeds of the largest |error| at 20000 s and 45000 s: ours at most the traditional
/// baseline's, and ours covered at least 0.8 of the time at 2 sigma.
fn never_worse_than_traditional(name: &str, mismatch: Mismatch, seeds: usize) {
    let ours = line(mismatch, Method::Windowed, seeds);
    let theirs = line(mismatch, Method::Traditional, seeds);
    // The columns at 20000 s and 45000 s (the first is 2000 s).
    for k in 1..3 {
        let (a, b) = (ours.error_at_arcsec[k].1, theirs.error_at_arcsec[k].1);
        println!("{name}, column {k}: p95 ours {a:.3}, traditional {b:.3} arcsec; ours within 2 sigma {:.3}", ours.coverage_2sigma[k]);
        assert!(
            a <= b,
            "{name}: p95 {a:.3} arcsec against the traditional baseline's {b:.3}"
        );
        assert!(
            ours.coverage_2sigma[k] >= 0.8,
            "{name}: only {:.3} within 2 sigma",
            ours.coverage_2sigma[k]
        );
    }
}

#[test]
fn coloured_noise_never_worse_than_traditional() {
    never_worse_than_traditional(
        "coloured noise 20 arcsec",
        Mismatch {
            coloured_noise_arcsec: 20.0,
            ..Mismatch::default()
        },
        8,
    );
}

#[test]
fn other_mismatch_effects_never_worse_than_traditional() {
    let effects = [
        (
            "period 0.5 % off",
            Mismatch {
                rotation_period_error: 0.005,
                ..Mismatch::default()
            },
        ),
        (
            "rotation jitter 0.05 deg",
            Mismatch {
                rotation_jitter_deg: 0.05,
                ..Mismatch::default()
            },
        ),
        (
            "drift 20 arcsec/day",
            Mismatch {
                error_drift_arcsec_per_day: 20.0,
                ..Mismatch::default()
            },
        ),
        (
            "low-frequency rate 20 % off",
            Mismatch {
                low_frequency_rate_error: 0.2,
                ..Mismatch::default()
            },
        ),
    ];
    for (name, m) in effects {
        never_worse_than_traditional(name, m, 3);
    }
}
