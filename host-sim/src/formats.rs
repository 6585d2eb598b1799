//! What the tool reads and writes, formats in `docs/log-format.md`.
//!
//! - [`log_csv`]: the attitude log, read as it streams ([`read_ahead`]: on a thread of its own)
//!   and written losslessly;
//! - [`truth_file`]: the truth file beside a generated log;
//! - [`log_paths`]: a log's name in messages and the names of the files that go with it;
//! - [`time_stamps`]: the log's time column (seconds, milliseconds, ISO 8601) and whether its
//!   interval makes sense for a RINS;
//! - [`binned_lines`]: a log at the navigation rate averaged into bins as it is read;
//! - [`estimates_csv`]: the estimates CSV, one row per input row;
//! - [`corrected_csv`]: the corrected-attitude CSV of `stream --nav-rate`, one row per
//!   navigation-rate sample;
//! - [`output_file`]: every output written through a temporary file and renamed, and never one of
//!   the run's inputs.

pub mod binned_lines;
pub mod corrected_csv;
pub mod estimates_csv;
pub mod log_csv;
pub mod log_paths;
pub mod output_file;
pub mod read_ahead;
pub mod time_stamps;
pub mod truth_file;
