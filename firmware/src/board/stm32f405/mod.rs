//! STM32F405 (Cortex-M4F, 1 MiB flash, 128 KiB SRAM + 64 KiB CCM) through stm32f4xx-hal 0.23.
//! One image runs on silicon and on QEMU's `netduinoplus2`; [`environment`] tells them apart at
//! run time, and everything QEMU does not model takes its QEMU path there:
//!
//! | part | silicon | QEMU netduinoplus2 |
//! |---|---|---|
//! | clocks | HSE crystal (`RINS_HSE_HZ`) and PLL at 168 MHz | HSI 16 MHz (QEMU has no RCC model: the PLL and HSE never report ready) |
//! | link | USART1, PA9 TX / PA10 RX, 115200 8N1 (`serial.rs`) | the same USART1 (QEMU's first `-serial`) |
//! | cost counter | SysTick at the core clock (a tick is a cycle) | SysTick at QEMU's CPU clock, [`QEMU_CPU_CLOCK_HZ`] |
//! | logs (defmt) | RTT, for a debug probe (`logger.rs`) | semihosting, QEMU's stdout |
//! | checkpoints | flash sectors 5-11 (`flash.rs`) | the host file `rins-flash.bin` (semihosting) |
//! | fatal error | reset (`SCB::sys_reset`) after the log has had time to drain | QEMU exits with status 1 |
//!
//! Nothing of this was run on silicon: the silicon column is written from the reference manual
//! (RM0090) and stm32f4xx-hal; the QEMU column is what the tests run.

mod flash;
mod logger;
mod serial;

use core::sync::atomic::{AtomicU8, Ordering};

use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;

pub use super::systick_cost::CostCounter;
pub use flash::Flash;
pub use serial::Uart;

// `HSE_HZ`: the crystal, `RINS_HSE_HZ` when the firmware was built (checked by build.rs).
include!(concat!(env!("OUT_DIR"), "/board_clock.rs"));

/// Core clock on silicon, Hz (the STM32F405's maximum).
const SYSCLK_HZ: u32 = 168_000_000;
/// The clock QEMU 7.2's netduinoplus2 gives its Cortex-M4 and so SysTick, whatever RCC is told:
/// under `-icount shift=0` one tick is 10^9 / 168e6 = 5.95 instructions.
pub const QEMU_CPU_CLOCK_HZ: u32 = 168_000_000;
/// Cycles to wait before a reset after a fatal error, so that a probe can read the last log
/// lines out of RTT (0.1 s at 168 MHz, 1 s if the clock setup itself failed and HSI still runs).
const FATAL_DRAIN_CYCLES: u32 = 16_800_000;

/// Where the image runs.
#[derive(Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum Environment {
    Silicon,
    Qemu,
}

/// 0: not yet detected; 1: silicon; 2: QEMU.
static ENVIRONMENT: AtomicU8 = AtomicU8::new(0);

/// Where the image runs, detected on first call: RCC_CR's HSIRDY is 1 on silicon from reset on
/// (the core runs from HSI; RM0090 6.3.1), and reads 0 under QEMU, whose RCC is a stub that
/// reads 0. Call first before touching the clocks ([`Board::init`] does).
pub fn environment() -> Environment {
    match ENVIRONMENT.load(Ordering::Relaxed) {
        1 => Environment::Silicon,
        2 => Environment::Qemu,
        _ => {
            // SAFETY: a read of RCC_CR, which has no side effect.
            let hsi_ready = unsafe { (*pac::RCC::ptr()).cr().read().hsirdy().bit_is_set() };
            let (e, code) = if hsi_ready {
                (Environment::Silicon, 1)
            } else {
                (Environment::Qemu, 2)
            };
            ENVIRONMENT.store(code, Ordering::Relaxed);
            e
        }
    }
}

/// The board's parts.
pub struct Board {
    pub uart: Uart,
    pub cost: CostCounter,
    /// Non-volatile storage for checkpoints; `None` if it cannot be opened.
    pub flash: Option<Flash>,
}

impl Board {
    /// Sets up the clocks, USART1, the cost counter and the checkpoint flash. Call once.
    pub fn init() -> Option<Board> {
        let environment = environment();
        let core = cortex_m::Peripherals::take()?;
        let device = pac::Peripherals::take()?;
        // Interrupts stay masked: USART1's pending RXNE interrupt only wakes the core from WFI.
        cortex_m::interrupt::disable();
        let config = match environment {
            Environment::Silicon => Config::hse(HSE_HZ.Hz()).sysclk(SYSCLK_HZ.Hz()),
            Environment::Qemu => Config::hsi(),
        };
        let mut rcc = device.RCC.freeze(config);
        let cost_hz = match environment {
            Environment::Silicon => {
                // Keep the debug port alive while the core sleeps in WFI, for RTT.
                device.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
                rcc.clocks.hclk().raw()
            }
            Environment::Qemu => QEMU_CPU_CLOCK_HZ,
        };
        let gpioa = device.GPIOA.split(&mut rcc);
        let Ok(uart) = Uart::init(device.USART1, gpioa.pa9, gpioa.pa10, &mut rcc) else {
            defmt::error!("USART1 rejected 115200 8N1 at the clocks set up");
            fatal()
        };
        defmt::info!(
            "STM32F405 on {}: core clock {=u32} Hz, cost counter {=u32} Hz",
            environment,
            rcc.clocks.hclk().raw(),
            cost_hz
        );
        Some(Board {
            uart,
            cost: CostCounter::init(core.SYST, cost_hz),
            flash: if cfg!(feature = "checkpoint") {
                Flash::open(environment, device.FLASH)
            } else {
                None
            },
        })
    }
}

/// After a panic or a fault has been logged: under QEMU end the run with exit status 1; on silicon
/// wait for the log to drain, then reset the chip.
pub fn fatal() -> ! {
    match environment() {
        Environment::Qemu => semihosting::process::exit(1),
        Environment::Silicon => {
            cortex_m::asm::delay(FATAL_DRAIN_CYCLES);
            cortex_m::peripheral::SCB::sys_reset()
        }
    }
}
