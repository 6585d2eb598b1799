//! Logs as trial recorders write them: ISO 8601 / RFC 3339 and millisecond stamps, headers in any
//! case with spaces, `;` and tab separators give the same estimates as the plain log; stamps in
//! the wrong unit and a `--sample-interval` that contradicts them are refused with the likely
//! cause; a clock step back is counted.

use crate::common::{host_sim, host_sim_ok, path_str, temp_dir};
use std::path::{Path, PathBuf};

/// A paper log of `duration` s stamped in Unix seconds from 1700000000 (2023-11-14T22:13:20Z).
fn unix_log(dir: &Path, duration: u32) -> PathBuf {
    let log = dir.join("unix.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        &duration.to_string(),
        "--time-offset",
        "1700000000",
        "--out",
        path_str(&log),
    ]);
    log
}

/// Rewrites a log: `header` replaces the header line, `time` each row's time, and the cells are
/// joined with `separator`.
fn rewrite(
    log: &Path,
    name: &str,
    header: &str,
    separator: &str,
    time: impl Fn(f64) -> String,
) -> PathBuf {
    let text = std::fs::read_to_string(log).unwrap();
    let mut out = format!("{header}\n");
    for line in text.lines().skip(1) {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        cells[0] = time(cells[0].parse().unwrap());
        out.push_str(&cells.join(separator));
        out.push('\n');
    }
    let path = log.with_file_name(name);
    std::fs::write(&path, out).unwrap();
    path
}

fn estimates(log: &Path) -> Vec<u8> {
    let out = log.with_extension("est.csv");
    host_sim_ok(&["estimate", path_str(log), "--out", path_str(&out)]);
    std::fs::read(out).unwrap()
}

/// 2023-11-14T22:13:20Z plus `t - 1700000000` seconds, as an ISO 8601 stamp.
fn iso(t: f64, separator: char, zone: &str) -> String {
    // Seconds after 2023-11-14T00:00:00Z.
    let s = 22 * 3600 + 13 * 60 + 20 + (t - 1_700_000_000.0) as i64;
    let (day, of_day) = (14 + s / 86_400, s % 86_400);
    format!(
        "2023-11-{day:02}{separator}{:02}:{:02}:{:02}{zone}",
        of_day / 3600,
        of_day / 60 % 60,
        of_day % 60
    )
}

#[test]
fn iso_8601_and_millisecond_stamps_give_the_estimates_of_unix_seconds() {
    let dir = temp_dir("cli-stamps-iso");
    let log = unix_log(&dir, 3000);
    let expected = estimates(&log);
    let header = "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg";
    let utc_header = header.replacen("time_s", "time_utc", 1);
    let ms_header = header.replacen("time_s", "time_ms", 1);
    let cases = [
        // ISO stamps in the time_s column (what made every row unreadable before).
        rewrite(&log, "iso_in_time_s.csv", header, ",", |t| iso(t, 'T', "Z")),
        rewrite(&log, "iso_space_no_zone.csv", &utc_header, ",", |t| {
            iso(t, ' ', "")
        }),
        rewrite(&log, "iso_utc.csv", &utc_header, ",", |t| {
            iso(t, 'T', "+00:00")
        }),
        rewrite(&log, "ms.csv", &ms_header, ",", |t| {
            format!("{}", t * 1000.0)
        }),
    ];
    for case in cases {
        assert!(
            estimates(&case) == expected,
            "{}: estimates differ",
            case.display()
        );
    }
}

#[test]
fn headers_in_any_case_with_spaces_and_semicolon_or_tab_separators_give_the_same_estimates() {
    let dir = temp_dir("cli-stamps-headers");
    let log = unix_log(&dir, 3000);
    let expected = estimates(&log);
    let spaced = "Time S;Rotation Deg;Platform Deg;Latitude Deg;Heading Deg;Roll Deg;Pitch Deg";
    let upper =
        "TIME_S\tROTATION_DEG\tPLATFORM_DEG\tLATITUDE_DEG\tHEADING_DEG\tROLL_DEG\tPITCH_DEG";
    for case in [
        rewrite(&log, "semicolon.csv", spaced, ";", |t| t.to_string()),
        rewrite(&log, "tab.csv", upper, "\t", |t| t.to_string()),
    ] {
        assert!(
            estimates(&case) == expected,
            "{}: estimates differ",
            case.display()
        );
    }
}

/// Runs `estimate` and expects it to fail before writing anything, with `needles` on standard error.
fn refused(args: &[&str], out: &Path, needles: &[&str]) {
    let result = host_sim(args);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{args:?}: {stderr}");
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "{args:?}: {needle:?} not in {stderr}"
        );
    }
    assert_eq!(
        stderr.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{stderr}"
    );
    assert!(!out.exists(), "no estimates written: {}", out.display());
}

#[test]
fn milliseconds_in_a_seconds_column_are_refused_naming_the_likely_cause() {
    let dir = temp_dir("cli-stamps-ms");
    let log = unix_log(&dir, 600);
    let header = "time_s,rotation_deg,platform_deg,latitude_deg,heading_deg,roll_deg,pitch_deg";
    let ms = rewrite(&log, "ms_in_s.csv", header, ",", |t| {
        format!("{}", t * 1000.0)
    });
    let out = dir.join("ms.est.csv");
    refused(
        &["estimate", path_str(&ms), "--out", path_str(&out)],
        &out,
        &["step by 1000 s", "milliseconds", "time_ms"],
    );
}

#[test]
fn a_sample_interval_that_contradicts_the_stamps_is_refused() {
    let dir = temp_dir("cli-stamps-pinned");
    let log = unix_log(&dir, 600);
    let out = dir.join("pinned.est.csv");
    refused(
        &[
            "estimate",
            path_str(&log),
            "--sample-interval",
            "2",
            "--out",
            path_str(&out),
        ],
        &out,
        &["--sample-interval 2 s contradicts the log's time stamps, which step by 1 s"],
    );
}

#[test]
fn a_clock_step_back_of_5_s_is_counted() {
    let dir = temp_dir("cli-stamps-clock-step");
    let log = dir.join("p.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "3000",
        "--out",
        path_str(&log),
    ]);
    // From t = 2000 on, the recorder's clock is 5 s late.
    let text = std::fs::read_to_string(&log).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        let (t, rest) = line.split_once(',').unwrap();
        match t.parse::<f64>() {
            Ok(t) if i > 0 && t >= 2000.0 => out.push_str(&format!("{},{rest}\n", t - 5.0)),
            _ => out.push_str(&format!("{line}\n")),
        }
    }
    std::fs::write(&log, out).unwrap();
    let stdout = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("e.csv")),
    ]);
    assert!(stdout.contains("1 clock steps"), "{stdout}");
}
