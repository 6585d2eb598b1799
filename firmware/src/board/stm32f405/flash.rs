//! Where the checkpoints go: on silicon, flash sectors 1 and 2 (16 KiB each, one checkpoint slot
//! per sector, erased and programmed through stm32f4xx-hal's `embedded_storage` NOR flash); under
//! QEMU, whose flash interface is a stub that never programs anything, the host file
//! `rins-flash.bin` ([`SemihostedFlash`], as on mps2-an386). `boards/stm32f405/memory.x` starts
//! the code at sector 3 (`_stext`), so the two sectors hold nothing else.
//!
//! Timing on silicon, from the STM32F405 datasheet (not measured): a 16 KiB sector erase takes
//! 0.25-0.5 s at 3.3 V, byte programming 16 us a byte, so a save (one erase, 13.8 KB) takes about
//! 0.5 s, once per checkpoint interval. The core stalls on instruction fetches from flash meanwhile;
//! the host is waiting for the answer to the sample that triggered the save, so no byte arrives.

use core::ptr::addr_of;

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use stm32f4xx_hal::flash::FlashExt;
use stm32f4xx_hal::pac;

use super::super::semihosted_flash::SemihostedFlash;
use super::Environment;

/// Checkpoint region: flash sectors 1 and 2, as offsets from the start of flash (0x0800_0000).
const REGION_OFFSET: u32 = 0x4000;
const REGION_BYTES: usize = 2 * SECTOR_BYTES;
const SECTOR_BYTES: usize = 16 * 1024;
/// Under QEMU: core cycles (instructions) per 256-byte page written, the same as on mps2-an386,
/// so that a save lasts as many instructions there and a power cut lands inside one as often.
const QEMU_PAGE_PROGRAM_CYCLES: u32 = 12_500;

extern "C" {
    /// Start of the code, from cortex-m-rt's `link.x` (`_stext` in memory.x).
    static __stext: u32;
}

/// The checkpoint store's flash on this board.
pub enum Flash {
    Internal(InternalFlash),
    Semihosted(SemihostedFlash),
}

impl Flash {
    pub fn open(environment: Environment, flash: pac::FLASH) -> Option<Flash> {
        match environment {
            Environment::Silicon => InternalFlash::new(flash).map(Flash::Internal),
            Environment::Qemu => SemihostedFlash::open(QEMU_PAGE_PROGRAM_CYCLES).map(Flash::Semihosted),
        }
    }
}

impl ErrorType for Flash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Flash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        match self {
            Flash::Internal(f) => f.read(offset, bytes),
            Flash::Semihosted(f) => f.read(offset, bytes),
        }
    }

    fn capacity(&self) -> usize {
        match self {
            Flash::Internal(f) => f.capacity(),
            Flash::Semihosted(f) => f.capacity(),
        }
    }
}

impl NorFlash for Flash {
    /// A multiple of both: 1 byte (internal) and 4 (semihosted).
    const WRITE_SIZE: usize = 4;
    /// A multiple of both: one 16 KiB sector (internal) and 4 KiB (semihosted).
    const ERASE_SIZE: usize = SECTOR_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), NorFlashErrorKind> {
        match self {
            Flash::Internal(f) => f.erase(from, to),
            Flash::Semihosted(f) => f.erase(from, to),
        }
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        match self {
            Flash::Internal(f) => f.write(offset, bytes),
            Flash::Semihosted(f) => f.write(offset, bytes),
        }
    }
}

/// Flash sectors 1 and 2 as a 32 KiB NOR flash with 16 KiB erase blocks (offset 0 = 0x0800_4000).
/// Unlocked only for the length of one erase or write.
pub struct InternalFlash {
    flash: pac::FLASH,
}

impl InternalFlash {
    /// `None` (and an error log) if the code was linked into the region.
    fn new(flash: pac::FLASH) -> Option<InternalFlash> {
        let code_start = addr_of!(__stext) as usize;
        let region_end = flash.address() + REGION_OFFSET as usize + REGION_BYTES;
        if code_start < region_end {
            defmt::error!(
                "code starts at {=usize:#x}, inside the checkpoint sectors: checkpoints off",
                code_start
            );
            return None;
        }
        Some(InternalFlash { flash })
    }

    #[allow(clippy::manual_is_multiple_of)] // is_multiple_of needs Rust 1.87; the workspace says 1.85
    fn check(offset: u32, len: usize, align: usize) -> Result<u32, NorFlashErrorKind> {
        if offset as usize % align != 0 || len % align != 0 {
            return Err(NorFlashErrorKind::NotAligned);
        }
        if offset as usize + len > REGION_BYTES {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        Ok(REGION_OFFSET + offset)
    }
}

impl ErrorType for InternalFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for InternalFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        let at = Self::check(offset, bytes.len(), 1)? as usize;
        let source = self
            .flash
            .read()
            .get(at..at + bytes.len())
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        bytes.copy_from_slice(source);
        Ok(())
    }

    fn capacity(&self) -> usize {
        REGION_BYTES
    }
}

impl NorFlash for InternalFlash {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = SECTOR_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), NorFlashErrorKind> {
        if to < from {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        let start = Self::check(from, (to - from) as usize, SECTOR_BYTES)?;
        let end = start + (to - from);
        let mut unlocked = self.flash.unlocked();
        NorFlash::erase(&mut unlocked, start, end).map_err(|e| e.kind())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        let at = Self::check(offset, bytes.len(), 1)?;
        let mut unlocked = self.flash.unlocked();
        NorFlash::write(&mut unlocked, at, bytes).map_err(|e| e.kind())
    }
}
