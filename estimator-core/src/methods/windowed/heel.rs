//! The heel in turns: when the filter's fifth state starts to be learned, and the turn channel
//! that learns it.
//!
//! A ship heels outward in a turn, in proportion to its rate of turn; the roll channels see that
//! heel where the rate correlates with the rotation, and their rows carry it in the fifth column
//! ([`crate::correlation::HEEL_STATE`]; the derivation is in the module doc of
//! [`crate::correlation`], "Heel in turns", and in docs/method.md, "Our default", item 3).
//!
//! - Until the ship turns (its low-passed rate beyond [`TURN_EXCITATION`]) the state is held at
//!   [`HEEL_HELD_SIGMA_RAD`]: a rate that is only the rest of eq (2)'s heading oscillation is
//!   locked to the rotation and would trade the heel for x3, x4.
//! - Once it turns, the turn channel's measurement of the heel (x1..x4 taken at their estimates)
//!   is averaged over a period of the roll pair's updates; beyond [`HEEL_SIGNIFICANT_RAD`] the
//!   state takes its prior and x3, x4 are learned again with it
//!   (`Windowed::weigh_heel_evidence`). A ship that turns without heeling never gets the state.
//! - Once learned, the turn channel updates the heel alone (`Windowed::update_turn_channel`);
//!   the roll channels update it too once its variance is below [`HEEL_LEARNED_VARIANCE_RAD2`].

use super::Windowed;
use crate::correlation::{Measurement, HEEL_STATE, STATES};
use crate::Real;

/// The prior 1-sigma of the heel state ([`crate::correlation::HEEL_STATE`]), rad: a heel of 10 deg
/// per deg/s of turn rate.
pub const HEEL_PRIOR_SIGMA_RAD: Real = 0.01;

/// The low-passed rate of turn beyond which the ship turns enough for its heel in turns to be
/// learned, in units of
/// [`crate::correlation::TURN_RATE_UNIT_RAD_S`] (0.029 deg/s): far above what eq (2)'s heading
/// oscillation left in the heading gives (about 0.001 deg/s), far below a course change or an
/// autopilot's yawing.
pub const TURN_EXCITATION: Real = 0.5;

/// The 1-sigma x3 and x4 go back to when the heel in turns starts to be learned, rad (200
/// arcsec: a course weave's heel leaks into them by hundreds of arcsec).
pub const HEEL_FORGET_SIGMA_RAD: Real = 1.0e-3;

/// A heel at the unit rate of turn beyond which the first turn channel's measurement makes x3,
/// x4 be learned again, rad (1.5 s of heel per rad/s of turn; one window's measurement of no heel
/// at sea scatters by a few 1e-4).
pub const HEEL_SIGNIFICANT_RAD: Real = 1.0e-3;

/// The heel state's variance below which the correlation channels update it too, rad^2: a heel
/// known to 2e-5 rad (4 arcsec) at the unit rate of turn.
pub const HEEL_LEARNED_VARIANCE_RAD2: Real = 4.0e-10;

/// The heel state's 1-sigma while it is held at 0, rad: next to nothing (0.002 arcsec of roll at a
/// brisk turn), but not zero, so that the covariance stays positive definite.
pub const HEEL_HELD_SIGMA_RAD: Real = 1.0e-9;

/// Whether the heel state is being learned (its variance above the held one's).
pub(super) fn heel_learned(p: Real) -> bool {
    p > 4.0 * HEEL_HELD_SIGMA_RAD * HEEL_HELD_SIGMA_RAD
}

impl<const CAP: usize> Windowed<CAP> {
    /// The turn channel's update, with the roll pair once the heel in turns is learned: it
    /// learns the heel (see "Heel in turns" in the module doc of [`crate::correlation`]) and
    /// only it, x1..x4 taken as they are. Its products are roll times the rate of turn, whose
    /// mean square is the row's last term. Returns whether the filter took it.
    // Called once, on the step's path.
    #[inline(always)]
    pub(super) fn update_turn_channel(&mut self, m: &Measurement, r_full: Real) -> bool {
        let heel_variance = self.kf.covariance()[(HEEL_STATE, HEEL_STATE)];
        if !(m.turn_row[HEEL_STATE] > 0.0 && heel_learned(heel_variance)) {
            return false;
        }
        // The channel's terms in x1..x4 taken at their estimates, their uncertainty added to the
        // measurement's: a measurement of the heel alone, which moves the other states only
        // through their covariance with it.
        let x = self.kf.state();
        let p = self.kf.covariance();
        let mut z = m.turn_z;
        let mut r_turn = 2.0 * r_full * m.turn_row[HEEL_STATE];
        for j in 0..HEEL_STATE {
            z -= m.turn_row[j] * x[j];
            r_turn += m.turn_row[j] * m.turn_row[j] * p[(j, j)];
        }
        let mut h = [0.0; STATES];
        h[HEEL_STATE] = m.turn_row[HEEL_STATE];
        if let Ok(applied) = self.kf.update_with_gain(&h, z, r_turn) {
            self.carry_roll_share(&h, &applied.gain, r_turn);
            return true;
        }
        false
    }

    /// Whether the heel in turns is to be learned: the turn channel's measurement of it (x1..x4
    /// taken at their estimates), averaged over a period of the roll pair's updates, is beyond
    /// [`HEEL_SIGNIFICANT_RAD`]. Then it starts to be learned (its prior covariance), and x3 and
    /// x4, which the roll channels gave with the heel taken as none, are learned again with it
    /// ([`HEEL_FORGET_SIGMA_RAD`]): a course weave near the rotation's frequency leaks its heel
    /// into them by hundreds of arcsec. A ship that turns without heeling is never given the
    /// state: its estimate would only scatter the roll channels' residuals.
    #[cold]
    #[inline(never)]
    pub(super) fn weigh_heel_evidence(&mut self, m: &Measurement) {
        let x = self.kf.state();
        let mut z = m.turn_z;
        for j in 0..HEEL_STATE {
            z -= m.turn_row[j] * x[j];
        }
        let heel = z / m.turn_row[HEEL_STATE];
        let n = (self.window.len() as u32 / 2).max(1);
        self.heel_evidence.1 = self.heel_evidence.1.saturating_add(1).min(n);
        let alpha = 1.0 / self.heel_evidence.1 as Real;
        self.heel_evidence.0 += alpha * (heel - self.heel_evidence.0);
        if self.heel_evidence.1 < n || self.heel_evidence.0.abs() <= HEEL_SIGNIFICANT_RAD {
            return;
        }
        let mut which = [false; STATES];
        let mut sigma = [HEEL_FORGET_SIGMA_RAD; STATES];
        which[HEEL_STATE] = true;
        which[2] = true;
        which[3] = true;
        sigma[HEEL_STATE] = HEEL_PRIOR_SIGMA_RAD;
        self.kf.forget(&which, &sigma);
        self.forget_roll_share(&which);
        self.heel_sensitivity = [0.0; STATES];
    }
}
