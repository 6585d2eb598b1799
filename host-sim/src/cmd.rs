//! The subcommands, one module each: its arguments (their doc comments are its `--help`) and the
//! function that runs it. The argument groups several subcommands share are in [`args`]; here,
//! what several do alike with what they print.

pub mod args;
pub mod commission;
pub mod compare;
pub mod estimate;
pub mod flash_life;
pub mod generate;
pub mod monte_carlo;
pub mod run;
pub mod stream;

use crate::formats::log_csv::{is_stdio, LogError};
use std::io::Write;
use std::path::Path;

/// Tells each unreadable row skipped (the first few) on standard error.
pub fn warn_row(e: &LogError) {
    eprintln!("warning: {e} (row skipped)");
}

/// Where a command's summary goes: standard output, or standard error when the estimates go to
/// standard output (`--out -`).
pub fn summary_writer(estimates: &Path) -> Box<dyn Write> {
    if is_stdio(estimates) {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout().lock())
    }
}
