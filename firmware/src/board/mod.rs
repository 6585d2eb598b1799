//! The board: everything that touches hardware. The rest of the firmware sees only:
//! - [`Board::init`], which returns the [`Board`]'s parts:
//!   - `uart`: the link's serial port, as `embedded_io::{Read, Write}`;
//!   - `cost`: a [`CostCounter`] that timestamps the estimator step;
//!   - `flash`: an `embedded_storage` NOR flash of at least 2 checkpoint slots, if there is one;
//! - [`fatal`]: what to do after a panic or fault (report has been logged; exit or reset);
//! - the defmt global logger (linked in by the board module).
//!
//! Porting to another board: write a module like `mps2_an386.rs` with the same items, select it
//! below, and put the board's memory map in the repository's `memory.x`.

mod mps2_an386;
pub use mps2_an386::{fatal, Board, CostCounter, Flash};
