//! The three identification methods, behind one enum the estimator drives.
//!
//! Each method sees only samples that passed every check (finite, in range, in time order, rotation
//! healthy, gate open) and is told when the moving average must restart (a long gap, a rotation
//! fault). None of them does I/O or allocates.

pub(crate) mod checkpoint;
#[cfg(feature = "paper-method")]
pub mod paper;
pub mod traditional;
pub mod windowed;

use crate::config::{Config, Method};
use crate::estimator::Feed;
use crate::gap_fill::{FillVariance, GridSample};
use crate::output::Estimate;

#[cfg(feature = "paper-method")]
pub use paper::Paper;
pub use traditional::Traditional;
pub use windowed::change::Alarm;
pub use windowed::{MethodEstimate, Windowed};

/// The running state of whichever method the configuration selects.
#[derive(Clone, Debug, PartialEq)]
pub enum MethodState<const CAP: usize> {
    /// The windowed method's ([`Method::Windowed`]).
    Windowed(Windowed<CAP>),
    /// The paper's method's ([`Method::Paper`]).
    #[cfg(feature = "paper-method")]
    Paper(Paper<CAP>),
    /// The traditional baseline's ([`Method::Traditional`]).
    Traditional(Traditional),
}

impl<const CAP: usize> MethodState<CAP> {
    /// Fresh state for `config.method`.
    pub fn new(config: &Config) -> Self {
        match config.method {
            Method::Windowed => MethodState::Windowed(Windowed::new(config)),
            #[cfg(feature = "paper-method")]
            Method::Paper => MethodState::Paper(Paper::new(config)),
            // Not reached: `Config::check`, which every constructor runs first, refuses the paper
            // method in a build without it (`ConfigError::MethodUnavailable`).
            #[cfg(not(feature = "paper-method"))]
            Method::Paper => MethodState::Traditional(Traditional::new(config)),
            Method::Traditional => MethodState::Traditional(Traditional::new(config)),
        }
    }

    /// Back to the state of [`MethodState::new`], in place when the method stays the same (the
    /// windowed and paper states hold the one-period ring, which must not pass through the stack
    /// of a microcontroller); a change of method builds the new state by value.
    pub fn reset(&mut self, config: &Config) {
        match (self, config.method) {
            (MethodState::Windowed(m), Method::Windowed) => m.reset(config),
            #[cfg(feature = "paper-method")]
            (MethodState::Paper(m), Method::Paper) => m.reset(config),
            (MethodState::Traditional(m), Method::Traditional) => *m = Traditional::new(config),
            (state, _) => state.replace(config),
        }
    }

    /// A change of method: the new state is built by value (its ring on the stack). Out of line,
    /// so that only a change of method uses that stack, not every reset.
    #[cold]
    #[inline(never)]
    fn replace(&mut self, config: &Config) {
        *self = MethodState::new(config);
    }

    /// While the period is being learned: the windowed method bins its window as a period of
    /// `period_samples` would (the other methods do not bin).
    pub fn expect_period(&mut self, period_samples: u32) {
        if let MethodState::Windowed(m) = self {
            m.expect_period(period_samples);
        }
    }

    /// Sets the moving average to one period of the rotation pattern.
    pub fn configure(&mut self, period_samples: u32) {
        match self {
            MethodState::Windowed(m) => m.configure(period_samples),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => m.configure(period_samples),
            MethodState::Traditional(_) => {}
        }
    }

    /// Feeds one sample (received or filled) of weight `weight` ([`crate::gap_fill`]); returns how
    /// many old window entries it removed. The windowed method takes samples from the first row on
    /// (its window keeps them while the period is learned) and updates in
    /// [`MethodState::update`], once per step; the others take samples once the period is known
    /// (`period_known`) and update here, and leave the weights aside.
    pub fn push(
        &mut self,
        config: &Config,
        feed: &Feed,
        sample: &GridSample,
        weight: u8,
        period_known: bool,
    ) -> u32 {
        match self {
            MethodState::Windowed(m) => m.push(sample, feed.reference_alpha, feed.interval, weight),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => {
                if period_known {
                    m.step(config, feed.interval_s, sample);
                }
                0
            }
            MethodState::Traditional(m) => {
                if period_known {
                    m.step(config, feed.interval, sample);
                }
                0
            }
        }
    }

    /// The windowed method's one update per step (see [`Windowed::update`]); the others update
    /// in [`MethodState::push`]. Returns the change of the errors declared, if any (only the
    /// windowed method detects changes).
    pub fn update(
        &mut self,
        config: &Config,
        feed: &Feed,
        fill_variance: FillVariance,
    ) -> Option<Alarm> {
        match self {
            MethodState::Windowed(m) => m.update(config, feed.interval, fill_variance),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(_) => None,
            MethodState::Traditional(_) => None,
        }
    }

    /// Forgets the moving-average window (the filter keeps what it learnt).
    pub fn restart_window(&mut self) {
        match self {
            MethodState::Windowed(m) => m.restart_window(),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => m.restart_window(),
            MethodState::Traditional(_) => {}
        }
    }

    /// The rotation pattern was forgotten: the windowed method's window lets go of its period
    /// ([`crate::methods::Windowed::forget_period`]); the others restart their window when the
    /// fault is reported and take no sample until the period is known again.
    pub fn forget_period(&mut self) {
        if let MethodState::Windowed(m) = self {
            m.forget_period();
        }
    }

    /// Whether the method needs a full window of one period before it can update.
    pub fn needs_window(&self) -> bool {
        !matches!(self, MethodState::Traditional(_))
    }

    /// Entries the method's window holds when full (0 for a method without one).
    pub fn window_len(&self) -> usize {
        match self {
            MethodState::Windowed(m) => m.window().len(),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => m.window().len(),
            MethodState::Traditional(_) => 0,
        }
    }

    /// Whether the method's window has spanned a whole period since it started (always, for a
    /// method without one).
    pub fn window_full(&self) -> bool {
        match self {
            MethodState::Windowed(m) => m.window().has_spanned_a_period(),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => m.window().is_full(),
            MethodState::Traditional(_) => true,
        }
    }

    /// x1..x4, their 1-sigma and whether the model is inconsistent, in rad, once the filter has
    /// had a measurement. Only the windowed method checks its residuals; the others never report
    /// a mismatch.
    // On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
    #[inline]
    pub fn estimate(&self, config: &Config) -> Option<MethodEstimate> {
        let plain = |e: Estimate| MethodEstimate {
            x_rad: e.x_rad,
            sigma_rad: e.sigma_rad,
            mismatch: false,
            relearning: false,
        };
        let estimate = match self {
            MethodState::Windowed(m) => m.estimate(config),
            #[cfg(feature = "paper-method")]
            MethodState::Paper(m) => m.estimate().map(plain),
            MethodState::Traditional(m) => m.estimate().map(plain),
        };
        // Before the first measurement: the known values, if the configuration has them.
        estimate.or_else(|| {
            config.prior.map(|p| MethodEstimate {
                x_rad: p.x_rad,
                sigma_rad: p.sigma_rad,
                mismatch: false,
                relearning: false,
            })
        })
    }
}
