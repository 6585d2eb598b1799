//! Power cuts, on both boards: the firmware (each board's build) saves a checkpoint every 300 s of
//! sample time into its checkpoint log (a host file under QEMU). QEMU is killed at random points,
//! and once in the middle of a save: the emulated flash is ordered to cut the power after 1-3 of
//! the save's 256-byte pages (`firmware::flash_layout::EMULATED_FLASH_CUT_ORDER_FILE`), so the cut
//! lands inside the save however loaded the machine is. Each time QEMU is restarted on the same
//! flash, restores a checkpoint (after the cut inside a save, the one before it), and the host
//! resumes streaming after it. The host mirrors the firmware: the same core, the same save schedule
//! (`firmware::checkpoint_store::SaveSchedule`), restored from its own image of the checkpoint the
//! firmware reports. At the end the firmware's estimate equals the mirror's bit for bit, and is
//! within 1 arcsec of the uninterrupted run's.

use crate::qemu_support::*;
use estimator_core::checkpoint::CHECKPOINT_LEN;
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Config, Estimate};
use firmware::checkpoint_store::{SaveSchedule, CHECKPOINT_INTERVAL_S};
use firmware::flash_layout::{EMULATED_FLASH_CUT_ORDER_FILE, EMULATED_FLASH_POWER_CUT_EXIT_CODE};
use host_sim::formats::log_csv::read_log;
use host_sim::replay::{sample_of, HostEstimator};
use host_sim::stream::{step_remote, Target};
use link_protocol::{Request, SampleMsg};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

fn file_len(path: &Path) -> u64 {
    std::fs::metadata(path).map_or(0, |m| m.len())
}

/// The host's mirror of the firmware: the same core and save schedule, and an image of every
/// checkpoint it saved, by the time of its last sample.
struct Mirror {
    estimator: HostEstimator,
    schedule: SaveSchedule,
    images: BTreeMap<u64, Vec<u8>>,
}

impl Mirror {
    fn new() -> Mirror {
        Mirror {
            estimator: HostEstimator::new(Config::default()).unwrap(),
            schedule: SaveSchedule::new(f64::from(CHECKPOINT_INTERVAL_S), None),
            images: BTreeMap::new(),
        }
    }

    /// Steps a sample; true if the firmware saves a checkpoint after it.
    fn step(&mut self, msg: &SampleMsg) -> bool {
        let Ok(output) = self.estimator.step(&msg.into()) else {
            return false;
        };
        let saves = self.schedule.due(output.time_s);
        if saves {
            let mut image = vec![0u8; CHECKPOINT_LEN];
            self.estimator.checkpoint(&mut image).unwrap();
            self.images.insert(output.time_s.to_bits(), image);
        }
        saves
    }

    /// What the firmware does at boot: restore the checkpoint of `time_s`, or start afresh.
    fn boot(&mut self, time_s: Option<f64>) {
        self.estimator = HostEstimator::new(Config::default()).unwrap();
        if let Some(t) = time_s {
            let image = self.images.get(&t.to_bits()).unwrap_or_else(|| {
                panic!("the firmware restored a checkpoint of {t} s it never saved")
            });
            self.estimator.restore(image).unwrap();
        }
        self.schedule = SaveSchedule::new(f64::from(CHECKPOINT_INTERVAL_S), time_s);
    }
}

#[test]
fn mps2_an386_power_cuts_at_random_points_and_mid_save_lose_nothing_but_time() {
    power_cuts(Board::Mps2An386);
}

#[test]
fn stm32f405_power_cuts_at_random_points_and_mid_save_lose_nothing_but_time() {
    power_cuts(Board::Stm32f405);
}

fn power_cuts(board: Board) {
    let elf = firmware_elf(board);
    let dir = scratch(&format!("power-cut-{}", board.name()));
    let log = paper_log(&dir, 6000);
    let lines = read_log(&log).unwrap();
    let msgs: Vec<SampleMsg> = lines
        .iter()
        .map(|l| SampleMsg::from(&sample_of(&l.row)))
        .collect();
    let mut uncut = HostEstimator::new(Config::default()).unwrap();
    for m in &msgs {
        uncut.step(&m.into()).unwrap();
    }
    let flash_dir = dir.join("flash");
    std::fs::create_dir_all(&flash_dir).unwrap();
    let flash = flash_dir.join("rins-flash.bin");

    let cut_order = flash_dir.join(EMULATED_FLASH_CUT_ORDER_FILE.to_str().unwrap());
    let mut rng = ChaCha8Rng::seed_from_u64(0x9E37_79B9);
    let mut mirror = Mirror::new();
    let (mut cuts, mut mid_save_cuts) = (0u32, 0u32);
    // The time of the save cut in its middle: the restart after it must restore an older one.
    let mut cut_save_time_s: Option<f64> = None;
    let final_estimate: Estimate = loop {
        let mut target = Target::boot_qemu(
            &elf,
            board.machine(),
            None,
            Some(&flash_dir),
            Duration::from_secs(10),
        )
        .unwrap();
        let resume = target.boot_status.checkpoint_time_s;
        if let Some(t) = cut_save_time_s.take() {
            assert!(
                resume.is_some_and(|r| r < t),
                "after a cut inside the save of {t} s the firmware restored {resume:?}"
            );
        }
        mirror.boot(resume);
        let start = msgs
            .iter()
            .position(|m| resume.is_none_or(|t| m.time_s > t))
            .unwrap();
        // Four cuts after 100..700 random rows; then one inside a save; then one more random cut;
        // then the rest of the log.
        let want_mid_save = mid_save_cuts == 0 && cuts >= 4;
        let stop_after = if want_mid_save {
            Some(1)
        } else if cuts < 5 + mid_save_cuts && msgs.len() - start > 1000 {
            Some(rng.gen_range(100..700))
        } else {
            None
        };
        let mut answer = None;
        let mut cut = false;
        for (sent, msg) in msgs[start..].iter().enumerate() {
            let saves = mirror.step(msg);
            if stop_after.is_some_and(|n| sent >= n) && (!want_mid_save || saves) {
                if want_mid_save {
                    // Order the cut, then send the sample whose step saves: the save's first
                    // `pages` pages reach the flash, then QEMU exits as a board whose power fails.
                    let pages: u32 = rng.gen_range(1..=3);
                    std::fs::write(&cut_order, pages.to_string()).unwrap();
                    let before = file_len(&flash);
                    target.link.send(&Request::Sample(*msg)).unwrap();
                    let qemu = target.qemu.as_mut().unwrap();
                    let deadline = Instant::now() + Duration::from_secs(60);
                    let status = loop {
                        if let Some(status) = qemu.exited() {
                            break status;
                        }
                        assert!(
                            Instant::now() < deadline,
                            "the ordered power cut never came"
                        );
                        std::thread::sleep(Duration::from_millis(5));
                    };
                    assert_eq!(
                        status.code(),
                        Some(EMULATED_FLASH_POWER_CUT_EXIT_CODE),
                        "QEMU did not stop at the ordered power cut: {}",
                        qemu.stderr_tail()
                    );
                    assert!(!cut_order.exists(), "the flash never took the cut order");
                    drop(target);
                    mid_save_cuts += 1;
                    cut_save_time_s = Some(msg.time_s);
                    println!(
                        "cut {}: inside the save of {} s, after {pages} of its pages ({} bytes \
                         written)",
                        cuts + 1,
                        msg.time_s,
                        file_len(&flash).saturating_sub(before)
                    );
                } else {
                    println!("cut {}: after {sent} rows from {resume:?} s", cuts + 1);
                    drop(target);
                }
                cut = true;
                break;
            }
            answer = Some(step_remote(&mut target, msg).unwrap());
        }
        if cut {
            cuts += 1;
            continue;
        }
        let output = answer.expect("rows were streamed").result.unwrap();
        break output.estimate.unwrap();
    };
    assert!(
        mid_save_cuts == 1 && cuts >= 6,
        "{cuts} cuts, {mid_save_cuts} in a save"
    );
    let mirrored = mirror.estimator.estimate().unwrap();
    let reference = uncut.estimate().unwrap();
    assert_eq!(
        final_estimate, mirrored,
        "the firmware's estimate differs from the host's mirror of its restarts"
    );
    for i in 0..4 {
        let diff = rad_to_arcsec(f64::from(final_estimate.x_rad[i] - reference.x_rad[i])).abs();
        println!(
            "x{}: {diff:.3} arcsec from the uninterrupted run after {cuts} power cuts",
            i + 1
        );
        assert!(
            diff <= 1.0,
            "x{} differs by {diff} arcsec from the uninterrupted run",
            i + 1
        );
    }
}
