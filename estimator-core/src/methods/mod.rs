//! The three identification methods, behind one enum the estimator drives.
//!
//! Each method sees only samples that passed every check (finite, in range, in time order, rotation
//! healthy, gate open) and is told when the moving average must restart (a long gap, a rotation
//! fault). None of them does I/O or allocates.

pub mod paper;
pub mod traditional;
pub mod windowed;

use crate::config::{Config, Method};
use crate::installation::Angles;
use crate::sample::Sample;
use crate::Real;

pub use paper::Paper;
pub use traditional::Traditional;
pub use windowed::Windowed;

/// The running state of whichever method the configuration selects.
#[derive(Clone, Debug, PartialEq)]
pub enum MethodState<const CAP: usize> {
    Windowed(Windowed<CAP>),
    Paper(Paper<CAP>),
    Traditional(Traditional),
}

impl<const CAP: usize> MethodState<CAP> {
    /// Fresh state for `config.method`.
    pub fn new(config: &Config) -> Self {
        match config.method {
            Method::Windowed => MethodState::Windowed(Windowed::new(config)),
            Method::Paper => MethodState::Paper(Paper::new(config)),
            Method::Traditional => MethodState::Traditional(Traditional::new(config)),
        }
    }

    /// Feeds one checked sample; true if the filter was updated.
    pub fn step(&mut self, config: &Config, sample: &Sample, angles: &Angles) -> bool {
        match self {
            MethodState::Windowed(m) => m.step(config, sample, angles),
            MethodState::Paper(m) => m.step(config, sample, angles),
            MethodState::Traditional(m) => m.step(config, sample, angles),
        }
    }

    /// Forgets the moving-average window (the filter keeps what it learnt).
    pub fn restart_window(&mut self) {
        match self {
            MethodState::Windowed(m) => m.restart_window(),
            MethodState::Paper(m) => m.restart_window(),
            MethodState::Traditional(_) => {}
        }
    }

    /// `(x, sigma, model mismatch)` of x1..x4 in rad, once the filter has had a measurement. Only
    /// the windowed method checks its residuals; the others never report a mismatch.
    pub fn estimate(&self, config: &Config) -> Option<([Real; 4], [Real; 4], bool)> {
        match self {
            MethodState::Windowed(m) => m.estimate(config),
            MethodState::Paper(m) => m.estimate().map(|(x, s)| (x, s, false)),
            MethodState::Traditional(m) => m.estimate().map(|(x, s)| (x, s, false)),
        }
    }
}
