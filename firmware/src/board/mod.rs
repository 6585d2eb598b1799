//! The board: everything that touches hardware. The rest of the firmware sees only:
//! - [`Board::init`], which returns the [`Board`]'s parts:
//!   - `uart`: the link's serial port, as `embedded_io::{Read, Write}` (0.6); `write` must never
//!     return `Ok(0)` for a non-empty buffer (wrap a HAL's transmitter in
//!     `link_protocol::BlockingWriter` if it can);
//!   - `cost`: a [`CostCounter`] that timestamps the estimator step (`stamp`, `ticks_since`, `hz`);
//!   - `flash`: an `embedded_storage` NOR flash of at least 2 checkpoint slots, if there is one;
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

mod semihosted_flash;
mod systick_cost;

#[cfg(feature = "board-mps2-an386")]
mod mps2_an386;
#[cfg(feature = "board-mps2-an386")]
pub use mps2_an386::{fatal, Board, CostCounter, Flash};

#[cfg(all(feature = "board-stm32f405", not(feature = "board-mps2-an386")))]
mod stm32f405;
#[cfg(all(feature = "board-stm32f405", not(feature = "board-mps2-an386")))]
pub use stm32f405::{fatal, Board, CostCounter, Flash};
