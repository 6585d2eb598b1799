//! Inputs as people have them: columns in another order or with extra ones, gzip, standard input
//! and output, a closed pipe, an output naming the log, a minimal or broken truth file, logs
//! starting at other times, negative option values, configuration errors.

use crate::common::{host_sim, host_sim_ok, paper, path_str, temp_dir};
use std::io::{Read, Write};
use std::path::Path;
use std::process::{Command, Stdio};

fn estimate_bytes(log: &Path, out: &Path) -> Vec<u8> {
    host_sim_ok(&["estimate", path_str(log), "--out", path_str(out)]);
    std::fs::read(out).unwrap()
}

#[test]
fn reordered_and_extra_columns_give_the_same_estimates() {
    let dir = temp_dir("cli-columns");
    let log = paper(&dir, 1500);
    let expected = estimate_bytes(&log, &dir.join("plain.est.csv"));
    let text = std::fs::read_to_string(&log).unwrap();
    // Columns reversed, spaces around the names, two extra columns (one in the middle, one trailing).
    let mut reordered = String::from("# exported by the ship's logger\n pitch_deg , roll_deg,heading_deg,speed_kn,latitude_deg,platform_deg,rotation_deg,time_s,flags\n");
    let mut trailing = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            trailing.push_str(&format!("{line},speed_kn,status\n"));
            continue;
        }
        let c: Vec<&str> = line.split(',').collect();
        reordered.push_str(&format!(
            "{},{},{},12.5,{},{},{},{},ok\n",
            c[6], c[5], c[4], c[3], c[2], c[1], c[0]
        ));
        trailing.push_str(&format!("{line},12.5,ok\n"));
    }
    let (r, t) = (dir.join("reordered.csv"), dir.join("trailing.csv"));
    std::fs::write(&r, reordered).unwrap();
    std::fs::write(&t, trailing).unwrap();
    assert_eq!(
        estimate_bytes(&r, &dir.join("r.est.csv")),
        expected,
        "reordered columns"
    );
    assert_eq!(
        estimate_bytes(&t, &dir.join("t.est.csv")),
        expected,
        "extra trailing columns"
    );
}

#[test]
fn a_gzip_log_and_standard_input_give_the_same_estimates_as_the_plain_log() {
    let dir = temp_dir("cli-gzip");
    let log = paper(&dir, 1500);
    let expected = estimate_bytes(&log, &dir.join("plain.est.csv"));
    let gz = dir.join("paper.csv.gz");
    let mut enc = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::default(),
    );
    enc.write_all(&std::fs::read(&log).unwrap()).unwrap();
    enc.finish().unwrap();
    // The default output of paper.csv.gz is paper.estimates.csv, and its truth file is found.
    let stdout = host_sim_ok(&["estimate", path_str(&gz)]);
    assert!(
        stdout.contains("estimates in ") && stdout.contains("paper.estimates.csv"),
        "{stdout}"
    );
    assert!(stdout.contains("accuracy against the truth"), "{stdout}");
    assert_eq!(
        std::fs::read(dir.join("paper.estimates.csv")).unwrap(),
        expected,
        "gzip log"
    );
    // `estimate - --out -`: gzip on standard input, estimates on standard output, summary on stderr.
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["estimate", "-", "--out", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let input = std::fs::read(&gz).unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(out.stdout, expected, "standard input to standard output");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("standard input: method windowed: 1500 rows")
    );
}

#[test]
fn generate_to_standard_output_writes_the_log_there_and_no_file() {
    let dir = temp_dir("generate-stdout");
    let file = paper(&dir, 60);
    // In a directory of its own, so that any file it wrote there would show.
    let cwd = dir.join("cwd");
    std::fs::create_dir_all(&cwd).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .current_dir(&cwd)
        .args([
            "generate",
            "--scenario",
            "paper",
            "--duration",
            "60",
            "--out",
            "-",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The log byte for byte as written to a file, nothing else on standard output.
    assert_eq!(out.stdout, std::fs::read(&file).unwrap());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("60 rows to standard output (no truth file)")
    );
    assert_eq!(
        std::fs::read_dir(&cwd).unwrap().count(),
        0,
        "a file written"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_output_naming_the_log_is_refused_and_the_log_kept() {
    let dir = temp_dir("cli-out-is-in");
    let log = paper(&dir, 600);
    let before = std::fs::read(&log).unwrap();
    let out = host_sim(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join(".").join("paper.csv")),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--out names the log itself"));
    assert_eq!(std::fs::read(&log).unwrap(), before);
}

#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = temp_dir("cli-pipe");
    let log = paper(&dir, 20_000);
    for args in [
        vec!["estimate", path_str(&log), "--out", "-"],
        vec![
            "estimate",
            path_str(&log),
            "--out",
            path_str(&dir.join("e.csv")),
        ],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // `| head -c 10`: read a little, then close the pipe.
        let mut first = [0u8; 10];
        child
            .stdout
            .as_mut()
            .unwrap()
            .read_exact(&mut first)
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("panicked") && !stderr.contains("error"),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn a_minimal_truth_file_gives_the_table_and_a_broken_one_a_warning() {
    let dir = temp_dir("cli-truth");
    let log = paper(&dir, 3000);
    let truth = dir.join("paper.truth.json");
    std::fs::write(&truth, "{\"x_arcsec\": [200, -150, 300, -250]}\n").unwrap();
    let out = host_sim(&["estimate", path_str(&log)]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("accuracy against the truth, ours (windowed):"),
        "{stdout}"
    );
    assert!(
        stdout.contains("| x1 | ") && stdout.contains("| x4 | "),
        "{stdout}"
    );
    assert!(!stdout.contains("not within at end"), "{stdout}");
    assert!(
        !stdout.contains("attitude error of eq (2)"),
        "no oscillation truth, no attitude table: {stdout}"
    );

    std::fs::write(&truth, "{\"x\": [200, -150, 300]}\n").unwrap();
    let est = dir.join("paper.estimates.csv");
    std::fs::remove_file(&est).unwrap();
    let out = host_sim(&["estimate", path_str(&log)]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: ") && stderr.contains("truth file unreadable, no accuracy table"),
        "{stderr}"
    );
    assert!(!stdout.contains("accuracy against the truth"), "{stdout}");
    std::fs::remove_file(&truth).unwrap();
    host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("again.csv")),
    ]);
    assert_eq!(
        std::fs::read(&est).unwrap(),
        std::fs::read(dir.join("again.csv")).unwrap(),
        "estimates written all the same"
    );
}

#[test]
fn a_log_starting_at_another_time_or_shifted_half_a_second_is_judged_against_its_truth() {
    let dir = temp_dir("cli-shift");
    let log = paper(&dir, 6000);
    let text = std::fs::read_to_string(&log).unwrap();
    for (name, shift) in [("late", 1000.0), ("half", 0.5)] {
        let shifted_log = dir.join(format!("{name}.csv"));
        let mut out = String::new();
        for (i, line) in text.lines().enumerate() {
            if i == 0 {
                out.push_str(line);
            } else {
                let (t, rest) = line.split_once(',').unwrap();
                out.push_str(&format!("{},{rest}", t.parse::<f64>().unwrap() + shift));
            }
            out.push('\n');
        }
        std::fs::write(&shifted_log, out).unwrap();
        std::fs::copy(
            dir.join("paper.truth.json"),
            dir.join(format!("{name}.truth.json")),
        )
        .unwrap();
        let stdout = host_sim_ok(&["estimate", path_str(&shifted_log)]);
        assert!(
            stdout.contains("accuracy against the truth"),
            "{name}: {stdout}"
        );
        assert!(
            !stdout.contains("not within at end"),
            "{name}: every error settles: {stdout}"
        );
        assert!(stdout.contains("after compensation"), "{name}: {stdout}");
    }
}

#[test]
fn negative_numbers_are_option_values() {
    let dir = temp_dir("cli-negative");
    let log = dir.join("south.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "100",
        "--latitude",
        "-35",
        "--errors-arcsec",
        "-20,10,-30,40",
        "--out",
        path_str(&log),
    ]);
    let truth = std::fs::read_to_string(dir.join("south.truth.json")).unwrap();
    assert!(truth.contains("\"latitude_deg\": -35.0"), "{truth}");
}

#[test]
fn a_configuration_error_names_the_parameter_its_value_and_its_bound() {
    let dir = temp_dir("cli-config");
    let log = paper(&dir, 100);
    let out = host_sim(&["estimate", path_str(&log), "--traditional-sigma-deg", "0"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("traditional_sigma_rad = 0 must be positive and finite (set by --traditional-sigma-deg, deg)"), "{stderr}");
    let out = host_sim(&["estimate", path_str(&log), "--max-filled-gap-samples", "4"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(
            "max_filled_gap_samples = 4 must be at most 3 (set by --max-filled-gap-samples)"
        ),
        "{stderr}"
    );
}
