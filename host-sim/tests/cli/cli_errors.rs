//! Malformed logs, NaN rows and gaps, through the binary.

use crate::common::{host_sim, host_sim_ok, path_str, temp_dir};
use host_sim::formats::estimates_csv::read_estimates;
use host_sim::formats::log_csv::HEADER;

/// Runs `estimate` (with `extra` arguments) on a log with `text`; expects failure and a one-line
/// `FILE:LINE: message`.
fn expect_error(name: &str, text: &str, line: usize, needle: &str, extra: &[&str]) {
    let dir = temp_dir(&format!("cli-err-{name}"));
    let log = dir.join("bad.csv");
    std::fs::write(&log, text).unwrap();
    let est = dir.join("e.csv");
    let mut args = vec!["estimate", path_str(&log), "--out", path_str(&est)];
    args.extend_from_slice(extra);
    let out = host_sim(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{name}: should fail");
    assert_eq!(
        out.status.code(),
        Some(1),
        "{name}: exit code (a panic gives 101)"
    );
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{name}: one line: {stderr}"
    );
    let prefix = format!("error: {}:{line}: ", log.display());
    assert!(
        stderr.starts_with(&prefix),
        "{name}: {stderr:?} should start with {prefix:?}"
    );
    assert!(stderr.contains(needle), "{name}: {stderr}");
}

#[test]
fn bad_header_is_reported_with_its_line() {
    expect_error("header", "# exported\ntime,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg\n0,1,2,3,4,5,6\n", 2, "bad header: no column \"time_s\"", &[]);
}

#[test]
fn strict_refuses_a_non_number_with_its_line() {
    expect_error(
        "nonnum",
        &format!("{HEADER}\n0,1,2,40,4,0.5,0.1\n1,1.75,2,40,4,abc,0.1\n"),
        3,
        "roll_deg: not a number",
        &["--strict"],
    );
}

#[test]
fn strict_refuses_a_short_row_with_its_line() {
    expect_error(
        "short",
        &format!("{HEADER}\n0,1,2,40,4,0.5,0.1\n\n1,1.75,2,40,4,0.5\n"),
        4,
        "short row",
        &["--strict"],
    );
}

/// Without --strict, a blank cell and a truncated last line are rejected rows, reported with their
/// line numbers; every other row is processed and written.
#[test]
fn unreadable_rows_are_skipped_counted_and_reported_with_their_lines() {
    let dir = temp_dir("cli-unreadable");
    let log = dir.join("p.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "1200",
        "--out",
        path_str(&log),
    ]);
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Line numbers are 1-based with the header on line 1: row t is on line t + 2.
    let blank = 500 + 1; // t = 500
    let mut cells: Vec<&str> = lines[blank].split(',').collect();
    cells[5] = "";
    lines[blank] = cells.join(",");
    // A log cut in the middle of its last line.
    let last = lines.len() - 1;
    lines[last] = lines[last][..12].to_string();
    std::fs::write(&log, lines.join("\n")).unwrap();
    let est = dir.join("e.csv");
    let out = host_sim(&["estimate", path_str(&log), "--out", path_str(&est)]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(
        stderr.contains(&format!(
            "{}:502: roll_deg: blank cell (row skipped)",
            log.display()
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!("{}:1201: short row", log.display())),
        "{stderr}"
    );
    assert!(stdout.contains("1198 rows, 1198 accepted"), "{stdout}");
    assert!(
        stdout.contains("unreadable rows skipped: 2 (lines 502, 1201;"),
        "{stdout}"
    );
    let rows = read_estimates(&est).unwrap();
    assert_eq!(rows.len(), 1198);
    assert!(rows.iter().all(|r| r.time_s != 500.0 && r.time_s != 1199.0));
}

#[test]
fn missing_file_is_an_error_not_a_panic() {
    let out = host_sim(&["estimate", "/nonexistent/log.csv"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/log.csv:0: cannot open"));
}

#[test]
fn nan_rows_are_rejected_and_short_gaps_filled_the_rest_processed() {
    let dir = temp_dir("cli-nan-gap");
    let log = dir.join("p.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "4000",
        "--out",
        path_str(&log),
    ]);
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Line index = 1 + time. NaN roll at t = 1000, inf pitch at t = 1001 (counted as non-finite);
    // drop t = 2000..=2001 (a 2-sample gap: filled) and t = 3000..=3009 (a run too long to fill,
    // shorter than an eighth of the period: left out, the rows around it tapered).
    let set = |l: &mut String, col: usize, v: &str| {
        let mut f: Vec<&str> = l.split(',').collect();
        f[col] = v;
        *l = f.join(",");
    };
    set(&mut lines[1001], 5, "nan");
    set(&mut lines[1002], 6, "inf");
    lines.insert(500, "# a comment in the middle".into());
    let kept: Vec<String> = lines
        .into_iter()
        .filter(|l| {
            let t: f64 = l.split(',').next().unwrap().parse().unwrap_or(-1.0);
            !(2000.0..=2001.0).contains(&t) && !(3000.0..=3009.0).contains(&t)
        })
        .collect();
    std::fs::write(&log, kept.join("\n") + "\n").unwrap();
    // Default: gaps of up to 2 lost samples are filled: the rejected NaN pair and the short gap
    // are interpolated; the run of 10 is left out, and the moving average goes on.
    let est = dir.join("e.csv");
    let stdout = host_sim_ok(&["estimate", path_str(&log), "--out", path_str(&est)]);
    assert!(
        stdout.contains("3988 rows, 3986 accepted, 4 filled"),
        "{stdout}"
    );
    assert!(stdout.contains("0 window restarts"), "{stdout}");
    assert!(
        stdout.contains("rejected rows: 2 (non_finite 2,"),
        "{stdout}"
    );
    assert!(
        stdout.contains("rotation: one-way, period 480 s; sample interval 1 s"),
        "{stdout}"
    );
    // No filling: the NaN pair and both gaps are left out, none restarts the moving average (a
    // restart takes a gap of an eighth of the period, 60 rows here).
    let unfilled = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("b.csv")),
        "--max-filled-gap-samples",
        "0",
    ]);
    assert!(
        unfilled.contains("3988 rows, 3986 accepted, 0 filled"),
        "{unfilled}"
    );
    assert!(unfilled.contains("0 window restarts"), "{unfilled}");
    let rows = read_estimates(&est).unwrap();
    assert_eq!(rows.len(), 3988, "one estimates row per input row");
    let r1000 = rows.iter().find(|r| r.time_s == 1000.0).unwrap();
    assert_eq!(r1000.status, "rejected_non_finite");
    let r999 = rows.iter().find(|r| r.time_s == 999.0).unwrap();
    assert_eq!(
        r1000.x_arcsec, r999.x_arcsec,
        "a rejected row carries the held estimate"
    );
    // Across the run left out the estimate goes on: no refill, no holding.
    let r3010 = rows.iter().find(|r| r.time_s == 3010.0).unwrap();
    assert!(
        r3010.status == "estimating" || r3010.status == "converged",
        "{}",
        r3010.status
    );
    assert!(
        rows.last().unwrap().status == "estimating" || rows.last().unwrap().status == "converged"
    );
    // The truth file is still there: the accuracy table is printed and the estimate is good.
    let x = [200.0, -150.0, 300.0, -250.0];
    let e = rows.last().unwrap().x_arcsec.unwrap();
    for i in 0..4 {
        assert!((e[i] - x[i]).abs() < 10.0, "x{}: {}", i + 1, e[i]);
    }
}
