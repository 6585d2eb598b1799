//! ARM MPS2+ AN386 (Cortex-M4F, 25 MHz) as QEMU emulates it (`-machine mps2-an386`).
//!
//! - UART0: CMSDK APB UART at 0x4000_4000, 115200 baud from the 25 MHz peripheral clock. The core
//!   sleeps (WFI) until a byte arrives: the RX interrupt (IRQ 0) is enabled in the UART and the NVIC
//!   but masked by PRIMASK, so it wakes the core without running a handler; no interrupt handler
//!   exists. Sleeping instead of spinning leaves the host's CPU to QEMU's I/O thread.
//! - Cost counter: SysTick on the core clock, free-running over 24 bits. On real silicon a tick is a
//!   core cycle (40 ns). Under QEMU with `-icount shift=0` each instruction takes 1 ns of virtual
//!   time, so one tick (1/25 MHz = 40 ns) is exactly 40 instructions; the TCG plugin
//!   `firmware/tools/stepcount.c` confirms it.
//! - Logs: defmt over semihosting (QEMU's stdout). Fatal errors: semihosting exit with status 1.
//! - Flash for checkpoints: the host file `rins-flash.bin` in QEMU's working directory
//!   (semihosting), behind the `embedded_storage` NOR flash traits.

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use defmt_semihosting as _;
use embedded_storage::nor_flash::{NorFlash, NorFlashErrorKind, ReadNorFlash};

/// Core (and SysTick) clock, Hz.
pub const CORE_CLOCK_HZ: u32 = 25_000_000;
const UART_CLOCK_HZ: u32 = 25_000_000;
const BAUD: u32 = 115_200;

const UART0_BASE: usize = 0x4000_4000;
const UART_DATA: usize = 0x00;
const UART_STATE: usize = 0x04;
const UART_CTRL: usize = 0x08;
const UART_INTSTATUS: usize = 0x0C;
const UART_BAUDDIV: usize = 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_INT_EN: u32 = 1 << 3;
const INTSTATUS_RX: u32 = 1 << 1;
/// UART0's receive interrupt on this board (QEMU hw/arm/mps2.c: UART0 RX = IRQ 0).
const UART0_RX_IRQ: u32 = 0;

/// The board's parts.
pub struct Board {
    pub uart: Uart,
    pub cost: CostCounter,
    /// Non-volatile storage for checkpoints; `None` without the `checkpoint` feature or if the
    /// host file cannot be opened.
    #[cfg_attr(not(feature = "checkpoint"), allow(dead_code))]
    pub flash: Option<Flash>,
}

impl Board {
    /// Sets up the UART and the cost counter. Call once.
    pub fn init() -> Option<Board> {
        let peripherals = cortex_m::Peripherals::take()?;
        // Interrupts stay masked: a pending UART interrupt only wakes the core from WFI.
        cortex_m::interrupt::disable();
        let nvic = peripherals.NVIC;
        // SAFETY: enabling an interrupt that PRIMASK keeps from being taken.
        unsafe { nvic.iser[0].write(1 << UART0_RX_IRQ) };
        Some(Board {
            uart: Uart::init(nvic),
            cost: CostCounter::init(peripherals.SYST),
            flash: if cfg!(feature = "checkpoint") {
                Flash::open()
            } else {
                None
            },
        })
    }
}

/// UART0.
pub struct Uart {
    nvic: cortex_m::peripheral::NVIC,
}

impl Uart {
    fn init(nvic: cortex_m::peripheral::NVIC) -> Uart {
        // SAFETY: UART0's registers, owned by this one `Uart` created once in `Board::init`.
        unsafe {
            reg_write(UART_BAUDDIV, UART_CLOCK_HZ / BAUD);
            reg_write(UART_CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN);
            reg_write(UART_INTSTATUS, 0xF);
            // One dummy read: QEMU wakes its chardev only when DATA is read, so without it the first
            // input byte waits about a second (measured under QEMU).
            let _ = reg_read(UART_DATA);
        }
        Uart { nvic }
    }

    fn read_byte(&mut self) -> u8 {
        while !self.rx_ready() {
            // Wakes when UART0's RX interrupt is pending (also if it became pending just before).
            cortex_m::asm::wfi();
        }
        // SAFETY: see `init`.
        let byte = unsafe { reg_read(UART_DATA) as u8 };
        // Clear the interrupt at the UART, then in the NVIC, so the next WFI sleeps.
        // SAFETY: see `init`; ICPR only clears a pending bit.
        unsafe {
            reg_write(UART_INTSTATUS, INTSTATUS_RX);
            self.nvic.icpr[0].write(1 << UART0_RX_IRQ);
        }
        byte
    }

    fn rx_ready(&self) -> bool {
        // SAFETY: see `init`; reading STATE has no side effect.
        unsafe { reg_read(UART_STATE) & STATE_RX_FULL != 0 }
    }

    fn write_byte(&mut self, byte: u8) {
        // SAFETY: see `init`.
        unsafe {
            while reg_read(UART_STATE) & STATE_TX_FULL != 0 {}
            reg_write(UART_DATA, byte as u32);
        }
    }
}

impl embedded_io::ErrorType for Uart {
    type Error = Infallible;
}

impl embedded_io::Read for Uart {
    /// Blocks until at least one byte has arrived, then takes what is already there.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            if n > 0 && !self.rx_ready() {
                break;
            }
            *slot = self.read_byte();
            n += 1;
        }
        Ok(n)
    }
}

impl embedded_io::Write for Uart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        for &b in buf {
            self.write_byte(b);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        // SAFETY: see `init`.
        unsafe { while reg_read(UART_STATE) & STATE_TX_FULL != 0 {} }
        Ok(())
    }
}

unsafe fn reg_read(offset: usize) -> u32 {
    read_volatile((UART0_BASE + offset) as *const u32)
}

unsafe fn reg_write(offset: usize, value: u32) {
    write_volatile((UART0_BASE + offset) as *mut u32, value)
}

/// SysTick as a free-running 24-bit down-counter at [`CORE_CLOCK_HZ`].
pub struct CostCounter {
    _syst: SYST,
}

/// A reading of the [`CostCounter`].
#[derive(Clone, Copy)]
pub struct CostStamp(u32);

impl CostCounter {
    /// Frequency of the ticks, Hz.
    pub const HZ: u32 = CORE_CLOCK_HZ;

    fn init(mut syst: SYST) -> CostCounter {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        CostCounter { _syst: syst }
    }

    /// Now.
    #[inline(always)]
    pub fn stamp(&self) -> CostStamp {
        CostStamp(SYST::get_current())
    }

    /// Ticks from `start` to now (correct for intervals below 2^24 ticks, 0.67 s).
    #[inline(always)]
    pub fn ticks_since(&self, start: CostStamp) -> u32 {
        start.0.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF
    }
}

/// The board's NOR flash for checkpoints, emulated by the host file `rins-flash.bin` in QEMU's
/// working directory (semihosting). 64 KiB, 4 KiB erase blocks, 4-byte writes; bytes past the end
/// of the file read as erased (0xFF). Writes overwrite (the checkpoint store always erases first).
pub struct Flash {
    file: semihosting::fs::File,
}

impl Flash {
    const CAPACITY: usize = 64 * 1024;
    const PATH: &'static core::ffi::CStr = c"rins-flash.bin";

    fn open() -> Option<Flash> {
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
        Some(Flash { file })
    }

    #[allow(clippy::manual_is_multiple_of)] // is_multiple_of needs Rust 1.87; the workspace says 1.85
    fn check(offset: u32, len: usize, align: usize) -> Result<(), NorFlashErrorKind> {
        let end = offset as usize + len;
        if offset as usize % align != 0 || len % align != 0 {
            return Err(NorFlashErrorKind::NotAligned);
        }
        if end > Self::CAPACITY {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        Ok(())
    }

    /// Writes page by page (256 bytes, a NOR flash's program page) and takes a NOR flash's time
    /// per page (0.5 ms of core clock), so that a save lasts about as long as on a real part and a
    /// power cut can land between any two pages.
    fn write_at(&mut self, offset: u32, bytes: &[u8]) -> Result<(), NorFlashErrorKind> {
        use semihosting::io::{Seek, SeekFrom, Write};
        const PAGE_PROGRAM_CYCLES: u32 = CORE_CLOCK_HZ / 2000;
        self.file
            .seek(SeekFrom::Start(offset as u64))
            .map_err(|_| NorFlashErrorKind::Other)?;
        for page in bytes.chunks(256) {
            self.file.write_all(page).map_err(|_| NorFlashErrorKind::Other)?;
            cortex_m::asm::delay(PAGE_PROGRAM_CYCLES);
        }
        Ok(())
    }
}

impl embedded_storage::nor_flash::ErrorType for Flash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Flash {
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
        Self::CAPACITY
    }
}

impl NorFlash for Flash {
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

/// After a panic or a fault has been logged: end the QEMU run with exit status 1 (on a real board
/// this would be `SCB::sys_reset()`).
pub fn fatal() -> ! {
    semihosting::process::exit(1)
}
