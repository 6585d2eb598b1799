//! Holding the roll pair while a turn passes through the window.
//!
//! A discrete turn's heel is a step of the roll's mean in and a step out, not in proportion to the
//! rate of turn that the heel state ([`crate::correlation::HEEL_STATE`]) models; inside the window
//! the centred correlation (eq 8) does not cancel it, and it pulls x3, x4 for as long as the window
//! holds the turn. So a turn the model does not explain is held: the roll pair takes no
//! measurement from a window that holds it (docs/method.md, "Turns held").
//!
//! # When a window holds a turn
//! While the ship turns within the window (the variance of its low-passed rate of turn over the
//! window beyond [`super::heel::TURN_EXCITATION`] squared; a yaw sway leaves far less), a roll update
//! counts towards a hold when
//! - a roll channel's innovation lies beyond [`ROLL_HOLD_SIGMAS`] times that channel's learned
//!   spread (the residual spread of [`super::pair`]), or
//! - the turn channel's innovation (its measurement less its row times the estimate, the heel
//!   state included) lies beyond [`TURN_HOLD_SIGMAS`] times its RMS over the updates that were not
//!   held (a steady weave, with or without a heel the heel state explains, sets that RMS; a turn
//!   that heels the ship more than the weave does stands out within seconds of its start; a turn
//!   sailed while a weave cancels its rate shows on the roll channels only).
//!
//! [`TURN_HOLD_RUN`] such updates in a row start a hold. Consecutive windows share all but one
//! entry, so a turn keeps the innovations out for as long as it is in the window, hundreds of
//! updates, while the windows of lost rows or of a rough sea leave a few in a row.
//!
//! A hold lasts until the newest entry at that moment has left the window and
//! an eighth of a period more (the reference's low-pass and the heel's die-away), renewed while the
//! run goes on. When a hold starts, the filter and its residual statistics go back to the
//! copy kept at the end of the roll pair's last clean block (as when the change detector starts to
//! hold): the windows of the turn's first seconds, taken before it showed, are undone. The turn
//! channel's RMS needs a period of the roll pair's updates before it holds anything; a heading that
//! only sways (a lab log, a turntable, the paper's scenario) never holds.
//!
//! The RMS is not kept by a checkpoint (after a restore it is learned again over a period of
//! updates, the roll channels' spreads holding meanwhile), nor is a hold (the window restarts).

use super::heel::TURN_EXCITATION;
use super::pair::channels;
use super::Windowed;
use crate::correlation::{Measurement, HEEL_STATE, ROLL_PAIR, STATES};
use crate::math::Compare;
use crate::Real;

/// How far beyond its RMS the turn channel's innovation counts towards a hold.
pub const TURN_HOLD_SIGMAS: Real = 3.0;

/// How far beyond its learned spread a roll channel's innovation counts towards a hold while the
/// ship's heading changes.
pub const ROLL_HOLD_SIGMAS: Real = 4.0;

/// Consecutive roll updates with an innovation beyond its bound that start a hold: a turn keeps
/// them beyond it for as long as it is in the window (hundreds of updates), while lost rows or a
/// rough sea leave a few in a row at most.
pub const TURN_HOLD_RUN: u32 = 10;

/// The turn hold: the turn channel's learned RMS and the entry up to which the roll pair waits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnHold {
    /// Mean square of the turn channel's innovation over the roll pair's updates not held, rad^2.
    spread_rad2: Real,
    /// Updates in it, saturating at a window's entries.
    count: u32,
    /// The entry number from which the roll pair takes windows again (none: not holding).
    until: Option<u32>,
    /// Consecutive roll updates with an innovation beyond its bound.
    run: u32,
}

/// What [`TurnHold::test`] decided for one roll update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TurnVerdict {
    /// The update is held.
    pub held: bool,
    /// The hold starts with this update (the filter goes back to its clean copy).
    pub started: bool,
}

impl TurnHold {
    /// Nothing learned, not holding.
    pub const NEW: TurnHold = TurnHold {
        spread_rad2: 0.0,
        count: 0,
        until: None,
        run: 0,
    };

    /// How far a hold reaches beyond the entry that trips it, entries.
    fn span(len: u32) -> u32 {
        len + len / 8
    }

    /// Whether the window whose newest entry is `newest` (`len` entries in a full window) is
    /// still held. Entry numbers grow by one an entry, so a hold ends at most [`TurnHold::span`]
    /// entries ahead; one further ahead (the grid's numbering went back) has ended too.
    fn holds(&self, newest: u32, len: u32) -> bool {
        self.until.is_some_and(|until| {
            let ahead = until.wrapping_sub(newest);
            ahead > 0 && ahead <= Self::span(len)
        })
    }

    /// Tests the roll pair's update of the window whose newest entry is `newest` (`len` entries
    /// in a full window): `turn_innovation_rad` the turn channel's innovation, `roll_beyond`
    /// whether a roll channel's innovation is beyond [`ROLL_HOLD_SIGMAS`] of its spread. Called
    /// only while the ship's heading changes.
    pub fn test(
        &mut self,
        turn_innovation_rad: Real,
        roll_beyond: bool,
        newest: u32,
        len: u32,
    ) -> TurnVerdict {
        let was = self.holds(newest, len);
        let e2 = turn_innovation_rad * turn_innovation_rad;
        let learned = self.count >= (len / 2).max(1);
        let bound = TURN_HOLD_SIGMAS * TURN_HOLD_SIGMAS * self.spread_rad2;
        let out = roll_beyond || (learned && e2 > bound);
        self.run = if out { self.run.saturating_add(1) } else { 0 };
        if self.run >= TURN_HOLD_RUN {
            self.until = Some(newest.wrapping_add(Self::span(len)));
        }
        let held = self.holds(newest, len);
        if !held {
            self.until = None;
            self.count = self.count.saturating_add(1).min(len.max(1));
            // Clipped as the roll channels' spreads are: a turn's first updates, before the run
            // is long enough to hold them, do not inflate it.
            let e2 = if learned { e2.smaller(bound) } else { e2 };
            self.spread_rad2 += (e2 - self.spread_rad2) / self.count as Real;
        }
        TurnVerdict {
            held,
            started: held && !was,
        }
    }

    /// The window restarted: a hold ends (the RMS stays learned).
    pub fn end(&mut self) {
        self.until = None;
        self.run = 0;
    }
}

impl<const CAP: usize> Windowed<CAP> {
    /// The turn hold's verdict on the roll pair's update of window `m` (see the module doc); none
    /// unless the ship turns within the window (the variance of its low-passed rate of turn over
    /// the window, the turn row's last term, beyond [`TURN_EXCITATION`] squared: the reference's
    /// low-pass leaves next to nothing of a yaw sway's rate, while a course weave or a turn moves
    /// the rate by far more). `spread_known`: the roll channels' spreads are learned (as for the
    /// innovation gate).
    pub(super) fn test_turn(&mut self, m: &Measurement, spread_known: bool) -> TurnVerdict {
        if !(m.turn_row[HEEL_STATE] > TURN_EXCITATION * TURN_EXCITATION) {
            return TurnVerdict::default();
        }
        let x = self.kf.state().as_slice();
        let innovation =
            |row: &[Real; STATES], z: Real| row.iter().zip(x).fold(z, |e, (h, xj)| e - h * xj);
        let mut roll_beyond = false;
        if spread_known {
            let [a, b] = channels(ROLL_PAIR);
            for (k, ch) in [a, b].into_iter().enumerate() {
                let e = innovation(&m.rows[ch], m.z[ch]);
                let bound =
                    ROLL_HOLD_SIGMAS * ROLL_HOLD_SIGMAS * self.pairs[ROLL_PAIR].spread_rad2[k];
                roll_beyond |= e * e > bound;
            }
        }
        let turn = innovation(&m.turn_row, m.turn_z);
        self.turn_hold.test(
            turn,
            roll_beyond,
            self.window.newest_number(),
            self.window.len() as u32,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LEN: u32 = 480;

    /// A steady turn innovation of RMS 1 for `n` roll updates from entry `first` (the roll pair
    /// takes every other window), none held; returns the next entry.
    fn steady(h: &mut TurnHold, first: u32, n: u32) -> u32 {
        let mut e = first;
        for k in 0..n {
            let v = if k % 2 == 0 { 1.0 } else { -1.0 };
            assert!(
                !h.test(v, false, e, LEN).held,
                "held a steady update at {e}"
            );
            e += 2;
        }
        e
    }

    #[test]
    fn a_turn_is_held_from_its_run_until_it_has_left_the_window() {
        let mut h = TurnHold::NEW;
        let mut entry = steady(&mut h, 0, LEN);
        // The turn: 90 updates far out, then back to the weave's level while its entries are
        // still in the window.
        let (mut starts, mut first_held, mut last_held, mut last_out) = (0, None, 0, 0);
        for k in 0..400 {
            let innovation = if k < 90 { 20.0 } else { 1.0 };
            let v = h.test(innovation, false, entry, LEN);
            starts += u32::from(v.started);
            if v.held {
                first_held.get_or_insert(k);
                last_held = entry;
            }
            if k < 90 {
                last_out = entry;
            }
            entry += 2;
        }
        assert_eq!(starts, 1);
        assert_eq!(first_held, Some(TURN_HOLD_RUN - 1));
        // Held until the last update out has left the window and an eighth of a period more.
        let end = last_out + LEN + LEN / 8;
        assert!(last_held < end && last_held + 2 >= end, "{last_held} {end}");
    }

    #[test]
    fn a_few_updates_out_in_a_row_hold_nothing() {
        let mut h = TurnHold::NEW;
        let mut entry = steady(&mut h, 0, LEN);
        for _ in 0..TURN_HOLD_RUN - 1 {
            assert!(!h.test(20.0, true, entry, LEN).held);
            entry += 2;
        }
        let entry = steady(&mut h, entry, 10);
        for _ in 0..TURN_HOLD_RUN - 1 {
            assert!(!h.test(0.0, true, entry, LEN).held);
        }
        assert!(h.test(0.0, true, entry, LEN).held);
    }

    #[test]
    fn the_turn_channel_holds_nothing_before_its_rms_is_learned() {
        let mut h = TurnHold::NEW;
        for k in 0..LEN / 2 - 1 {
            assert!(
                !h.test(if k < 20 { 1.0 } else { 1.0e3 }, false, 2 * k, LEN)
                    .held
            );
        }
    }

    #[test]
    fn a_restart_of_the_window_ends_the_hold() {
        let mut h = TurnHold::NEW;
        for k in 0..TURN_HOLD_RUN {
            h.test(0.0, true, 1000 + 2 * k, LEN);
        }
        assert!(h.test(0.0, false, 1020, LEN).held);
        h.end();
        assert!(!h.test(0.0, false, 1022, LEN).held);
    }
}
