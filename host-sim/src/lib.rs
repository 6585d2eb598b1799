//! host-sim: the std side of the project. Generates scenarios, replays logs through the same
//! `estimator-core` the firmware runs, and reports.
pub mod cli_args;
pub mod estimates_csv;
pub mod log_csv;
pub mod replay;
pub mod scenario;
pub mod stream;
