//! The method part of a checkpoint image: the state of whichever method the header names,
//! zero-padded to the longest. Each method's layout and checks are next to it
//! (`windowed/checkpoint.rs`, `paper/checkpoint.rs`, `traditional/checkpoint.rs`); every
//! method's variances are bounded by `max(`[`MAX_VARIANCE`]`, 4 prior^2)`.

use super::{windowed, MethodState, Traditional, Windowed};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{CheckpointError, MAX_VARIANCE};
use crate::config::{Config, Method};
use crate::kalman::ConstantStateKalman;
use crate::moving_average::checkpoint::window_average_len;

/// Bytes of the paper method's state for a ring of `cap` entries (kept in a build without the
/// method, so that the image length does not depend on the features; the layout is in
/// `paper/checkpoint.rs`).
pub(crate) const fn paper_len(cap: usize) -> usize {
    4 + 4 + 8 + 4 * 8 + 4 * ConstantStateKalman::<f64, 3>::CHECKPOINT_LEN + window_average_len(4, cap)
}

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// Bytes of the method part for ring capacity `cap`: the longest of the three methods.
pub(crate) const fn max_len(cap: usize) -> usize {
    max(windowed::checkpoint::checkpoint_len(cap), max(paper_len(cap), Traditional::CHECKPOINT_LEN))
}

/// Bytes `method` actually writes (for the layout test).
#[cfg(test)]
pub(crate) const fn written_len(method: Method, cap: usize) -> usize {
    match method {
        Method::Windowed => windowed::checkpoint::checkpoint_len(cap),
        Method::Paper => paper_len(cap),
        Method::Traditional => Traditional::CHECKPOINT_LEN,
    }
}

impl<const CAP: usize> MethodState<CAP> {
    /// Writes the running method's state.
    pub(crate) fn write_checkpoint(&self, w: &mut Writer<'_>) {
        match self {
            MethodState::Windowed(m) => m.write_checkpoint(w),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => m.write_checkpoint(w),
            MethodState::Traditional(m) => m.write_checkpoint(w),
        }
    }

    /// Reads and checks the method part for `config` (whose method the header named) and the
    /// rotation period, if known. With `dst` (a state already reset to `config`'s method), also
    /// writes it there.
    pub(crate) fn read_checkpoint(
        r: &mut Reader<'_>,
        config: &Config,
        period_samples: Option<u32>,
        dst: Option<&mut Self>,
    ) -> Result<(), CheckpointError> {
        let prior = f64::from(config.prior_sigma_rad);
        let max_variance = MAX_VARIANCE.max(4.0 * prior * prior);
        match config.method {
            Method::Windowed => {
                let dst = match dst {
                    Some(MethodState::Windowed(m)) => Some(m),
                    _ => None,
                };
                Windowed::read_checkpoint(r, dst, period_samples, max_variance)
            }
            #[cfg(feature = "paper-method")]
            Method::Paper => {
                let dst = match dst {
                    Some(MethodState::Paper(m)) => Some(m),
                    _ => None,
                };
                super::Paper::read_checkpoint(r, dst, period_samples, max_variance)
            }
            // Not reached: `Config::check` refused the configuration.
            #[cfg(not(feature = "paper-method"))]
            Method::Paper => Err(CheckpointError::InvalidConfig(crate::config::ConfigError::MethodUnavailable)),
            Method::Traditional => {
                let dst = match dst {
                    Some(MethodState::Traditional(m)) => Some(m),
                    _ => None,
                };
                Traditional::read_checkpoint(r, dst, max_variance)
            }
        }
    }
}
