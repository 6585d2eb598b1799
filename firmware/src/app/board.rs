//! The board: everything that touches hardware. The rest of the firmware sees only:
//! - [`Board::init`], which returns the [`Board`]'s parts:
//!   - `tx`: the link's transmitter, as `embedded_io::Write` (0.6); `write` must never return
//!     `Ok(0)` for a non-empty buffer (wrap a HAL's transmitter in `link_protocol::BlockingWriter`
//!     if it can), and should not wait for the bytes to leave (interrupt or DMA);
//!   - `rx`: the link's [`Receiver`], which receives in the background (an interrupt handler or a
//!     DMA, never the main loop) into a buffer: `next()` (a byte or a gap, never blocking),
//!     `wait()` (sleep until something may have arrived; where a watchdog must be fed, it wakes
//!     at least every second) and
//!     `counters(lost_frames)`;
//!   - `cost`: a [`CostCounter`] that timestamps the estimator step (`stamp`, `ticks_since`, `hz`);
//!   - `flash`: an `embedded_storage` NOR flash of at least 2 checkpoint slots, if there is one;
//!   - `watchdog`: a `firmware::watchdog::Watchdog` (a copyable handle), already started;
//!   - `reset_cause` and `clock_source`, for the status;
//! - [`fatal`]: what to do after a panic or fault (report has been logged; exit or reset);
//! - the defmt global logger (linked in by the board module).
//!
//! One board per build, chosen by a cargo feature: `board-mps2-an386` (the default; QEMU only) or
//! `board-stm32f405` (silicon, and QEMU's netduinoplus2). Porting to another MCU: docs/firmware.md.

#[cfg(all(feature = "board-mps2-an386", feature = "board-stm32f405"))]
compile_error!(
    "two boards selected: build the STM32F405 image with `--no-default-features --features board-stm32f405`"
);
#[cfg(not(any(feature = "board-mps2-an386", feature = "board-stm32f405")))]
compile_error!("no board selected: enable `board-mps2-an386` (the default) or `board-stm32f405`");

mod interrupt_rx;
mod reset_mark;
mod semihosted_flash;
mod systick_cost;

#[cfg(feature = "board-mps2-an386")]
mod mps2_an386;
#[cfg(feature = "board-mps2-an386")]
pub use mps2_an386::{
    fatal, Board, BoardWatchdog, CostCounter, Flash as RawFlash, Receiver, Transmitter,
};

#[cfg(all(feature = "board-stm32f405", not(feature = "board-mps2-an386")))]
mod stm32f405;
#[cfg(all(feature = "board-stm32f405", not(feature = "board-mps2-an386")))]
pub use stm32f405::{
    fatal, Board, BoardWatchdog, CostCounter, Flash as RawFlash, Receiver, Transmitter,
};

/// The checkpoint flash as the store uses it: the board's, feeding the watchdog before each erase
/// block and each write.
pub type Flash = firmware::watchdog::FedFlash<RawFlash, BoardWatchdog>;
