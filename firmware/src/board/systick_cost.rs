//! The cost counter of every Cortex-M board here: SysTick on the core clock, free-running over its
//! 24 bits. On silicon a tick is a core cycle. Under QEMU with `-icount shift=0` each instruction
//! takes 1 ns of virtual time, so a tick is exactly 10^9 / `hz` instructions (40 at mps2-an386's
//! 25 MHz). QEMU does not implement the DWT cycle counter (CYCCNT reads 0), so it is not used.
//!
//! On a board with a watchdog to feed, its wrap (every 2^24 ticks: 0.67 s at 25 MHz, 0.1 s at
//! 168 MHz) raises the SysTick exception, whose handler does nothing: it only wakes the main loop
//! from WFI, so that it feeds the watchdog while no byte arrives. (A wrap during a step adds the
//! exception's entry and exit, about 20 instructions, to that step's measured cost.) Without a
//! watchdog (the STM32F405 under QEMU) the wrap stays silent: a periodic interrupt only slows
//! QEMU's idle loop.

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;

/// SysTick as a free-running 24-bit down-counter at `hz`.
pub struct CostCounter {
    _syst: SYST,
    hz: u32,
}

/// A reading of the [`CostCounter`].
#[derive(Clone, Copy)]
pub struct CostStamp(u32);

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
        CostStamp(SYST::get_current())
    }

    /// Ticks from `start` to now (correct for intervals below 2^24 ticks: 0.67 s at 25 MHz,
    /// 0.1 s at 168 MHz).
    #[inline(always)]
    pub fn ticks_since(&self, start: CostStamp) -> u32 {
        start.0.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF
    }
}

/// The wrap: nothing to do but wake the main loop (see the module's doc).
#[exception]
fn SysTick() {}
