//! host-sim: the std side of the project. Generates scenarios, replays logs through the same
//! `estimator-core` the firmware runs, and reports.
pub mod scenario;
