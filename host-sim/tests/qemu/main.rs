//! The firmware in QEMU, end to end: both boards, the link, checkpoints, restarts, faults and
//! budgets.
//!
//! One test program of modules, one per area, linked once; `cargo test --release -p host-sim --test
//! qemu MODULE` runs one module.

mod qemu_budgets;
mod qemu_checkpoint_interval;
mod qemu_configured;
mod qemu_e2e;
mod qemu_faults;
mod qemu_nav_rate;
mod qemu_port;
mod qemu_power_cut;
mod qemu_report;
mod qemu_restart;
mod qemu_software_update;
mod qemu_stale_state;
mod qemu_stream_nav_rate;
mod qemu_support;
mod qemu_watchdog;
