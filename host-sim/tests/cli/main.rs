//! The command-line tool through its binary: every subcommand, its inputs, outputs, reports and
//! errors.
//!
//! One test program of modules, one per area, linked once; `cargo test --release -p host-sim --test
//! cli MODULE` runs one module.

mod cli_binning;
mod cli_commission;
mod cli_error_exits;
mod cli_errors;
mod cli_flash_life;
mod cli_generate;
mod cli_inputs;
mod cli_interface;
mod cli_outputs;
mod cli_report;
mod cli_restart;
mod cli_scenarios;
mod cli_scheme_tables;
mod cli_time_stamps;
mod common;
mod error_changes;
