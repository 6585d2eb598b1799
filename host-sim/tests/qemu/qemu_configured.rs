//! The firmware's configuration set at build time (`firmware/build.rs`): a rotation angle read
//! 0.2 s before the attitude (`RINS_ANGLE_LATENCY_MS=200`) and known values of the installation
//! errors (`RINS_PRIOR_ARCSEC`, `RINS_PRIOR_SIGMA_ARCSEC`). A sea log whose rotation angle lags by
//! 0.2 s, streamed through that image (mps2-an386, one sample at a time), gives the estimates CSV
//! of `host-sim estimate --angle-latency-s 0.2 --prior-arcsec ... --prior-sigma-arcsec ...` byte
//! for byte: the known values on its first row, the lag carried forward, the same estimates to the
//! end.

use crate::qemu_support::*;
use host_sim::formats::truth_file::{read_truth, truth_path};

#[test]
fn mps2_an386_built_with_a_latency_and_known_values_estimates_as_the_host_configured_alike() {
    let board = Board::Mps2An386;
    let dir = scratch("configured-mps2-an386");
    let log = generated_log(
        &dir,
        "late.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "3000",
            "--log-angle-latency-s",
            "0.2",
        ],
    );
    let truth = read_truth(&truth_path(&log))
        .unwrap()
        .expect("generate writes the truth");
    // Known values 5 arcsec off the truth, known to 20 arcsec.
    let prior: Vec<String> = truth
        .x_arcsec
        .iter()
        .map(|x| format!("{}", x + 5.0))
        .collect();
    let prior = prior.join(",");
    let elf = firmware_elf_with_env(
        "firmware-configured",
        &[
            ("RINS_ANGLE_LATENCY_MS", "200"),
            ("RINS_PRIOR_ARCSEC", prior.as_str()),
            ("RINS_PRIOR_SIGMA_ARCSEC", "20"),
        ],
    );
    let streamed = stream_and_compare_with_estimate(
        board,
        &elf,
        &dir,
        &log,
        &[
            "--angle-latency-s",
            "0.2",
            "--prior-arcsec",
            &prior,
            "--prior-sigma-arcsec",
            "20",
        ],
        false,
    );
    // The known values from the first row on.
    let rows = host_sim::formats::estimates_csv::read_estimates(&streamed).unwrap();
    let first = rows[0].x_arcsec.expect("the known values on the first row");
    for i in 0..4 {
        assert!(
            (first[i] - (truth.x_arcsec[i] + 5.0)).abs() < 1e-3,
            "{first:?}"
        );
    }
}
