//! STM32F405 (Cortex-M4F, 1 MiB flash, 128 KiB SRAM + 64 KiB CCM) through stm32f4xx-hal 0.23.
//! One image runs on silicon and on QEMU's `netduinoplus2`; [`environment`] tells them apart at
//! run time, and everything QEMU does not model takes its QEMU path there:
//!
//! | part | silicon | QEMU netduinoplus2 |
//! |---|---|---|
//! | clocks | HSE crystal (`RINS_HSE_HZ`) and PLL at 168 MHz, the clock security system on; if the crystal has not started within 100 ms, HSI at 16 MHz instead, said in the log and the status | HSI 16 MHz (QEMU has no RCC model: the PLL and HSE never report ready) |
//! | link | USART1, PA9 TX / PA10 RX, 115200 8N1, receive and transmit by DMA (`serial.rs`) | the same USART1, receive by interrupt, blocking transmit |
//! | watchdog | IWDG, `firmware::watchdog::STM32F405_IWDG_TIMEOUT_MS` | none (QEMU does not model the IWDG) |
//! | reset cause | RCC_CSR's flags | power-on |
//! | brown-out | the option bytes' BOR level checked at boot (2.7 V wanted; docs/firmware.md) | not modelled |
//! | cost counter | SysTick at the core clock (a tick is a cycle) | SysTick at QEMU's CPU clock, [`QEMU_CPU_CLOCK_HZ`] |
//! | logs (defmt) | RTT, for a debug probe (`logger.rs`) | semihosting, QEMU's stdout |
//! | checkpoints | flash sectors 5-11 (`flash.rs`) | the host file `rins-flash.bin` (semihosting) |
//! | fatal error | reset (`SCB::sys_reset`) after the log has had time to drain | QEMU exits with status 1 |
//!
//! Nothing of this was run on silicon: the silicon column is written from the reference manual
//! (RM0090), the datasheet (DS8626) and stm32f4xx-hal; the QEMU column is what the tests run.
//! Interrupts are dispatched by number from cortex-m-rt's `DefaultHandler` (the PAC's vector
//! table is not linked in).

mod flash;
mod logger;
mod serial;

use core::sync::atomic::{AtomicU8, Ordering};

use cortex_m_rt::exception;
use firmware::reset_cause::ResetFlags;
use firmware::watchdog::{Watchdog, STM32F405_IWDG_TIMEOUT_MS as IWDG_TIMEOUT_MS};
use link_protocol::{ClockSource, ResetCause};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::watchdog::IndependentWatchdog;

pub use super::systick_cost::CostCounter;
pub use flash::Flash;
pub use serial::{Receiver, Transmitter};

// `HSE_HZ`: the crystal, `RINS_HSE_HZ` when the firmware was built (checked by build.rs).
include!(concat!(env!("OUT_DIR"), "/board_clock.rs"));

/// Core clock on silicon, Hz (the STM32F405's maximum).
const SYSCLK_HZ: u32 = 168_000_000;
/// The clock QEMU 7.2's netduinoplus2 gives its Cortex-M4 and so SysTick, whatever RCC is told:
/// under `-icount shift=0` one tick is 10^9 / 168e6 = 5.95 instructions.
pub const QEMU_CPU_CLOCK_HZ: u32 = 168_000_000;
/// How long the crystal may take to start before the firmware gives up on it, in polls of
/// [`HSE_POLL_CYCLES`] on HSI (16 MHz): 100 ms, ST's own HSE start-up timeout; a crystal starts in
/// about 2 ms (DS8626, HSE oscillator characteristics).
const HSE_STARTUP_POLLS: u32 = 1_600;
const HSE_POLL_CYCLES: u32 = 1_000;
/// USART1's interrupt number (RM0090 table 61).
const USART1_IRQ: i16 = 37;

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
    pub tx: Transmitter,
    pub rx: Receiver,
    pub cost: CostCounter,
    /// Non-volatile storage for checkpoints; `None` if it cannot be opened.
    pub flash: Option<Flash>,
    pub watchdog: BoardWatchdog,
    pub reset_cause: ResetCause,
    pub clock_source: ClockSource,
}

impl Board {
    /// Sets up the clocks, the watchdog, USART1 and its DMA, the cost counter and the checkpoint
    /// flash. Call once.
    pub fn init() -> Option<Board> {
        let environment = environment();
        let core = cortex_m::Peripherals::take()?;
        let device = pac::Peripherals::take()?;
        cortex_m::interrupt::disable();
        let reset_cause = match environment {
            Environment::Silicon => reset_cause(&device.RCC),
            Environment::Qemu => ResetCause::PowerOn,
        };
        let clock_source = match environment {
            Environment::Silicon if start_crystal(&device.RCC) => ClockSource::Crystal,
            Environment::Silicon => ClockSource::InternalFallback,
            Environment::Qemu => ClockSource::Fixed,
        };
        let config = match clock_source {
            ClockSource::Crystal => Config::hse(HSE_HZ.Hz()).sysclk(SYSCLK_HZ.Hz()),
            // HSI alone, 16 MHz, no PLL: the fewest parts that can fail (a step then takes
            // 168 / 16 times as long as at 168 MHz, still a small share of the 1 s sample period:
            // docs/firmware.md, "Watchdogs, reset cause, clocks, brown-out").
            ClockSource::InternalFallback | ClockSource::Fixed => Config::hsi(),
        };
        let mut rcc = device.RCC.freeze(config);
        let watchdog = start_watchdog(
            environment,
            clock_source,
            device.IWDG,
            &device.DBGMCU,
            &device.FLASH,
        );
        let cost_hz = match environment {
            Environment::Silicon => rcc.clocks.hclk().raw(),
            Environment::Qemu => QEMU_CPU_CLOCK_HZ,
        };
        let gpioa = device.GPIOA.split(&mut rcc);
        let (tx, rx) = match serial::init(
            environment,
            device.USART1,
            device.DMA2,
            gpioa.pa9,
            gpioa.pa10,
            &mut rcc,
        ) {
            Ok(Some(ends)) => ends,
            Ok(None) => return None,
            Err(_) => {
                defmt::error!("USART1 rejected 115200 8N1 at the clocks set up");
                fatal()
            }
        };
        // SAFETY: the handlers' state is in place.
        unsafe { cortex_m::interrupt::enable() };
        // A crystal that did not start shows here as `InternalFallback` (the internal RC
        // oscillator, 16 MHz, +-1 %), and in every status.
        defmt::info!(
            "STM32F405 on {}: core clock {=u32} Hz from {}, cost counter {=u32} Hz, reset cause {}",
            environment,
            rcc.clocks.hclk().raw(),
            clock_source,
            cost_hz,
            reset_cause
        );
        Some(Board {
            tx,
            rx,
            cost: CostCounter::init(core.SYST, cost_hz, environment == Environment::Silicon),
            flash: if cfg!(feature = "checkpoint") {
                Flash::open(environment, device.FLASH)
            } else {
                None
            },
            watchdog,
            reset_cause,
            clock_source,
        })
    }
}

/// On silicon: the clock security system armed when the crystal runs, the debug port kept alive
/// in WFI, the independent watchdog started (stopped while a debugger halts the core) and the
/// brown-out level checked. Under QEMU no watchdog runs.
fn start_watchdog(
    environment: Environment,
    clock_source: ClockSource,
    iwdg: pac::IWDG,
    dbgmcu: &pac::DBGMCU,
    flash: &pac::FLASH,
) -> BoardWatchdog {
    match environment {
        Environment::Silicon => {
            if clock_source == ClockSource::Crystal {
                // SAFETY: RCC_CR's CSSON: from now on a crystal failure raises the NMI
                // (below), and the hardware switches the core to HSI.
                unsafe { (*pac::RCC::ptr()).cr().modify(|_, w| w.csson().set_bit()) };
            }
            // Keep the debug port alive while the core sleeps in WFI, for RTT; stop the IWDG
            // while a debugger halts the core.
            dbgmcu.cr().modify(|_, w| w.dbg_sleep().set_bit());
            let mut iwdg = IndependentWatchdog::new(iwdg);
            iwdg.stop_on_debug(dbgmcu, true);
            iwdg.start(IWDG_TIMEOUT_MS.millis());
            check_brown_out_level(flash);
            BoardWatchdog { enabled: true }
        }
        Environment::Qemu => BoardWatchdog { enabled: false },
    }
}

/// Turns the crystal oscillator on and waits for it at most 100 ms; `false` (and the oscillator
/// off again) if it did not start. The HAL's own wait has no time limit: a dead crystal would hang
/// the board before `Ready`.
fn start_crystal(rcc: &pac::RCC) -> bool {
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    for _ in 0..HSE_STARTUP_POLLS {
        if rcc.cr().read().hserdy().bit_is_set() {
            return true;
        }
        cortex_m::asm::delay(HSE_POLL_CYCLES);
    }
    rcc.cr().modify(|_, w| w.hseon().clear_bit());
    false
}

/// Why the chip reset, from RCC_CSR's flags (RM0090 7.3.21), which are then cleared
/// (`firmware::reset_cause`, host-tested, orders them); a cause the firmware left itself (a clock
/// failure) comes first.
fn reset_cause(rcc: &pac::RCC) -> ResetCause {
    let csr = rcc.csr().read();
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    let flags = ResetFlags {
        watchdog: csr.wdgrstf().bit_is_set(),
        power_on: csr.porrstf().bit_is_set(),
        brown_out: csr.borrstf().bit_is_set(),
        software: csr.sftrstf().bit_is_set(),
        pin: csr.padrstf().bit_is_set(),
    };
    firmware::reset_cause::reset_cause(super::reset_mark::take(), flags)
}

/// The brown-out reset level in the option bytes (FLASH_OPTCR bits 3:2, RM0090 3.7.1: 00 is
/// level 3, 2.70 V; the PAC's names for these values do not follow the manual, so the bits are
/// read as they are). It is set once, when the board is flashed (docs/firmware.md): the firmware
/// never reprograms option bytes itself (a power cut during that could lock the chip), it only
/// says so when the level is not 2.7 V.
fn check_brown_out_level(flash: &pac::FLASH) {
    let level_bits = (flash.optcr().read().bits() >> 2) & 0b11;
    if level_bits != 0b00 {
        defmt::error!(
            "brown-out reset is not at 2.7 V (FLASH_OPTCR BOR_LEV = {=u32:#04b}, wanted 0b00): set the option bytes as docs/firmware.md says",
            level_bits
        );
    }
}

/// The IWDG (silicon) or nothing (QEMU, which does not model it).
#[derive(Clone, Copy)]
pub struct BoardWatchdog {
    enabled: bool,
}

impl Watchdog for BoardWatchdog {
    /// Reloads the IWDG's counter (key 0xAAAA, RM0090 21.4.1).
    fn feed(&self) {
        if self.enabled {
            // SAFETY: a write of the reload key; the IWDG was started by `Board::init`.
            unsafe { (*pac::IWDG::ptr()).kr().write(|w| w.key().bits(0xAAAA)) };
        }
    }
}

/// The NMI: on this chip, the clock security system saw the crystal fail (the hardware has
/// already switched the core to HSI, so the PLL-derived baud rate is wrong). Clears the flag,
/// leaves the cause for the next boot and resets: the next start tries the crystal again and
/// falls back to HSI if it is dead.
#[exception]
unsafe fn NonMaskableInt() {
    // SAFETY: RCC_CIR's CSSC clears the flag that raised this NMI.
    let rcc = unsafe { &*pac::RCC::ptr() };
    if rcc.cir().read().cssf().bit_is_set() {
        rcc.cir().write(|w| w.cssc().set_bit());
        super::reset_mark::set(ResetCause::ClockFailure);
        cortex_m::peripheral::SCB::sys_reset();
    }
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == USART1_IRQ {
        super::systick_cost::timed_interrupt(|| serial::usart1_interrupt(environment()));
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
