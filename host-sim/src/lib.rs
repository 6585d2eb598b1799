//! host-sim: the std side of the project. Generates scenarios, replays logs through the same
//! `estimator-core` the firmware runs, and reports.
#![warn(missing_docs)]
pub mod binned_lines;
pub mod cli_args;
pub mod commission;
pub mod compare;
pub mod estimates_csv;
pub mod exit_status;
pub mod figures;
pub mod flash_life;
pub mod flash_model;
pub mod html_report;
pub mod log_csv;
pub mod monte_carlo;
pub mod output_file;
pub mod pipeline;
pub mod plots;
pub mod recorder;
pub mod replay;
pub mod report;
pub mod rotation_scheme;
pub mod scenario;
pub mod stream;
pub mod time_stamps;
pub mod timeline;
pub mod trial_report;
