//! Where the checkpoints go: on silicon, flash sectors 5-11 (seven of 128 KiB, every sector after
//! the code's, `firmware::flash_layout::STM32F405`), erased and programmed through stm32f4xx-hal's
//! `embedded_storage` NOR flash (x8: a byte at a time); under QEMU, whose flash interface is a stub
//! that never programs anything, the host file `rins-flash.bin` ([`SemihostedFlash`], as on
//! mps2-an386) of the same size. `boards/stm32f405/memory.x` ends the code's FLASH region at the
//! end of sector 4, so the linker never puts code in the checkpoint sectors.
//!
//! Timing on silicon, from the STM32F405 datasheet (not measured; `firmware::flash_layout`): a
//! save programs its item a byte at a time (16 us typical, 100 us maximum a byte), and now and
//! then erases a 128 KiB sector first (2 s typical, 4 s maximum). The core stalls on instruction
//! fetches from flash meanwhile. How many bytes a save programs, how often it erases and what
//! that stalls: `host-sim flash-life --board stm32f405` (docs/firmware.md, "Checkpoints in
//! flash").

use core::ptr::addr_of;

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use stm32f4xx_hal::flash::FlashExt;
use stm32f4xx_hal::pac;

use firmware::flash_layout::STM32F405;

use super::super::semihosted_flash::SemihostedFlash;
use super::Environment;

/// Checkpoint region: flash sectors 5-11, as offsets from the start of flash (0x0800_0000).
const REGION_OFFSET: u32 = STM32F405.region_offset;
const REGION_BYTES: usize = STM32F405.region_bytes() as usize;
const SECTOR_BYTES: usize = STM32F405.sector_bytes as usize;

extern "C" {
    /// End of the read-only data in flash, from cortex-m-rt's `link.x`.
    static __erodata: u32;
}

/// The checkpoint store's flash on this board.
pub enum Flash {
    Internal(InternalFlash),
    Semihosted(SemihostedFlash<REGION_BYTES>),
}

impl Flash {
    pub fn open(environment: Environment, flash: pac::FLASH) -> Option<Flash> {
        match environment {
            Environment::Silicon => InternalFlash::new(flash).map(Flash::Internal),
            Environment::Qemu => {
                SemihostedFlash::open(super::QEMU_CPU_CLOCK_HZ).map(Flash::Semihosted)
            }
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

/// Flash sectors 5-11 as an 896 KiB NOR flash with 128 KiB erase blocks (offset 0 =
/// 0x0802_0000).
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

    fn check(offset: u32, len: usize, align: usize) -> Result<u32, NorFlashErrorKind> {
        if !(offset as usize).is_multiple_of(align) || !len.is_multiple_of(align) {
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
