//! A change of the installation errors (a re-installation, a shock) is detected from the residuals,
//! reported (status `errors_changed`, the summary) and learned again; no change is declared on
//! logs without one. Reduced runs here; the full study (200-run Monte Carlos, 30-day logs, every
//! scheme and period) is `bash scripts/change-study.sh`, which runs the `#[ignore]`d tests below
//! with `--ignored --nocapture`; docs/uncertainty.md quotes its tables.

use crate::common::{host_sim_ok, path_str, temp_dir};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Config, ErrorChange, Estimator, Status};
use host_sim::replay::sample_of;
use host_sim::sim::recorder::Recorder;
use host_sim::sim::rotation_scheme::RotationScheme;
use host_sim::sim::samples::Samples;
use host_sim::sim::scenario::{ErrorsStep, Mismatch, ScenarioKind, ScenarioParams};
use host_sim::study::monte_carlo::Draw;
use rayon::prelude::*;

/// What a run of one log shows.
#[derive(Clone, Debug, Default)]
struct Run {
    /// Every change declared.
    changes: Vec<ErrorChange>,
    /// Statuses seen after the step (or from the start without one), in order, each once.
    statuses: Vec<Status>,
    /// From one period after the step: (row, error) pairs, and those within 2 and 3 sigma.
    pairs: usize,
    within_2_sigma: usize,
    within_3_sigma: usize,
    /// The largest |error| from 2,000 s after the step on, arcsec.
    worst_after_2000_s: f64,
    /// Time from the step until every error stayed within 10 arcsec, s.
    within_10_from_s: Option<f64>,
    /// The largest |error| at the end, arcsec.
    final_error_arcsec: f64,
}

/// Replays a generated log through a fresh estimator of `config`, row by row.
fn run(p: &ScenarioParams, config: Config) -> Run {
    let mut est: Estimator = Estimator::new(config).unwrap();
    let mut recorder = Recorder::new(&p.recording, p.seed, p.sample_interval_s);
    let step = p.errors_step.map(|s| s.at_s);
    let from_s = step.unwrap_or(0.0);
    let mut r = Run::default();
    for (row, truth) in Samples::new(p) {
        let Some(logged) = recorder.record(&row) else {
            continue;
        };
        let Ok(out) = est.step(&sample_of(&logged)) else {
            continue;
        };
        if let Some(c) = est.error_change().filter(|c| c.detected_s == out.time_s) {
            r.changes.push(c);
        }
        if row.time_s >= from_s && r.statuses.last() != Some(&out.status) {
            r.statuses.push(out.status);
        }
        let Some(e) = out.estimate else { continue };
        let error: [f64; 4] =
            core::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - truth.errors_arcsec[i]);
        let worst = error.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        r.final_error_arcsec = worst;
        let Some(t0) = step else { continue };
        let after = row.time_s - t0;
        if after < 0.0 {
            continue;
        }
        r.within_10_from_s = if worst <= 10.0 {
            r.within_10_from_s.or(Some(after))
        } else {
            None
        };
        if after >= 2000.0 {
            r.worst_after_2000_s = r.worst_after_2000_s.max(worst);
        }
        if after >= p.rotation_period_s {
            for i in 0..4 {
                let sigma = rad_to_arcsec(e.sigma_rad[i] as f64);
                r.pairs += 1;
                r.within_2_sigma += usize::from(error[i].abs() <= 2.0 * sigma);
                r.within_3_sigma += usize::from(error[i].abs() <= 3.0 * sigma);
            }
        }
    }
    r
}

/// A sea log of run `i` of `draw`, `after_s` long after a step at `at_s` of error `which` by
/// `step_arcsec`.
fn stepped(
    draw: &Draw,
    i: usize,
    which: usize,
    step_arcsec: f64,
    at_s: f64,
    after_s: f64,
) -> ScenarioParams {
    let mut p = draw.params(i);
    p.duration_s = at_s + after_s;
    let mut after = p.errors_arcsec;
    after[which] += step_arcsec;
    p.errors_step = Some(ErrorsStep {
        at_s,
        errors_after_arcsec: after,
    });
    p
}

/// One line of a step table: what `runs` show together.
#[derive(Clone, Debug)]
struct StepLine {
    detected: usize,
    runs: usize,
    false_or_repeated: usize,
    /// Largest delay from the step to the detection, s.
    worst_delay_s: f64,
    /// Largest time from the step until every error stayed within 10 arcsec, s.
    worst_within_10_s: f64,
    worst_after_2000_s: f64,
    coverage_2_sigma: f64,
    coverage_3_sigma: f64,
    worst_final_arcsec: f64,
}

fn step_line(params: &[ScenarioParams], config: Config) -> StepLine {
    let runs: Vec<(f64, Run)> = params
        .par_iter()
        .map(|p| (p.errors_step.unwrap().at_s, run(p, config)))
        .collect();
    let mut line = StepLine {
        detected: 0,
        runs: runs.len(),
        false_or_repeated: 0,
        worst_delay_s: 0.0,
        worst_within_10_s: 0.0,
        worst_after_2000_s: 0.0,
        coverage_2_sigma: 0.0,
        coverage_3_sigma: 0.0,
        worst_final_arcsec: 0.0,
    };
    let (mut pairs, mut in2, mut in3) = (0, 0, 0);
    for (at_s, r) in &runs {
        let after: Vec<&ErrorChange> = r.changes.iter().filter(|c| c.detected_s > *at_s).collect();
        line.false_or_repeated += r.changes.len() - after.len().min(1);
        if let Some(c) = after.first() {
            line.detected += 1;
            line.worst_delay_s = line.worst_delay_s.max(c.detected_s - at_s);
        }
        line.worst_within_10_s = line
            .worst_within_10_s
            .max(r.within_10_from_s.unwrap_or(f64::INFINITY));
        line.worst_after_2000_s = line.worst_after_2000_s.max(r.worst_after_2000_s);
        line.worst_final_arcsec = line.worst_final_arcsec.max(r.final_error_arcsec);
        pairs += r.pairs;
        in2 += r.within_2_sigma;
        in3 += r.within_3_sigma;
    }
    line.coverage_2_sigma = in2 as f64 / pairs.max(1) as f64;
    line.coverage_3_sigma = in3 as f64 / pairs.max(1) as f64;
    line
}

fn print_step_header() {
    println!("| error | step arcsec | scheme | period s | detected | false or repeated | worst delay s | every error within 10 arcsec from s | worst after 2000 s arcsec | within 2 / 3 sigma from one period after | worst at the end arcsec |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
}

fn print_step_line(which: usize, step: f64, scheme: RotationScheme, period_s: f64, l: &StepLine) {
    println!(
        "| x{} | {step} | {} | {period_s} | {} / {} | {} | {:.0} | {:.0} | {:.2} | {:.1} % / {:.1} % | {:.2} |",
        which + 1,
        scheme.name(),
        l.detected,
        l.runs,
        l.false_or_repeated,
        l.worst_delay_s,
        l.worst_within_10_s,
        l.worst_after_2000_s,
        100.0 * l.coverage_2_sigma,
        100.0 * l.coverage_3_sigma,
        l.worst_final_arcsec
    );
}

/// What the targets require of every line: detected once, after the step, within 3.5 periods;
/// every error within 10 arcsec of the new values by 2,000 s after the step (at long periods the
/// detector's blocks are a quarter of the period or less, so that the run a change must last stays
/// about a period and a passing disturbance: a 20 arcsec step of a 720 s period is declared within
/// 1,900 s); the 1-sigma
/// covering the error from one period after the step on (at 2 sigma, about
/// as often as on the same logs without a step: the clean sea's coverage is 95-97 %, and a few
/// runs of 6,000 s swing by several points; at 3 sigma all but a few rows).
fn check_step_line(name: &str, period_s: f64, l: &StepLine) {
    assert_eq!(
        (l.detected, l.false_or_repeated),
        (l.runs, 0),
        "{name}: {l:?}"
    );
    assert!(l.worst_delay_s <= 3.5 * period_s, "{name}: {l:?}");
    assert!(
        l.worst_within_10_s <= 2000.0 && l.worst_after_2000_s <= 10.0,
        "{name}: {l:?}"
    );
    assert!(
        l.coverage_2_sigma >= 0.85 && l.coverage_3_sigma >= 0.985,
        "{name}: {l:?}"
    );
    assert!(l.worst_final_arcsec <= 2.0, "{name}: {l:?}");
}

/// One line of the study: steps of `size` arcsec of error `which` at 20,000 s on `seeds` sea logs
/// (alternating signs) of `scheme` at `period_s`, printed and checked.
fn study_line(seeds: usize, which: usize, size: f64, scheme: RotationScheme, period_s: f64) {
    let mut draw = Draw::new(ScenarioKind::Sea, 21);
    draw.scheme = scheme;
    draw.rotation_period_s = Some(period_s);
    let params: Vec<ScenarioParams> = (0..seeds)
        .map(|i| {
            stepped(
                &draw,
                i,
                which,
                if i % 2 == 0 { size } else { -size },
                20_000.0,
                6_000.0,
            )
        })
        .collect();
    let line = step_line(&params, Config::default());
    print_step_line(which, size, scheme, period_s, &line);
    check_step_line(
        &format!("x{} {size} {} {period_s}", which + 1, scheme.name()),
        period_s,
        &line,
    );
}

/// Steps of each error, of each of `sizes` arcsec, at 20,000 s on sea logs (`seeds` runs a line,
/// alternating signs), on `schemes` at `periods_s`.
fn steps(seeds: usize, sizes: &[f64], schemes: &[RotationScheme], periods_s: &[f64]) {
    print_step_header();
    for &scheme in schemes {
        for &period_s in periods_s {
            for which in 0..4 {
                for &size in sizes {
                    study_line(seeds, which, size, scheme, period_s);
                }
            }
        }
    }
}

#[test]
fn steps_of_20_and_150_arcsec_of_each_error_are_detected_and_learned_again_within_2000_s() {
    steps(2, &[20.0, 150.0], &[RotationScheme::Continuous], &[480.0]);
}

/// A 30 arcsec step of `which` at 20,000 s of a 26,000 s sea log (seed 22) of `scheme` at
/// `period_s`: its line of the table.
fn one_step_line(scheme: RotationScheme, period_s: f64, which: usize) -> StepLine {
    let mut draw = Draw::new(ScenarioKind::Sea, 22);
    draw.scheme = scheme;
    draw.rotation_period_s = Some(period_s);
    let line = step_line(
        &[stepped(&draw, 0, which, 30.0, 20_000.0, 6_000.0)],
        Config::default(),
    );
    print_step_header();
    print_step_line(which, 30.0, scheme, period_s, &line);
    line
}

#[test]
fn a_step_is_detected_and_learned_again_on_a_reciprocating_720_s_rotation() {
    let line = one_step_line(RotationScheme::Reciprocating, 720.0, 1);
    check_step_line("reciprocating", 720.0, &line);
}

#[test]
fn a_step_is_detected_and_learned_again_on_a_four_position_360_s_rotation() {
    let line = one_step_line(RotationScheme::FourPosition, 360.0, 3);
    check_step_line("four-position", 360.0, &line);
}

/// The three lines of the full study that once fell short, at full size (4 logs each): a 20 arcsec
/// step of x3 on a four-position 360 s rotation (a block of the run short of half the shift: once
/// declared after 4.96 periods), and 150 arcsec steps of x3 at 360 s and of x1 at 720 s, one-way
/// (an unchanged error moved by the block it was learned again from, and a noise scale learned
/// again from a few residual means: once 98.1 % and 98.4 % within 3 sigma).
#[test]
fn the_hardest_lines_of_the_study_meet_every_target() {
    print_step_header();
    study_line(4, 2, 20.0, RotationScheme::FourPosition, 360.0);
    study_line(4, 2, 150.0, RotationScheme::Continuous, 360.0);
    study_line(4, 0, 150.0, RotationScheme::Continuous, 720.0);
}

/// `runs` logs of `draw`, each of `duration_s` (`course_deg` overrides the course, so that a
/// month-long voyage keeps its latitude): the changes declared in all of them.
fn declared(
    draw: &Draw,
    runs: usize,
    duration_s: f64,
    course_deg: Option<f64>,
) -> Vec<(usize, ErrorChange)> {
    (0..runs)
        .into_par_iter()
        .flat_map_iter(|i| {
            let mut p = draw.params(i);
            p.duration_s = duration_s;
            if let Some(c) = course_deg {
                p.course_deg = c;
            }
            run(&p, Config::default())
                .changes
                .into_iter()
                .map(move |c| (i, c))
        })
        .collect()
}

/// The sea scenarios of the no-false-detection checks: the rough-sea Monte Carlo of the README
/// (latitudes 0-70 deg, roll up to 10 deg), and the sea scenario with coloured noise of 20 arcsec,
/// errors drifting 20 arcsec a day, heel in turns of 3 deg and of 0.5 deg.
fn no_change_draws(period_s: f64) -> Vec<(&'static str, Draw)> {
    let sea = |mismatch: Mismatch| {
        let mut d = Draw::new(ScenarioKind::Sea, 31);
        d.mismatch = mismatch;
        d.rotation_period_s = Some(period_s);
        d
    };
    let mut rough = sea(Mismatch::default());
    rough.lat_range_deg = Some((0.0, 70.0));
    rough.max_roll_deg = Some(10.0);
    vec![
        ("rough sea, latitudes 0-70 deg, roll up to 10 deg", rough),
        (
            "coloured noise 20 arcsec, 60 s",
            sea(Mismatch {
                coloured_noise_arcsec: 20.0,
                ..Mismatch::default()
            }),
        ),
        (
            "errors drifting 20 arcsec a day",
            sea(Mismatch {
                error_drift_arcsec_per_day: 20.0,
                ..Mismatch::default()
            }),
        ),
        (
            "heel in turns, 3 deg",
            sea(Mismatch {
                heel_in_turns_deg: 3.0,
                ..Mismatch::default()
            }),
        ),
        (
            "heel in turns, 0.5 deg",
            sea(Mismatch {
                heel_in_turns_deg: 0.5,
                ..Mismatch::default()
            }),
        ),
    ]
}

/// `runs` 45,000 s logs of each of [`no_change_draws`] at a rotation period of `period_s`, and
/// `thirty_day_runs` month-long voyages clean and with drifting errors: no change declared.
fn no_false_detection(runs: [usize; 5], thirty_day_runs: usize, period_s: f64) {
    println!("| log | rotation period s | runs | days each | changes declared |");
    println!("|---|---|---|---|---|");
    for ((name, draw), n) in no_change_draws(period_s).into_iter().zip(runs) {
        if n == 0 {
            continue;
        }
        let changes = declared(&draw, n, 45_000.0, None);
        println!(
            "| {name} | {period_s} | {n} | {:.2} | {} |",
            45_000.0 / 86_400.0,
            changes.len()
        );
        assert!(changes.is_empty(), "{name}: {changes:?}");
    }
    // A month at sea on a steady course east (the sea scenario's 5 m/s north-east would take the
    // ship over the pole in a month), clean and with drifting errors.
    if thirty_day_runs == 0 {
        return;
    }
    // The two voyages side by side (each is one long run, which `declared` cannot spread).
    let voyages: Vec<_> = [
        ("30 days, clean", Mismatch::default()),
        (
            "30 days, errors drifting 20 arcsec a day",
            Mismatch {
                error_drift_arcsec_per_day: 20.0,
                ..Mismatch::default()
            },
        ),
    ]
    .into_par_iter()
    .map(|(name, mismatch)| {
        let mut draw = Draw::new(ScenarioKind::Sea, 41);
        draw.mismatch = mismatch;
        draw.rotation_period_s = Some(period_s);
        (
            name,
            declared(&draw, thirty_day_runs, 30.0 * 86_400.0, Some(90.0)),
        )
    })
    .collect();
    for (name, changes) in voyages {
        println!(
            "| {name} | {period_s} | {thirty_day_runs} | 30 | {} |",
            changes.len()
        );
        assert!(changes.is_empty(), "{name}: {changes:?}");
    }
}

#[test]
fn no_change_is_declared_at_sea_under_coloured_noise_drift_or_turns_nor_in_a_month() {
    no_false_detection([20, 6, 6, 4, 4], 1, 480.0);
    // A long period, whose blocks are a quarter of it (240 s at most) and tested only from some
    // 9,800 s on: the first turn, at 7,200 s, comes before that (turns at 720 s were declared
    // on the seeds 6 and 10 of 0.5 deg and 8 of 3 deg before a gross block held the filter
    // ahead of the first test).
    no_false_detection([6, 3, 3, 12, 12], 0, 720.0);
}

#[test]
fn generate_estimate_and_the_summary_say_when_the_errors_changed() {
    let dir = temp_dir("error-changes");
    let log = dir.join("stepped.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "12000",
        "--errors-step-at",
        "8000",
        "--errors-after-arcsec",
        "230,-150,300,-250",
        "--out",
        path_str(&log),
    ]);
    let truth =
        host_sim::formats::truth_file::read_truth(&host_sim::formats::truth_file::truth_path(&log))
            .unwrap()
            .unwrap();
    let step = truth
        .params
        .unwrap()
        .errors_step
        .expect("the step in the truth file");
    assert_eq!(
        (step.at_s, step.errors_after_arcsec),
        (8000.0, [230.0, -150.0, 300.0, -250.0])
    );

    let out = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("est.csv")),
    ]);
    let line = out
        .lines()
        .find(|l| l.contains("change of the installation errors detected at"))
        .unwrap_or_else(|| panic!("{out}"));
    let detected_s: f64 = line
        .split("detected at ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (8000.0..=8000.0 + 3.5 * 480.0).contains(&detected_s),
        "{line}"
    );
    assert!(line.contains("x1"), "{line}");
    let estimates = std::fs::read_to_string(dir.join("est.csv")).unwrap();
    assert!(
        estimates.contains(",errors_changed,"),
        "no errors_changed status in the estimates"
    );
    // Against the truth: x1 within 10 arcsec of its new value from before 2,000 s after the step.
    let x1 = out
        .lines()
        .find(|l| l.starts_with("| x1 |"))
        .unwrap_or_else(|| panic!("{out}"));
    let from_s: f64 = x1
        .trim_end_matches(" s |")
        .rsplit("| ")
        .next()
        .unwrap()
        .parse()
        .unwrap_or_else(|_| panic!("{x1}"));
    assert!(from_s <= 10_000.0, "{x1}");

    // Detection off: no change said (that the filter then lags the step by hours is the core's
    // `a_step_of_the_errors_is_declared_reported_and_learned_again`).
    let out = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("off.csv")),
        "--change-detection-arcsec",
        "0",
    ]);
    assert!(!out.contains("change of the installation errors"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The full study: every error, steps of 20 to 150 arcsec, three schemes at three periods.
#[test]
#[ignore = "the full study: bash scripts/change-study.sh"]
fn study_steps() {
    steps(
        4,
        &[20.0, 30.0, 50.0, 150.0],
        &[
            RotationScheme::Continuous,
            RotationScheme::Reciprocating,
            RotationScheme::FourPosition,
        ],
        &[360.0, 480.0, 720.0],
    );
}

/// The full study: 200 runs of each sea scenario, ten 30-day voyages of each.
#[test]
#[ignore = "the full study: bash scripts/change-study.sh"]
fn study_no_false_detection() {
    no_false_detection([200; 5], 10, 480.0);
    no_false_detection([200; 5], 10, 720.0);
}
