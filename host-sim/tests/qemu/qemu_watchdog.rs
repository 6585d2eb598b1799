//! The watchdog, in QEMU's mps2-an386 (whose CMSDK watchdog QEMU models; QEMU has no model of the
//! STM32F405's IWDG). A test build of the firmware (feature `test-hang`) stops its main loop for
//! good when it receives the link request `Hang`, as a firmware bug would stop it. The host
//! streams a log in push mode and sends `Hang` in the middle. The watchdog must reset the board
//! (QEMU keeps running: a reset, not an exit), the firmware must restore its last checkpoint and
//! announce `Ready`, report the watchdog as the reset's cause, and the host's stream must carry on:
//! nothing lost but the samples sent while the firmware was down, one contiguous block right after
//! the `Hang`, and every sample after the restart answered.

use crate::qemu_support::*;
use host_sim::formats::estimates_csv::EstimatesWriter;
use host_sim::formats::log_csv::{LogReader, RowFilter};
use host_sim::stream::push::{stream_log_push, PushOptions};
use host_sim::stream::qemu::Machine;
use host_sim::stream::sink::SampleSink;
use host_sim::stream::Target;
use link_protocol::{Request, ResetCause};
use std::time::{Duration, Instant};

/// The row before which the host sends `Hang`: after the first checkpoint (300 s of samples, the
/// default interval), so that the restart restores it.
const HANG_AT_ROW: u64 = 450;
/// Long enough for an estimate at the end (`host-sim estimate` fails without one).
const LOG_S: u32 = 1800;

#[test]
fn a_hung_main_loop_is_reset_by_the_watchdog_and_the_stream_carries_on() {
    let elf = firmware_elf_with_features("firmware-test-hang", &["test-hang"]);
    let dir = scratch("watchdog");
    let log = paper_log(&dir, LOG_S);
    let flash_dir = dir.join("flash");
    std::fs::create_dir_all(&flash_dir).unwrap();
    let host_estimates = dir.join("estimate.csv");
    host_sim(&[
        "estimate",
        log.to_str().unwrap(),
        "--out",
        host_estimates.to_str().unwrap(),
    ]);

    let start = Instant::now();
    // The reset takes the watchdog's 2 s and a boot: a generous answer timeout.
    let mut target = Target::boot_qemu(
        &elf,
        Machine::Mps2An386,
        Some(&dir.join("defmt.bin")),
        Some(&flash_dir),
        Duration::from_secs(30),
    )
    .unwrap();
    let window = PushOptions::default_window(&target.boot_status);
    let options = PushOptions {
        realtime: false,
        window,
        inject: Some((HANG_AT_ROW, Request::Hang)),
    };
    let mut lines = LogReader::open(&log).unwrap();
    let mut writer = EstimatesWriter::new(Vec::new()).unwrap();
    let mut info = Vec::new();
    let mut each = |_: &_, _: &_| {};
    let mut sink = SampleSink::unchecked(&mut writer, &mut each);
    let summary = stream_log_push(
        &mut target,
        &mut lines,
        RowFilter::new(true),
        None,
        &mut sink,
        None,
        &options,
        &mut info,
    )
    .unwrap_or_else(|e| panic!("{e:#}\n{}", String::from_utf8_lossy(&info)));
    drop(sink);
    let info = String::from_utf8_lossy(&info).into_owned();
    println!(
        "{info}{:?}\nwall {:.1} s, window {window}",
        summary.link,
        start.elapsed().as_secs_f64()
    );

    // A reset, not an exit: QEMU still runs the firmware.
    assert!(
        target.qemu.as_mut().unwrap().exited().is_none(),
        "QEMU exited instead of resetting"
    );
    assert_eq!(
        summary.link.restarts, 1,
        "one Ready in the middle of the stream"
    );
    let after = summary
        .restart_status
        .first()
        .expect("the status after the restart");
    assert_eq!(
        ResetCause::try_from(after.reset_cause),
        Ok(ResetCause::Watchdog)
    );
    let restored_s = after
        .checkpoint_time_s
        .expect("the restart restored a checkpoint");
    assert!(
        restored_s > 0.0 && restored_s < HANG_AT_ROW as f64 + 1.0,
        "restored the checkpoint of {restored_s} s, before the hang"
    );
    assert!(info.contains("reset cause watchdog"), "{info}");

    // Nothing lost but the samples of the reset itself: at most what was in flight, one block
    // right after the Hang; every row before and after answered.
    let link = summary.link;
    assert_eq!(link.sent, u64::from(LOG_S));
    assert_eq!(link.answered + link.lost, link.sent);
    assert!(
        link.lost >= 1 && link.lost <= window as u64,
        "lost {} of a window of {window}",
        link.lost
    );
    let streamed = String::from_utf8(writer.finish().unwrap()).unwrap();
    let expected = std::fs::read_to_string(&host_estimates).unwrap();
    let streamed_rows: Vec<&str> = streamed.lines().skip(1).collect();
    let expected_rows: Vec<&str> = expected.lines().skip(1).collect();
    assert_eq!(expected_rows.len(), LOG_S as usize);
    let time_of = |row: &str| row.split(',').next().unwrap().to_string();
    let answered_times: Vec<String> = streamed_rows.iter().map(|r| time_of(r)).collect();
    let lost_block = HANG_AT_ROW as usize..HANG_AT_ROW as usize + link.lost as usize;
    let want_times: Vec<String> = expected_rows
        .iter()
        .enumerate()
        .filter(|(i, _)| !lost_block.contains(i))
        .map(|(_, r)| time_of(r))
        .collect();
    assert_eq!(
        answered_times, want_times,
        "the rows lost are exactly the block after the Hang"
    );
    // Before the hang the firmware's answers are the host's own, byte for byte.
    assert_eq!(
        streamed_rows[..HANG_AT_ROW as usize],
        expected_rows[..HANG_AT_ROW as usize]
    );
    // After the restart the firmware carries on from its checkpoint: the stream ends answered.
    assert_eq!(summary.final_status.reset_cause, ResetCause::Watchdog as u8);
    assert_eq!(
        summary.final_status.link.lost_frames, 0,
        "after the restart no frame was lost"
    );
}
