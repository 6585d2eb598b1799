//! Power cuts, on both boards: the firmware (each board's build) saves a checkpoint every 60 s of
//! sample time into two alternating flash slots (a host file under QEMU). QEMU is killed at random
//! points, once provably in the middle of a save; each time it is restarted on the same flash, the
//! host resumes streaming after the checkpoint the firmware restored, and at the end the estimates
//! equal those of the uninterrupted run (required: within 1 arcsec).

mod qemu_support;

use estimator_core::units::rad_to_arcsec;
use estimator_core::Config;
use host_sim::log_csv::read_log;
use host_sim::replay::{sample_of, HostEstimator};
use host_sim::stream::{step_remote, Target};
use link_protocol::{Request, SampleMsg};
use qemu_support::*;
use std::path::Path;
use std::time::Duration;

const INTERVAL_S: f64 = 60.0;

/// Bytes of a checkpoint slot in the board's flash: the 16-byte header and the core's image,
/// rounded up to the flash's erase blocks (4 KiB on mps2-an386; on the STM32F405 one 128 KiB
/// sector, which its QEMU flash file keeps too).
fn slot_bytes(board: Board) -> usize {
    let erase = match board {
        Board::Mps2An386 => 4096,
        Board::Stm32f405 => 128 * 1024,
    };
    (16 + estimator_core::checkpoint::CHECKPOINT_LEN).div_ceil(erase) * erase
}

/// Whether each of the two slots starts with the store's magic.
fn slots_valid(flash: &Path, board: Board) -> [bool; 2] {
    let slot_bytes = slot_bytes(board);
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut file) = std::fs::File::open(flash) else {
        return [false, false];
    };
    let mut valid = |slot: usize| {
        let mut magic = [0u8; 4];
        file.seek(SeekFrom::Start((slot * slot_bytes) as u64)).is_ok()
            && file.read_exact(&mut magic).is_ok()
            && &magic == b"RCKP"
    };
    [valid(0), valid(1)]
}

struct Rng(u32);
impl Rng {
    fn below(&mut self, n: u32) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0 % n
    }
}

#[test]
fn mps2_an386_power_cuts_at_random_points_and_mid_write_lose_nothing() {
    power_cuts_at_random_points_and_mid_write_lose_nothing(Board::Mps2An386);
}

#[test]
fn stm32f405_power_cuts_at_random_points_and_mid_write_lose_nothing() {
    power_cuts_at_random_points_and_mid_write_lose_nothing(Board::Stm32f405);
}

fn power_cuts_at_random_points_and_mid_write_lose_nothing(board: Board) {
    let elf = firmware_elf(board);
    let dir = scratch(&format!("power-cut-{}", board.name()));
    let log = paper_log(&dir, 6000);
    let lines = read_log(&log).unwrap();
    let mut host = HostEstimator::new(Config::default()).unwrap();
    for l in &lines {
        host.step(&sample_of(&l.row)).unwrap();
    }
    let reference = host.estimate().unwrap();
    let flash_dir = dir.join("flash");
    std::fs::create_dir_all(&flash_dir).unwrap();
    let flash = flash_dir.join("rins-flash.bin");

    let mut rng = Rng(0x9E37_79B9);
    let (mut cuts, mut mid_write_cuts, mut attempts) = (0u32, 0u32, 0u32);
    // The last sample sent whose step may have run (answered, or sent just before a cut).
    let mut last_sent_s: Option<f64> = None;
    let final_estimate = loop {
        let mut target =
            Target::boot_qemu(&elf, board.machine(), None, Some(&flash_dir), Duration::from_secs(10)).unwrap();
        let resume = target.boot_status.checkpoint_time_s;
        if let (Some(r), Some(done)) = (resume, last_sent_s) {
            assert!(
                r <= done,
                "restored a checkpoint ({r} s) from after the last sample sent ({done} s)"
            );
        }
        let start = lines
            .iter()
            .position(|l| resume.is_none_or(|t| l.row.time_s > t))
            .unwrap();
        // The firmware's rule: a save when 60 s have passed since the last (or since its first sample).
        let mut last_save_s = resume;
        // Three cuts after 30..400 random rows; then cuts at saves (sent, not waited for) until one
        // lands inside a save; then one more random cut; then the rest of the log.
        let want_mid_write = mid_write_cuts == 0 && cuts >= 3;
        let stop_after = if want_mid_write {
            Some(1)
        } else if cuts < 4 + mid_write_cuts && lines.len() - start > 600 {
            Some(30 + rng.below(370) as usize)
        } else {
            None
        };
        let mut sent = 0usize;
        let mut answer = None;
        let mut cut = false;
        for line in &lines[start..] {
            let msg = SampleMsg::from(&sample_of(&line.row));
            let t = line.row.time_s;
            let saves = last_save_s.is_some_and(|s| t - s >= INTERVAL_S);
            match last_save_s {
                None => last_save_s = Some(t),
                Some(_) if saves => last_save_s = Some(t),
                _ => {}
            }
            if let Some(n) = stop_after {
                if sent >= n && (!want_mid_write || (saves && slots_valid(&flash, board) == [true, true])) {
                    if want_mid_write {
                        // Send the sample whose step saves, and cut the power while it writes.
                        attempts += 1;
                        target.link.send(&Request::Sample(msg)).unwrap();
                        last_sent_s = Some(t);
                        // Watch the flash file: once a slot's header is erased the save is under way;
                        // cut the power a random 0..3 ms into it (a save takes about 60 ms of core time).
                        let deadline = std::time::Instant::now() + Duration::from_millis(50);
                        while slots_valid(&flash, board) == [true, true] && std::time::Instant::now() < deadline {}
                        std::thread::sleep(Duration::from_micros(rng.below(3000) as u64));
                    }
                    drop(target);
                    cut = true;
                    break;
                }
            }
            answer = Some(step_remote(&mut target, &msg).unwrap());
            last_sent_s = Some(t);
            sent += 1;
        }
        if cut {
            cuts += 1;
            if want_mid_write && slots_valid(&flash, board) != [true, true] {
                mid_write_cuts += 1;
                println!("cut {cuts}: in the middle of a save (slots {:?})", slots_valid(&flash, board));
            } else {
                println!("cut {cuts}: after {sent} rows from {resume:?} s");
            }
            assert!(attempts < 5, "no cut landed inside a save in {attempts} attempts");
            continue;
        }
        let output = answer.expect("rows were streamed").result.unwrap();
        break output.estimate.unwrap();
    };
    assert!(
        mid_write_cuts == 1 && cuts >= 5,
        "{cuts} cuts, {mid_write_cuts} mid-write"
    );
    for i in 0..4 {
        let diff = rad_to_arcsec((final_estimate.x_rad[i] - reference.x_rad[i]) as f64).abs();
        println!(
            "x{}: {} rad after power cuts, {} rad uninterrupted",
            i + 1,
            final_estimate.x_rad[i],
            reference.x_rad[i]
        );
        assert!(
            diff <= 1.0,
            "x{} differs by {diff} arcsec from the uninterrupted run",
            i + 1
        );
    }
}
