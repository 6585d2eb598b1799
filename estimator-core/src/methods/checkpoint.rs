//! The method part of a checkpoint image: what a restart keeps of whichever method the header
//! names, zero-padded to the longest. Each method's fields and checks are next to it
//! (`windowed/checkpoint.rs`, `paper/checkpoint.rs`, `traditional/checkpoint.rs`); every
//! method's variances are bounded by `max(`[`MAX_VARIANCE`]`, 4 prior^2)`.

use super::{windowed, MethodState, Traditional};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{CheckpointError, Part, Stored, MAX_VARIANCE};
use crate::config::{Config, Method};
use crate::kalman::ConstantStateKalman;

/// Bytes of the paper method's part (kept in a build without the method, so that the image
/// length does not depend on the features; the fields are in `paper/checkpoint.rs`).
pub(crate) const PAPER_LEN: usize = 4 + 4 + 8 + 4 * 8 + 4 * ConstantStateKalman::<f64, 3>::LEN;

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// What a restart keeps of the running method.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum MethodPart {
    Windowed(windowed::checkpoint::Learned),
    #[cfg(feature = "paper-method")]
    Paper(super::paper::checkpoint::Learned),
    Traditional(Traditional),
}

impl MethodPart {
    /// Bytes the method writes before its padding.
    fn written_len(&self) -> usize {
        match self {
            MethodPart::Windowed(_) => windowed::checkpoint::Learned::LEN,
            #[cfg(feature = "paper-method")]
            MethodPart::Paper(_) => PAPER_LEN,
            MethodPart::Traditional(_) => Traditional::LEN,
        }
    }
}

impl<const CAP: usize> MethodState<CAP> {
    /// What a restart keeps of this method.
    pub(crate) fn learned(&self) -> MethodPart {
        match self {
            MethodState::Windowed(m) => MethodPart::Windowed(m.learned()),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => MethodPart::Paper(m.learned()),
            MethodState::Traditional(m) => MethodPart::Traditional(m.clone()),
        }
    }

    /// Takes over what a restart keeps, into a fresh state of the same method (at restore; a
    /// part of another method is ignored, which restore never passes).
    pub(crate) fn keep_learned(&mut self, part: MethodPart) {
        match (self, part) {
            (MethodState::Windowed(m), MethodPart::Windowed(l)) => m.keep_learned(l),
            #[cfg(feature = "paper-method")]
            (MethodState::Paper(m), MethodPart::Paper(l)) => m.keep_learned(l),
            (MethodState::Traditional(m), MethodPart::Traditional(t)) => *m = t,
            #[allow(unreachable_patterns)]
            _ => {}
        }
    }
}

/// Read for the configuration whose method the header names.
impl Stored for MethodPart {
    const LEN: usize = max(
        windowed::checkpoint::Learned::LEN,
        max(PAPER_LEN, Traditional::LEN),
    );
    type Context<'a> = &'a Config;

    fn write(&self, w: &mut Writer<'_>) {
        match self {
            MethodPart::Windowed(m) => m.write(w),
            #[cfg(feature = "paper-method")]
            MethodPart::Paper(m) => m.write(w),
            MethodPart::Traditional(m) => m.write(w),
        }
        // The padding: the image is zero-filled before it is written.
        w.skip(Self::LEN - self.written_len());
    }

    fn read(r: &mut Reader<'_>, config: &Config) -> Result<MethodPart, CheckpointError> {
        let prior = f64::from(config.prior_sigma_rad);
        let max_variance = MAX_VARIANCE.max(4.0 * prior * prior);
        let part = match config.method {
            Method::Windowed => {
                MethodPart::Windowed(windowed::checkpoint::Learned::read(r, max_variance)?)
            }
            #[cfg(feature = "paper-method")]
            Method::Paper => {
                MethodPart::Paper(super::paper::checkpoint::Learned::read(r, max_variance)?)
            }
            // Not reached: `Config::check` refused the configuration.
            #[cfg(not(feature = "paper-method"))]
            Method::Paper => {
                return Err(CheckpointError::InvalidConfig(
                    crate::config::ConfigError::MethodUnavailable,
                ))
            }
            Method::Traditional => MethodPart::Traditional(Traditional::read(r, max_variance)?),
        };
        let padding_start = r.pos();
        r.skip(Self::LEN - part.written_len());
        r.zeros_since(padding_start, Part::Padding)?;
        Ok(part)
    }
}
