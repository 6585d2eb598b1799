//! Each board's checkpoint flash: where it lies, its sectors, and the datasheet's figures for
//! erasing and programming it (what a save costs in stalls, and how long the flash lives).
//!
//! STM32F405 (datasheet DS8626, reference manual RM0090): flash sectors 0-3 are 16 KiB, 4 is
//! 64 KiB, 5-11 are 128 KiB. The code lives in sectors 0-4 (128 KiB; its budget within them:
//! docs/firmware.md, "Flash layout and checkpoints"); the checkpoints get every sector after it,
//! 5-11: 7 sectors of 128 KiB. Endurance: 10,000 erase cycles per sector (minimum, -40 to 85 C).
//! A 128 KiB sector erases in 2 s typical, 4 s maximum at x8 parallelism (stm32f4xx-hal's, which
//! the firmware uses); a byte programs in 16 us typical, 100 us maximum at x8. One flash bank: any
//! instruction fetch from flash stalls while it erases or programs.
//!
//! mps2-an386 (QEMU only): no flash controller; the firmware keeps its checkpoints in a host file
//! through semihosting, laid out as a NOR flash of 64 sectors of 4 KiB. It has no datasheet: its
//! life is reckoned at the same 10,000 cycles, and it has no timing (nothing stalls in QEMU).

/// A board's checkpoint flash.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlashLayout {
    /// The board's name, as the firmware's features and the docs give it.
    pub board: &'static str,
    /// Offset of the checkpoint region from the start of the flash, bytes.
    pub region_offset: u32,
    /// Bytes of one sector (the erase unit).
    pub sector_bytes: u32,
    /// Sectors given to the checkpoints.
    pub sectors: u32,
    /// Erase cycles per sector the datasheet guarantees.
    pub endurance_cycles: u32,
    /// Time to erase one sector, typical and maximum, s (`None`: not a real part).
    pub sector_erase_s: Option<[f64; 2]>,
    /// Time to program one byte, typical and maximum, s (`None`: not a real part).
    pub byte_program_s: Option<[f64; 2]>,
}

impl FlashLayout {
    /// Bytes of the checkpoint region.
    pub const fn region_bytes(&self) -> u32 {
        self.sector_bytes * self.sectors
    }
}

/// STM32F405: sectors 5-11 (see the module doc).
pub const STM32F405: FlashLayout = FlashLayout {
    board: "stm32f405",
    region_offset: 0x2_0000,
    sector_bytes: 128 * 1024,
    sectors: 7,
    endurance_cycles: 10_000,
    sector_erase_s: Some([2.0, 4.0]),
    byte_program_s: Some([16e-6, 100e-6]),
};

/// mps2-an386 under QEMU: a NOR flash of 64 sectors of 4 KiB (see the module doc).
pub const MPS2_AN386: FlashLayout = FlashLayout {
    board: "mps2-an386",
    region_offset: 0,
    sector_bytes: 4096,
    sectors: 64,
    endurance_cycles: 10_000,
    sector_erase_s: None,
    byte_program_s: None,
};

/// Under QEMU, the host file (in QEMU's working directory, beside the emulated flash
/// `rins-flash.bin`) that orders the emulated flash to cut the power: it holds a decimal number N,
/// and the flash programs N more 256-byte pages and then stops the board. How a test cuts a save
/// at an exact point; a board with real flash never looks for it.
pub const EMULATED_FLASH_CUT_ORDER_FILE: &core::ffi::CStr = c"rins-flash.cut";

/// QEMU's exit code when the emulated flash cuts the power on order.
pub const EMULATED_FLASH_POWER_CUT_EXIT_CODE: i32 = 75;
