//! `generate`'s log, read back: rotation schemes, sample interval, lost rows, outages, time
//! stamps, and the default scenarios unchanged.

use crate::common::{host_sim, host_sim_ok, path_str, temp_dir};
use std::path::Path;

/// CRC-64 (ECMA-182) and length of a file.
fn checksum(path: &Path) -> (u64, usize) {
    let bytes = std::fs::read(path).unwrap();
    (
        crc::Crc::<u64>::new(&crc::CRC_64_ECMA_182).checksum(&bytes),
        bytes.len(),
    )
}

/// The three scenarios' logs, without any of the rotation-scheme or recorder options, are
/// byte for byte those of the generator before those options existed (checksums of the logs it
/// wrote): logs, results and figures quoted in docs/ stay reproducible.
#[test]
fn default_scenarios_unchanged() {
    let dir = temp_dir("gen-golden");
    let expected: [(&str, &str, u64, usize); 3] = [
        ("paper", "2000", 1_676_693_016_960_452_731, 203_234),
        ("turntable", "1500", 14_224_204_780_103_870_363, 152_109),
        ("sea", "1500", 1_519_086_973_725_290_067, 174_608),
    ];
    for (scenario, duration, crc, len) in expected {
        let log = dir.join(format!("{scenario}.csv"));
        host_sim_ok(&[
            "generate",
            "--scenario",
            scenario,
            "--seed",
            "3",
            "--duration",
            duration,
            "--out",
            path_str(&log),
        ]);
        assert_eq!(checksum(&log), (crc, len), "{scenario}");
    }
}

/// The same for the model-mismatch switches of `monte-carlo` and `compare` (rotation period
/// error, rotation-angle jitter, coloured noise, drifting errors) on the rough sea.
#[test]
fn mismatch_logs_unchanged() {
    use host_sim::sim::scenario::{generate, Mismatch, ScenarioKind, ScenarioParams};
    let mut p = ScenarioParams::new(ScenarioKind::Sea, 11);
    p.duration_s = 1200.0;
    p.mismatch = Mismatch {
        rotation_period_error: 0.005,
        rotation_jitter_deg: 0.05,
        error_drift_arcsec_per_day: 20.0,
        low_frequency_rate_error: 0.2,
        coloured_noise_arcsec: 2.0,
        ..Mismatch::default()
    };
    let mut bytes = Vec::new();
    host_sim::formats::log_csv::write_log_to(&mut bytes, &generate(&p).rows).unwrap();
    let crc = crc::Crc::<u64>::new(&crc::CRC_64_ECMA_182).checksum(&bytes);
    assert_eq!((crc, bytes.len()), (8_036_464_345_581_861_486, 139_024));
}

use host_sim::formats::estimates_csv::read_estimates;
use host_sim::formats::log_csv::read_log;
use host_sim::formats::truth_file::{read_truth, truth_path};
use host_sim::sim::scenario::{Row, ScenarioParams};

/// What `generate` records beside a log: the scenario's parameters.
struct Truth {
    params: ScenarioParams,
}

/// Generates a paper-scenario log with `extra` options; returns its rows and truth.
fn generate(dir: &Path, name: &str, extra: &[&str]) -> (Vec<Row>, Truth) {
    let log = dir.join(format!("{name}.csv"));
    let mut args = vec![
        "generate",
        "--scenario",
        "paper",
        "--seed",
        "5",
        "--out",
        path_str(&log),
    ];
    args.extend_from_slice(extra);
    host_sim_ok(&args);
    let rows = read_log(&log).unwrap().into_iter().map(|l| l.row).collect();
    let truth = read_truth(&truth_path(&log)).unwrap().expect("truth file");
    (
        rows,
        Truth {
            params: truth
                .params
                .expect("generate records the scenario's parameters"),
        },
    )
}

/// Change of the logged rotation angle from one row to the next, deg, in (-180, 180].
fn angle_steps_deg(rows: &[Row]) -> Vec<f64> {
    rows.windows(2)
        .map(|w| -(w[0].rotation_deg - w[1].rotation_deg + 180.0).rem_euclid(360.0) + 180.0)
        .collect()
}

/// Runs of rows where the angle stands still: (first time, duration s, angle from the start deg).
fn dwells(rows: &[Row], phase_deg: f64) -> Vec<(f64, f64, f64)> {
    let mut runs: Vec<(f64, f64, f64)> = Vec::new();
    for (w, d) in rows.windows(2).zip(angle_steps_deg(rows)) {
        if d.abs() > 1e-9 {
            continue;
        }
        match runs.last_mut() {
            Some(r) if r.0 + r.1 == w[0].time_s => r.1 += w[1].time_s - w[0].time_s,
            _ => runs.push((
                w[0].time_s,
                w[1].time_s - w[0].time_s,
                (w[0].rotation_deg - phase_deg).rem_euclid(360.0),
            )),
        }
    }
    runs
}

#[test]
fn one_way_and_reciprocating_schemes_turn_as_stated() {
    let dir = temp_dir("gen-schemes-rate");
    // (scheme, period s, rate deg/s in the first half of a period, in the second half)
    for (scheme, period, first, second) in [
        ("continuous", 480.0, 0.75, 0.75),
        ("reversed", 480.0, -0.75, -0.75),
        ("reciprocating", 480.0, 1.5, -1.5),
        ("reciprocating", 720.0, 1.0, -1.0),
    ] {
        let (rows, truth) = generate(
            &dir,
            scheme,
            &[
                "--scheme",
                scheme,
                "--rotation-period",
                &period.to_string(),
                "--duration",
                "1500",
            ],
        );
        assert_eq!(rows.len(), 1500);
        assert_eq!(
            (truth.params.scheme.name(), truth.params.rotation_period_s),
            (scheme, period)
        );
        assert!((rows[0].rotation_deg - truth.params.rotation_phase_deg).abs() < 1e-9);
        for (k, d) in angle_steps_deg(&rows).into_iter().enumerate() {
            let u = (k as f64).rem_euclid(period);
            // The row after the turnaround moves partly each way.
            if u == period / 2.0 - 1.0 || u == period - 1.0 && first != second {
                continue;
            }
            let expected = if u < period / 2.0 { first } else { second };
            assert!(
                (d - expected).abs() < 1e-9,
                "{scheme} {period} s: step after {k} s is {d} deg, expected {expected}"
            );
        }
    }
}

#[test]
fn stop_and_go_schemes_dwell_at_their_positions() {
    let dir = temp_dir("gen-schemes-dwell");
    // (scheme, period s, dwell s, angles of the positions of one period, deg from the start)
    let cases: [(&str, f64, f64, &[f64]); 3] = [
        ("four-position", 480.0, 105.0, &[90.0, 180.0, 270.0, 0.0]),
        ("four-position", 360.0, 75.0, &[90.0, 180.0, 270.0, 0.0]),
        (
            "eight-position",
            480.0,
            45.0,
            &[90.0, 180.0, 270.0, 0.0, 270.0, 180.0, 90.0, 0.0],
        ),
    ];
    for (scheme, period, dwell, positions) in cases {
        let (rows, truth) = generate(
            &dir,
            scheme,
            &[
                "--scheme",
                scheme,
                "--rotation-period",
                &period.to_string(),
                "--duration",
                &(2.0 * period + 1.0).to_string(),
            ],
        );
        let runs = dwells(&rows, truth.params.rotation_phase_deg);
        assert_eq!(
            runs.len(),
            2 * positions.len(),
            "{scheme} {period}: {runs:?}"
        );
        let step = period / positions.len() as f64;
        for (i, (start, len, angle)) in runs.iter().enumerate() {
            assert_eq!(
                *start,
                i as f64 * step + 15.0,
                "{scheme} {period}: move of 15 s before dwell {i}: {runs:?}"
            );
            assert_eq!(*len, dwell, "{scheme} {period}: dwell {i}: {runs:?}");
            let expected = positions[i % positions.len()];
            let off = (angle - expected + 180.0).rem_euclid(360.0) - 180.0;
            assert!(
                off.abs() < 1e-9,
                "{scheme} {period}: dwell {i} at {angle} deg, expected {expected}"
            );
        }
        // Moves go forward (+) or back (-) by up to 12 deg/s in the middle, never more.
        let steps = angle_steps_deg(&rows);
        assert!(steps.iter().all(|d| d.abs() <= 12.0 + 1e-9));
        if scheme == "eight-position" {
            assert!(steps[5] > 0.0 && steps[period as usize / 2 + 5] < 0.0);
        } else {
            assert!(steps.iter().all(|d| *d >= 0.0));
        }
    }
}

#[test]
fn scheme_needs_room_for_its_moves_and_ranges_are_checked() {
    let dir = temp_dir("gen-ranges");
    let log = dir.join("x.csv");
    for (args, message) in [
        (
            &["--scheme", "eight-position", "--rotation-period", "100"][..],
            "at least 120 s",
        ),
        (
            &["--rotation-period", "4000"][..],
            "--rotation-period must be between 60 and 3600",
        ),
        (
            // Down to 200 Hz, for `estimate --bin-interval-s` (cli_binning.rs).
            &["--sample-interval", "0.004"][..],
            "--sample-interval must be between 0.005 and 10",
        ),
        (
            &["--drop-fraction", "1"][..],
            "--drop-fraction must be in [0, 1)",
        ),
        (
            &["--time-jitter", "0.5"][..],
            "below half the sample interval",
        ),
        (&["--outages", "17"][..], "do not fit"),
    ] {
        let mut a = vec![
            "generate",
            "--scenario",
            "paper",
            "--duration",
            "1000",
            "--out",
            path_str(&log),
        ];
        a.extend_from_slice(args);
        let out = crate::common::host_sim(&a);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(message),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn dropped_rows_follow_the_drop_fraction_and_leave_the_rest_unchanged() {
    let dir = temp_dir("gen-drop");
    let (all, _) = generate(&dir, "all", &["--duration", "4000"]);
    let (kept, truth) = generate(
        &dir,
        "kept",
        &["--duration", "4000", "--drop-fraction", "0.05"],
    );
    assert_eq!(truth.params.recording.drop_fraction, 0.05);
    // Binomial(4000, 0.05): mean 200, sigma 13.8; 4.5 sigma either side.
    let dropped = all.len() - kept.len();
    assert!((138..=262).contains(&dropped), "{dropped} of 4000 dropped");
    // Every kept row is the lossless log's row at that instant: loss does not change the data.
    for r in &kept {
        assert_eq!(*r, all[r.time_s as usize]);
    }
    // Spread over the log, not bunched: each quarter loses between 20 and 80 rows.
    for q in 0..4 {
        let lost = 1000
            - kept
                .iter()
                .filter(|r| (r.time_s / 1000.0).floor() as usize == q)
                .count();
        assert!((20..=80).contains(&lost), "quarter {q}: {lost}");
    }
}

#[test]
fn outages_are_60_s_of_missing_rows_at_the_recorded_times() {
    let dir = temp_dir("gen-outages");
    let (rows, truth) = generate(&dir, "out", &["--duration", "3000", "--outages", "3"]);
    let starts = &truth.params.recording.outage_starts_s;
    assert_eq!(starts.len(), 3);
    assert_eq!(truth.params.recording.outage_duration_s, 60.0);
    assert_eq!(
        rows.len(),
        3000 - 3 * 60,
        "each outage removes 60 one-second rows"
    );
    let present: std::collections::HashSet<u64> = rows.iter().map(|r| r.time_s as u64).collect();
    for t in 0..3000u64 {
        let inside = starts
            .iter()
            .any(|s| (t as f64) >= *s && (t as f64) < s + 60.0);
        assert_eq!(
            present.contains(&t),
            !inside,
            "row at {t} s (outages from {starts:?})"
        );
    }
    // Seen from the log: three jumps of 61 s, every other step 1 s.
    let mut gaps: Vec<f64> = rows
        .windows(2)
        .map(|w| w[1].time_s - w[0].time_s)
        .filter(|d| *d != 1.0)
        .collect();
    gaps.sort_by(f64::total_cmp);
    assert_eq!(gaps, vec![61.0; 3], "{starts:?}");
}

#[test]
fn stamps_carry_the_offset_and_jitter_within_bounds_and_full_precision() {
    let dir = temp_dir("gen-stamps");
    let (rows, truth) = generate(
        &dir,
        "stamps",
        &[
            "--duration",
            "3000",
            "--time-offset",
            "1.7e9",
            "--time-jitter",
            "0.02",
        ],
    );
    assert_eq!(
        (
            truth.params.recording.time_offset_s,
            truth.params.recording.time_jitter_s
        ),
        (1.7e9, 0.02)
    );
    assert_eq!(rows.len(), 3000);
    let jitter: Vec<f64> = rows
        .iter()
        .enumerate()
        .map(|(k, r)| r.time_s - 1.7e9 - k as f64)
        .collect();
    assert!(
        jitter.iter().all(|j| j.abs() <= 0.02 + 1e-6),
        "{:?}",
        jitter.iter().fold(0.0f64, |m, j| m.max(j.abs()))
    );
    // Uniform in [-0.02, 0.02]: spans the range, mean near 0 (sigma of the mean 0.0002).
    let (lo, hi) = jitter
        .iter()
        .fold((0.0f64, 0.0f64), |(lo, hi), j| (lo.min(*j), hi.max(*j)));
    assert!(lo < -0.019 && hi > 0.019, "{lo} {hi}");
    assert!((jitter.iter().sum::<f64>() / 3000.0).abs() < 0.001);
    // Written as decimals to the microsecond, which read back as the stamps.
    let text = std::fs::read_to_string(dir.join("stamps.csv")).unwrap();
    for (k, line) in text.lines().skip(1).enumerate() {
        let field = line.split(',').next().unwrap();
        let decimals = field.split('.').nth(1).map_or(0, str::len);
        assert!(decimals <= 6 && !field.contains('e'), "{field}");
        let whole: i64 = field.split('.').next().unwrap().parse().unwrap();
        assert!(
            (whole - 1_700_000_000 - k as i64).abs() <= 1,
            "{field} at row {k}"
        );
    }
    // The data are those of the true instants: the exact-stamp log's rows.
    let (exact, _) = generate(&dir, "exact", &["--duration", "3000"]);
    for (a, b) in rows.iter().zip(&exact) {
        assert_eq!(
            Row {
                time_s: b.time_s,
                ..*a
            },
            *b
        );
    }
}

#[test]
fn sample_interval_sets_the_row_spacing() {
    let dir = temp_dir("gen-interval");
    let (rows, truth) = generate(
        &dir,
        "fast",
        &["--duration", "200", "--sample-interval", "0.1"],
    );
    assert_eq!(truth.params.sample_interval_s, 0.1);
    assert_eq!(rows.len(), 2000);
    assert!(rows
        .windows(2)
        .all(|w| (w[1].time_s - w[0].time_s - 0.1).abs() < 1e-9));
    let text = std::fs::read_to_string(dir.join("fast.csv")).unwrap();
    assert!(
        text.lines().nth(4).unwrap().starts_with("0.3,"),
        "{}",
        text.lines().nth(4).unwrap()
    );
    // The rotation at 0.1 s: 0.075 deg per row (480 s period).
    let d = angle_steps_deg(&rows);
    assert!(d.iter().all(|x| (x - 0.075).abs() < 1e-9));
    let (slow, _) = generate(
        &dir,
        "slow",
        &["--duration", "200", "--sample-interval", "2"],
    );
    assert_eq!(slow.len(), 100);
    assert_eq!(slow[99].time_s, 198.0);
}

#[test]
fn estimator_learns_the_period_and_interval_or_takes_them_from_the_command_line() {
    let dir = temp_dir("gen-pin");
    let log = dir.join("two.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "6000",
        "--sample-interval",
        "2",
        "--out",
        path_str(&log),
    ]);
    let x = read_truth(&truth_path(&log)).unwrap().unwrap().x_arcsec;
    // Nothing pinned: the 2 s interval and the 480 s period are learned from the log.
    let learned = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("u.csv")),
    ]);
    assert!(
        learned.contains("rotation: one-way, period 480 s; sample interval 2 s"),
        "{learned}"
    );
    // Pinned to 2 s and 480 s: said so, and estimating from the first window.
    let pinned = host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--sample-interval",
        "2",
        "--rotation-period",
        "480",
        "--out",
        path_str(&dir.join("p.csv")),
    ]);
    assert!(pinned.contains("period 480 s (pinned)"), "{pinned}");
    for name in ["u.csv", "p.csv"] {
        let rows = read_estimates(&dir.join(name)).unwrap();
        let e = rows.last().unwrap().x_arcsec.expect("an estimate");
        for i in 0..4 {
            assert!(
                (e[i] - x[i]).abs() < 2.0,
                "{name}: x{}: {} vs {}",
                i + 1,
                e[i],
                x[i]
            );
        }
    }
    let first = |name: &str| {
        read_estimates(&dir.join(name))
            .unwrap()
            .iter()
            .find(|r| r.x_arcsec.is_some())
            .map(|r| r.time_s)
    };
    assert!(
        first("p.csv") < first("u.csv"),
        "pinned {:?}, learned {:?}",
        first("p.csv"),
        first("u.csv")
    );
}

#[test]
fn an_offset_log_estimates_and_reports_as_the_plain_one() {
    let dir = temp_dir("gen-offset");
    let (plain, offset) = (dir.join("plain.csv"), dir.join("offset.csv"));
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "3000",
        "--out",
        path_str(&plain),
    ]);
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "3000",
        "--time-offset",
        "1.7e9",
        "--out",
        path_str(&offset),
    ]);
    let report = |log: &Path, est: &str| {
        let out = host_sim_ok(&["estimate", path_str(log), "--out", path_str(&dir.join(est))]);
        out[out.find("accuracy against the truth").expect("report")..].to_string()
    };
    // The accuracy table maps the stamps back to the sample instants: same settling times.
    assert_eq!(report(&offset, "o.csv"), report(&plain, "p.csv"));
    let (a, b) = (
        read_estimates(&dir.join("o.csv")).unwrap(),
        read_estimates(&dir.join("p.csv")).unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.time_s, y.time_s + 1.7e9);
        assert_eq!(x.x_arcsec, y.x_arcsec);
    }
}

/// `generate`'s ship options put their motion into the roll and pitch (true attitude: the truth
/// file records them, the errors' oscillation is unchanged) and nothing else; the sinusoids'
/// phases come from the seed and are recorded.
#[test]
fn ship_options_add_slow_heel_trim_and_heel_in_turns() {
    use host_sim::sim::ship_motion::turns;
    use std::f64::consts::PI;
    let dir = tempfile::tempdir().unwrap();
    let (plain, _) = generate(dir.path(), "plain", &["--duration", "7500"]);
    let (ship, truth) = generate(
        dir.path(),
        "ship",
        &[
            "--duration",
            "7500",
            "--slow-heel-deg",
            "0.3,0.15",
            "--slow-heel-period-s",
            "1200,2500",
            "--slow-trim-deg",
            "0.1",
            "--slow-trim-period-s",
            "1800",
            "--heel-in-turns-deg",
            "3",
            "--heel-per-turn-rate",
            "0.4",
        ],
    );
    let m = &truth.params.ship_motion;
    assert_eq!(truth.params.mismatch.heel_in_turns_deg, 3.0);
    assert_eq!(m.heel_per_turn_rate_deg_per_deg_s, 0.4);
    let heel: Vec<(f64, f64)> = m
        .slow_heel
        .iter()
        .map(|c| (c.amplitude_deg, c.period_s))
        .collect();
    assert_eq!(heel, vec![(0.3, 1200.0), (0.15, 2500.0)]);
    assert_eq!(
        (m.slow_trim[0].amplitude_deg, m.slow_trim[0].period_s),
        (0.1, 1800.0)
    );
    let wave = |c: &host_sim::sim::scenario::SwayComponent, t: f64| {
        c.amplitude_deg * (2.0 * PI * t / c.period_s + c.phase_rad).sin()
    };
    assert_eq!(plain.len(), ship.len());
    let mut turning = 0;
    for (a, b) in plain.iter().zip(&ship) {
        let t = a.time_s;
        // The paper scenario has no heading weave: the course turns only in the turns (the first
        // at 7200 s, to starboard at 0.5 deg/s), heeling 3 deg outward plus 0.4 x 0.5 deg.
        let turn = turns(3.0, t);
        if turn.rate_deg_s != 0.0 {
            turning += 1;
            assert_eq!(turn.rate_deg_s, 0.5);
        }
        let roll = m.slow_heel.iter().map(|c| wave(c, t)).sum::<f64>() + turn.heel_deg
            - 0.4 * turn.rate_deg_s;
        let pitch = wave(&m.slow_trim[0], t);
        let heading = (b.heading_deg - a.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
        assert!((b.roll_deg - a.roll_deg - roll).abs() < 2e-9, "roll at {t}");
        assert!(
            (b.pitch_deg - a.pitch_deg - pitch).abs() < 2e-9,
            "pitch at {t}"
        );
        assert!((heading - turn.heading_deg).abs() < 2e-9, "heading at {t}");
        assert_eq!(
            (a.rotation_deg, a.platform_deg, a.latitude_deg),
            (b.rotation_deg, b.platform_deg, b.latitude_deg)
        );
    }
    assert_eq!(turning, 180, "one turn of 180 s from 7200 s");
    // An amplitude without its period, or counts that differ, are refused with the reason.
    let log = dir.path().join("x.csv");
    for (args, message) in [
        (
            &["--slow-heel-deg", "0.3,0.1", "--slow-heel-period-s", "1200"][..],
            "--slow-heel-deg gives 2 amplitudes but --slow-heel-period-s 1 periods",
        ),
        (&["--slow-trim-deg", "0.1"][..], "--slow-trim-period-s"),
        (
            &["--slow-trim-deg", "0.1", "--slow-trim-period-s", "0"][..],
            "every period must be a finite number of seconds above 0, got 0",
        ),
    ] {
        let mut a = vec![
            "generate",
            "--scenario",
            "paper",
            "--duration",
            "100",
            "--out",
        ];
        a.push(path_str(&log));
        a.extend_from_slice(args);
        let out = crate::common::host_sim(&a);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(message),
            "{args:?}: {stderr}"
        );
    }
    assert!(!log.exists());
}

/// `--sway-lines N` draws the sea's wave spectra (roll, pitch, heading sway) with N lines each at
/// the same sway level; only the sea scenario has wave spectra.
#[test]
fn sway_lines_redraw_the_sea_spectra_at_the_same_level() {
    let dir = temp_dir("gen-sway-lines");
    let params_of = |name: &str, extra: &[&str]| {
        let log = dir.join(format!("{name}.csv"));
        let mut args = vec![
            "generate",
            "--scenario",
            "sea",
            "--seed",
            "2",
            "--duration",
            "100",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", path_str(&log)]);
        host_sim_ok(&args);
        read_truth(&truth_path(&log))
            .unwrap()
            .expect("truth file")
            .params
            .expect("generate records the scenario's parameters")
    };
    let rms = |c: &[host_sim::sim::scenario::SwayComponent]| {
        c.iter()
            .map(|s| s.amplitude_deg * s.amplitude_deg / 2.0)
            .sum::<f64>()
            .sqrt()
    };
    let default = params_of("default", &[]);
    let dense = params_of("dense", &["--sway-lines", "500"]);
    for (few, many) in [
        (&default.roll_sway, &dense.roll_sway),
        (&default.pitch_sway, &dense.pitch_sway),
        (&default.heading_sway, &dense.heading_sway),
    ] {
        assert_eq!((few.len(), many.len()), (40, 500));
        assert!((rms(few) - rms(many)).abs() < 1e-9 * rms(few));
    }
    let log = dir.join("paper.csv");
    let r = host_sim(&[
        "generate",
        "--scenario",
        "paper",
        "--sway-lines",
        "500",
        "--out",
        path_str(&log),
    ]);
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr)
        .contains("--sway-lines applies to the sea scenario only"));
    assert!(!log.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
