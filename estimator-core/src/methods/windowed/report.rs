//! What the windowed method reports: the estimate (the filter's, or the one held while the
//! first windows' bumps go on, [`super::start`]) and each error's 1-sigma.
//!
//! The filter's covariance `P` is the one for the configured noise; each pair's noise scale
//! `lambda` ([`super::pair::Pair::noise_scale`]) rescales it to the noise the residuals show.
//! The roll pair's share `C` of `P` is carried through every update with that update's gain, the
//! roll measurements' noise joining it ([`Windowed::carry_roll_share`]; the prior and the random
//! walk join neither pair's share), so the variance of error `i` is
//! `lambda_pitch (P_ii - C_ii) + lambda_roll C_ii`, within `[0, P_ii]` and at least the error's
//! own pair's scale times `P_ii` ([`Windowed::scaled_variance`]). While the ship turns and the
//! heel in turns is not yet learned, what it may have moved each error by is added
//! ([`Windowed::heel_to_consider`]). The residual check's widening,
//! the lag a drift leaves and the change detector's widening are added by
//! [`super::pair::Pair::refresh_report`]. A pair's report is refreshed once per update of the
//! pair, not every step: the other pair's is at most one update old.
//!
//! The derivation is in docs/method.md and docs/uncertainty.md.

use super::heel::{heel_learned, HEEL_PRIOR_SIGMA_RAD};
use super::pair::channels;
use super::{MethodEstimate, Windowed};
use crate::config::Config;
use crate::correlation::{HEEL_STATE, STATES};
use crate::kalman::{carry_sensitivity, carry_share};
use crate::math::Compare;
use crate::Real;

impl<const CAP: usize> Windowed<CAP> {
    /// The estimate to report now: the filter's, or, while the first windows' bumps go on, the
    /// one held at the end of the last bump (none before the first ends).
    pub(crate) fn estimate_now(&self) -> Option<MethodEstimate> {
        if !self.start.holds() {
            return self.live_estimate();
        }
        self.start.has_held().then_some(MethodEstimate {
            x_rad: [
                self.held_x_rad[0],
                self.held_x_rad[1],
                self.held_x_rad[2],
                self.held_x_rad[3],
            ],
            sigma_rad: self.reported_sigma_rad(),
            mismatch: false,
            relearning: false,
        })
    }

    /// The filter's estimate now (see [`Windowed::estimate`]).
    pub(super) fn live_estimate(&self) -> Option<MethodEstimate> {
        if self.updates == 0 {
            return None;
        }
        // Flag only with a full horizon of residuals: the first windows carry sway residuals of
        // tens of arcsec that the average has not yet taken down (their widening of the 1-sigma
        // stays: it is conservative).
        let horizon = self.residual_horizon();
        let mismatch = self.pairs.iter().any(|p| p.mismatch.iter().any(|m| *m))
            && self.pairs.iter().all(|p| p.stats.count >= horizon);
        let x = self.kf.state();
        Some(MethodEstimate {
            x_rad: [x[0], x[1], x[2], x[3]],
            sigma_rad: self.reported_sigma_rad(),
            mismatch,
            relearning: self.changed_entries > 0 || self.pairs.iter().any(|p| p.relearning),
        })
    }

    /// Each error's reported 1-sigma, rad, as its pair last refreshed it.
    pub(super) fn reported_sigma_rad(&self) -> [Real; 4] {
        let [p, r] = &self.pairs;
        [
            p.reported_sigma_rad[0],
            p.reported_sigma_rad[1],
            r.reported_sigma_rad[0],
            r.reported_sigma_rad[1],
        ]
    }

    /// At the end of one of the first windows' bumps ([`start`]), the estimate to hold until the
    /// next bump ends: the filter's now, with this pair's report, and the other pair's at its
    /// next update (a window of weight 0 too: the next bump's first), one report a step as
    /// always (not refreshed in between). At the first bump's end both pairs' reports are made:
    /// the other pair's is still its prior's, which says nothing of what the filter has taken.
    // Called once, on the step's path.
    #[inline(always)]
    pub(super) fn report_at_bump_end(&mut self, config: &Config, pair: usize, ends_bump: bool) {
        if ends_bump {
            let x = self.kf.state();
            self.held_x_rad = (*x).into();
            self.refresh_report(config, pair);
            if self.report.is_none() {
                self.refresh_report(config, 1 - pair.min(1));
            }
            self.held_report_due = self.start.holds();
        } else if core::mem::take(&mut self.held_report_due) {
            self.refresh_report(config, pair);
        }
    }

    /// Refreshes what is reported of the errors of `pair` (after its update, or after anything
    /// that changed the filter): [`Pair::refresh_report`] with the filter's variance of the pair's
    /// errors and the change detector's widening. Once per update of the pair, not every step:
    /// the other pair's report is at most one update old.
    pub(super) fn refresh_report(&mut self, config: &Config, pair: usize) {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let [a, b] = channels(pair);
        let widening = self.change.widening_rad();
        let k = if self.considering_heel {
            HEEL_PRIOR_SIGMA_RAD
        } else {
            0.0
        };
        let (sa, sb) = (self.heel_sensitivity[a] * k, self.heel_sensitivity[b] * k);
        let scaled = [
            self.scaled_variance(a) + sa * sa,
            self.scaled_variance(b) + sb * sb,
        ];
        self.pairs[pair].refresh_report(
            config,
            self.window.bin(),
            self.window.len(),
            scaled,
            [widening[a], widening[b]],
        );
    }

    /// The variance of error `i`, each pair's share of the filter's covariance rescaled by that
    /// pair's noise scale: `lambda_pitch (P_ii - C_ii) + lambda_roll C_ii`, `C` the roll pair's
    /// share ([`Windowed::roll_share`]), within `[0, P_ii]`; at least the error's own pair's scale
    /// times `P_ii`.
    pub(super) fn scaled_variance(&self, i: usize) -> Real {
        let i = i.min(STATES - 1);
        let p_ii = self.kf.covariance()[(i, i)].larger(0.0);
        let roll_share = self.roll_share[i][i].larger(0.0).smaller(p_ii);
        let (pitch, roll) = (self.pairs[0].noise_scale(), self.pairs[1].noise_scale());
        // Never below the error's own pair's scale times its variance: a roll pair quieter than
        // the pitch pair does not make x1, x2 surer than their own channels' noise says.
        let own = if i < 2 { pitch } else { roll };
        (pitch * (p_ii - roll_share) + roll * roll_share).larger(own * p_ii)
    }

    /// Whether the report considers the heel in turns: while the ship turns, the heel state is
    /// held at none and the turn channel's evidence of a heel is not yet in
    /// ([`Windowed::weigh_heel_evidence`]). Not once the heel is learned (the filter then carries
    /// it) or the evidence found none. Meanwhile the sensitivity `S` of the estimate to the heel
    /// is carried through every update ([`crate::kalman::carry_sensitivity`]; from 0 when the ship
    /// starts to turn: before, the rate of turn, and with it the heel's column, is next to
    /// nothing) and what the heel may have moved error `i` by, `S_i` times the heel's prior
    /// 1-sigma, is added to the error's variance. Taken once an update (and again after the
    /// evidence is weighed) into `considering_heel`, which the update's steps read.
    pub(super) fn heel_to_consider(&self) -> bool {
        self.turning
            && self.heel_evidence.1 < (self.window.len() as u32 / 2).max(1)
            && !heel_learned(self.kf.covariance()[(HEEL_STATE, HEEL_STATE)])
    }

    /// Carries the roll pair's share of the covariance through an update of row `h` applied with
    /// gain `gain`; `roll_r` is the measurement's variance when it is one of the roll pair's, 0
    /// when it is the pitch pair's ([`carry_share`]).
    // On the step's path, twice an update.
    #[inline(always)]
    pub(super) fn carry_roll_share(
        &mut self,
        h: &[Real; STATES],
        gain: &[Real; STATES],
        roll_r: Real,
    ) {
        carry_share(&mut self.roll_share, h, gain, roll_r.larger(0.0));
        if self.considering_heel {
            carry_sensitivity(&mut self.heel_sensitivity, h, gain);
        }
    }

    /// Forgets the roll pair's share on the states `which` (as the filter forgets them: their
    /// prior is no pair's).
    pub(super) fn forget_roll_share(&mut self, which: &[bool; STATES]) {
        for j in 0..STATES {
            if which[j] {
                for k in 0..STATES {
                    self.roll_share[j][k] = 0.0;
                    self.roll_share[k][j] = 0.0;
                }
                self.heel_sensitivity[j] = 0.0;
            }
        }
    }
}
