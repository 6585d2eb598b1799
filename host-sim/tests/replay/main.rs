//! The estimator on generated and recorded logs, through the library: accuracy, coverage,
//! checkpoints and the store on the host.
//!
//! One test program of modules, one per area, linked once; `cargo test --release -p host-sim --test
//! replay MODULE` runs one module.

mod beyond_paper;
mod binning_cost;
mod checkpoint_roundtrip;
mod coverage;
mod gap_logs;
mod jittered_stamps;
mod real_logs;
mod sea_day;
mod store_across_versions;
mod store_power_fail;
