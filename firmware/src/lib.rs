//! The firmware's hardware-free parts: compiled into the firmware, and for the host too, where
//! their tests run (`cargo test -p firmware`) and `host-sim flash-life` drives the very same store
//! code on a model of each board's flash.
//!
//! - [`checkpoint_store`]: the estimator's checkpoints in a wear-levelled, power-fail-safe log on
//!   the board's flash (`sequential-storage`), and when to save one;
//! - [`flash_layout`]: each board's checkpoint flash: its sectors and the datasheet's timing;
//! - [`interrupt_ring`]: the receive ring an interrupt handler fills (mps2-an386; the STM32F405
//!   under QEMU);
//! - [`dma_ring`]: the reader of a circular DMA receive buffer, with overrun detection (the
//!   STM32F405 on silicon);
//! - [`rx_stats`]: the receive path's error counters, shared with interrupt handlers;
//! - [`request_receiver`]: bytes to numbered requests; [`sequence`]: lost requests from their
//!   numbers;
//! - [`watchdog`]: the watchdog as the loop sees it, and a flash that feeds it between erases;
//! - [`reset_cause`]: the last reset's cause from the chip's reset flags.
//!
//! `tests/receive_timeline.rs` runs the receive path against the STM32F405's timeline at 115200
//! baud, the flash stalls included.
#![warn(missing_docs)]
#![cfg_attr(not(test), no_std)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
#![cfg_attr(
    test,
    allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)
)]

#[cfg(test)]
extern crate std;

pub mod checkpoint_store;
pub mod dma_ring;
pub mod estimator_config;
pub mod flash_layout;
pub mod interrupt_ring;
pub mod request_receiver;
pub mod reset_cause;
pub mod rx_stats;
pub mod sequence;
pub mod watchdog;

/// Bytes of the STM32F405's circular DMA receive buffer. At one sample frame a second (at most
/// `link_protocol::MAX_SAMPLE_FRAME` = 43 bytes) half of it, the most that may arrive between two
/// looks of the reader (`dma_ring.rs`), holds 23 s of frames: 5 times the longest time the main
/// loop is away (a 128 KiB sector erase and a checkpoint's programming at the datasheet's maximum,
/// 4.26 s, plus a step and an answer; docs/firmware.md, the one-second budget).
/// `tests/receive_timeline.rs` checks it against that timeline.
pub const DMA_RX_BUFFER_BYTES: usize = 2048;

/// Entries of the interrupt-filled receive ring (`interrupt_ring.rs`; one entry a byte, 1023
/// usable): 23 frames, where the interrupt handler always runs (mps2-an386 and the STM32F405 under
/// QEMU, whose flash never stalls).
pub const INTERRUPT_RX_RING_ENTRIES: usize = 1024;

/// One item of the receive path: a byte, or the mark of a hole (bytes lost just before the next
/// byte: the receive buffer overflowed, or the UART overran).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Received {
    /// A byte received.
    Byte(u8),
    /// Bytes were lost just before the next one.
    Gap,
}
