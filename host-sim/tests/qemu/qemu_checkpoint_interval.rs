//! The firmware's checkpoint interval is a build-time setting (`RINS_CHECKPOINT_INTERVAL_S`,
//! default 300 s, checked by `firmware/build.rs`). Built with 20 s and fed 200 s of samples, it
//! saves at 20, 40, ..., 180 s after the first sample; a restart restores the newest image and
//! saves every 20 s from its time on. The default build's rule is what `qemu_power_cut` follows.

use crate::qemu_support::*;
use host_sim::formats::log_csv::read_log;
use host_sim::replay::sample_of;
use host_sim::stream::qemu::Machine;
use host_sim::stream::{step_remote, Target};
use link_protocol::SampleMsg;
use std::time::Duration;

#[test]
fn checkpoint_interval_is_set_at_build_time() {
    let elf = firmware_elf_checkpoint_20s();
    let dir = scratch("checkpoint-interval");
    let log = paper_log(&dir, 300);
    let lines = read_log(&log).unwrap();
    let flash_dir = dir.join("flash");
    std::fs::create_dir_all(&flash_dir).unwrap();

    let mut target = Target::boot_qemu(
        &elf,
        Machine::Mps2An386,
        None,
        Some(&flash_dir),
        Duration::from_secs(10),
    )
    .unwrap();
    assert_eq!(
        target.boot_status.checkpoint_time_s, None,
        "a fresh flash holds no checkpoint"
    );
    let t0 = lines[0].row.time_s;
    for line in &lines[..200] {
        step_remote(&mut target, &SampleMsg::from(&sample_of(&line.row))).unwrap();
    }
    let status = target.status().unwrap();
    assert_eq!(
        status.checkpoints_saved, 9,
        "saves at 20, 40, ..., 180 s after the first sample"
    );
    assert_eq!(status.checkpoint_time_s, Some(t0 + 180.0));
    drop(target);

    // A restart restores the newest image and saves every 20 s from there.
    let mut target = Target::boot_qemu(
        &elf,
        Machine::Mps2An386,
        None,
        Some(&flash_dir),
        Duration::from_secs(10),
    )
    .unwrap();
    assert_eq!(target.boot_status.checkpoint_time_s, Some(t0 + 180.0));
    for line in lines.iter().filter(|l| l.row.time_s > t0 + 180.0) {
        step_remote(&mut target, &SampleMsg::from(&sample_of(&line.row))).unwrap();
    }
    let status = target.status().unwrap();
    assert_eq!(status.checkpoints_saved, 5, "saves at 200, 220, ..., 280 s");
    assert_eq!(status.checkpoint_time_s, Some(t0 + 280.0));
}
