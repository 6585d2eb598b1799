//! `generate`'s log, read back: rotation schemes, sample interval, lost rows, outages, time
//! stamps, and the default scenarios unchanged.

mod common;

use common::{host_sim_ok, path_str, temp_dir};
use std::path::Path;

/// CRC-64 (ECMA-182) and length of a file.
fn checksum(path: &Path) -> (u64, usize) {
    let bytes = std::fs::read(path).unwrap();
    (crc::Crc::<u64>::new(&crc::CRC_64_ECMA_182).checksum(&bytes), bytes.len())
}

/// The three scenarios' logs, without any of the rotation-scheme or recorder options, are
/// byte for byte those of the generator before those options existed (checksums of the logs it
/// wrote): logs, results and figures quoted in the README stay reproducible.
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
        host_sim_ok(&["generate", "--scenario", scenario, "--seed", "3", "--duration", duration, "--out", path_str(&log)]);
        assert_eq!(checksum(&log), (crc, len), "{scenario}");
    }
}

/// The same for the model-mismatch switches of `monte-carlo` and `compare` (rotation period
/// error, rotation-angle jitter, coloured noise, drifting errors) on the rough sea.
#[test]
fn mismatch_logs_unchanged() {
    use host_sim::scenario::{generate, Mismatch, ScenarioKind, ScenarioParams};
    let mut p = ScenarioParams::new(ScenarioKind::Sea, 11);
    p.duration_s = 1200.0;
    p.mismatch = Mismatch {
        rotation_period_error: 0.005,
        rotation_jitter_deg: 0.05,
        error_drift_arcsec_per_day: 20.0,
        low_frequency_rate_error: 0.2,
        coloured_noise_arcsec: 2.0,
    };
    let mut bytes = Vec::new();
    host_sim::log_csv::write_log_to(&mut bytes, &generate(&p).rows).unwrap();
    let crc = crc::Crc::<u64>::new(&crc::CRC_64_ECMA_182).checksum(&bytes);
    assert_eq!((crc, bytes.len()), (8_036_464_345_581_861_486, 139_024));
}
