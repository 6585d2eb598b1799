//! A NOR flash emulated by the host file `rins-flash.bin` in QEMU's working directory
//! (semihosting), behind the `embedded_storage` NOR flash traits: where the checkpoints go under
//! QEMU, whose boards have no flash controller to program (mps2-an386 has none; netduinoplus2's is
//! a stub). `CAPACITY` bytes (each board's checkpoint region, `firmware::flash_layout`), 4 KiB
//! erase blocks, 4-byte writes; bytes past the end of the file read as erased (0xFF). Writes
//! replace the bytes (the store writes only erased flash). Not modelled: a torn write (a write
//! reaches the file whole, page by page) and any stall.
//!
//! **A power cut on order**, for tests: when the file `rins-flash.cut` in the same directory
//! (`firmware::flash_layout::EMULATED_FLASH_CUT_ORDER_FILE`) holds a decimal number N, the flash
//! reads and removes it at its next write or erase, programs N more 256-byte pages and then cuts
//! the power: QEMU exits with `EMULATED_FLASH_POWER_CUT_EXIT_CODE` before the next page reaches
//! the file. A test thereby cuts a save after exactly N of its pages, on a loaded machine as on
//! an idle one.

use embedded_storage::nor_flash::{NorFlash, NorFlashErrorKind, ReadNorFlash};

pub struct SemihostedFlash<const CAPACITY: usize> {
    file: semihosting::fs::File,
    page_program_cycles: u32,
    /// Pages still to program before a power cut on order; `None` when none is ordered.
    pages_before_cut: Option<u32>,
}

impl<const CAPACITY: usize> SemihostedFlash<CAPACITY> {
    const PATH: &'static core::ffi::CStr = c"rins-flash.bin";

    /// Opens (or creates) the file. Every 256-byte page written then takes the time the
    /// STM32F405 takes to program 256 bytes at x8 (16 us a byte, typical: 4.1 ms) of a core clock
    /// of `core_clock_hz`, so that a save lasts about as long as on the chip and a power cut can
    /// land between any two pages; an erase, written as pages of 0xFF, lasts as long per page.
    pub fn open(core_clock_hz: u32) -> Option<Self> {
        let page_program_cycles = (u64::from(core_clock_hz) * 4096 / 1_000_000) as u32;
        use semihosting::fs::File;
        let file = File::options()
            .read(true)
            .write(true)
            .open(Self::PATH)
            .ok()
            .or_else(|| {
                File::options()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .open(Self::PATH)
                    .ok()
            })?;
        Some(SemihostedFlash {
            file,
            page_program_cycles,
            pages_before_cut: None,
        })
    }

    /// The number of pages in `rins-flash.cut`, which is removed once read; `None` when there is
    /// no such file or it holds no decimal number.
    fn take_cut_order() -> Option<u32> {
        use semihosting::io::Read;
        let mut file =
            semihosting::fs::File::open(firmware::flash_layout::EMULATED_FLASH_CUT_ORDER_FILE)
                .ok()?;
        let mut text = [0u8; 12];
        let len = file.read(&mut text).ok()?;
        drop(file);
        let _ = semihosting::fs::remove_file(firmware::flash_layout::EMULATED_FLASH_CUT_ORDER_FILE);
        let digits = text.get(..len)?.trim_ascii();
        if digits.is_empty() || !digits.iter().all(u8::is_ascii_digit) {
            return None;
        }
        digits.iter().try_fold(0u32, |n, d| {
            n.checked_mul(10)?.checked_add(u32::from(d - b'0'))
        })
    }

    fn check(offset: u32, len: usize, align: usize) -> Result<(), NorFlashErrorKind> {
        let end = offset as usize + len;
        if !(offset as usize).is_multiple_of(align) || !len.is_multiple_of(align) {
            return Err(NorFlashErrorKind::NotAligned);
        }
        if end > CAPACITY {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        Ok(())
    }

    /// Writes page by page (256 bytes, a NOR flash's program page), each taking the page time.
    fn write_at(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        use semihosting::io::{Seek, SeekFrom, Write};
        if self.pages_before_cut.is_none() {
            self.pages_before_cut = Self::take_cut_order();
        }
        self.file
            .seek(SeekFrom::Start(offset as u64))
            .map_err(|_| NorFlashErrorKind::Other)?;
        for page in bytes.chunks(256) {
            if let Some(left) = self.pages_before_cut.as_mut() {
                if *left == 0 {
                    semihosting::process::exit(
                        firmware::flash_layout::EMULATED_FLASH_POWER_CUT_EXIT_CODE,
                    );
                }
                *left -= 1;
            }
            self.file
                .write_all(page)
                .map_err(|_| NorFlashErrorKind::Other)?;
            cortex_m::asm::delay(self.page_program_cycles);
        }
        Ok(())
    }
}

impl<const CAPACITY: usize> embedded_storage::nor_flash::ErrorType for SemihostedFlash<CAPACITY> {
    type Error = NorFlashErrorKind;
}

impl<const CAPACITY: usize> ReadNorFlash for SemihostedFlash<CAPACITY> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        use semihosting::io::{Read, Seek, SeekFrom};
        Self::check(offset, bytes.len(), 1)?;
        bytes.fill(0xFF);
        self.file
            .seek(SeekFrom::Start(offset as u64))
            .map_err(|_| NorFlashErrorKind::Other)?;
        let mut done = 0;
        while let Some(rest) = bytes.get_mut(done..) {
            if rest.is_empty() {
                break;
            }
            match self.file.read(rest) {
                Ok(0) => break,
                Ok(n) => done += n,
                Err(_) => return Err(NorFlashErrorKind::Other),
            }
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        CAPACITY
    }
}

impl<const CAPACITY: usize> NorFlash for SemihostedFlash<CAPACITY> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = 4096;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), NorFlashErrorKind> {
        if to < from {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        Self::check(from, (to - from) as usize, Self::ERASE_SIZE)?;
        let erased = [0xFFu8; 256];
        let mut at = from;
        while at < to {
            self.write_at(at, &erased)?;
            at += erased.len() as u32;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        Self::check(offset, bytes.len(), Self::WRITE_SIZE)?;
        self.write_at(offset, bytes)
    }
}
