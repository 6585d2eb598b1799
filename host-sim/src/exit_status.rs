//! Exit statuses a script can use, and errors told once.
//!
//! | status | meaning |
//! |---|---|
//! | 0 | done; for `estimate` and `stream`: an estimate was reached |
//! | 1 | failed (the reason on standard error): a file cannot be read or written, a log refused (bad header, `--strict`, time stamps that make no sense), an option out of range; no output is replaced |
//! | 2 | the command line cannot be parsed (clap's usage error) |
//! | 3 | no row of the log could be read (every row unreadable, or none); nothing written |
//! | 4 | rows were read but no estimate was reached by the end of the log (the reason on standard error); the estimates and the report are written; `commission`: its fits too close to tell (or none reached an estimate) |
//! | 5 | `commission`: a variant of the log's conventions fits better than the log as it is |
//!
//! The text of [`HELP`] goes into `--help`; `docs/log-format.md` has the same table.

use std::fmt::Write as _;

/// The exit statuses, for `--help`.
pub const HELP: &str = "Exit status:
  0  done; estimate and stream: an estimate was reached
  1  failed (reason on standard error); no output replaced
  2  the command line cannot be parsed
  3  no row of the log could be read; nothing written
  4  rows read but no estimate reached (reason on standard error); outputs written;
     commission: the fits too close to tell
  5  commission: a variant of the log's conventions fits better than the log as it is";

/// A run that ended without an estimate: not a failure of the tool, but a script must tell it
/// from a run with one.
#[derive(Debug, thiserror::Error)]
pub enum RunEnd {
    /// Not one row of the log could be read.
    #[error("{log}: no row of the log could be read{detail}")]
    NothingRead {
        /// The log's name in messages: its path, or `standard input`.
        log: String,
        /// The unreadable rows and the first of them, or that there were no rows, in parentheses
        /// after a space.
        detail: String,
    },
    /// Rows were read, but the estimator reached no estimate.
    #[error("no estimate: {reason}")]
    NoEstimate {
        /// What held the estimate back.
        reason: String,
    },
    /// `commission`: the log's fits cannot tell its conventions (too close, or no fit).
    #[error("conventions undecided: {reason}")]
    Undecided {
        /// Why the fits cannot tell.
        reason: String,
    },
    /// `commission`: a variant of the log's conventions fits better than the log as it is.
    #[error("a variant of the log's conventions fits better than the log as it is: {variants}")]
    VariantFitsBetter {
        /// The names of the variants that fit better, joined by `or`.
        variants: String,
    },
}

impl RunEnd {
    /// The end of a log none of whose rows could be read: `skipped` unreadable rows, the first of
    /// them (`FILE:LINE: why`) if any.
    pub fn nothing_read(log: &str, skipped: u64, first: Option<&impl std::fmt::Display>) -> RunEnd {
        let detail = match first {
            Some(e) => format!(" ({skipped} unreadable rows; the first: {e})"),
            None => " (no rows after the header)".to_string(),
        };
        RunEnd::NothingRead {
            log: log.to_string(),
            detail,
        }
    }

    /// The exit status of this end: 3, 4 or 5 (see the module doc).
    pub fn status(&self) -> i32 {
        match self {
            RunEnd::NothingRead { .. } => 3,
            RunEnd::NoEstimate { .. } | RunEnd::Undecided { .. } => 4,
            RunEnd::VariantFitsBetter { .. } => 5,
        }
    }
}

/// The exit status of a failed run (see the module doc).
pub fn status_of(error: &anyhow::Error) -> i32 {
    error.downcast_ref::<RunEnd>().map_or(1, RunEnd::status)
}

/// An error as one line, each cause in the chain added only when it says something the line does
/// not already say (a wrapper whose message repeats its source's is told once).
pub fn message(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if line.is_empty() {
            line = text;
        } else {
            let _ = write!(line, ": {text}");
        }
    }
    line
}

/// What is printed on standard error for a failed run, and its exit status.
pub fn report(error: &anyhow::Error) -> (String, i32) {
    let text = message(error);
    match error.downcast_ref::<RunEnd>() {
        // Not an error: the outputs are written; the reason is told as it is.
        Some(
            end @ (RunEnd::NoEstimate { .. }
            | RunEnd::Undecided { .. }
            | RunEnd::VariantFitsBetter { .. }),
        ) => (text, end.status()),
        Some(end) => (format!("error: {text}"), end.status()),
        None => (format!("error: {text}"), 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("{0}")]
    struct Repeats(#[source] std::io::Error);

    #[test]
    fn a_cause_that_repeats_its_wrapper_is_told_once() {
        let io = std::io::Error::other("t.csv:3: roll_deg: not a number");
        let e = anyhow::Error::new(Repeats(io));
        assert_eq!(message(&e), "t.csv:3: roll_deg: not a number");
        let with_context =
            anyhow::Error::new(std::io::Error::other("disk full")).context("e.csv:0: cannot write");
        assert_eq!(message(&with_context), "e.csv:0: cannot write: disk full");
    }

    #[test]
    fn statuses_tell_the_ends_apart() {
        let nothing = anyhow::Error::new(RunEnd::nothing_read(
            "t.csv",
            2,
            Some(&"t.csv:2: time_s: not a number"),
        ));
        let none = anyhow::Error::new(RunEnd::NoEstimate {
            reason: "rotation period not yet detected".into(),
        });
        let failed = anyhow::anyhow!("t.csv:0: cannot open");
        assert_eq!(report(&nothing), ("error: t.csv: no row of the log could be read (2 unreadable rows; the first: t.csv:2: time_s: not a number)".into(), 3));
        assert_eq!(
            report(&none),
            ("no estimate: rotation period not yet detected".into(), 4)
        );
        assert_eq!(report(&failed), ("error: t.csv:0: cannot open".into(), 1));
        assert_eq!(status_of(&none), 4);
    }
}
