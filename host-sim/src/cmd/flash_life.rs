//! `host-sim flash-life`: how long a board's checkpoint flash lasts. Runs N days of 1 Hz samples
//! of a generated sea log through the estimator, saving checkpoints when the firmware would
//! ([`SaveSchedule`] with the firmware's interval), through the firmware's own store code
//! ([`CheckpointStore`], the same crate compiled for the host) on a model of the board's flash
//! ([`crate::flash_model`]) that counts the erases of each sector. Prints the checkpoint's size,
//! the erases of each sector, the stalls a save causes (from the datasheet's erase and program
//! times, where the board has a datasheet) and the flash life at the datasheet's endurance.

use crate::flash_model::{FlashCounts, FlashModel};
use crate::replay::sample_of;
use crate::sim::samples::Samples;
use crate::sim::scenario::{ScenarioKind, ScenarioParams};
use anyhow::{ensure, Context};
use estimator_core::checkpoint::CHECKPOINT_LEN;
use estimator_core::{Config, Estimator};
use firmware::checkpoint_store::{
    CheckpointStore, Restored, SaveSchedule, StoreBuffers, CHECKPOINT_INTERVAL_S,
};
use firmware::flash_layout::{FlashLayout, MPS2_AN386, STM32F405};
use std::io::Write;

/// The boards `flash-life` knows.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoardArg {
    /// Flash sectors 5-11 of the STM32F405 (128 KiB each).
    Stm32f405,
    /// The mps2-an386's semihosted flash under QEMU (4 KiB sectors).
    Mps2An386,
}

/// `host-sim flash-life`.
#[derive(clap::Args, Debug)]
pub struct FlashLifeArgs {
    /// The board whose flash layout is modelled.
    #[arg(long, value_enum)]
    pub board: BoardArg,
    /// Days of 1 Hz samples to run.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    pub days: f64,
    /// Seconds of sample time between checkpoints (the firmware's default: its build setting
    /// RINS_CHECKPOINT_INTERVAL_S).
    #[arg(long, value_name = "S", default_value_t = f64::from(CHECKPOINT_INTERVAL_S), allow_negative_numbers = true)]
    pub interval_s: f64,
    /// Seed of the sea log.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// What a run of the store measured.
#[derive(Clone, Debug, PartialEq)]
pub struct FlashLife {
    /// The board's checkpoint flash.
    pub layout: FlashLayout,
    /// Days of sea log run through the store.
    pub days: f64,
    /// Checkpoints saved.
    pub saves: u64,
    /// What the model of the flash counted: erases of each sector, bytes programmed.
    pub counts: FlashCounts,
    /// Bytes programmed by the save that programmed most, and by the one that programmed least.
    pub save_bytes: [u64; 2],
    /// Saves that erased a sector.
    pub erasing_saves: u64,
}

impl FlashLife {
    /// The most erases any sector had.
    pub fn max_sector_erases(&self) -> u64 {
        self.counts.erases.iter().copied().max().unwrap_or(0)
    }

    /// Years until the most-erased sector reaches the datasheet's endurance, at this rate;
    /// `None` if no sector was erased (the run was too short to tell).
    pub fn life_years(&self) -> Option<f64> {
        let per_year = self.max_sector_erases() as f64 * 365.25 / self.days;
        (per_year > 0.0).then(|| f64::from(self.layout.endurance_cycles) / per_year)
    }
}

/// Runs `days` of the sea scenario through the store on the model of `layout`.
fn run_on<const SECTOR: usize, const WORD: usize>(
    layout: FlashLayout,
    days: f64,
    interval_s: f64,
    seed: u64,
) -> anyhow::Result<FlashLife> {
    let mut params = ScenarioParams::new(ScenarioKind::Sea, seed);
    params.duration_s = days * 86_400.0;
    params.sample_interval_s = 1.0;
    // Steaming east: the sea scenario's course (40 deg) would take the ship past the pole within
    // a month of sea time.
    params.course_deg = 90.0;
    let mut flash = FlashModel::<SECTOR, WORD>::for_layout(&layout);
    let mut estimator: Estimator =
        Estimator::new(Config::default()).context("the default configuration")?;
    let mut schedule = SaveSchedule::new(interval_s, None);
    let mut buffers = StoreBuffers::new();
    let (mut saves, mut erasing_saves, mut save_bytes) = (0u64, 0u64, [0u64, u64::MAX]);
    for (row, _truth) in Samples::new(&params) {
        let output = estimator
            .step(&sample_of(&row))
            .map_err(|e| anyhow::anyhow!("row at {} s rejected: {e}", row.time_s))?;
        if !schedule.due(output.time_s) {
            continue;
        }
        let before = (
            flash.counts().programmed_bytes,
            flash.counts().erases.iter().sum::<u64>(),
        );
        // The store keeps nothing between operations but its buffer (no cache): one made for
        // each save, as the firmware's lives for ever, does the same to the flash, and lets the
        // model's counters be read between saves.
        CheckpointStore::new(&mut flash, &mut buffers)
            .and_then(|mut store| store.save(&estimator))
            .map_err(|e| anyhow::anyhow!("save at {} s: {e}", output.time_s))?;
        saves += 1;
        let bytes = flash.counts().programmed_bytes - before.0;
        if flash.counts().erases.iter().sum::<u64>() > before.1 {
            erasing_saves += 1;
        }
        save_bytes = [save_bytes[0].max(bytes), save_bytes[1].min(bytes)];
    }
    ensure!(
        saves > 0,
        "no checkpoint was saved in {days} days at one every {interval_s} s"
    );
    // The newest image restores.
    let mut restored: Estimator = Estimator::new(Config::default())?;
    let found = CheckpointStore::new(&mut flash, &mut buffers)
        .and_then(|mut store| store.restore(&mut restored))
        .map_err(|e| anyhow::anyhow!("restore: {e}"))?;
    ensure!(
        matches!(found, Restored::Image { .. }),
        "the last checkpoint did not restore: {found:?}"
    );
    ensure!(
        flash.counts().impossible_writes == 0,
        "the store programmed flash that was not erased"
    );
    Ok(FlashLife {
        layout,
        days,
        saves,
        counts: flash.counts().clone(),
        save_bytes,
        erasing_saves,
    })
}

/// Runs the store on `board`'s flash model for `days` with a save every `interval_s`.
pub fn measure(
    board: BoardArg,
    days: f64,
    interval_s: f64,
    seed: u64,
) -> anyhow::Result<FlashLife> {
    ensure!(
        days.is_finite() && days > 0.0,
        "--days must be positive, got {days}"
    );
    ensure!(
        interval_s.is_finite() && interval_s >= 1.0,
        "--interval-s must be at least 1 s, got {interval_s}"
    );
    match board {
        BoardArg::Stm32f405 => run_on::<{ 128 * 1024 }, 4>(STM32F405, days, interval_s, seed),
        BoardArg::Mps2An386 => run_on::<4096, 4>(MPS2_AN386, days, interval_s, seed),
    }
}

/// The report `flash-life` prints.
pub fn report(life: &FlashLife, interval_s: f64, out: &mut impl Write) -> std::io::Result<()> {
    let l = &life.layout;
    writeln!(
        out,
        "{}: checkpoints every {interval_s} s over {} days of 1 Hz samples (generated sea log), in {} sectors of {} KiB",
        l.board,
        life.days,
        l.sectors,
        l.sector_bytes / 1024
    )?;
    writeln!(out, "checkpoint: {CHECKPOINT_LEN} bytes")?;
    writeln!(
        out,
        "saves: {}, programming {} to {} bytes each; {} of them erased a sector (one save in {:.0}, every {:.1} h)",
        life.saves,
        life.save_bytes[1],
        life.save_bytes[0],
        life.erasing_saves,
        life.saves as f64 / life.erasing_saves.max(1) as f64,
        life.days * 24.0 / life.erasing_saves.max(1) as f64
    )?;
    let erases: Vec<String> = (0u32..)
        .zip(&life.counts.erases)
        .map(|(i, n)| format!("{} {n}", sector_name(l, i)))
        .collect();
    writeln!(out, "erases per sector: {}", erases.join(", "))?;
    if let (Some(erase), Some(program)) = (l.sector_erase_s, l.byte_program_s) {
        let bytes = life.save_bytes[0] as f64;
        writeln!(
            out,
            "stall of a save (datasheet): {:.0} ms typical, {:.0} ms worst when it only programs; {:.1} s typical, {:.1} s worst when it also erases a sector",
            bytes * program[0] * 1e3,
            bytes * program[1] * 1e3,
            erase[0] + bytes * program[0],
            erase[1] + bytes * program[1]
        )?;
    }
    match life.life_years() {
        Some(years) => writeln!(out, "flash life: {years:.0} years at {} cycles", l.endurance_cycles),
        None => writeln!(
            out,
            "flash life: no sector was erased in {} days: run more days to measure it (at {} cycles)",
            life.days, l.endurance_cycles
        ),
    }
}

/// The `index`-th sector of the checkpoint region, as the board's documents number it.
fn sector_name(layout: &FlashLayout, index: u32) -> String {
    match layout.board {
        // Sectors 0-3 (16 KiB) and 4 (64 KiB) hold the code: the region starts at sector 5.
        "stm32f405" => format!("sector {}", 5 + index),
        _ => format!("sector {index}"),
    }
}

/// `host-sim flash-life`.
pub fn run(a: &FlashLifeArgs) -> anyhow::Result<()> {
    let life = measure(a.board, a.days, a.interval_s, a.seed)?;
    report(&life, a.interval_s, &mut std::io::stdout().lock())?;
    Ok(())
}
