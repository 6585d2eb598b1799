//! host-sim: the std side of the project. Generates scenarios, replays logs through the same
//! `estimator-core` the firmware runs, and reports.
pub mod cli_args;
pub mod compare;
pub mod estimates_csv;
pub mod figures;
pub mod flash_life;
pub mod flash_model;
pub mod log_csv;
pub mod monte_carlo;
pub mod pipeline;
pub mod plots;
pub mod recorder;
pub mod replay;
pub mod report;
pub mod rotation_scheme;
pub mod scenario;
pub mod stream;
