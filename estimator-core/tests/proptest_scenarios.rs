//! Long and adverse scenarios through the core (default configuration: windowed method, rotation
//! period (480 s) and sample interval (1 s) learned from the data):
//! - a 30-day run (2,592,000 samples; release mode only, a few seconds there);
//! - latitudes 0, 45, 80 and 89 deg: what roll can and cannot tell, and whether the 1-sigma and the
//!   status say so honestly;
//! - the rotation stopping, running at another period, reversing: the status says so, the estimates
//!   freeze and estimation resumes once the rotation is healthy again.
//!
//! The samples come from `estimator_core::synthetic` (sinusoidal roll and pitch sway, eq (2)'s
//! oscillation for known errors in f64, white noise from a seeded 64-bit LCG, the platform turning
//! at the Earth rate), the test turning the rotation itself. Internal values (Kalman covariance, window sums) are read through
//! `Estimator::windowed`.

use estimator_core::correlation::CorrelationSums;
use estimator_core::rotation_pattern::SHORT_STEPS;
use estimator_core::synthetic::Signal;
use estimator_core::units::{rad_to_arcsec, RAD_PER_DEG};
use estimator_core::Counters;
use estimator_core::{Config, Estimator, Output, Real, RotationFault, Sample, Status};
use std::f64::consts::PI;

const X_ARCSEC: [f64; 4] = [120.0, -80.0, 250.0, -190.0];

/// Deterministic RINS output with known errors; the caller advances the rotation angle.
struct Source {
    signal: Signal,
    rho_rad: f64,
    t_s: f64,
}

impl Source {
    /// 3 deg roll and 1 deg pitch sway, no low-frequency error, 10 arcsec of noise on roll, pitch
    /// and heading.
    fn new(latitude_deg: f64) -> Source {
        let mut signal = Signal::new(X_ARCSEC, latitude_deg).with_seed(0x9E37_79B9_7F4A_7C15);
        signal.pitch_sway_phase_rad = 0.3;
        signal.platform_phase_rad = 1.3;
        signal.low_frequency_deg = 0.0;
        signal.noise_arcsec = 10.0;
        signal.heading_noise_arcsec = 10.0;
        Source {
            signal,
            rho_rad: 0.4,
            t_s: 0.0,
        }
    }

    /// The next sample, one second later, the rotation having turned by `increment_rad`.
    fn next(&mut self, increment_rad: f64) -> Sample {
        self.t_s += 1.0;
        self.rho_rad = (self.rho_rad + increment_rad).rem_euclid(2.0 * PI);
        self.signal.sample_at(self.t_s, self.rho_rad)
    }
}

/// Nominal rotation increment for the default 480-sample period.
const NOMINAL_RAD: f64 = 2.0 * PI / 480.0;

fn errors_arcsec(out: &Output) -> [f64; 4] {
    let e = out.estimate.expect("estimate");
    std::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - X_ARCSEC[i])
}

fn sigma_arcsec(out: &Output) -> [f64; 4] {
    let e = out.estimate.expect("estimate");
    std::array::from_fn(|i| rad_to_arcsec(e.sigma_rad[i] as f64))
}

fn updating(status: Status) -> bool {
    matches!(
        status,
        Status::Estimating | Status::Converged | Status::ModelMismatch
    )
}

/// The windowed method's internals.
struct Internals {
    updates: u32,
    p: [[f64; 4]; 4],
    window_len: usize,
    window_filled: usize,
    sums: CorrelationSums,
    /// The sums formed again from the entries stored in the window.
    direct_sums: CorrelationSums,
}

fn internals(est: &Estimator) -> Internals {
    let w = est.windowed().expect("the default method is windowed");
    let p =
        std::array::from_fn(|i| std::array::from_fn(|j| w.filter().covariance()[(i, j)] as f64));
    let mut direct_sums = CorrelationSums::default();
    for e in w.window().entries() {
        direct_sums.add(&e.sample, e.fill_weight(), e.weight);
    }
    Internals {
        updates: w.updates(),
        p,
        window_len: w.window().len(),
        window_filled: w.window().filled(),
        sums: *w.window().sums(),
        direct_sums,
    }
}

/// Cholesky in f64: true if every pivot is positive.
fn positive_definite(p: &[[f64; 4]; 4]) -> bool {
    let mut l = [[0.0f64; 4]; 4];
    for i in 0..4 {
        for j in 0..=i {
            let s: f64 = p[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return false;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    true
}

/// 30 days at 1 Hz through the default estimator.
/// - running sums: each day, every window sum equals the exact sum of the window's samples;
/// - covariance: each day, exactly symmetric and positive definite (and restore validates it);
/// - estimates: from the end of day 1 on, every step's four errors within 10 arcsec of truth;
/// - per-step work constant: after the first window, every step takes the same path: one sample
///   accepted, nothing filled, no window restart, the window full, exactly one filter update
///   (the Kalman update count grows by one a step), status updating. The step has no loop whose
///   count depends on the data except gap filling, which is counted and stays 0, so the same path
///   is the same amount of work. (Instructions per step are measured on the target.)
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "30-day run: 2.6 million steps, run with `cargo test --release`"
)]
fn thirty_day_run_keeps_sums_exact_covariance_spd_estimates_within_10_arcsec_and_work_constant() {
    const DAY: u64 = 86_400;
    const DAYS: u64 = 30;
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut src = Source::new(40.0);
    let mut worst_after_day1 = [0.0f64; 4];
    let mut first_update = None;
    let mut first_estimate = None;
    let mut statuses = std::collections::BTreeMap::<&'static str, u64>::new();
    for k in 1..=DAYS * DAY {
        let before = est.counters();
        let out = est
            .step(&src.next(NOMINAL_RAD))
            .expect("healthy sample accepted");
        let after = est.counters();
        assert_eq!(
            after,
            Counters {
                accepted: before.accepted + 1,
                ..before
            },
            "step {k}: counters"
        );
        *statuses.entry(out.status.name()).or_default() += 1;
        if first_update.is_none() && est.windowed().is_some_and(|w| w.updates() > 0) {
            first_update = Some(k);
        }
        // The first estimate comes at the end of the first windows' first bump, after the
        // first update (`estimator_core::methods::windowed::start`).
        if first_estimate.is_none() && updating(out.status) {
            first_estimate = Some(k);
        }
        if let Some(first) = first_estimate {
            assert!(updating(out.status), "step {k}: status {:?}", out.status);
            assert!(first <= 600, "first estimate at step {first}");
        }
        if k > DAY {
            let e = errors_arcsec(&out);
            for i in 0..4 {
                worst_after_day1[i] = worst_after_day1[i].max(e[i].abs());
            }
            assert!(
                e.iter().all(|v| v.abs() < 10.0),
                "step {k}: errors {e:?} arcsec"
            );
        }
        if k % DAY == 0 {
            let s = internals(&est);
            assert_eq!(
                s.sums,
                s.direct_sums,
                "day {}: running sums drifted",
                k / DAY
            );
            assert_eq!((s.window_len, s.window_filled), (480, 480));
            let first = first_update.expect("updating by day 1");
            assert_eq!(
                u64::from(s.updates),
                k - first + 1,
                "day {}: not one filter update per step",
                k / DAY
            );
            for i in 0..4 {
                for j in 0..4 {
                    assert_eq!(
                        s.p[i][j].to_bits(),
                        s.p[j][i].to_bits(),
                        "day {}: P not symmetric",
                        k / DAY
                    );
                }
            }
            assert!(
                positive_definite(&s.p),
                "day {}: P not positive definite: {:?}",
                k / DAY,
                s.p
            );
            let sigma = sigma_arcsec(&out);
            let e = errors_arcsec(&out);
            println!(
                "day {:2}: errors {:7.3?} arcsec, 1-sigma {:6.3?} arcsec, {}",
                k / DAY,
                e,
                sigma,
                out.status.name()
            );
        }
    }
    println!("worst |error| after day 1: {worst_after_day1:.3?} arcsec; statuses {statuses:?}");
    assert_eq!(
        est.counters(),
        Counters {
            accepted: 2_592_000,
            ..Counters::default()
        }
    );
}

/// The configuration of the latitude runs: the defaults without the random walk. The windowed
/// method learns how much of the walk to apply from its residuals, so with it the covariance
/// would depend on the noise drawn; without it the covariance is that of the information alone,
/// what the pitch-only comparison below is about.
fn latitude_config() -> Config {
    Config {
        drift_rad_per_sqrt_s: 0.0,
        ..Config::default()
    }
}

/// Runs `steps` healthy samples at `latitude_deg`; returns the last output, whether any step
/// was `Converged` and the share of the last hour's steps that were, and checks honesty at every
/// hour: each error within 3 sigma.
fn run_latitude(latitude_deg: f64, steps: u64) -> (Output, bool, Estimator, f64) {
    let mut est: Estimator = Estimator::new(latitude_config()).unwrap();
    let mut src = Source::new(latitude_deg);
    let mut last = None;
    let mut converged = false;
    let mut converged_last_hour = 0u32;
    for k in 1..=steps {
        let out = est.step(&src.next(NOMINAL_RAD)).unwrap();
        converged |= out.status == Status::Converged;
        if k + 3600 > steps && out.status == Status::Converged {
            converged_last_hour += 1;
        }
        if k % 3600 == 0 {
            let (e, s) = (errors_arcsec(&out), sigma_arcsec(&out));
            for i in 0..4 {
                assert!(
                    e[i].abs() <= 3.0 * s[i],
                    "lat {latitude_deg}, hour {}: x{} error {:.3} arcsec > 3 sigma {:.3}",
                    k / 3600,
                    i + 1,
                    e[i],
                    s[i]
                );
            }
        }
        last = Some(out);
    }
    let share = f64::from(converged_last_hour) / 3600.0;
    (last.unwrap(), converged, est, share)
}

/// The scalar filter x1 would have if it were observed by the pitch channel alone (its gain
/// `gain`, 1/2 times the low-pass of the reference, and the measurement noise and random walk of
/// [`latitude_config`]): its variance after `updates`.
fn pitch_only_variance(updates: u64, gain: f64) -> f64 {
    let c = latitude_config();
    let (r, q) = (
        (c.measurement_sigma_rad as f64).powi(2),
        (c.drift_rad_per_sqrt_s as f64).powi(2),
    );
    let mut p = (c.prior_sigma_rad as f64).powi(2);
    for _ in 0..updates {
        p += q;
        p = p * r / (gain * gain * p + r);
    }
    p
}

const LATITUDE_STEPS: u64 = 8 * 3600;

/// The pitch channels' gain for x1 in the current window (constant for a uniform rotation): the
/// low-passed reference lags, so both pitch channels see x1 (with gains `g cos(lag)` and
/// `g sin(lag)`); together they inform it as one channel of gain `g`.
fn pitch_gain(est: &Estimator) -> f64 {
    let rows = est
        .windowed()
        .unwrap()
        .window()
        .sums()
        .measurement()
        .unwrap()
        .rows;
    (rows[0][0] as f64).hypot(rows[1][0] as f64)
}

/// At the equator roll carries no x1, x2 (sin L = 0): they come from pitch alone. The filter's
/// x1 and x2 variances equal those of a pitch-only scalar filter, the errors are within 3 sigma,
/// and everything converges.
#[test]
fn equator_x1_x2_come_from_pitch_alone() {
    let (out, converged, est, last_hour) = run_latitude(0.0, LATITUDE_STEPS);
    let s = internals(&est);
    let p = s.p;
    let pitch_only = pitch_only_variance(u64::from(s.updates), pitch_gain(&est));
    for i in 0..2 {
        // Within 2 %: the scalar filter uses the gain of the last window, while the first windows,
        // filled as the reference's low-pass settled, had slightly other gains; without a random
        // walk the filter never forgets them (measured: 1.1 %; 0.5 % with the default walk, which
        // the windowed method now switches off when its residuals show no drift).
        assert!(
            (p[i][i] / pitch_only - 1.0).abs() < 2e-2,
            "x{}: variance {} vs pitch-only {}",
            i + 1,
            p[i][i],
            pitch_only
        );
        assert_eq!(p[i][2], 0.0);
        assert_eq!(p[i][3], 0.0);
    }
    assert_converged(converged, last_hour);
    let e = errors_arcsec(&out);
    assert!(e.iter().all(|v| v.abs() < 1.0), "errors {e:?}");
    println!(
        "lat 0: errors {e:.3?}, sigma {:.3?} arcsec",
        sigma_arcsec(&out)
    );
}

/// The status said `Converged`, and says it through the last hour but for the blocks whose
/// residual mean the change detector finds beyond 2 of its standard deviations (about one in 20
/// under noise, by design): while such a block is the last, the error of its channel has its
/// 1-sigma widened by the excess (`estimator_core::methods::windowed::change`), and at 45 deg
/// the widening of x4 (gain cos L / 2) can take it past the 1 arcsec of `Converged`. (The last
/// step alone was asserted before: whether it falls on such a block depends on where the blocks
/// begin, measured: 94 % of the last hour `Converged` with the reference angles 5 deg from the
/// first angle, 100 % with them at 22.5 deg.)
fn assert_converged(converged: bool, last_hour_share: f64) {
    assert!(converged, "never converged");
    assert!(
        last_hour_share >= 0.9,
        "converged in {last_hour_share:.3} of the last hour"
    );
}

/// At 45 deg roll also informs x1 (through the leakage of eq 12): its variance is below the
/// pitch-only one; everything converges within 3 sigma.
#[test]
fn mid_latitude_converges_honestly() {
    let (out, converged, est, last_hour) = run_latitude(45.0, LATITUDE_STEPS);
    let s = internals(&est);
    assert!(s.p[0][0] < pitch_only_variance(u64::from(s.updates), pitch_gain(&est)));
    assert_converged(converged, last_hour);
    let e = errors_arcsec(&out);
    assert!(e.iter().all(|v| v.abs() < 1.0), "errors {e:?}");
    println!(
        "lat 45: errors {e:.3?}, sigma {:.3?} arcsec",
        sigma_arcsec(&out)
    );
}

/// At 80 deg (cos L = 0.17) roll sees x3, x4 six times more weakly: their 1-sigma is at least
/// twice that of x1, x2, and the errors stay within 3 sigma.
#[test]
fn high_latitude_weakens_x3_x4_and_says_so() {
    let (out, _, _, _) = run_latitude(80.0, LATITUDE_STEPS);
    let s = sigma_arcsec(&out);
    for j in 2..4 {
        for i in 0..2 {
            assert!(s[j] > 2.0 * s[i], "sigma {s:?}");
        }
    }
    println!(
        "lat 80: errors {:.3?}, sigma {s:.3?} arcsec, {}",
        errors_arcsec(&out),
        out.status.name()
    );
}

/// At 89 deg (cos L = 0.017) x3, x4 are all but unobservable from roll: their 1-sigma stays above
/// the convergence threshold and at least 10 times that of x1, x2, the status is never
/// `converged`, and the errors stay within 3 sigma. x1, x2 still converge (pitch).
#[test]
fn near_pole_x3_x4_unobservable_and_status_says_so() {
    let (out, converged, _, _) = run_latitude(89.0, LATITUDE_STEPS);
    let s = sigma_arcsec(&out);
    let threshold = rad_to_arcsec(Config::default().converged_sigma_rad as f64);
    assert!(!converged, "status was converged at 89 deg");
    for j in 2..4 {
        assert!(s[j] > threshold, "x{} sigma {} arcsec", j + 1, s[j]);
        for i in 0..2 {
            assert!(s[j] > 10.0 * s[i], "sigma {s:?}");
        }
    }
    let e = errors_arcsec(&out);
    assert!(e[0].abs() < 1.0 && e[1].abs() < 1.0, "x1, x2 errors {e:?}");
    assert!(s[0] < threshold && s[1] < threshold, "x1, x2 sigma {s:?}");
    println!(
        "lat 89: errors {e:.3?}, sigma {s:.3?} arcsec, {}",
        out.status.name()
    );
}

/// What happened around a rotation fault.
struct FaultRun {
    /// Status of the first faulty sample.
    first_fault_status: Status,
    /// Samples from the return of healthy rotation to the first updating step.
    resume_delay: u64,
    /// Largest change of any estimate while not updating (must be exactly 0), arcsec.
    frozen_change_arcsec: f64,
    /// Change of the estimate from the last step before the fault to the step before resumption.
    change_across_fault_arcsec: f64,
    /// Errors at the end.
    final_errors_arcsec: [f64; 4],
    final_status: Status,
    /// Fault samples after the first report that did not report the same fault.
    unreported_fault_samples: u64,
}

/// 3 h healthy, `fault_s` of the given rotation increment, then healthy again for 3 h.
fn run_fault(fault_increment_rad: f64, fault_s: u64) -> FaultRun {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut src = Source::new(40.0);
    let healthy_s = 3 * 3600;
    let mut pre_fault = None;
    let mut frozen_at: Option<[Real; 4]> = None;
    let mut frozen_change: f64 = 0.0;
    let mut first_fault_status = None;
    let mut resume_delay = None;
    let mut change_across = 0.0f64;
    let mut last = None;
    let mut unreported = 0u64;
    let direction_after = if fault_increment_rad < 0.0 { -1.0 } else { 1.0 };
    for k in 1..=(2 * healthy_s + fault_s) {
        let in_fault = k > healthy_s && k <= healthy_s + fault_s;
        let increment = if k <= healthy_s {
            NOMINAL_RAD
        } else if in_fault {
            fault_increment_rad
        } else {
            direction_after * NOMINAL_RAD
        };
        let out = est.step(&src.next(increment)).unwrap();
        let Some(estimate) = out.estimate else {
            assert!(k < 3 * 480, "no estimate at step {k}");
            continue;
        };
        let x = estimate.x_rad;
        if k == healthy_s {
            assert!(updating(out.status));
            pre_fault = Some(x);
        }
        if k > healthy_s && first_fault_status.is_none() && !updating(out.status) {
            first_fault_status = Some(out.status);
        }
        if in_fault && first_fault_status.is_some() && Some(out.status) != first_fault_status {
            unreported += 1;
        }
        if k > healthy_s && resume_delay.is_none() {
            if updating(out.status) {
                if !in_fault && first_fault_status.is_some() {
                    resume_delay = Some(k - healthy_s - fault_s);
                }
                frozen_at = None;
            } else {
                let f = *frozen_at.get_or_insert(x);
                for i in 0..4 {
                    frozen_change = frozen_change.max(rad_to_arcsec((x[i] - f[i]).abs() as f64));
                    change_across = change_across
                        .max(rad_to_arcsec((x[i] - pre_fault.unwrap()[i]).abs() as f64));
                }
            }
        }
        last = Some(out);
    }
    let last = last.unwrap();
    FaultRun {
        first_fault_status: first_fault_status.expect("the fault was never reported"),
        resume_delay: resume_delay.expect("estimation never resumed"),
        frozen_change_arcsec: frozen_change,
        change_across_fault_arcsec: change_across,
        final_errors_arcsec: errors_arcsec(&last),
        final_status: last.status,
        unreported_fault_samples: unreported,
    }
}

/// Steps the rotation monitor's short mean (exponential over `SHORT_STEPS` steps) takes to fall
/// below a quarter of a step change (a stop), plus the two samples a pattern without dwells may
/// stand still (a reversal passes through zero), plus the delay of the gap filler.
fn stop_settle() -> u64 {
    let alpha = 1.0 / SHORT_STEPS as f64;
    (0.25f64.ln() / (1.0 - alpha).ln()).ceil() as u64
        + 2
        + u64::from(estimator_core::gap_fill::DELAY)
}

/// What the status did during the fault.
#[derive(PartialEq)]
enum During {
    /// Reported the first fault at every faulty sample.
    SameFault,
    /// Reported the fault, then (the rotation repeating a new pattern) detected it anew.
    Relearned,
}

fn check_fault(
    name: &str,
    run: &FaultRun,
    expected: RotationFault,
    during: During,
    max_resume_delay: u64,
) {
    println!(
        "{name}: first status {:?}, resumed {} samples after healthy rotation, frozen change {} arcsec, change across fault {:.4} arcsec, final errors {:.3?}, {:?}",
        run.first_fault_status, run.resume_delay, run.frozen_change_arcsec, run.change_across_fault_arcsec, run.final_errors_arcsec, run.final_status
    );
    assert_eq!(
        run.first_fault_status,
        Status::RotationFault(expected),
        "{name}"
    );
    if during == During::SameFault {
        assert_eq!(
            run.unreported_fault_samples, 0,
            "{name}: the status stopped reporting the fault"
        );
    }
    assert_eq!(
        run.frozen_change_arcsec, 0.0,
        "{name}: estimates moved while frozen"
    );
    assert!(
        run.change_across_fault_arcsec < 1.0,
        "{name}: estimates drifted by {} arcsec",
        run.change_across_fault_arcsec
    );
    assert!(
        run.resume_delay <= max_resume_delay,
        "{name}: resumed after {} samples",
        run.resume_delay
    );
    assert!(
        run.final_errors_arcsec.iter().all(|e| e.abs() < 1.0),
        "{name}: {:?}",
        run.final_errors_arcsec
    );
    assert!(updating(run.final_status), "{name}: {:?}", run.final_status);
}

/// Rotation stopped for an hour: `rotation_stopped` at every sample, frozen; resumes one window
/// (480 samples) after the restart is recognised.
#[test]
fn rotation_stopped_freezes_and_resumes() {
    let run = run_fault(0.0, 3600);
    check_fault(
        "stopped",
        &run,
        RotationFault::Stopped,
        During::SameFault,
        stop_settle() + 480,
    );
}

/// Rotating at a 400 s period (20 % fast) for an hour: `rotation_rate_mismatch`, frozen; the new
/// period is detected and estimation goes on at it; back at 480 s, the same again: the pattern is
/// learned anew within two periods, and the window fills in a third.
#[test]
fn rotation_at_another_period_freezes_and_relearns() {
    let run = run_fault(2.0 * PI / 400.0, 3600);
    check_fault(
        "period 400 s",
        &run,
        RotationFault::RateMismatch,
        During::Relearned,
        3 * 480 + stop_settle(),
    );
}

/// Rotating at a 600 s period (20 % slow) for an hour: same.
#[test]
fn rotation_slower_freezes_and_relearns() {
    let run = run_fault(2.0 * PI / 600.0, 3600);
    check_fault(
        "period 600 s",
        &run,
        RotationFault::RateMismatch,
        During::Relearned,
        3 * 480 + stop_settle(),
    );
}

/// A one-way rotation reverses and goes on the other way: `rotation_reversed` at once, frozen; after
/// one period the other way the pattern is learned anew (eq (2) holds in either direction).
#[test]
fn rotation_reversal_freezes_and_relearns() {
    let run = run_fault(-NOMINAL_RAD, 1);
    check_fault(
        "reversed",
        &run,
        RotationFault::Reversed,
        During::Relearned,
        4 * 480 + stop_settle(),
    );
}

/// The rotation angle read with 0.15 deg (1-sigma) of white jitter, 28 % of a 0.75 deg step, for
/// 6 h: no rotation fault, no window restart, and the estimates converge.
#[test]
fn rotation_jitter_of_0_15_deg_raises_no_fault() {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut src = Source::new(40.0);
    src.signal.rotation_jitter_rad = 0.15 * RAD_PER_DEG;
    let mut last = None;
    for k in 1..=6 * 3600u32 {
        let out = est.step(&src.next(NOMINAL_RAD)).unwrap();
        assert!(
            !matches!(out.status, Status::RotationFault(_)),
            "step {k}: {:?}",
            out.status
        );
        last = Some(out);
    }
    assert_eq!(est.counters().window_restarts, 0, "window restarts");
    let last = last.unwrap();
    let e = errors_arcsec(&last);
    println!(
        "jitter 0.15 deg, 6 h: errors {e:.3?} arcsec, {}",
        last.status.name()
    );
    assert!(updating(last.status), "{:?}", last.status);
    assert!(e.iter().all(|v| v.abs() < 1.0), "{e:?}");
}
