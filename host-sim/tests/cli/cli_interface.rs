//! The RINS's interface on the command line: a rotation angle that lags the attitude
//! (`generate --log-angle-latency-s`, `estimate --angle-latency-s`), known values to start from
//! (`--prior-arcsec`, `--prior-sigma-arcsec`), and their refusals.

use crate::common::{host_sim, host_sim_ok, path_str, temp_dir};
use std::path::Path;

/// The last row's x1..x4 of an estimates CSV, arcsec, and the first row's.
fn first_and_last_arcsec(est: &Path) -> ([f64; 4], [f64; 4]) {
    let text = std::fs::read_to_string(est).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let x = |r: &Vec<&str>| -> [f64; 4] {
        core::array::from_fn(|i| r[1 + i].parse().unwrap_or(f64::NAN))
    };
    (x(&rows[0]), x(rows.last().unwrap()))
}

/// The truth file's x1..x4, arcsec.
fn truth_arcsec(log: &Path) -> [f64; 4] {
    let text = std::fs::read_to_string(log.with_extension("truth.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    core::array::from_fn(|i| v["x_arcsec"][i].as_f64().unwrap())
}

fn worst_off(x: [f64; 4], truth: [f64; 4]) -> f64 {
    (0..4).fold(0.0, |m: f64, i| m.max((x[i] - truth[i]).abs()))
}

/// A rotation angle logged 0.2 s late (480 s one-way, rough sea): with `--angle-latency-s 0.2`
/// the estimate at 6,000 s is as good as on the same log without the lag; left unset it is off by
/// the phase error's share of the errors (0.15 deg on errors of a few hundred arcsec).
#[test]
fn a_lagging_rotation_angle_costs_accuracy_unless_the_latency_is_set() {
    let dir = temp_dir("cli-latency");
    let gen = |name: &str, lag: &str| {
        let log = dir.join(name);
        host_sim_ok(&[
            "generate",
            "--scenario",
            "sea",
            "--seed",
            "4",
            "--duration",
            "6000",
            "--log-angle-latency-s",
            lag,
            "--out",
            path_str(&log),
        ]);
        log
    };
    let exact = gen("exact.csv", "0");
    let late = gen("late.csv", "0.2");
    let run = |log: &Path, extra: &[&str]| {
        let est = log.with_extension("est.csv");
        let mut args = vec!["estimate", path_str(log), "--out", path_str(&est)];
        args.extend_from_slice(extra);
        host_sim_ok(&args);
        worst_off(first_and_last_arcsec(&est).1, truth_arcsec(log))
    };
    let on_exact = run(&exact, &[]);
    // A clean sea log sets no limit beyond the white noise.
    let clean_est = dir.join("clean.est.csv");
    let clean = host_sim_ok(&["estimate", path_str(&exact), "--out", path_str(&clean_est)]);
    assert!(clean.contains("alarms: 0 changes declared"), "{clean}");
    assert!(!clean.contains("limit:"), "{clean}");
    let set = run(&late, &["--angle-latency-s", "0.2"]);
    let unset = run(&late, &[]);
    assert!(on_exact < 0.5, "{on_exact}");
    assert!((set - on_exact).abs() < 0.1, "set {set}, exact {on_exact}");
    assert!(unset > on_exact + 0.4, "unset {unset}, exact {on_exact}");
    let refused = host_sim(&["estimate", path_str(&late), "--angle-latency-s", "1.5"]);
    assert_eq!(refused.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("--angle-latency-s"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Known values: reported on the first row, with their 1-sigma, and learned past (the last row
/// as near the truth as without them); either option alone, a wrong count or a 1-sigma beyond the
/// configuration's prior is refused with exit status 1 and no output written.
#[test]
fn known_values_are_reported_from_the_first_row_and_learned_past() {
    let dir = temp_dir("cli-prior");
    let log = dir.join("sea.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "sea",
        "--seed",
        "2",
        "--duration",
        "3000",
        "--out",
        path_str(&log),
    ]);
    let truth = truth_arcsec(&log);
    let prior: Vec<String> = [5.0, -5.0, -10.0, 10.0]
        .iter()
        .zip(truth)
        .map(|(d, x)| format!("{}", x + d))
        .collect();
    let prior = prior.join(",");
    let est = dir.join("with.csv");
    host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&est),
        "--prior-arcsec",
        &prior,
        "--prior-sigma-arcsec",
        "20",
    ]);
    let (first, last) = first_and_last_arcsec(&est);
    let expected: Vec<f64> = prior.split(',').map(|v| v.parse().unwrap()).collect();
    for i in 0..4 {
        assert!(
            (first[i] - expected[i]).abs() < 1e-3,
            "x{} {}",
            i + 1,
            first[i]
        );
    }
    let first_row = std::fs::read_to_string(&est).unwrap();
    assert!(
        first_row
            .lines()
            .nth(1)
            .unwrap()
            .contains(",20.0000,20.0000,20.0000,20.0000,"),
        "{}",
        first_row.lines().nth(1).unwrap()
    );
    let without = dir.join("without.csv");
    host_sim_ok(&["estimate", path_str(&log), "--out", path_str(&without)]);
    let (none, last_without) = first_and_last_arcsec(&without);
    assert!(
        none.iter().all(|v| v.is_nan()),
        "no estimate on the first row without a prior"
    );
    assert!(worst_off(last, truth) < 1.0, "{last:?} against {truth:?}");
    assert!(worst_off(last_without, truth) < 1.0);
    let out = dir.join("refused.csv");
    for (args, needle) in [
        (
            vec!["--prior-arcsec", "1,2,3,4"],
            "needs --prior-sigma-arcsec",
        ),
        (vec!["--prior-sigma-arcsec", "3"], "needs --prior-arcsec"),
        (
            vec!["--prior-arcsec", "1,2,3", "--prior-sigma-arcsec", "3"],
            "four values",
        ),
        (
            vec!["--prior-arcsec", "1,2,3,4", "--prior-sigma-arcsec", "3,3"],
            "one value for all four errors or four values",
        ),
        (
            vec!["--prior-arcsec", "1,2,3,4", "--prior-sigma-arcsec", "5000"],
            "prior.sigma_rad[0]",
        ),
    ] {
        let mut a = vec!["estimate", path_str(&log), "--out", path_str(&out)];
        a.extend(args.iter().copied());
        let r = host_sim(&a);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!out.exists(), "{args:?} wrote its output");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The alarm columns latch: on a log with two outages and a slow heel that ends in
/// `model_mismatch`, the counts never go down, the window restarts are counted, and `mismatch_s`
/// on each row is the number of `model_mismatch` rows so far times the interval; the residual
/// levels and noise scales appear with the first estimate.
#[test]
fn the_alarm_columns_latch_and_agree_with_the_rows() {
    let dir = temp_dir("cli-alarms");
    let log = dir.join("heel.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "sea",
        "--seed",
        "3",
        "--duration",
        "8000",
        "--outages",
        "2",
        "--slow-heel-deg",
        "0.5",
        "--slow-heel-period-s",
        "900",
        "--out",
        path_str(&log),
    ]);
    let est = dir.join("heel.est.csv");
    let summary = host_sim_ok(&["estimate", path_str(&log), "--out", path_str(&est)]);
    let text = std::fs::read_to_string(&est).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (status, restarts, mismatch, residual, scale, x1) = (
        col("status"),
        col("window_restarts"),
        col("mismatch_s"),
        col("residual_roll_arcsec"),
        col("noise_scale_roll"),
        col("x1_arcsec"),
    );
    let (mut in_mismatch, mut last_restarts) = (0u32, 0u32);
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), header.len(), "{line}");
        if cells[status] == "model_mismatch" {
            in_mismatch += 1;
        }
        let r: u32 = cells[restarts].parse().unwrap();
        assert!(r >= last_restarts, "{line}");
        last_restarts = r;
        let m: f64 = cells[mismatch].parse().unwrap();
        assert_eq!(m, f64::from(in_mismatch), "{line}");
        // Residual level and noise scale from the first estimate on, never before.
        assert_eq!(cells[residual].is_empty(), cells[x1].is_empty(), "{line}");
        assert_eq!(cells[scale].is_empty(), cells[x1].is_empty(), "{line}");
    }
    assert!(in_mismatch > 0, "the slow heel ends in model_mismatch");
    assert!(
        last_restarts >= 2,
        "two outages restart the window: {last_restarts}"
    );
    // The summary says the same.
    let alarms = format!(
        "alarms: 0 changes declared, {last_restarts} window restarts, 0 rejected, {in_mismatch} s in model_mismatch; residual level pitch "
    );
    assert!(summary.contains(&alarms), "{summary}");
    // A slow heel of 0.5 deg at 900 s: the summary names the limit it sets on the roll pair.
    assert!(
        summary.contains("limit: the residuals hold more than the white noise the model gives")
            && summary.contains("the roll pair (x3, x4)"),
        "{summary}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Rows lost at a regular cadence set a limit the 1-sigma does not carry: the summary names the
/// cadence; rows lost at random, which average out, are not named.
#[test]
fn rows_lost_at_a_regular_cadence_are_named_and_random_loss_is_not() {
    let dir = temp_dir("cli-cadence");
    let summary_of = |name: &str, recorder: &[&str]| {
        let log = dir.join(format!("{name}.csv"));
        let mut args = vec![
            "generate",
            "--scenario",
            "sea",
            "--seed",
            "3",
            "--duration",
            "6000",
        ];
        args.extend_from_slice(recorder);
        args.extend_from_slice(&["--out", path_str(&log)]);
        host_sim_ok(&args);
        let est = dir.join(format!("{name}.est.csv"));
        host_sim_ok(&["estimate", path_str(&log), "--out", path_str(&est)])
    };
    let cadence = summary_of(
        "cadence",
        &[
            "--gap-every",
            "90",
            "--gap-rows",
            "3",
            "--drop-fraction",
            "0.01",
        ],
    );
    assert!(
        cadence.contains("limit: rows lost at a regular cadence (")
            && cadence.contains(" s later)")
            && cadence.contains("have another 90 s later"),
        "{cadence}"
    );
    let random = summary_of("random", &["--drop-fraction", "0.02"]);
    assert!(!random.contains("regular cadence"), "{random}");
    let _ = std::fs::remove_dir_all(&dir);
}
