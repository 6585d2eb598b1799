//! A ship's ordinary day, reduced lines of `bash scripts/sea-day-study.sh` (its figures in
//! docs/sea-day-study.md): slow heel and trim, heel in turns and rows lost at a cadence that
//! divides the rotation period, each on two seeds of 20,001 s of the sea scenario. What a
//! navigator relies on: the 1-sigma holds (some error beyond 3 sigma on at most 1 % of the rows
//! after the first estimate), and the estimate is never worse than the traditional baseline;
//! with heel in turns, within 10 arcsec from 1.25 periods on, through every turn.
//!
//! What the study shows and these lines do not assert (not met): no row beyond 5 sigma on every
//! line (the first estimates on a trim lie beyond it for tens of rows; the course weave's line
//! asserts it), within 10 arcsec by 6,000 s on the heel and trim of the first line.

use estimator_core::{Config, Method};
use host_sim::sim::scenario::ScenarioKind;
use host_sim::study::compare::{compare_one, CompareRow};
use host_sim::study::monte_carlo::Draw;

const SEEDS: usize = 2;
const DURATION_S: f64 = 20_001.0;

fn sea(shape: impl FnOnce(&mut Draw)) -> Draw {
    let mut d = Draw::new(ScenarioKind::Sea, 1);
    d.duration_s = Some(DURATION_S);
    shape(&mut d);
    d
}

fn line(draw: &Draw, method: Method) -> CompareRow {
    compare_one(draw, Config::with_method(method), SEEDS).unwrap()
}

/// Ours: at most 1 % of rows beyond 3 sigma, and at 20,000 s (p95 over the seeds) never worse
/// than the traditional baseline; returns our p95 worst error at 20,000 s and our line.
fn honest_and_never_worse(name: &str, draw: &Draw) -> (f64, CompareRow) {
    let ours = line(draw, Method::Windowed);
    let theirs = line(draw, Method::Traditional);
    let h = &ours.honesty;
    let beyond_3 = h.beyond_3_sigma_rows as f64 / h.rows.max(1) as f64;
    // The column at 20,000 s (the first is 2,000 s).
    let (a, b) = (ours.error_at_arcsec[1].1, theirs.error_at_arcsec[1].1);
    println!(
        "{name}: rows beyond 3 sigma {:.2} %, largest error/sigma {:.1}; p95 at 20000 s ours {a:.2}, traditional {b:.2} arcsec",
        100.0 * beyond_3,
        h.largest.map_or(f64::NAN, |l| l.ratio)
    );
    assert!(h.rows > 10_000, "{name}: {} rows judged", h.rows);
    assert!(
        beyond_3 <= 0.01,
        "{name}: {:.2} % of rows beyond 3 sigma",
        100.0 * beyond_3
    );
    assert!(
        a <= b,
        "{name}: {a:.2} arcsec against the traditional {b:.2}"
    );
    (a, ours)
}

#[test]
fn slow_heel_and_trim_keep_the_1_sigma_and_beat_the_traditional_baseline() {
    let draw = sea(|d| {
        d.ship_motion.slow_heel = vec![(0.3, 1200.0), (0.15, 2500.0)];
        d.ship_motion.slow_trim = vec![(0.1, 1800.0)];
    });
    let (error, _) = honest_and_never_worse(
        "heel 0.3 deg / 1200 s + 0.15 deg / 2500 s, trim 0.1 deg",
        &draw,
    );
    // The study's 3.3 arcsec at 20,000 s (one seed), with room for the second seed.
    assert!(error <= 6.0, "{error:.2} arcsec at 20000 s");
}

/// A trim alone leaks into x3, x4 through the joint filter; their 1-sigma carries the pitch pair's
/// share of their covariance at the pitch pair's noise scale, so it knows.
#[test]
fn a_trim_alone_keeps_the_1_sigma() {
    let draw = sea(|d| d.ship_motion.slow_trim = vec![(0.1, 1800.0)]);
    honest_and_never_worse("trim 0.1 deg / 1800 s", &draw);
}

#[test]
fn heel_in_turns_keeps_the_1_sigma_and_the_estimate() {
    let draw = sea(|d| d.mismatch.heel_in_turns_deg = 3.0);
    let (error, ours) = honest_and_never_worse("heel in turns 3 deg", &draw);
    // As without turns at 20,000 s: a few tenths of an arcsec.
    assert!(error <= 0.5, "{error:.2} arcsec at 20000 s");
    // As without turns: within 10 arcsec from 1.25 periods of the 480 s rotation on, through
    // every turn (p95 over the seeds).
    let settled_s = ours.to_arcsec_s.1;
    assert!(
        settled_s <= 1.25 * 480.0,
        "within 10 arcsec only from {settled_s} s"
    );
}

/// The first estimates too: until the turn channel has shown the heel, what it may have moved
/// x1..x4 by is in their 1-sigma (they lay hundreds of sigma off while it was not).
#[test]
fn a_heel_that_follows_the_course_weave_keeps_the_1_sigma() {
    let draw = sea(|d| d.ship_motion.heel_per_turn_rate_deg_per_deg_s = 4.0);
    let (_, ours) = honest_and_never_worse("heel 4 deg per deg/s of turn rate", &draw);
    let largest = ours.honesty.largest.map_or(f64::INFINITY, |l| l.ratio);
    assert!(largest <= 5.0, "an error {largest:.1} times its 1-sigma");
}

#[test]
fn rows_lost_at_a_cadence_that_divides_the_period_keep_the_1_sigma() {
    let draw = sea(|d| {
        d.rotation_period_s = Some(360.0);
        d.recorder.gap_every_s = 60.0;
        d.recorder.gap_rows = 3;
    });
    let (error, _) = honest_and_never_worse("3 rows lost every 60 s at 360 s", &draw);
    assert!(error <= 1.0, "{error:.2} arcsec at 20000 s");
}
