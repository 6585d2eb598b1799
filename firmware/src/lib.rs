//! The firmware's hardware-free parts: compiled into the firmware, and for the host too, where
//! their tests run and `host-sim flash-life` drives the very same store code on a model of each
//! board's flash.
//!
//! - [`checkpoint_store`]: the estimator's checkpoints in a wear-levelled, power-fail-safe log on
//!   the board's flash (`sequential-storage`), and when to save one;
//! - [`flash_layout`]: each board's checkpoint flash: its sectors and the datasheet's timing.
#![no_std]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing, clippy::panic)]

pub mod checkpoint_store;
pub mod flash_layout;
