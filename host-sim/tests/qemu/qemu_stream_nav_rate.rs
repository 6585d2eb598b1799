//! `host-sim stream --nav-rate` through the firmware in QEMU: a 100 Hz sea log, with a repeated
//! row and a row stamped back in time added, sent row by row as `NavSample`s. The estimates CSV (a
//! row a bin the firmware stepped) and the corrected-attitude CSV (a row a sample) must be, byte
//! for byte, what the core's `Binner`, `Estimator::step` and `Estimator::compensate` give the same
//! rows on the host, written with the same writers, and the estimates CSV is `host-sim estimate
//! --bin-interval-s 1`'s but for its last row (the bin the firmware leaves open); the two refused
//! rows are reported with their lines and counted, and change nothing.

use crate::qemu_support::*;
use estimator_core::binning::Binner;
use estimator_core::{Config, Estimator};
use host_sim::formats::corrected_csv::CorrectedWriter;
use host_sim::formats::estimates_csv::{read_estimates, EstimatesWriter};
use host_sim::formats::log_csv::read_log;
use host_sim::formats::truth_file::{read_truth, truth_path};
use host_sim::replay::sample_of;
use std::path::{Path, PathBuf};

/// What the host core writes for the log's rows: the estimates CSV (a row a completed bin) and
/// the corrected-attitude CSV (a row a sample).
fn host_outputs(log: &Path) -> (Vec<u8>, Vec<u8>) {
    let mut binner = Binner::default();
    let mut host: Estimator = Estimator::new(Config::default()).unwrap();
    let mut estimates = EstimatesWriter::new(Vec::new()).unwrap();
    let mut corrected = CorrectedWriter::new(Vec::new()).unwrap();
    for line in read_log(log).unwrap() {
        let sample = sample_of(&line.row);
        match binner.push(&sample) {
            Err(e) => corrected.write_refused(sample.time_s, e.reason()).unwrap(),
            Ok(bin) => {
                if let Some(bin) = bin {
                    estimates.write_step(bin.time_s, &host.step(&bin)).unwrap();
                }
                let angles = host
                    .compensate(&sample)
                    .ok()
                    .map(|a| [a.heading_rad, a.roll_rad, a.pitch_rad]);
                corrected.write_corrected(sample.time_s, angles).unwrap();
            }
        }
    }
    (estimates.finish().unwrap(), corrected.finish().unwrap())
}

/// The first line at which two files differ, if they do.
fn first_difference(got: &[u8], want: &[u8]) -> Option<usize> {
    let (got, want) = (
        String::from_utf8_lossy(got).into_owned(),
        String::from_utf8_lossy(want).into_owned(),
    );
    let mut lines = got.lines().zip(want.lines()).enumerate();
    if let Some((i, _)) = lines.find(|(_, (g, w))| g != w) {
        return Some(i + 1);
    }
    (got.lines().count() != want.lines().count())
        .then(|| got.lines().count().min(want.lines().count()) + 1)
}

/// A generated 100 Hz sea log of 120 s (12,000 rows) with row 3,001 repeated (its time not after
/// the last one) and a row stamped back at 50.5 s after row 6,001 (60 s): both refused by the
/// firmware's binner, at lines 3,003 and 6,004 of the file (the header is line 1).
fn log_with_two_refused_rows(dir: &Path) -> PathBuf {
    // A 60 s rotation, so that the first estimate comes (about 105 s in) within the log.
    let generated = generated_log(
        dir,
        "nav-100hz.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "120",
            "--sample-interval",
            "0.01",
            "--rotation-period",
            "60",
        ],
    );
    let text = std::fs::read_to_string(&generated).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert_eq!(lines.len(), 12_001);
    let repeated = lines[3001].clone();
    let mut back: Vec<String> = lines[6001].split(',').map(String::from).collect();
    back[0] = "50.5".into();
    lines.insert(3002, repeated);
    lines.insert(6003, back.join(","));
    let log = dir.join("nav-100hz-refused.csv");
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    std::fs::copy(truth_path(&generated), truth_path(&log)).unwrap();
    log
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

/// One estimates row a second at the bins' centres, the last bin (119 s) left open; an estimate
/// at the end, whose truth lies within three of its reported 1-sigma (15 s after the first
/// estimate the errors are far from learned: a 1-sigma of hundreds of arcsec on x3, x4).
fn assert_estimates_sensible(est: &Path, log: &Path) {
    let rows = read_estimates(est).unwrap();
    assert_eq!(rows.len(), 119);
    assert_eq!((rows[0].time_s, rows[118].time_s), (0.5, 118.5));
    let last = rows.last().unwrap();
    assert!(
        ["estimating", "converged"].contains(&last.status.as_str()),
        "{}",
        last.status
    );
    let (x, sigma) = (last.x_arcsec.unwrap(), last.sigma_arcsec.unwrap());
    let truth = read_truth(&truth_path(log)).unwrap().unwrap().x_arcsec;
    for i in 0..4 {
        assert!(
            (x[i] - truth[i]).abs() < 3.0 * sigma[i],
            "x{} = {} arcsec (1-sigma {}), truth {}",
            i + 1,
            x[i],
            sigma[i],
            truth[i]
        );
    }
}

/// `host-sim estimate --bin-interval-s 1` writes the same estimates CSV, and one row more: it
/// steps the last bin at the end of the log, which the firmware leaves open.
fn assert_estimate_binned_writes_the_same(dir: &Path, log: &Path, streamed: &[u8]) {
    let estimated = dir.join("estimate.csv");
    host_sim(&[
        "estimate",
        &s(log),
        "--bin-interval-s",
        "1",
        "--out",
        &s(&estimated),
    ]);
    let estimated = std::fs::read_to_string(&estimated).unwrap();
    let mut all_but_last: Vec<&str> = estimated.lines().collect();
    all_but_last.pop();
    assert_eq!(
        first_difference(streamed, (all_but_last.join("\n") + "\n").as_bytes()),
        None,
        "stream --nav-rate and estimate --bin-interval-s 1 differ at that line"
    );
}

#[test]
fn stream_nav_rate_sends_a_100_hz_log_as_navigation_samples_and_answers_as_the_host_core() {
    let board = Board::Mps2An386;
    let dir = scratch("stream-nav-rate-mps2-an386");
    let log = log_with_two_refused_rows(&dir);
    let (est, cor) = (dir.join("est.csv"), dir.join("corrected.csv"));
    let stdout = host_sim(&[
        "stream",
        "--qemu",
        &s(&firmware_elf(board)),
        &s(&log),
        "--nav-rate",
        "--out",
        &s(&est),
        "--corrected-out",
        &s(&cor),
        "--defmt-log",
        &s(&dir.join("defmt.bin")),
    ]);
    println!("{stdout}");

    let (want_est, want_cor) = host_outputs(&log);
    let (got_est, got_cor) = (std::fs::read(&est).unwrap(), std::fs::read(&cor).unwrap());
    assert_eq!(
        first_difference(&got_est, &want_est),
        None,
        "estimates CSV: firmware and host core differ at that line"
    );
    assert_eq!(
        first_difference(&got_cor, &want_cor),
        None,
        "corrected-attitude CSV: firmware and host core differ at that line"
    );
    assert_estimates_sensible(&est, &log);
    assert_estimate_binned_writes_the_same(&dir, &log, &got_est);

    // A row a sample, the refused ones too.
    let corrected = String::from_utf8_lossy(&got_cor);
    assert_eq!(corrected.lines().count(), 1 + 12_002);
    let compensated = corrected
        .lines()
        .filter(|l| l.ends_with(",compensated"))
        .count();
    assert!(compensated >= 1_000, "{compensated} samples compensated");
    for expected in [
        "rows streamed through QEMU mps2-an386",
        "as navigation-rate samples (NavSample)",
        "  binned by the firmware: 12002 rows averaged into 119 bins of 1 s (2 rows refused: time_not_increasing 2)",
        "  rows the firmware refused: lines 3003 (time_not_increasing), 6004 (time_not_increasing); they changed nothing",
        "  the last bin (100 rows) left open",
        &format!("  compensated: {compensated} of 12002 samples"),
        "  rejected samples: 2 (",
        "frames sent 12002, answered 12002, lost 0, overruns 0",
        "sample cost: max ",
        "with its bin's step: max ",
    ] {
        assert!(stdout.contains(expected), "{expected:?} not in:\n{stdout}");
    }
}
