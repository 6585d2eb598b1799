//! The cost counter of every Cortex-M board here: SysTick on the core clock, free-running over its
//! 24 bits. On silicon a tick is a core cycle. Under QEMU with `-icount shift=0` each instruction
//! takes 1 ns of virtual time, so a tick is exactly 10^9 / `hz` instructions (40 at mps2-an386's
//! 25 MHz). QEMU does not implement the DWT cycle counter (CYCCNT reads 0), so it is not used.
//!
//! On a board with a watchdog to feed, its wrap (every 2^24 ticks: 0.67 s at 25 MHz, 0.1 s at
//! 168 MHz) raises the SysTick exception, whose handler does nothing: it only wakes the main loop
//! from WFI, so that it feeds the watchdog while no byte arrives. (A wrap during a step adds the
//! exception's entry and exit to that step's measured cost: docs/firmware.md, "Measured
//! figures".) Without a
//! watchdog (the STM32F405 under QEMU) the wrap stays silent: a periodic interrupt only slows
//! QEMU's idle loop.
//!
//! **Interrupts are left out of a step's cost.** While samples are pushed, the link's receive and
//! transmit interrupts run in the middle of steps (under QEMU a whole frame's bytes can arrive
//! during one). Each board's interrupt dispatcher runs its handlers through [`timed_interrupt`],
//! which adds the ticks they take to a running total; [`CostCounter::ticks_since`] subtracts the
//! total's growth, so that a step's cost is the step's own work whether or not the link is busy
//! (the handlers' entry and exit stay in it: docs/firmware.md, "How each figure is measured").

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;

/// Ticks spent in interrupt handlers since start-up (wrapping).
static INTERRUPT_TICKS: AtomicU32 = AtomicU32::new(0);

/// Runs an interrupt handler's work and adds the ticks it takes to the interrupt total, so that
/// the step it interrupted is not charged for it. Handlers of one priority do not nest, so the
/// total is never counted twice.
#[inline(always)]
pub fn timed_interrupt(handler: impl FnOnce()) {
    let start = SYST::get_current();
    handler();
    let ticks = start.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF;
    INTERRUPT_TICKS.fetch_add(ticks, Ordering::Relaxed);
}

/// SysTick as a free-running 24-bit down-counter at `hz`.
pub struct CostCounter {
    _syst: SYST,
    hz: u32,
}

/// A reading of the [`CostCounter`]: SysTick and the interrupt total.
#[derive(Clone, Copy)]
pub struct CostStamp {
    systick: u32,
    interrupt_ticks: u32,
}

impl CostCounter {
    /// Starts SysTick; `hz` is the frequency it counts at (the core clock); `wake`: its wrap
    /// wakes the main loop (for a watchdog to be fed).
    pub fn init(mut syst: SYST, hz: u32, wake: bool) -> CostCounter {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        if wake {
            syst.enable_interrupt();
        }
        syst.enable_counter();
        CostCounter { _syst: syst, hz }
    }

    /// Frequency of the ticks, Hz.
    pub fn hz(&self) -> u32 {
        self.hz
    }

    /// Now.
    #[inline(always)]
    pub fn stamp(&self) -> CostStamp {
        CostStamp {
            interrupt_ticks: INTERRUPT_TICKS.load(Ordering::Relaxed),
            systick: SYST::get_current(),
        }
    }

    /// Ticks from `start` to now, less those spent in interrupt handlers meanwhile (correct for
    /// intervals below 2^24 ticks: 0.67 s at 25 MHz, 0.1 s at 168 MHz).
    #[inline(always)]
    pub fn ticks_since(&self, start: CostStamp) -> u32 {
        let elapsed = start.systick.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF;
        let interrupts = INTERRUPT_TICKS
            .load(Ordering::Relaxed)
            .wrapping_sub(start.interrupt_ticks);
        elapsed.saturating_sub(interrupts)
    }
}

/// The wrap: nothing to do but wake the main loop (see the module's doc).
#[exception]
fn SysTick() {}
