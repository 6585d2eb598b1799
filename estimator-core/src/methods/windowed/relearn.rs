//! What the windowed method does with the change detector ([`super::change`]): it passes each
//! pair's residuals to it, keeps the clean copy of the filter that a hold goes back to, and
//! learns the errors that changed again from one block of residuals.
//!
//! - **Clean copy** ([`super::CleanState`]): the filter, the roll pair's share of its covariance and each
//!   pair's residual statistics, kept at the end of every roll block that did not hold the filter.
//!   A hold (a block in a run and significant, or a turn the heel state does not explain) goes back
//!   to it, so that neither a change nor a passing disturbance pulls at the filter.
//! - **Learning again**: when a change is declared the filter goes back to the clean copy, the
//!   errors that changed take the prior's covariance
//!   ([`crate::kalman::ConstantStateKalman::forget`]), and x3, x4 go with any change of x1, x2
//!   (through the leakage a change of x1 or x2 can cancel one of x3 or x4 on their channels). Each
//!   pair then applies one block of residuals against the held estimate as one measurement per
//!   channel, of the learned block variance over the pair's noise scale: in the filter's units the
//!   gain is then `lambda P h / (lambda h' P h + s^2)`, what the errors' covariance and the block's
//!   variance call for.
//! - **The noise learned again**: the residual check starts afresh, the noise scale is 1 and the
//!   random walk the configured one until a full horizon is averaged again; the long averages
//!   then go on from what they learned before, with the weight of one horizon (the data's noise
//!   did not change with the errors).
//!
//! The derivation is in docs/method.md, "Changes of the errors: what the filter does".

use super::change::{self, persistence_blocks, Alarm, BlockContext};
use super::pair::channels;
use super::{prior_sigma_rad, Windowed};
use crate::config::Config;
use crate::correlation::{ROLL_PAIR, STATES};
use crate::Real;

impl<const CAP: usize> Windowed<CAP> {
    /// Passes the pair's residuals to the change detector; when it declares a change, the errors
    /// that changed are learned again (see the module doc). Returns the change declared, if any,
    /// and whether a block ended (and was tested).
    // Called once, on the step's path.
    #[inline(always)]
    pub(super) fn detect_change(
        &mut self,
        config: &Config,
        pair: usize,
        residual: [Real; 2],
        rows: &[[Real; STATES]; 4],
        entry_s: Real,
    ) -> (Option<Alarm>, bool) {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let holding = self.change.holding();
        self.pairs[pair].block_held &= holding;
        // A block's updates of a pair: half its entries.
        let block_entries = change::block_entries(self.window.len() as u32, entry_s);
        let Some(block) = self
            .change
            .accumulate(pair, residual, (block_entries / 2).max(1))
        else {
            return (None, false);
        };
        // Kept for learning the errors again, should a change be declared while the filter holds.
        let p = &mut self.pairs[pair];
        p.last_block.held = p.block_held;
        if p.block_held {
            let [a, b] = channels(pair);
            p.last_block.rad = block;
            p.last_block.rows = [rows[a], rows[b]];
        }
        p.block_held = true;
        let len = self.window.len() as u32;
        let horizon = self.residual_horizon().max(1);
        let ctx = BlockContext {
            persistence_blocks: persistence_blocks(len, block_entries, entry_s),
            floor_rad2: self.block_floor_rad2(pair, block_entries),
            step_rad: config.change_detection_step_rad,
            settled: self.pairs[pair].stats.count >= horizon,
            armed: self.pairs.iter().all(|p| p.stats.count >= horizon),
            max_widening_rad: config.prior_sigma_rad,
            blocks_per_half_period: change::blocks_per_half_period(len, block_entries),
        };
        let was_holding = self.change.holding();
        let alarm = self.change.test(pair, block, self.pairs[pair].gains, &ctx);
        // Kept at the next update: this one has the block's work already.
        self.clean_state_due |= alarm.is_none() && pair == 1 && !self.change.holding();
        if self.change.holding() && !was_holding {
            // The block that started the hold was taken: back to before it. Each pair's report
            // follows at its next update without a block's test (the other pair's block ends at
            // its next update, so some three windows on): a step that tests a block refreshes no
            // report, so the hold's first step stays within the step's budget.
            self.restore_clean_state();
        }
        let Some(mut alarm) = alarm else {
            return (None, true);
        };
        // The roll channels carry the leakage of x1 and x2: a change of those can hide a change
        // of x3 or x4 on their channels (their shifts cancel), so x3 and x4 are learned again
        // with any change. The pitch channels see x1 and x2 alone.
        if alarm.changed[0] || alarm.changed[1] {
            alarm.changed[2] = true;
            alarm.changed[3] = true;
        }
        self.relearn(config, &alarm.changed);
        (Some(alarm), true)
    }

    /// The model's variance of a block mean of the change detector for blocks of `block` entries,
    /// rad^2 ([`change::block_variance_factor`]).
    pub(super) fn block_floor_rad2(&self, pair: usize, block: u32) -> Real {
        let len = self.window.len().max(1) as u32;
        self.pairs[pair.min(1)].product_variance_rad2 * change::block_variance_factor(len, block)
            / len as Real
    }

    /// Keeps a copy of the filter and its residual statistics ([`CleanState`]).
    /// Field by field, in place: a whole `CleanState` built first would take its size again on
    /// the stack (at a restore, on top of the image's parts).
    pub(super) fn keep_clean_state(&mut self) {
        let c = &mut self.clean;
        c.kf.clone_from(&self.kf);
        c.roll_share = self.roll_share;
        c.heel_sensitivity = self.heel_sensitivity;
        for (kept, p) in c.stats.iter_mut().zip(&self.pairs) {
            *kept = p.stats;
        }
    }

    /// Goes back to the copy of [`Windowed::keep_clean_state`].
    pub(super) fn restore_clean_state(&mut self) {
        let c = &self.clean;
        self.kf = c.kf.clone();
        self.roll_share = c.roll_share;
        self.heel_sensitivity = c.heel_sensitivity;
        for (p, kept) in self.pairs.iter_mut().zip(&c.stats) {
            p.stats = *kept;
        }
    }

    /// Starts learning the errors `changed` again: their covariance back to the prior, the residual
    /// check of their pairs (polluted by the step) back to its start and the long averages of the
    /// noise and the drift down to the weight of one horizon (see "Changes of the errors: what the
    /// filter does" in docs/method.md), the detector's blocks started over; both pairs' updates
    /// then wait for one block of residuals against the estimate held now
    /// ([`Windowed::relearn_from_block`]: a pair updated from a single window would take that
    /// window's sway for the change, and through the leakage of x1, x2 into the roll channels the
    /// roll pair's update would move a forgotten x1 or x2). The other errors, and the statistics of
    /// a pair whose channels showed nothing, keep what they learnt.
    pub(super) fn relearn(&mut self, config: &Config, changed: &[bool; 4]) {
        // Back to before the change began to pull at the filter: through the leakage of x1, x2
        // into the roll channels, the errors that did not change were pulled too.
        self.restore_clean_state();
        self.clean_state_due = false;
        let prior = prior_sigma_rad(config, true);
        let forget: [bool; STATES] =
            core::array::from_fn(|i| changed.get(i).copied().unwrap_or(false));
        self.kf.forget(&forget, &prior);
        self.forget_roll_share(&forget);
        let horizon = self.residual_horizon();
        for (pair, p) in self.pairs.iter_mut().enumerate() {
            let [a, b] = channels(pair);
            if changed[a] || changed[b] {
                p.stats.relearn(horizon);
            }
        }
        self.held_x_rad = (*self.kf.state()).into();
        self.changed_entries = self.window.len() as u32;
        self.change.restart_blocks();
        for p in &mut self.pairs {
            p.relearning = true;
            p.block_held = true;
        }
        self.refresh_report(config, 0);
        self.refresh_report(config, 1);
    }

    /// An update of a pair while the errors are learned again. Its last block of residuals, when
    /// the filter held through all of it, was formed against the estimate the filter went back to
    /// and holds now, and (a change being declared only after a run longer than a passing
    /// disturbance) from windows wholly after the change began: it is applied at once. Otherwise
    /// the residuals against the estimate held now are summed over one more block first. Applied
    /// as one measurement per channel, of the learned variance of a block mean over the pair's
    /// noise scale (in the filter's units, see the module doc): with
    /// the prior's covariance the filter takes the changed errors from it, as from a window at a
    /// cold start but with the block's far smaller sway; the pair updates from windows again from
    /// then on.
    /// Returns whether the block was applied (the filter changed).
    pub(super) fn relearn_from_block(
        &mut self,
        pair: usize,
        rows: &[[Real; STATES]; 4],
        z: &[Real; 4],
        entry_s: Real,
    ) -> bool {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let held = self.held_x_rad;
        let fit = |row: &[Real; STATES]| -> Real { (0..STATES).map(|i| row[i] * held[i]).sum() };
        let block_entries = change::block_entries(self.window.len() as u32, entry_s);
        let chs = channels(pair);
        let (block, rows) = if self.pairs[pair].last_block.held {
            let last = &mut self.pairs[pair].last_block;
            last.held = false;
            (last.rad, last.rows)
        } else {
            let pair_rows = [rows[chs[0]], rows[chs[1]]];
            let residual = [
                z[chs[0]] - fit(&pair_rows[0]),
                z[chs[1]] - fit(&pair_rows[1]),
            ];
            let Some(block) = self
                .change
                .accumulate(pair, residual, (block_entries / 2).max(1))
            else {
                return false;
            };
            (block, pair_rows)
        };
        let floor = self.block_floor_rad2(pair, block_entries);
        let mut applied = false;
        for k in 0..2 {
            // The channel from its pair and rank (`chs[k]`), not read back from an array: below 4
            // as the optimiser sees it (no bound check left in the C library's step).
            let ch = 2 * pair + k;
            let target = block[k] + fit(&rows[k]);
            let r = self.change.block_variance(ch, floor) / self.pairs[pair].stats.noise_scale;
            if let Ok(update) = self.kf.update_with_gain(&rows[k], target, r) {
                applied = true;
                let roll_r = if pair == ROLL_PAIR { r } else { 0.0 };
                self.carry_roll_share(&rows[k], &update.gain, roll_r);
            }
            self.pairs[pair].gains[k] = rows[k][ch].abs();
        }
        if applied {
            self.updates = self.updates.saturating_add(1);
        }
        self.pairs[pair].relearning = false;
        true
    }
}
