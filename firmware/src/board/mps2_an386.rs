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
//!   ([`Flash`], `semihosted_flash.rs`), laid out as `firmware::flash_layout::MPS2_AN386` (64
//!   sectors of 4 KiB), each 256-byte page written in the STM32F405's time (4.1 ms of core clock).

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};

use defmt_semihosting as _;

pub use super::systick_cost::CostCounter;

/// The checkpoint flash: the semihosted file, as big as the board's checkpoint region.
pub type Flash = super::semihosted_flash::SemihostedFlash<{ firmware::flash_layout::MPS2_AN386.region_bytes() as usize }>;

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
            cost: CostCounter::init(peripherals.SYST, CORE_CLOCK_HZ),
            flash: if cfg!(feature = "checkpoint") {
                Flash::open(CORE_CLOCK_HZ)
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

/// After a panic or a fault has been logged: end the QEMU run with exit status 1.
pub fn fatal() -> ! {
    semihosting::process::exit(1)
}
