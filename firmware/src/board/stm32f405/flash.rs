//! Where the checkpoints go: on silicon, flash sectors 10 and 11 (the last two, 128 KiB each, one
//! checkpoint slot per sector, erased and programmed through stm32f4xx-hal's `embedded_storage` NOR
//! flash); under QEMU, whose flash interface is a stub that never programs anything, the host file
//! `rins-flash.bin` ([`SemihostedFlash`], as on mps2-an386). `boards/stm32f405/memory.x` ends the
//! code's FLASH region before sector 10, so the linker never puts code there.
//!
//! Why those sectors: an image is 23.4 KB, more than one of the 16 KiB sectors 1-3, and a slot
//! must be whole erase blocks that the other slot does not share.
//!
//! Timing on silicon, from the STM32F405 datasheet (not measured): a 128 KiB sector erase takes
//! 1-2 s at 3.3 V (x32 parallelism), byte programming 16 us a byte, so a save (one erase, 23.4 KB)
//! takes 1.4-2.4 s, once per checkpoint interval (60 s by default). The core stalls on instruction
//! fetches from flash meanwhile; the host is waiting for the answer to the sample that triggered
//! the save, so no byte arrives (the host's link timeout is 10 s).

use core::ptr::addr_of;

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use stm32f4xx_hal::flash::FlashExt;
use stm32f4xx_hal::pac;

use super::super::semihosted_flash::SemihostedFlash;
use super::Environment;

/// Checkpoint region: flash sectors 10 and 11, as offsets from the start of flash (0x0800_0000).
const REGION_OFFSET: u32 = 0xC_0000;
const REGION_BYTES: usize = 2 * SECTOR_BYTES;
const SECTOR_BYTES: usize = 128 * 1024;
/// Under QEMU: core cycles (instructions) per 256-byte page written, the same as on mps2-an386,
/// so that a save lasts as many instructions there and a power cut lands inside one as often.
const QEMU_PAGE_PROGRAM_CYCLES: u32 = 12_500;

extern "C" {
    /// End of the read-only data in flash, from cortex-m-rt's `link.x`.
    static __erodata: u32;
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
    /// A multiple of both: one 128 KiB sector (internal) and 4 KiB (semihosted).
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

/// Flash sectors 10 and 11 as a 256 KiB NOR flash with 128 KiB erase blocks (offset 0 =
/// 0x080C_0000).
/// Unlocked only for the length of one erase or write.
pub struct InternalFlash {
    flash: pac::FLASH,
}

impl InternalFlash {
    /// `None` (and an error log) if the code was linked into the region (a memory.x whose FLASH
    /// reaches sector 10).
    fn new(flash: pac::FLASH) -> Option<InternalFlash> {
        let code_end = addr_of!(__erodata) as usize;
        let region_start = flash.address() + REGION_OFFSET as usize;
        if code_end > region_start {
            defmt::error!(
                "code ends at {=usize:#x}, inside the checkpoint sectors: checkpoints off",
                code_end
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
