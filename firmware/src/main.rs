//! RINS installation-error estimator firmware (Cortex-M4F).
//!
//! Thin layers, one file each, in the target-only module `app`:
//! - `board`: the hardware (UART as `embedded_io`, the cost counter, logging, fatal exit), one
//!   module per board, chosen by a cargo feature (`board-mps2-an386`, `board-stm32f405`);
//! - `link`: frames in and out (the codec itself is the `link-protocol` crate);
//! - `service`: request in, `estimator-core` step, response out, checkpoints when due;
//! - `stack`: stack painting for the high-water mark; `fault`: panic and hard-fault handlers.
//!
//! The checkpoint store itself is hardware-free and lives in the crate's library
//! (`firmware::checkpoint_store`, tested on the host).
//!
//! `app` wires them together, announces `Ready` on the link and runs the loop; this file only
//! selects it. The protocol is in docs/link-protocol.md.
//!
//! Built for any other target (as `cargo test --workspace` does on the host), the crate is an
//! empty program that says where it runs; nothing of the firmware is compiled.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

#[cfg(target_os = "none")]
mod app;

/// On the host: the firmware is not built; say how to build it.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("the firmware runs on thumbv7em-none-eabihf: cargo build -p firmware --target thumbv7em-none-eabihf --profile firmware");
    std::process::exit(2);
}
