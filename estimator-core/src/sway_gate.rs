//! The start gate on roll sway, as in the paper's sea test: nothing is estimated until the roll
//! sway amplitude exceeds `Config::sway_gate_rad`.

mod checkpoint;

use crate::math::sqrt;
use crate::Real;

/// Roll sway amplitude for the start gate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SwayMonitor {
    /// Exponential mean of roll.
    mean_rad: Real,
    /// Exponential mean of roll squared.
    mean_square_rad2: Real,
    /// Samples taken (saturating).
    samples: u32,
}

impl SwayMonitor {
    /// Nothing observed.
    pub const NEW: SwayMonitor = SwayMonitor {
        mean_rad: 0.0,
        mean_square_rad2: 0.0,
        samples: 0,
    };

    /// Samples in the exponential average (and before the gate may open).
    pub const SAMPLES: u32 = 64;

    /// Takes one roll sample.
    pub fn observe(&mut self, roll_rad: Real) {
        self.samples = self.samples.saturating_add(1);
        let alpha = 1.0 / (self.samples.min(Self::SAMPLES) as Real);
        self.mean_rad += alpha * (roll_rad - self.mean_rad);
        self.mean_square_rad2 += alpha * (roll_rad * roll_rad - self.mean_square_rad2);
    }

    /// Amplitude of a sinusoid with the same RMS about the mean.
    pub fn amplitude_rad(&self) -> Real {
        let var = (self.mean_square_rad2 - self.mean_rad * self.mean_rad).max(0.0);
        sqrt(2.0 * var)
    }

    /// Whether the gate of `gate_rad` opens now: a full average whose amplitude reaches it.
    pub fn opens(&self, gate_rad: Real) -> bool {
        self.samples >= Self::SAMPLES && self.amplitude_rad() >= gate_rad
    }
}
