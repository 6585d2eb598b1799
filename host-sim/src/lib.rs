//! host-sim: the std side of the project. Generates scenarios, replays logs through the same
//! `estimator-core` the firmware runs, and reports.
#![warn(missing_docs)]
pub mod cmd;
pub mod commission;
pub mod exit_status;
pub mod flash_model;
pub mod formats;
pub mod replay;
pub mod report;
pub mod sim;
pub mod stream;
pub mod study;
