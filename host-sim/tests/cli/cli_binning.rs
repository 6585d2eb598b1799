//! Attitude at the navigation rate: a 200 Hz log (`generate --sample-interval 0.005`) read with
//! `estimate --bin-interval-s 1` estimates as the same log averaged to 1 s by a navigator, and near
//! the truth; without the option such a log is refused with the option named; bad rows in a
//! binned log are refused, counted, and leave the bins as they were. (`stream --bin-interval-s`
//! bins through the same code: its tests with a stand-in firmware are in
//! `host-sim/src/stream/push.rs`.)

use crate::common::{host_sim, host_sim_ok, path_str, temp_dir};
use host_sim::formats::estimates_csv::read_estimates;
use host_sim::formats::log_csv::{read_log, write_log};
use host_sim::sim::scenario::Row;
use std::path::Path;

/// The generated log's interval, s (200 Hz).
const NAV_INTERVAL_S: f64 = 0.005;
/// Rows a second.
const ROWS_PER_S: usize = 200;

/// The truth file's x1..x4, arcsec.
fn truth_arcsec(log: &Path) -> [f64; 4] {
    let text = std::fs::read_to_string(log.with_extension("truth.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    core::array::from_fn(|i| v["x_arcsec"][i].as_f64().unwrap())
}

/// The time and x1..x4 (arcsec) of an estimates CSV's last row.
fn last_estimate(est: &Path) -> (f64, [f64; 4]) {
    let rows = read_estimates(est).unwrap();
    let last = rows.last().unwrap();
    (last.time_s, last.x_arcsec.expect("an estimate at the end"))
}

/// Wraps to [-180, 180).
fn wrap_180(deg: f64) -> f64 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

/// The mean of each second of 200 Hz rows, as a navigator averages them: the angles that wrap
/// (rotation, platform, heading) as offsets from the second's first row, stamped at the second's
/// middle.
fn average_each_second(rows: &[Row]) -> Vec<Row> {
    let second = |r: &Row| (r.time_s / NAV_INTERVAL_S).round() as usize / ROWS_PER_S;
    rows.chunk_by(|a, b| second(a) == second(b))
        .map(|chunk| {
            assert_eq!(chunk.len(), ROWS_PER_S, "every second of the log is full");
            let first = chunk[0];
            let n = chunk.len() as f64;
            let mean = |f: fn(&Row) -> f64, wraps: bool| {
                let sum: f64 = chunk
                    .iter()
                    .map(|r| {
                        let d = f(r) - f(&first);
                        if wraps {
                            wrap_180(d)
                        } else {
                            d
                        }
                    })
                    .sum();
                f(&first) + sum / n
            };
            Row {
                time_s: second(&first) as f64 + 0.5,
                rotation_deg: mean(|r| r.rotation_deg, true).rem_euclid(360.0),
                platform_deg: mean(|r| r.platform_deg, true).rem_euclid(360.0),
                latitude_deg: mean(|r| r.latitude_deg, false),
                heading_deg: mean(|r| r.heading_deg, true).rem_euclid(360.0),
                roll_deg: mean(|r| r.roll_deg, false),
                pitch_deg: mean(|r| r.pitch_deg, false),
            }
        })
        .collect()
}

/// A 2,000 s sea log at 200 Hz: `estimate --bin-interval-s 1` ends within 0.1 arcsec of the same
/// log averaged to 1 s in this test and estimated without the option, and both end within 1
/// arcsec of the truth (the sea scenario's 1 Hz logs end 0.35 arcsec off at 2,000 s, median of 3
/// seeds: docs/interface.md).
#[test]
fn a_200_hz_log_binned_to_1_s_estimates_as_its_own_1_s_average() {
    let dir = temp_dir("cli-binning");
    let log = dir.join("nav200.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "sea",
        "--seed",
        "1",
        "--duration",
        "2000",
        "--sample-interval",
        "0.005",
        "--out",
        path_str(&log),
    ]);
    let truth = truth_arcsec(&log);

    let binned_est = dir.join("binned.est.csv");
    let report = dir.join("report");
    let summary = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--bin-interval-s",
        "1",
        "--out",
        path_str(&binned_est),
        "--report",
        path_str(&report),
    ]);
    let binned = "400000 rows averaged into 2000 bins of 1 s (0 rows refused)";
    assert!(
        summary.contains(&format!("binned: {binned}")) && summary.contains("sample interval 1 s"),
        "{summary}"
    );
    let page = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(
        page.contains(binned),
        "the report page says what was binned"
    );

    let rows: Vec<Row> = read_log(&log).unwrap().iter().map(|l| l.row).collect();
    assert_eq!(rows.len(), 2000 * ROWS_PER_S);
    let averaged = average_each_second(&rows);
    let averaged_log = dir.join("nav1.csv");
    write_log(&averaged_log, &averaged).unwrap();
    let averaged_est = dir.join("averaged.est.csv");
    host_sim_ok(&[
        "estimate",
        path_str(&averaged_log),
        "--out",
        path_str(&averaged_est),
    ]);

    let (t_binned, x_binned) = last_estimate(&binned_est);
    let (t_averaged, x_averaged) = last_estimate(&averaged_est);
    eprintln!("at {t_binned} s: binned {x_binned:?}, averaged {x_averaged:?}, truth {truth:?}");
    assert_eq!(t_binned, 1999.5, "the last bin's centre");
    assert_eq!(t_averaged, t_binned);
    for i in 0..4 {
        let apart = (x_binned[i] - x_averaged[i]).abs();
        assert!(
            apart < 0.1,
            "x{}: binned {} against averaged {}",
            i + 1,
            x_binned[i],
            x_averaged[i]
        );
        for (what, x) in [("binned", x_binned), ("averaged", x_averaged)] {
            let off = (x[i] - truth[i]).abs();
            assert!(
                off < 1.0,
                "{what}: x{} off the truth by {off} arcsec",
                i + 1
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without `--bin-interval-s` a 200 Hz log is refused, naming the option; the option out of its
/// range, or against another `--sample-interval`, is refused; rows the binner refuses (a NaN, a
/// stamp going back) are counted and leave their bins as they were: the estimates are those of
/// the log without them, byte for byte.
#[test]
fn binning_is_asked_for_its_range_checked_and_bad_rows_left_out() {
    let dir = temp_dir("cli-binning-refusals");
    let log = dir.join("nav200.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "1000",
        "--sample-interval",
        "0.005",
        "--out",
        path_str(&log),
    ]);
    let refused = |args: &[&str], expect: &[&str]| {
        let out = host_sim(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        for e in expect {
            assert!(stderr.contains(e), "{args:?}: {stderr}");
        }
    };
    let est = dir.join("e.csv");
    refused(
        &["estimate", path_str(&log), "--out", path_str(&est)],
        &["step by 0.005 s", "--bin-interval-s"],
    );
    for bad in ["0.05", "11", "nan"] {
        refused(
            &["estimate", path_str(&log), "--bin-interval-s", bad],
            &["--bin-interval-s must be between 0.1 and 10 s"],
        );
        // `stream` refuses it before it opens the port.
        refused(
            &[
                "stream",
                "--port",
                "/nonexistent/port",
                path_str(&log),
                "--out",
                path_str(&est),
                "--bin-interval-s",
                bad,
            ],
            &["--bin-interval-s must be between 0.1 and 10 s"],
        );
    }
    refused(
        &[
            "estimate",
            path_str(&log),
            "--bin-interval-s",
            "1",
            "--sample-interval",
            "2",
        ],
        &["--sample-interval 2 contradicts --bin-interval-s 1"],
    );
    assert!(!est.exists(), "nothing written by a refused run");

    // A NaN roll, and a row stamped back into the previous second, added to the log.
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut nan_row: Vec<String> = lines[1001].split(',').map(String::from).collect();
    nan_row[0] = "5.0025".into();
    nan_row[5] = "nan".into();
    let mut back_row: Vec<String> = lines[2001].split(',').map(String::from).collect();
    back_row[0] = "9.5".into();
    lines.insert(1002, nan_row.join(","));
    lines.insert(2003, back_row.join(","));
    let bad_log = dir.join("bad.csv");
    std::fs::write(&bad_log, lines.join("\n") + "\n").unwrap();
    let run = |log: &Path, out: &Path| {
        host_sim_ok(&[
            "estimate",
            path_str(log),
            "--bin-interval-s",
            "1",
            "--out",
            path_str(out),
        ])
    };
    let clean_est = dir.join("clean.est.csv");
    let bad_est = dir.join("bad.est.csv");
    run(&log, &clean_est);
    let summary = run(&bad_log, &bad_est);
    assert!(
        summary.contains(
            "binned: 200002 rows averaged into 1000 bins of 1 s (2 rows refused: non_finite 1, time_not_increasing 1)"
        ),
        "{summary}"
    );
    assert_eq!(
        std::fs::read(&bad_est).unwrap(),
        std::fs::read(&clean_est).unwrap(),
        "the refused rows changed the estimates"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `stream --nav-rate` (the firmware bins the rows) is refused with `--bin-interval-s` (binning
/// on the host), and `--corrected-out` without it (exit status 2, the options named);
/// `--corrected-out` may not name an input nor the estimates file, nor `--defmt-log` it, and it
/// may not share standard output with `--out` (exit status 1). All refused before the port is
/// opened, nothing written. With `--push`, `--realtime`, `--window` and `--resume` it is taken:
/// the run gets as far as the port.
#[test]
fn stream_nav_rate_conflicts_and_its_corrected_output_are_refused_before_streaming() {
    let dir = temp_dir("cli-stream-nav-rate-refusals");
    let log = dir.join("nav.csv");
    std::fs::write(
        &log,
        "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n0,1,2,3,4,1,2\n",
    )
    .unwrap();
    let (est, cor) = (dir.join("e.csv"), dir.join("c.csv"));
    let stream = |extra: &[&str], status: i32, expect: &[&str]| {
        let mut args = vec![
            "stream",
            "--port",
            "/nonexistent/port",
            path_str(&log),
            "--out",
            path_str(&est),
        ];
        args.extend_from_slice(extra);
        let out = host_sim(&args);
        assert_eq!(out.status.code(), Some(status), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        for e in expect {
            assert!(stderr.contains(e), "{args:?}: {stderr}");
        }
    };
    stream(
        &["--nav-rate", "--bin-interval-s", "1"],
        2,
        &["--nav-rate", "--bin-interval-s", "cannot be used with"],
    );
    for taken in [
        &["--push", "--realtime", "--window", "3"][..],
        &["--resume"][..],
        &["--push", "--resume"][..],
    ] {
        let mut extra = vec!["--nav-rate"];
        extra.extend_from_slice(taken);
        stream(
            &extra,
            1,
            &["cannot open serial port /nonexistent/port at 115200 baud"],
        );
    }
    stream(
        &["--corrected-out", path_str(&cor)],
        2,
        &["--corrected-out", "--nav-rate"],
    );
    stream(
        &["--nav-rate", "--corrected-out", path_str(&log)],
        1,
        &["--corrected-out names the log itself"],
    );
    stream(
        &["--nav-rate", "--corrected-out", path_str(&est)],
        1,
        &["--corrected-out names the estimates file (--out)"],
    );
    stream(
        &[
            "--nav-rate",
            "--corrected-out",
            path_str(&cor),
            "--defmt-log",
            path_str(&cor),
        ],
        1,
        &["--defmt-log names the corrected-attitude file (--corrected-out)"],
    );
    let mut args = vec!["stream", "--port", "/nonexistent/port", path_str(&log)];
    args.extend_from_slice(&["--nav-rate", "--out", "-", "--corrected-out", "-"]);
    let out = host_sim(&args);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr)
        .contains("--out and --corrected-out cannot both be standard output"));
    assert!(!est.exists() && !cor.exists(), "nothing written");
    let _ = std::fs::remove_dir_all(&dir);
}
