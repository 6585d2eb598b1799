//! End to end through QEMU, a real log's shape (reciprocating rotation at 360 s, 2 % of rows lost,
//! jittered Unix time stamps) pushed through the mps2-an386 image (`--push`: frames sent without
//! waiting for answers, queued in the firmware's receive ring, matched by their numbers): the
//! rotation pattern and the interval learned, the gaps filled, on the target bit for bit as on
//! the host, every frame answered, none lost, no overrun. The long streams of both boards (20,000
//! s of a sea log, one sample at a time on mps2-an386 and pushed on the STM32F405) are the first
//! half of `qemu_restart`, which checks them the same way.

use crate::qemu_support::*;

#[test]
fn reciprocating_log_with_2_percent_loss_and_jittered_unix_stamps_pushed_through_mps2_an386_is_byte_identical(
) {
    let board = Board::Mps2An386;
    let dir = scratch("e2e-lossy-mps2-an386");
    let log = generated_log(
        &dir,
        "reciprocating.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "12000",
            "--scheme",
            "reciprocating",
            "--rotation-period",
            "360",
            "--drop-fraction",
            "0.02",
            "--time-offset",
            "1700000000",
            "--time-jitter",
            "0.02",
        ],
    );
    stream_and_compare_with_estimate(board, &firmware_elf(board), &dir, &log, &[], true);
}

/// Stamps set on receipt, on the board: a sea log whose stamps are jittered by up to +-0.45 s of
/// their 1 s interval, pushed through the STM32F405 image (QEMU netduinoplus2), gives the estimates
/// CSV of `host-sim estimate` byte for byte (the grid learned from the jittered stamps on the target
/// as on the host) and ends within 10 arcsec of the truth.
#[test]
fn stamps_jittered_by_045_of_the_interval_pushed_through_stm32f405_are_byte_identical() {
    let board = Board::Stm32f405;
    let dir = scratch("e2e-jitter-stm32f405");
    let log = generated_log(
        &dir,
        "jittered.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "4000",
            "--time-offset",
            "1700000000",
            "--time-jitter",
            "0.45",
        ],
    );
    stream_and_compare_with_estimate(board, &firmware_elf(board), &dir, &log, &[], true);
}

/// The same at 10 Hz on mps2-an386: stamps jittered by up to +-0.045 s of their 0.1 s interval,
/// pushed through the image, byte for byte `host-sim estimate`, within 10 arcsec of the truth.
#[test]
fn a_10_hz_log_with_stamps_jittered_by_045_of_the_interval_pushed_through_mps2_an386_is_byte_identical(
) {
    let board = Board::Mps2An386;
    let dir = scratch("e2e-jitter-10hz-mps2-an386");
    let log = generated_log(
        &dir,
        "jittered-10hz.csv",
        &[
            "--scenario",
            "sea",
            "--duration",
            "2000",
            "--sample-interval",
            "0.1",
            "--time-jitter",
            "0.045",
        ],
    );
    stream_and_compare_with_estimate(board, &firmware_elf(board), &dir, &log, &[], true);
}
