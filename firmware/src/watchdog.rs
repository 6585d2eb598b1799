//! The watchdog as the rest of the firmware sees it, and a flash that feeds it.
//!
//! The board's watchdog resets the chip unless it is fed in time (STM32F405: the IWDG, about 10 s;
//! mps2-an386: the CMSDK watchdog; docs/firmware.md). The main loop feeds it each time it wakes
//! (a byte, or the SysTick tick at least every 0.67 s). The longest thing the loop does is a flash
//! erase (a 128 KiB sector of the STM32F405: 4 s at most by its datasheet), and a `Reset` may
//! erase several: [`FedFlash`] erases one block at a time and feeds the watchdog before each, so
//! no erase sequence, however long, starves it, while a loop that hangs still does.

use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};

/// The STM32F405's IWDG timeout, nominal (LSI at 32 kHz). The LSI runs at 17 to 47 kHz (DS8626,
/// LSI oscillator characteristics), so the reset comes after 6.8 to 18.8 s
/// ([`iwdg_timeout_range_ms`]): above the main loop's longest legitimate stall (a 128 KiB sector
/// erase, 4 s at most, and a checkpoint's programming: 4.26 s; docs/firmware.md, the one-second
/// budget; `tests/receive_timeline.rs` checks it), and a `Reset` that erases several sectors feeds
/// it between them ([`FedFlash`]).
pub const STM32F405_IWDG_TIMEOUT_MS: u32 = 10_000;

/// The IWDG's real timeout, ms, at the LSI's slowest (17 kHz) and fastest (47 kHz) frequency
/// (DS8626), for a timeout `nominal_ms` set for 32 kHz: (shortest, longest).
pub const fn iwdg_timeout_range_ms(nominal_ms: u32) -> (u32, u32) {
    (nominal_ms * 32 / 47, nominal_ms * 32 / 17)
}

/// Something that must be fed in time. Feeding is a register write: a copyable handle suffices.
pub trait Watchdog {
    /// Restarts the watchdog's countdown.
    fn feed(&self);
}

/// No watchdog (a board without one, or a host test).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoWatchdog;

impl Watchdog for NoWatchdog {
    fn feed(&self) {}
}

/// A NOR flash whose erases go one erase block at a time, each after feeding the watchdog, and
/// whose writes feed it first.
pub struct FedFlash<F, W> {
    flash: F,
    watchdog: W,
}

impl<F, W> FedFlash<F, W> {
    /// `flash`, feeding `watchdog` before each erase block and each write.
    pub fn new(flash: F, watchdog: W) -> Self {
        FedFlash { flash, watchdog }
    }

    /// The flash inside.
    pub fn inner(&self) -> &F {
        &self.flash
    }
}

impl<F: ErrorType, W> ErrorType for FedFlash<F, W> {
    type Error = F::Error;
}

impl<F: ReadNorFlash, W> ReadNorFlash for FedFlash<F, W> {
    const READ_SIZE: usize = F::READ_SIZE;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.flash.read(offset, bytes)
    }

    fn capacity(&self) -> usize {
        self.flash.capacity()
    }
}

impl<F: NorFlash, W: Watchdog> NorFlash for FedFlash<F, W> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let block = F::ERASE_SIZE as u32;
        if block == 0 || to <= from {
            // Nothing to split: the flash decides (and reports a bad range).
            self.watchdog.feed();
            return self.flash.erase(from, to);
        }
        let mut at = from;
        while at < to {
            let end = at.saturating_add(block).min(to);
            self.watchdog.feed();
            self.flash.erase(at, end)?;
            at = end;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.watchdog.feed();
        self.flash.write(offset, bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::cell::RefCell;
    use embedded_storage::nor_flash::NorFlashErrorKind;
    use std::vec::Vec;

    /// What happened, in order: feeds and erases.
    #[derive(Debug, PartialEq)]
    enum Event {
        Feed,
        Erase(u32, u32),
        Write(u32, usize),
    }

    struct Log<'a>(&'a RefCell<Vec<Event>>);

    impl Watchdog for Log<'_> {
        fn feed(&self) {
            self.0.borrow_mut().push(Event::Feed);
        }
    }

    struct MockFlash<'a>(&'a RefCell<Vec<Event>>);

    impl ErrorType for MockFlash<'_> {
        type Error = NorFlashErrorKind;
    }

    impl ReadNorFlash for MockFlash<'_> {
        const READ_SIZE: usize = 1;
        fn read(&mut self, _: u32, _: &mut [u8]) -> Result<(), NorFlashErrorKind> {
            Ok(())
        }
        fn capacity(&self) -> usize {
            4 * 1024
        }
    }

    impl NorFlash for MockFlash<'_> {
        const WRITE_SIZE: usize = 1;
        const ERASE_SIZE: usize = 1024;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), NorFlashErrorKind> {
            if !from.is_multiple_of(1024) || !to.is_multiple_of(1024) || to > 4096 {
                return Err(NorFlashErrorKind::NotAligned);
            }
            self.0.borrow_mut().push(Event::Erase(from, to));
            Ok(())
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
            self.0.borrow_mut().push(Event::Write(offset, bytes.len()));
            Ok(())
        }
    }

    #[test]
    fn a_long_erase_is_split_into_blocks_each_after_a_feed() {
        let log = RefCell::new(Vec::new());
        let mut flash = FedFlash::new(MockFlash(&log), Log(&log));
        flash.erase(1024, 4096).unwrap();
        flash.write(1024, &[1, 2, 3]).unwrap();
        assert_eq!(
            *log.borrow(),
            [
                Event::Feed,
                Event::Erase(1024, 2048),
                Event::Feed,
                Event::Erase(2048, 3072),
                Event::Feed,
                Event::Erase(3072, 4096),
                Event::Feed,
                Event::Write(1024, 3),
            ]
        );
    }

    #[test]
    fn a_bad_range_is_the_flash_s_error() {
        let log = RefCell::new(Vec::new());
        let mut flash = FedFlash::new(MockFlash(&log), Log(&log));
        assert_eq!(flash.erase(100, 2048), Err(NorFlashErrorKind::NotAligned));
        // Past the end: the blocks before the bad one are erased, then the error stops it.
        log.borrow_mut().clear();
        assert_eq!(flash.erase(3072, 6144), Err(NorFlashErrorKind::NotAligned));
        assert_eq!(
            *log.borrow(),
            [Event::Feed, Event::Erase(3072, 4096), Event::Feed]
        );
    }
}
