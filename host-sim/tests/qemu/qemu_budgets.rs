//! The firmware's budgets, measured on each board's release ELF (`--profile firmware`, checkpoints
//! on): flash and static RAM read from the ELF's section headers (the figures `llvm-size` prints as
//! text + data and data + bss): at most 124 KiB and 64 KiB on both boards; the painted stack's peaks reported, the start-up's at most 8 KiB (a fresh flash; `qemu_restart` checks it after a restore); and the estimator step at most 6000 instructions
//! (max over a 6000 s stream of the paper's log and of a lossy sea log, counted in QEMU with `-icount shift=0` and SysTick: 40 instructions
//! per tick at mps2-an386's 25 MHz, 5.95 at netduinoplus2's 168 MHz). On mps2-an386 the clean log
//! is `qemu_restart`'s 20,000 s sea log one sample at a time, which asserts the same step and
//! start-up stack budgets.

use crate::qemu_support::*;

/// `(flash, static RAM)` budgets of the board's image, bytes. Flash: the STM32F405's code lives
/// in sectors 0-4, 128 KiB (the rest holds the checkpoint log: `firmware/src/flash_layout.rs`);
/// the image may take 124 KiB of them, 4 KiB kept as a margin so that a fix in the field never
/// outgrows the region (which would move the checkpoint log). How the margin shrank, and what
/// took it, is recorded in docs/firmware.md ("Measured figures"). The firmware inlines little and
/// builds its own crate at opt-level 2 (.cargo/config.toml, Cargo.toml). The mps2-an386 (4 MiB)
/// is held to the same figure, so that growth shows on either board. Static RAM: half of the
/// STM32F405's 128 KiB SRAM, the rest for the stack and room to grow.
const FLASH_BUDGET_BYTES: u64 = 124 * 1024;
const STATIC_RAM_BUDGET_BYTES: u64 = 64 * 1024;

fn budgets(_board: Board) -> (u64, u64) {
    (FLASH_BUDGET_BYTES, STATIC_RAM_BUDGET_BYTES)
}

/// `(text, data, bss)` as `llvm-size` (Berkeley format) counts them: allocated sections that are
/// read-only, writable with contents, writable without contents (NOBITS).
fn berkeley_sizes(elf: &[u8]) -> (u64, u64, u64) {
    let u16_at = |o: usize| u16::from_le_bytes([elf[o], elf[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_le_bytes([elf[o], elf[o + 1], elf[o + 2], elf[o + 3]]) as u64;
    assert_eq!(&elf[..4], b"\x7fELF");
    assert_eq!((elf[4], elf[5]), (1, 1), "ELF32 little-endian");
    let shoff = u32_at(0x20) as usize;
    let (shentsize, shnum) = (u16_at(0x2E), u16_at(0x30));
    let (mut text, mut data, mut bss) = (0, 0, 0);
    for i in 0..shnum {
        let h = shoff + i * shentsize;
        let (kind, flags, size) = (u32_at(h + 4), u32_at(h + 8), u32_at(h + 20));
        const SHF_WRITE: u64 = 1;
        const SHF_ALLOC: u64 = 2;
        const SHT_NOBITS: u64 = 8;
        if flags & SHF_ALLOC == 0 {
            continue;
        }
        match (flags & SHF_WRITE != 0, kind == SHT_NOBITS) {
            (false, _) => text += size,
            (true, false) => data += size,
            (true, true) => bss += size,
        }
    }
    (text, data, bss)
}

#[test]
fn mps2_an386_flash_and_static_ram_are_within_budget() {
    flash_and_static_ram_are_within_budget(Board::Mps2An386);
}

#[test]
fn stm32f405_flash_and_static_ram_are_within_budget() {
    flash_and_static_ram_are_within_budget(Board::Stm32f405);
}

fn flash_and_static_ram_are_within_budget(board: Board) {
    let (flash_budget_bytes, static_ram_budget_bytes) = budgets(board);
    let elf = firmware_elf(board);
    let (text, data, bss) = berkeley_sizes(&std::fs::read(&elf).unwrap());
    let (flash, ram) = (text + data, data + bss);
    println!(
        "{}: text {text} data {data} bss {bss}: flash {flash} bytes, static RAM {ram} bytes",
        elf.display()
    );
    assert!(
        flash <= flash_budget_bytes,
        "{}: flash {flash} bytes > {flash_budget_bytes}",
        board.name()
    );
    assert!(
        ram <= static_ram_budget_bytes,
        "{}: static RAM {ram} bytes > {static_ram_budget_bytes}",
        board.name()
    );
    assert!(
        bss >= std::mem::size_of::<host_sim::replay::HostEstimator>() as u64,
        "the estimator's state is static"
    );
}

#[test]
fn mps2_an386_step_cost_is_within_6000_instructions_and_the_stack_is_measured() {
    step_cost_is_within_6000_instructions_and_the_stack_is_measured(Board::Mps2An386);
}

#[test]
fn stm32f405_step_cost_is_within_6000_instructions_and_the_stack_is_measured() {
    step_cost_is_within_6000_instructions_and_the_stack_is_measured(Board::Stm32f405);
}

fn step_cost_is_within_6000_instructions_and_the_stack_is_measured(board: Board) {
    let elf = firmware_elf(board);
    let dir = scratch(&format!("budgets-{}", board.name()));
    // The paper's log without loss, and a lossy one: a reciprocating sea log that loses 10 rows in
    // a row every 120 s, 2 % of rows at random and has jittered Unix stamps (filled rows, runs
    // left out with their taper, the window catching up after filled rows). mps2-an386's paper
    // log one sample at a time is `qemu_restart`'s 20,000 s sea stream, which checks the same budgets.
    let mut logs = Vec::new();
    if board != Board::Mps2An386 {
        logs.push(("paper, every row", paper_log(&dir, 6000)));
    }
    logs.push((
        "sea reciprocating, 10 rows lost every 120 s + 2 %, jittered Unix stamps",
        generated_log(
            &dir,
            "lossy.csv",
            &[
                "--scenario",
                "sea",
                "--duration",
                "6000",
                "--scheme",
                "reciprocating",
                "--gap-every",
                "120",
                "--gap-rows",
                "10",
                "--drop-fraction",
                "0.02",
                "--time-offset",
                "1.7e9",
                "--time-jitter",
                "0.02",
            ],
        ),
    ));
    for (name, log) in &logs {
        let out = host_sim(&[
            "stream",
            "--qemu",
            elf.to_str().unwrap(),
            "--machine",
            board.machine().name(),
            log.to_str().unwrap(),
            "--out",
            dir.join("stream.csv").to_str().unwrap(),
        ]);
        println!("{} ({name}):\n{out}", board.name());
        assert_step_and_start_up_stack_within_budgets(board, name, &out);
    }
}
