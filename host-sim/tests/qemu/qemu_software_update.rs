//! Compensation across a software update, on the firmware in QEMU: its flash holds the item a
//! build of another checkpoint format saved (the learned errors' record, then an image of format
//! version `VERSION + 1`, written by the firmware's own store code on a model of mps2-an386's
//! flash). The firmware refuses the image, starts from the record, and its first answer already
//! carries the record's estimate with a 1-sigma of at least 1 arcsec; the estimate goes on from
//! there.

use crate::qemu_support::*;
use estimator_core::checkpoint::{crc32, CHECKPOINT_LEN, VERSION};
use estimator_core::learned::{LEARNED_LEN, LEARNED_MIN_SIGMA_RAD};
use estimator_core::{Config, Estimator};
use firmware::checkpoint_store::{CheckpointStore, StoreBuffers};
use firmware::flash_layout::MPS2_AN386;
use host_sim::flash_model::FlashModel;
use host_sim::formats::log_csv::read_log;
use host_sim::replay::sample_of;
use host_sim::stream::qemu::Machine;
use host_sim::stream::{step_remote, Target};
use link_protocol::SampleMsg;
use std::time::Duration;

#[test]
fn mps2_an386_starts_from_the_learned_errors_of_another_checkpoint_version() {
    let dir = scratch("software-update");
    let log = paper_log(&dir, 2300);
    let lines = read_log(&log).unwrap();
    // The build before the update: 2,000 s, then its item.
    let mut old: Estimator = Estimator::new(Config::default()).unwrap();
    for line in &lines[..2000] {
        old.step(&sample_of(&line.row)).unwrap();
    }
    let learned = old.learned_errors().expect("an estimate after 2,000 s");
    let mut image = vec![0u8; CHECKPOINT_LEN];
    old.checkpoint(&mut image).unwrap();
    image[4..6].copy_from_slice(&(VERSION + 1).to_le_bytes());
    let n = image.len();
    let crc = crc32(&image[..n - 4]);
    image[n - 4..].copy_from_slice(&crc.to_le_bytes());
    let mut item = learned.encode().to_vec();
    item.extend_from_slice(&image);
    assert_eq!(item.len(), LEARNED_LEN + CHECKPOINT_LEN);

    // Its flash, as the firmware's store lays it out on mps2-an386 (4 KiB sectors, 4-byte words).
    let mut flash = FlashModel::<4096, 4>::new(MPS2_AN386.sectors as usize, 4);
    {
        let mut buffers = StoreBuffers::new();
        let mut store = CheckpointStore::new(&mut flash, &mut buffers).unwrap();
        store.save_item(&item).unwrap();
    }
    let flash_dir = dir.join("flash");
    std::fs::create_dir_all(&flash_dir).unwrap();
    std::fs::write(flash_dir.join("rins-flash.bin"), flash.bytes()).unwrap();

    // The updated firmware boots on it.
    let mut target = Target::boot_qemu(
        &firmware_elf(Board::Mps2An386),
        Machine::Mps2An386,
        None,
        Some(&flash_dir),
        Duration::from_secs(10),
    )
    .unwrap();
    assert_eq!(
        target.boot_status.checkpoint_time_s, None,
        "the image of another version is not restored"
    );
    let mut previous_x = None;
    for (k, line) in lines[2000..].iter().enumerate() {
        let answer = step_remote(&mut target, &SampleMsg::from(&sample_of(&line.row))).unwrap();
        let out = answer.result.expect("an accepted sample");
        let e = out
            .estimate
            .unwrap_or_else(|| panic!("no estimate {k} samples after the update"));
        if k == 0 {
            assert_eq!(
                e.x_rad, learned.x_rad,
                "the learned errors at the first sample"
            );
            assert!(e.sigma_rad.iter().all(|s| *s >= LEARNED_MIN_SIGMA_RAD));
        }
        previous_x = Some(e.x_rad);
    }
    // Still near the old build's estimate at the end (the paper scenario's errors are known to
    // within a few tenths of an arcsec at 2,000 s).
    let last = previous_x.unwrap();
    for i in 0..4 {
        let moved = estimator_core::units::rad_to_arcsec(f64::from(last[i] - learned.x_rad[i]));
        assert!(moved.abs() < 1.0, "x{} moved {moved} arcsec", i + 1);
    }
}
