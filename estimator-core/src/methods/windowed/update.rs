//! One update of the windowed method: at most one a step, of the pair whose turn it is.
//!
//! 1. **Prediction**: each pair's errors take the configured random walk over the entries since
//!    the last update, times the pair's drift share; the heel state takes none.
//! 2. **Noise**: the per-product variance `r` of the window (not the window mean's: consecutive
//!    windows share all but one entry), over the `b` samples of an entry, raised by the weight the
//!    window lacks near lost rows and by the interpolation error of its filled samples. Each pair
//!    takes every other window with `r / 2`; the first windows enter with the weights of
//!    [`super::start`].
//! 3. **Measurement**: the roll pair's turn channel learns the heel in turns ([`super::heel`]);
//!    then the pair's two channels update the filter, each left out when its innovation is beyond
//!    [`super::GATE_SIGMAS`] standard deviations of `h' P h + s` (`s` the channel's learned
//!    spread). The filter holds instead while a change may be building up ([`super::change`]) or
//!    a turn the heel state does not explain is in the window ([`super::turn_hold`]).
//! 4. **Residuals**: the pair's post-fit residuals go to the residual check and the learned noise
//!    and drift ([`super::pair`]), the long-run batches ([`super::long_run`]) and the change
//!    detector; what the filter held out stays out of all but the detector.
//!
//! The measurement (`apply_measurement`, with the channels' `update_channels`) and the residual
//! bookkeeping (`average_residuals`) run once a step yet stay out of line: inlined, the compiler
//! copies their calls for each constant that the pair, the gate or the outcome takes, and the
//! STM32F405's image outgrows its flash budget; out of line, the step runs no more instructions
//! than inlined (the figures: docs/firmware.md). The other steps are
//! inlined.
//!
//! The derivation of each step is in docs/method.md, "The windowed method in full".

use super::change::Alarm;
use super::heel::{heel_learned, HEEL_LEARNED_VARIANCE_RAD2};
use super::turn_hold::TurnVerdict;
use super::{start, Windowed, GATE_SIGMAS, RESIDUAL_PERIODS};
use crate::config::Config;
use crate::correlation::{Measurement, FULL_WEIGHT, HEEL_STATE, ROLL_PAIR, STATES};
use crate::gap_fill::FillVariance;
use crate::kalman::KalmanError;
use crate::math::Compare;
use crate::Real;

/// What became of a window's measurement in an update of its pair.
#[derive(Clone, Copy, Debug)]
struct Outcome {
    /// The filter took some channel of it.
    applied: bool,
    /// It was held out, by the innovation gate or the change detector's hold: its residuals
    /// still go on to the change detector.
    held_out: bool,
}

impl<const CAP: usize> Windowed<CAP> {
    /// Updates the filter with the window's measurement, if the window is full and has new
    /// entries. `interval` is the sample interval, s, `fill_variance` a filled single sample's
    /// error variance of roll and of pitch ([`crate::gap_fill::GapFiller::single_fill_variance`]).
    /// Returns the change of the errors this update declared, if any (see [`super::change`]).
    pub fn update(
        &mut self,
        config: &Config,
        interval: Real,
        fill_variance: FillVariance,
    ) -> Option<Alarm> {
        let alarm = self.update_filter(config, interval, fill_variance);
        self.report = self.estimate_now();
        alarm
    }

    /// [`Windowed::update`] but for the report: the random walk since the last update, the pair
    /// whose turn it is takes the window's measurement ([`Windowed::apply_measurement`]), and its
    /// residuals go on to the checks ([`Windowed::average_residuals`]) and to the change detector.
    // Called once, on the step's path.
    #[inline(always)]
    fn update_filter(
        &mut self,
        config: &Config,
        interval: Real,
        fill_variance: FillVariance,
    ) -> Option<Alarm> {
        if !self.window.is_full() || self.entries_since_update == 0 {
            return None;
        }
        let pair = usize::from(self.next_pair.min(1));
        let m = self.window.sums().measurement_of(pair)?;
        self.next_pair = 1 - pair as u8;
        let bin = self.window.bin() as Real;
        self.considering_heel = self.heel_to_consider();
        self.predict(config, interval, bin);
        self.weigh_product_noise(config, bin, fill_variance);
        if core::mem::take(&mut self.clean_state_due) && !self.change.holding() {
            self.keep_clean_state();
        }
        if self.pairs[pair].relearning {
            if self.relearn_from_block(pair, &m.rows, &m.z, interval * bin) {
                self.refresh_report(config, 0);
                self.refresh_report(config, 1);
            }
            return None;
        }
        // Each pair takes every other window, so each of its updates carries two entries' worth;
        // the first windows come with the weights of [`super::start`].
        let weight = self.start.weight(
            self.window.newest_number(),
            self.window.first_number(),
            start::Layout {
                len: self.window.len() as u32,
                bin: self.window.bin(),
                from_learning: self.window.holds_samples_from_learning(),
            },
            self.updates == 0,
        );
        let mut r = 0.5 * self.pairs[pair].product_variance_rad2;
        // The turn channel's, at full weight from the first window on: the heel it learns is what
        // the first windows need to tell x3, x4 from the heel of a course weave.
        let r_full = r;
        if weight.value < 1.0 {
            // A window of weight 0 (at the ends of a bump) adds next to nothing, but is taken as
            // every window is: one update a step.
            r /= weight.value.larger(start::MIN_WEIGHT);
        }
        let detecting = config.change_detection_step_rad > 0.0;
        let horizon = self.residual_horizon();
        let gate = (detecting
            && self.pairs[pair].spread_count >= (horizon / RESIDUAL_PERIODS as u32).max(1))
        .then_some(GATE_SIGMAS);
        let outcome = self.apply_measurement(pair, &m, r, r_full, gate);
        self.report_at_bump_end(config, pair, weight.ends_bump);
        if !(outcome.applied || outcome.held_out) {
            return None;
        }
        if outcome.applied {
            self.updates = self.updates.saturating_add(1);
        }
        let settled = !self.start.holds();
        let residual = self.average_residuals(config, pair, &m, outcome.applied, settled, horizon);
        let (alarm, tested) = if detecting && settled {
            self.pairs[pair].learn_spread(horizon, residual, outcome.held_out);
            self.detect_change(config, pair, residual, &m.rows, interval * bin)
        } else {
            (None, false)
        };
        // A block's test is the costliest part of an update: after it, the pair's report waits
        // for the pair's next update, two windows later (a change declared has refreshed both).
        if !(tested || self.start.holds()) {
            self.refresh_report(config, pair);
        }
        alarm
    }

    /// The prediction over the entries since the last update (`bin` samples of `interval` s
    /// each): each pair's errors take the configured random walk times the pair's drift share
    /// (see "Learning the noise and the drift" in docs/method.md); the heel state takes none.
    // Called once, on the step's path.
    #[inline(always)]
    fn predict(&mut self, config: &Config, interval: Real, bin: Real) {
        let elapsed_s = interval * bin * self.entries_since_update as Real;
        self.changed_entries = self
            .changed_entries
            .saturating_sub(self.entries_since_update);
        self.entries_since_update = 0;
        let q = config.drift_rad_per_sqrt_s * config.drift_rad_per_sqrt_s * elapsed_s;
        let (qp, qr) = (
            q * self.pairs[0].stats.drift_share,
            q * self.pairs[1].stats.drift_share,
        );
        self.kf.predict(&[qp, qp, qr, qr, 0.0]);
    }

    /// Each pair's per-product variance for the window now, rad^2: the configured noise over the
    /// `bin` samples of an entry, raised by the share of weight the window lacks and by its
    /// filled samples' interpolation error (see "Filled samples and bins" in docs/method.md).
    // Called once, on the step's path.
    #[inline(always)]
    fn weigh_product_noise(&mut self, config: &Config, bin: Real, fill_variance: FillVariance) {
        let sums = self.window.sums();
        let filled = sums.fill_weight as Real / (sums.count as Real * bin * bin);
        let mut r0 = config.measurement_sigma_rad * config.measurement_sigma_rad / bin;
        // Entries left out or weighted down near lost rows: the window carries their share less
        // information (its weight over that of a full window of full-weight entries).
        let full = (self.window.len() as u32).saturating_mul(u32::from(FULL_WEIGHT));
        if sums.weight < full && sums.weight > 0 {
            r0 *= full as Real / sums.weight as Real;
        }
        self.pairs[0].product_variance_rad2 = r0 + 0.5 * filled * fill_variance.pitch_rad2;
        self.pairs[1].product_variance_rad2 = r0 + 0.5 * filled * fill_variance.roll_rad2;
    }

    /// The filter takes the window's measurement `m` for `pair`, each channel of variance `r` (the
    /// turn channel's `r_full`), gated at `gate` standard deviations when it is set; or holds it
    /// out while a change may be building up ([`super::change`]) or a turn the heel state does not
    /// explain is in the window ([`super::turn_hold`]).
    // Called once, on the step's path; out of line on purpose (see the module doc).
    #[inline(never)]
    fn apply_measurement(
        &mut self,
        pair: usize,
        m: &Measurement,
        r: Real,
        r_full: Real,
        gate: Option<Real>,
    ) -> Outcome {
        let mut outcome = Outcome {
            applied: false,
            held_out: false,
        };
        let turn = if pair == ROLL_PAIR {
            self.test_turn(m, gate.is_some())
        } else {
            TurnVerdict::default()
        };
        if self.change.holding() {
            // A change may be building up: the filter waits.
            outcome.held_out = true;
        } else if turn.held {
            // The window holds a turn the heel state does not explain: the roll pair waits until
            // it has left the window, from the copy of before it began to pull.
            if turn.started {
                self.restore_clean_state();
            }
        } else {
            if pair == ROLL_PAIR
                && self.turning
                && self.updates > 0
                && !self.start.holds()
                && !heel_learned(self.kf.covariance()[(HEEL_STATE, HEEL_STATE)])
                && m.turn_row[HEEL_STATE] > 0.0
            {
                self.weigh_heel_evidence(m);
                self.considering_heel = self.heel_to_consider();
            }
            if pair == ROLL_PAIR {
                outcome.applied |= self.update_turn_channel(m, r_full);
            }
            let channels = self.update_channels(pair, m, r, gate);
            outcome.applied |= channels.applied;
            outcome.held_out |= channels.held_out;
        }
        outcome
    }

    /// The two channels of `pair` update the filter in turn, each of variance `r`, gated at
    /// `gate` standard deviations of its learned spread when it is set.
    // Called once, on the step's path; out of line on purpose (see the module doc).
    #[inline(never)]
    fn update_channels(
        &mut self,
        pair: usize,
        m: &Measurement,
        r: Real,
        gate: Option<Real>,
    ) -> Outcome {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let mut outcome = Outcome {
            applied: false,
            held_out: false,
        };
        // Until the turn channel has learned the heel, the channels only consider it: its
        // uncertainty widens the others', its estimate stays (over a window or two, a course
        // weave near the rotation's frequency cannot tell it from x3, x4).
        let mut all_but_heel = [true; STATES];
        all_but_heel[HEEL_STATE] = false;
        let learned = self.kf.covariance()[(HEEL_STATE, HEEL_STATE)] < HEEL_LEARNED_VARIANCE_RAD2;
        let updated = (!learned).then_some(&all_but_heel);
        // A heel held at its negligible variance (no turn has shown one) is left out of the
        // update: x1..x4 alone, at two thirds of the cost.
        let heel_active = heel_learned(self.kf.covariance()[(HEEL_STATE, HEEL_STATE)]);
        for k in 0..2 {
            // The channel from its pair and rank, not read back from an array: below 4 as the
            // optimiser sees it (no bound check left in the C library's step).
            let ch = 2 * (pair & 1) + k;
            let gate = gate.map(|g| (self.pairs[pair].spread_rad2[k], g));
            let result = if heel_active {
                self.kf
                    .update_masked(&m.rows[ch], m.z[ch], r, gate, updated)
            } else {
                self.kf
                    .update_leading::<HEEL_STATE>(&m.rows[ch], m.z[ch], r, gate, updated)
            };
            match result {
                Ok(applied) => {
                    outcome.applied = true;
                    let roll_r = if pair == ROLL_PAIR { r } else { 0.0 };
                    self.carry_roll_share(&m.rows[ch], &applied.gain, roll_r);
                }
                Err(KalmanError::Gated) => {
                    outcome.held_out = true;
                    self.gated = self.gated.saturating_add(1);
                }
                Err(_) => {}
            }
        }
        outcome
    }

    /// The residual bookkeeping after an update of `pair` with window `m` (`applied`: the filter
    /// took some channel of it; `settled`: the first windows' bumps are over): the pair's
    /// residual average and the check, the learned noise and drift, the long-run batches.
    /// Returns the pair's two post-fit residuals, rad.
    ///
    /// What the filter held out (the gate, the detector's hold) stays out of the residual averages:
    /// the check and the learned noise and drift are about the data the filter took; the detector
    /// sees everything. So do the windows of the first bumps ([`super::start`]): the filter has
    /// taken a few windows, most of them at a fraction of their weight, and a window's residual is
    /// then mostly its sway, which would inflate the learned noise.
    // Called once, on the step's path; out of line on purpose (see the module doc).
    #[inline(never)]
    fn average_residuals(
        &mut self,
        config: &Config,
        pair: usize,
        m: &Measurement,
        applied: bool,
        settled: bool,
        horizon: u32,
    ) -> [Real; 2] {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let residual = self.pairs[pair].average_residuals(
            pair,
            horizon,
            &m.rows,
            &m.z,
            self.kf.state().as_slice(),
            applied && settled,
        );
        if self.change.holding() {
            self.entries_since_hold = 0;
        }
        if applied && settled {
            let (bin, len) = (self.window.bin(), self.window.len());
            self.pairs[pair].learn_noise_and_drift(config, bin, len, horizon);
        }
        // The first batch a quarter of a period of the pair's updates, from the first update on
        // ([`super::long_run`]); the windows that hold what the filter held out are left out of it
        // as they were of the filter.
        if applied && self.entries_since_hold >= self.window.len() as u32 {
            let len = self.window.len() as u32;
            let q = self.pairs[pair].product_variance_rad2;
            self.pairs[pair]
                .long_run
                .add(residual, (len / 16).max(1), len, q);
        }
        residual
    }
}
