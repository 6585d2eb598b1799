//! Changes of the installation errors, detected from the filter's residuals.
//!
//! A re-installation or a shock moves the errors by a step `D` at some time `t0`. The filter, whose
//! memory grows without bound while the errors look constant, barely moves; the step shows in its
//! post-fit residuals `e = z - H x` instead. This detector decides, from those residuals, that the
//! errors have changed, and which, so that [`super::Windowed`] can learn them again.
//!
//! # What the residual does after a step
//! Each measurement `z` is the mean over the last window of `W` entries (one rotation period), so
//! after the step the residual of channel `c` ramps from 0 at `t0` to `(H D)_c` at `t0 + W` and
//! stays there. For a step of one error `x_i` alone, `(H D)_c` is about `g_c D` on its own channel
//! `c = i` (`g_c` the channel's gain: 1/2 for x1, x2; `cos L / 2` for x3, x4), so the smallest step
//! the detector is sized for, `Config::change_detection_step_rad = d`, shifts the residual by
//! `a_c = g_c d`: 10 arcsec on a pitch channel for the default 20 arcsec.
//!
//! # The statistic: block means of the residuals
//! One residual is the mean of a window and carries the sway's residual of that window: tens of
//! arcsec at sea (the product of a 6 deg, 10 s sway and the reference, averaged over 480 s, falls
//! only like `1 / (pi f W)`). Consecutive residuals share `W - 1` of their `W` entries, so they are
//! no independent tests either. So the residuals are averaged once more, over **blocks of half a
//! period** of each pair's updates (`W / 4` updates, `W / 2` entries): the block mean `b` weighs the
//! raw products with a trapezoid `1.5 W` long, whose response to the sway falls like
//! `1 / (pi f W)(pi f W / 2)`, below an arcsec (measured on the sea scenario: 0.2 to 1.2 arcsec,
//! against 10 to 50 for a window's residual). At periods over 480 s a block is a quarter of the
//! period, or an eighth..., the longest of these within [`MAX_BLOCK_S`] = 240 s
//! ([`block_entries`]): the trapezoid `W + B` long still takes the sway down as far
//! (`1 / (pi f W)(pi f B)`, with `W B` at least that of a 480 s period), and the run a change must
//! last (below) shrinks with the block: at 720 s a 20 arcsec step was declared up to 2,044 s after
//! it with half-period blocks, 1,864 s with 180 s blocks (docs/uncertainty.md).
//!
//! Under the model, `b` is zero-mean with a variance `s^2` learned from the blocks themselves (a
//! running mean of `b^2` over [`VARIANCE_BLOCKS`] blocks, each `b^2` clipped at
//! [`WINSOR_SIGMAS`]^2 `s^2`; a block that holds the filter, below, is left out: disturbances an
//! hour apart would otherwise raise `s` without bound), never below the model's: white products
//! of variance `q` give `s^2 = q (1 - 1/6) / W` (the trapezoid's sum of squared weights). Learning
//! `s` from the data, not from the configured noise, is what keeps coloured noise and a rough sea
//! from reading as steps: their block means are larger, and so is `s` (about 5 arcsec under
//! 20 arcsec of coloured noise). It is learned once the residual average has a full horizon (the
//! filter settled), and tested after [`MIN_VARIANCE_BLOCKS`] = 16 blocks (8 periods; with 8,
//! coloured noise made 5 false declarations in 200 runs within the first two hours, before the
//! variance and the correlation below were learned; with 16, none in 600). Both counts are of
//! half-period blocks: with shorter blocks (periods over 480 s) they are multiplied by the blocks
//! in half a period, so that the variance is learned from as much time (with 180 s blocks at 720 s
//! and 16 of them, coloured noise made a false declaration in 200 runs; with 32, none).
//!
//! # Correlated blocks
//! Consecutive blocks are not independent: their trapezoids overlap, and the filter's own error,
//! which the residuals carry, persists from block to block (under coloured noise, for hours). A
//! run of positively correlated blocks sums its log-likelihood ratio as if each block were new
//! evidence. So the ratio is formed with the long-run variance of an AR(1) process of the blocks'
//! learned lag-one correlation `rho` (the running mean of the product of consecutive block means,
//! clipped alike, over `s^2`): `s_run^2 = s^2 (1 + rho) / (1 - rho)`, the variance per block of a
//! long sum of such blocks, `rho` taken in `[0, `[`MAX_BLOCK_CORRELATION`]`]`. Measured: `rho` is
//! negative on the sea scenario (the sway's residual alternates from one half period to the next;
//! taken as 0), 0.45 to 0.7 under 20 arcsec of coloured noise (`s_run` 1.6 to 2.4 times `s`).
//!
//! # The test: a log-likelihood ratio over a run of blocks
//! Between "no change" (`b ~ N(0, s^2)`) and "a change of the smallest size" (`b ~ N(+-a, s^2)`),
//! the log-likelihood ratio of one block is `(+-a b - a^2 / 2) / s^2` (with `s_run^2`, above), with
//! no square root. Per
//! channel and direction it is summed over a **run**: consecutive blocks in which it is positive
//! (the block mean beyond `a / 2`), with at most one block at a time where it is not (a dip,
//! below); a second such block in a row, or a dip that takes the sum to zero, ends the run and
//! clears the sum (what a CUSUM does when its sum falls to zero, except that two blocks below
//! `a / 2` end it whatever the sum: a change is expected to stay beyond `a / 2`). A change is
//! declared when, for some channel and direction,
//!
//! - the sum reaches [`LLR_THRESHOLD`] `= 20`, and
//! - the run has lasted [`persistence_blocks`] blocks beyond `a / 2` (its dips not counted):
//!   longer than any passing disturbance.
//!
//! **False alarms.** Under "no change", `E[exp(llr)] = 1` for each block, so by Markov's inequality
//! a run starting at a given block reaches a sum of `h` with probability at most `exp(-h)`,
//! whatever its length. With 4 channels, 2 directions and a block every half period, a false alarm
//! comes at most `8 x 2 x (periods a year) x exp(-20)` times a year: 0.0022 for a 480 s period
//! (one in 460 years of sea time), 0.017 for the shortest period, 60 s (one in 57 years). That
//! bound holds for independent Gaussian blocks of the learned variance, and, through the long-run
//! variance, approximately for correlated ones; what logs with what is neither (sway, coloured
//! noise, heel in turns, drifting errors) show is measured: docs/uncertainty.md.
//!
//! **Persistence.** A passing disturbance (a turn's heel, a few minutes of roll offset) biases
//! every window that contains it: the residuals over `W + D` for a disturbance of `D`, up to four
//! consecutive blocks for `D = W / 2`. A step never passes. A run must therefore last until a block
//! lies wholly after the longest disturbance the detector is to ignore, `D = max(B,
//! `[`PASSING_S`]`)` for blocks of `B`: the residuals over `W + D` overlap at most
//! `ceil((W + D) / B)` blocks and one more, so a run must last one block longer than that;
//! `3 + ceil(2 D / W)` blocks for half-period blocks, 5 for a 480 s period (2.5 periods), 7 blocks
//! of 180 s (1,260 s) for a 720 s period. A 20 arcsec
//! step on a calm sea is detected within about three periods (the ramp of the first block, then
//! the run); when it is, the window holds only samples from after the step, so the errors can be
//! learned again from the next update on.
//!
//! **A dip in a run.** A step of the smallest size shifts its channel's blocks by about `a`, and
//! the blocks' noise can take one of them below `a / 2`. With four-position rotation at 360 s, a
//! 20 arcsec step of x3 shifted the roll channel's blocks by 5.9 to 7.7 arcsec (`a` 6.7, `s` 1.3;
//! the blocks alternate from one half period to the next, a learned lag-one correlation of -0.4),
//! and one block at 2.3 arcsec restarted the run: declared 1,784 s (4.96 periods) after the step,
//! where the other runs of that line took 1,064 to 1,244 s. So a run goes on through one such
//! block (a **dip**): its ratio, negative, is added to the sum, and it does not count towards the
//! persistence. The false-alarm bound above stands: the sum is still that of every block since
//! the run began, dips included. What a dip costs: a passing disturbance's run, then one block of
//! noise short of `a / 2` and one beyond it, is as long as a run with the disturbance and the
//! block beyond it alone; measured, no declaration more on the logs without a change
//! (docs/uncertainty.md). That line is now declared within 1,244 s (3.46 periods). Runs go on
//! through dips only once the blocks are tested.
//!
//! **Drift.** Errors that drift are followed by the filter with a lag (about 2 arcsec for
//! 20 arcsec a day); the residual that lag leaves is a fraction of `a / 2`, so a drift never starts
//! a run.
//!
//! # While a change builds up
//! Until it is declared, the block mean beyond `2 s` widens the reported 1-sigma of the channel's
//! error by `(|b| - 2 s) / g` (as the residual check does with its longer average), so that the
//! 1-sigma covers a step from the first block that shows it. And while a channel's block is in a
//! run and beyond [`HOLD_SIGMAS`]` s` (beyond `a / 2` and significant), the filter holds its
//! updates: it would otherwise fit what does not fit, and through the leakage of x1, x2 into the
//! roll channels a step of one pair pulls the other pair's errors too. A disturbance that passes
//! costs the filter the windows it held; a change is learned again anyway.
//!
//! # Before the first test
//! Blocks are tested once 8 periods of them are learned; at a 720 s period that is some 9,800 s
//! into a log (the residual average's horizon first, then 32 blocks of 180 s). A disturbance
//! before then used to go straight into the filter: a turn's heel at 7,200 s (180 s of 0.5 deg)
//! biased the roll channels' blocks by 250 to 360 arcsec, the filter took a share of it, and its
//! long memory then left the residuals some 20 arcsec off for hours, a run that the detector,
//! once armed, declared a change of x3 and x4 (in 20 of 200 sea logs with 3 deg of heel, 81 of 200
//! with 0.5 deg). So from [`HOLD_FROM_BLOCKS`] = 4 half periods of blocks learned on, runs are
//! counted and a block in a run and beyond [`UNTESTED_HOLD_SIGMAS`] = 10 standard deviations of
//! the variance learned so far holds the filter as above, for no longer than the persistence;
//! nothing is summed, widened or declared until the blocks are tested. Ten, not the tested
//! blocks' 3: a variance learned from a few blocks is itself uncertain, and at 3 the blocks of a
//! rough sea held the filter in some of the 200 runs of the README's Monte Carlo (p95 of x4 at
//! 5,000 s 0.51 arcsec, 0.48 without); a turn's blocks are hundreds of deviations out. Unlike a tested block that holds, such a block is still
//! learned into the variance (clipped at [`WINSOR_SIGMAS`]): left out, under 20 arcsec of
//! coloured noise the few blocks beyond 3 sigma of an early variance were missing from it, and a
//! channel's variance learned too small made one false declaration in 200 logs at 480 s. A
//! change before the first test is held for at most the persistence, then learned by the filter
//! as before, and can be declared once the blocks are tested.
//! Measured (docs/uncertainty.md): no declaration in 200 sea logs with turns at 720 s, with 3 or
//! 0.5 deg of heel.
//!
//! # Cost
//! Per update two additions; per block and channel three divisions, a root when the block is
//! beyond 2 `s`, and two dozen multiply-adds, once a half period (docs/uncertainty.md has the
//! step's cost on the Cortex-M4F).

pub(crate) mod checkpoint;

use crate::math::{sqrt, Compare};
use crate::Real;

/// Sum of the log-likelihood ratio over a run at which a change is declared (see the module doc:
/// at most `exp(-20) = 2.1e-9` false alarms per block, channel and direction).
pub const LLR_THRESHOLD: Real = 20.0;

/// Half-period blocks whose block means the variance of a block mean is averaged over (time
/// constant of the running mean, 32 periods; times [`BlockContext::blocks_per_half_period`]).
pub const VARIANCE_BLOCKS: u32 = 64;

/// Half-period blocks learned before the first test (8 periods; times
/// [`BlockContext::blocks_per_half_period`]).
pub const MIN_VARIANCE_BLOCKS: u32 = 16;

/// Half-period blocks learned before a block far beyond them holds the filter, although none is
/// tested yet (2 periods; times [`BlockContext::blocks_per_half_period`]).
pub const HOLD_FROM_BLOCKS: u32 = 4;

/// Before the first test, a block in a run and beyond this many standard deviations of the
/// variance learned so far holds the filter (see "Before the first test").
pub const UNTESTED_HOLD_SIGMAS: Real = 10.0;

/// Largest lag-one correlation of the blocks taken into the run's variance (a factor of 19 at most).
pub const MAX_BLOCK_CORRELATION: Real = 0.9;

/// A block mean enters the learned variance clipped at this many of its standard deviations.
pub const WINSOR_SIGMAS: Real = 3.0;

/// A block in a run and beyond this many standard deviations holds the filter's updates.
pub const HOLD_SIGMAS: Real = 3.0;

/// The longest passing disturbance the detector ignores at any period, s (a turn's heel: a 90 deg
/// course change at 0.5 deg/s takes 180 s); at least half a period.
pub const PASSING_S: Real = 300.0;

/// The longest block, s: a block is half a period, or a quarter, an eighth... of it, the longest of
/// these that is at most this long. At long periods the run a change must last (about a period,
/// plus the longest passing disturbance, plus a block or two) then does not grow with the block
/// too; at periods up to 480 s a block is half a period.
pub const MAX_BLOCK_S: Real = 240.0;

/// Entries in a block of the change detector, for a window of `window_entries` entries of
/// `entry_s` seconds each: half the window, halved again while it is longer than [`MAX_BLOCK_S`]
/// (and at least 2 entries), and even (a block is whole updates of a pair, each two entries on).
pub fn block_entries(window_entries: u32, entry_s: Real) -> u32 {
    let mut block = window_entries / 2;
    while block > 2 && block as Real * entry_s > MAX_BLOCK_S {
        block /= 2;
    }
    (block & !1).max(2)
}

/// Blocks a run must last before a change is declared, for a window of `window_entries` entries
/// of `entry_s` seconds each and blocks of `block` entries ([`block_entries`]): until a block lies
/// wholly after the longest passing disturbance. A disturbance of `D` biases the residuals over
/// `W + D`, which overlaps at most `ceil((W + D) / B)` blocks of `B` entries and one more: a run
/// one block longer than that is no disturbance (`3 + ceil(2 D / W)` for half-period blocks).
pub fn persistence_blocks(window_entries: u32, block: u32, entry_s: Real) -> u32 {
    let passing = (PASSING_S / entry_s).larger(block as Real);
    // Half-period blocks: 2 + ceil(D / B) blocks overlap, the run one more; shorter ones:
    // ceil((W + D) / B), the run one more.
    let (base, ratio) = if is_half_period(window_entries, block) {
        (3, passing / block as Real)
    } else {
        (1, (window_entries as Real + passing) / block as Real)
    };
    // ceil without libm: the ratio is positive and small.
    let whole = ratio as u32;
    base + if (whole as Real) < ratio {
        whole + 1
    } else {
        whole
    }
}

/// Whether blocks of `block` entries are half a window of `window_entries` (periods up to 480 s).
fn is_half_period(window_entries: u32, block: u32) -> bool {
    2 * block >= window_entries
}

/// Blocks of `block` entries in half a window of `window_entries`
/// ([`BlockContext::blocks_per_half_period`]).
pub fn blocks_per_half_period(window_entries: u32, block: u32) -> u32 {
    if is_half_period(window_entries, block) {
        1
    } else {
        window_entries / 2 / block.max(1)
    }
}

/// The model's variance of a block mean over that of one entry's product, times the window's
/// entries: white products of variance `r` give a block mean of variance `r (1 - B / (3 W)) / W`
/// for blocks of `B` entries (the trapezoid `W + B` long's sum of squared weights), `r (1 - 1/6) /
/// W` for half a period.
pub fn block_variance_factor(window_entries: u32, block: u32) -> Real {
    if is_half_period(window_entries, block) {
        5.0 / 6.0
    } else {
        1.0 - block as Real / (3.0 * window_entries.max(1) as Real)
    }
}

/// What a block is tested against, from the method's state at the block's end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockContext {
    /// Blocks a run must last ([`persistence_blocks`]).
    pub persistence_blocks: u32,
    /// The model's variance of a block mean, rad^2 (the floor of the learned one).
    pub floor_rad2: Real,
    /// The smallest step of an error to detect, rad (`Config::change_detection_step_rad`).
    pub step_rad: Real,
    /// Whether the pair's residual average has a full horizon (its blocks are learned from).
    pub settled: bool,
    /// Whether both pairs' have (blocks are tested).
    pub armed: bool,
    /// The largest widening of a 1-sigma, rad (the prior's).
    pub max_widening_rad: Real,
    /// Blocks in half a period (1 up to 480 s, 2 or more beyond: [`block_entries`]): the blocks
    /// learned before the first test and the variance's time constant are counted in half
    /// periods, so that a shorter block does not learn from less time.
    pub blocks_per_half_period: u32,
}

/// A change declared: which errors changed, and since how many blocks the residuals showed it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Alarm {
    /// The errors x1..x4 whose channels were in a run when the change was declared.
    pub changed: [bool; 4],
    /// The longest of those runs, in blocks.
    pub run_blocks: u32,
}

/// The detector's state (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct ChangeDetector {
    /// Sum of each channel's residuals over the current block, rad.
    block_sum: [Real; 4],
    /// Updates of each pair in the current block.
    block_updates: [u32; 2],
    /// Running mean of each channel's squared block mean (clipped), rad^2.
    mean_square_rad2: [Real; 4],
    /// Running mean of the product of each channel's block mean and the one before (clipped),
    /// rad^2: the lag-one covariance.
    lag_product_rad2: [Real; 4],
    /// Each channel's previous block mean, rad.
    previous_block_rad: [Real; 4],
    /// Blocks learned into it, per pair (saturates at [`VARIANCE_BLOCKS`]).
    learned_blocks: [u32; 2],
    /// Per channel, for a rise and a fall: the log-likelihood ratio summed over the current run.
    llr: [[Real; 2]; 4],
    /// Per channel, for a rise and a fall: blocks in the current run.
    run: [[u32; 2]; 4],
    /// Per channel, for a rise and a fall: the last block of the current run was a dip (not
    /// beyond `a / 2`).
    dipped: [[bool; 2]; 4],
    /// Widening of each error's 1-sigma from its channel's last block, rad.
    widening_rad: [Real; 4],
    /// Per channel: in a run, with its last block beyond [`HOLD_SIGMAS`] standard deviations.
    holding: [bool; 4],
}

impl Default for ChangeDetector {
    fn default() -> Self {
        Self::NEW
    }
}

impl ChangeDetector {
    /// Nothing learned, nothing accumulated.
    pub const NEW: ChangeDetector = ChangeDetector {
        block_sum: [0.0; 4],
        block_updates: [0; 2],
        mean_square_rad2: [0.0; 4],
        lag_product_rad2: [0.0; 4],
        previous_block_rad: [0.0; 4],
        learned_blocks: [0; 2],
        llr: [[0.0; 2]; 4],
        run: [[0; 2]; 4],
        dipped: [[false; 2]; 4],
        widening_rad: [0.0; 4],
        holding: [false; 4],
    };

    /// Widening of each error's 1-sigma while a change builds up, rad.
    pub fn widening_rad(&self) -> &[Real; 4] {
        &self.widening_rad
    }

    /// The learned variance of each channel's block mean, rad^2 (0 until learned).
    pub fn block_variance_rad2(&self) -> &[Real; 4] {
        &self.mean_square_rad2
    }

    /// Whether the filter should hold its updates: some channel is in a run whose last block is
    /// beyond [`HOLD_SIGMAS`] standard deviations (see "While a change builds up").
    pub fn holding(&self) -> bool {
        self.holding.iter().any(|h| *h)
    }

    /// The learned lag-one correlation of each channel's block means (see "Correlated blocks").
    pub fn block_correlation(&self) -> [Real; 4] {
        core::array::from_fn(|ch| {
            if self.mean_square_rad2[ch] > 0.0 {
                self.lag_product_rad2[ch] / self.mean_square_rad2[ch]
            } else {
                0.0
            }
        })
    }

    /// Whether some channel is in a run (its last block beyond half the smallest step's shift).
    pub fn in_run(&self) -> bool {
        self.run.iter().flatten().any(|r| *r > 0)
    }

    /// Starts over on the current blocks and runs (after a change was declared, or the window
    /// changed its length); keeps the learned variances.
    pub fn restart_blocks(&mut self) {
        self.block_sum = [0.0; 4];
        self.block_updates = [0; 2];
        self.llr = [[0.0; 2]; 4];
        self.run = [[0; 2]; 4];
        self.dipped = [[false; 2]; 4];
        self.widening_rad = [0.0; 4];
        self.holding = [false; 4];
        self.previous_block_rad = [0.0; 4];
    }

    /// Adds one update of `pair` (0 pitch, 1 roll): its two channels' post-fit residuals, rad.
    /// At the end of a block of `updates_per_block` updates, returns the block's means.
    pub fn accumulate(
        &mut self,
        pair: usize,
        residual_rad: [Real; 2],
        updates_per_block: u32,
    ) -> Option<[Real; 2]> {
        let pair = pair.min(1);
        self.block_sum[2 * pair] += residual_rad[0];
        self.block_sum[2 * pair + 1] += residual_rad[1];
        self.block_updates[pair] = self.block_updates[pair].saturating_add(1);
        if self.block_updates[pair] < updates_per_block.max(1) {
            return None;
        }
        let inv_n = 1.0 / self.block_updates[pair] as Real;
        self.block_updates[pair] = 0;
        let means = [
            self.block_sum[2 * pair] * inv_n,
            self.block_sum[2 * pair + 1] * inv_n,
        ];
        self.block_sum[2 * pair] = 0.0;
        self.block_sum[2 * pair + 1] = 0.0;
        Some(means)
    }

    /// The variance of a block mean of channel `ch` that a block is tested and weighed with, rad^2:
    /// the learned one, at least `floor_rad2`.
    pub fn block_variance(&self, ch: usize, floor_rad2: Real) -> Real {
        self.mean_square_rad2[ch.min(3)].larger(floor_rad2)
    }

    /// Tests a block of `pair` whose means are `block_rad` and learns from it (see the module doc);
    /// `gains` are the pair's channel gains. Returns the change declared, if any.
    pub fn test(
        &mut self,
        pair: usize,
        block_rad: [Real; 2],
        gains: [Real; 2],
        ctx: &BlockContext,
    ) -> Option<Alarm> {
        let pair = pair.min(1);
        let learned = self.learned_blocks[pair];
        let per_half_period = ctx.blocks_per_half_period.max(1);
        let testing = ctx.armed && learned >= MIN_VARIANCE_BLOCKS.saturating_mul(per_half_period);
        // Before that, a gross disturbance still holds the filter (see "Before the first test").
        let guarding = testing || learned >= HOLD_FROM_BLOCKS.saturating_mul(per_half_period);
        let count = learned
            .saturating_add(1)
            .min(VARIANCE_BLOCKS.saturating_mul(per_half_period));
        let weight = 1.0 / count as Real;
        let mut declared = false;
        for (k, ch) in (2 * pair..2 * pair + 2).enumerate() {
            let b = block_rad[k];
            let var = self.block_variance(ch, ctx.floor_rad2);
            if guarding {
                let a = gains[k] * ctx.step_rad;
                // The run's blocks are not independent: the long-run variance of an AR(1) of the
                // learned lag-one correlation (see "Correlated blocks" in the module doc).
                let rho = (self.lag_product_rad2[ch] / var).clamp(0.0, MAX_BLOCK_CORRELATION);
                let run_var = var * (1.0 + rho) / (1.0 - rho);
                for dir in 0..2 {
                    // A rise (0) or a fall (1) of the smallest size: at most one direction gains,
                    // the one of the block's sign, when |b| > a / 2.
                    let shift = if dir == 0 { b } else { -b };
                    let llr = (a * shift - 0.5 * a * a) / run_var;
                    if llr > 0.0 {
                        // Before the first test, the run is counted for the hold alone.
                        self.llr[ch][dir] += if testing { llr } else { 0.0 };
                        self.run[ch][dir] = self.run[ch][dir].saturating_add(1);
                        self.dipped[ch][dir] = false;
                        declared |= self.llr[ch][dir] >= LLR_THRESHOLD
                            && self.run[ch][dir] >= ctx.persistence_blocks;
                    } else if testing
                        && self.run[ch][dir] > 0
                        && !self.dipped[ch][dir]
                        && self.llr[ch][dir] + llr > 0.0
                    {
                        // A dip (see "A dip in a run"): the run goes on, its sum takes the block's
                        // ratio, its length does not count the block.
                        self.llr[ch][dir] += llr;
                        self.dipped[ch][dir] = true;
                    } else {
                        self.llr[ch][dir] = 0.0;
                        self.run[ch][dir] = 0;
                        self.dipped[ch][dir] = false;
                    }
                }
                // Held while the run is shorter than a passing disturbance can make it; a longer
                // one is a change (declared) or an inconsistency the filter must work through.
                let run = self.run[ch][0].max(self.run[ch][1]);
                let hold_sigmas = if testing {
                    HOLD_SIGMAS
                } else {
                    UNTESTED_HOLD_SIGMAS
                };
                self.holding[ch] = run > 0
                    && run < ctx.persistence_blocks
                    && b * b > hold_sigmas * hold_sigmas * var;
                self.widening_rad[ch] = if testing && b * b > 4.0 * var && gains[k] > 1e-6 {
                    ((b.abs() - 2.0 * sqrt(var)) / gains[k]).smaller(ctx.max_widening_rad)
                } else {
                    0.0
                };
            }
            // A block that holds the filter is a disturbance or a change, not the blocks' noise;
            // before the first test, one that holds is learned from all the same (clipped), see
            // "Before the first test".
            if ctx.settled && !(testing && self.holding[ch]) {
                // The first block has no variance to be clipped against yet.
                let b2 = if learned == 0 {
                    b * b
                } else {
                    (b * b).smaller(WINSOR_SIGMAS * WINSOR_SIGMAS * var)
                };
                self.mean_square_rad2[ch] += (b2 - self.mean_square_rad2[ch]) * weight;
                // The product with the previous block, both clipped alike: the lag-one covariance.
                if learned > 0 {
                    // max/min, not clamp: clamp's bounds come from a learned value here, and its
                    // check of them (a panic that formats floats) cost 31 KB of flash on the
                    // Cortex-M4F.
                    let bound = WINSOR_SIGMAS * WINSOR_SIGMAS * var;
                    let product = (b * self.previous_block_rad[ch])
                        .larger(-bound)
                        .smaller(bound);
                    self.lag_product_rad2[ch] += (product - self.lag_product_rad2[ch]) * weight;
                }
            }
            self.previous_block_rad[ch] = b;
        }
        if ctx.settled && !(testing && (self.holding[2 * pair] || self.holding[2 * pair + 1])) {
            self.learned_blocks[pair] = count;
        }
        if !declared {
            return None;
        }
        let mut alarm = Alarm {
            changed: [false; 4],
            run_blocks: 0,
        };
        for ch in 0..4 {
            let run = self.run[ch][0].max(self.run[ch][1]);
            alarm.changed[ch] = run > 0;
            alarm.run_blocks = alarm.run_blocks.max(run);
        }
        Some(alarm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Gaussian numbers from a seeded ChaCha8 stream (Box-Muller), for blocks of noise.
    struct Noise(ChaCha8Rng);

    impl Noise {
        fn new(seed: u64) -> Noise {
            Noise(ChaCha8Rng::seed_from_u64(seed))
        }

        fn uniform(&mut self) -> f64 {
            ((self.0.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }

        fn gaussian(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            libm::sqrt(-2.0 * libm::log(u)) * libm::cos(2.0 * core::f64::consts::PI * v)
        }
    }

    const SIGMA: Real = 1e-6;
    const GAIN: Real = 0.5;

    /// A context for blocks of 1-sigma [`SIGMA`] and a smallest step 20 times as large (a shift
    /// of 10 sigma at gain 1/2), both pairs settled.
    fn context(persistence_blocks: u32) -> BlockContext {
        BlockContext {
            persistence_blocks,
            floor_rad2: 0.0,
            step_rad: 20.0 * SIGMA,
            settled: true,
            armed: true,
            max_widening_rad: 1.0,
            blocks_per_half_period: 1,
        }
    }

    /// Feeds `blocks` block means of channel 0 (`shift(k) + noise`, channel 1 noise only), one
    /// block per call of `test`; returns the block at which a change was declared, if any.
    fn run(
        d: &mut ChangeDetector,
        blocks: usize,
        shift: impl Fn(usize) -> Real,
        noise: &mut Noise,
        ctx: &BlockContext,
    ) -> Option<(usize, Alarm)> {
        for k in 0..blocks {
            let b = [
                shift(k) + SIGMA * noise.gaussian() as Real,
                SIGMA * noise.gaussian() as Real,
            ];
            if let Some(alarm) = d.test(0, b, [GAIN, GAIN], ctx) {
                return Some((k, alarm));
            }
        }
        None
    }

    fn learned(noise: &mut Noise, ctx: &BlockContext) -> ChangeDetector {
        let mut d = ChangeDetector::NEW;
        assert_eq!(run(&mut d, 200, |_| 0.0, noise, ctx), None);
        d
    }

    #[test]
    fn persistence_outlasts_a_passing_disturbance() {
        // 480 entries of 1 s: a turn of up to 300 s (more than half a period): 3 + 2 blocks.
        let persistence =
            |w: u32, entry_s: Real| persistence_blocks(w, block_entries(w, entry_s), entry_s);
        assert_eq!(persistence(480, 1.0), 5);
        // Short periods: 300 s is the longer (60 s: blocks of 30 s, 3 + 10).
        assert_eq!(persistence(60, 1.0), 13);
        // Bins of 2 samples: the same time.
        assert_eq!(persistence(240, 2.0), 5);
        // Long periods: blocks of a quarter of 720 s, 180 s; W + D = 1020 s overlaps 6 of them,
        // and one more: 7 (1,260 s, where half-period blocks took 4, 1,440 s). 3600 s: blocks of
        // 224 s, 18 + 1 (4,256 s; half-period blocks took 4 of 1,800 s, 7,200 s).
        assert_eq!(persistence(720, 1.0), 7);
        assert_eq!(persistence(3600, 1.0), 19);
    }

    #[test]
    fn a_block_is_half_a_period_up_to_240_s_and_a_quarter_or_less_beyond() {
        assert_eq!(block_entries(360, 1.0), 180);
        assert_eq!(block_entries(480, 1.0), 240);
        assert_eq!(block_entries(720, 1.0), 180);
        assert_eq!(block_entries(3600, 1.0), 224);
        // Entries of 2 s (bins): 480 s in 240 entries, half of them, 240 s.
        assert_eq!(block_entries(240, 2.0), 120);
        assert_eq!(block_entries(4, 1.0), 2);
    }

    #[test]
    fn noise_alone_is_never_declared_and_its_variance_is_learned() {
        let ctx = context(5);
        let mut noise = Noise::new(3);
        let mut d = learned(&mut noise, &ctx);
        // 20,000 more blocks (the blocks of four years at a 480 s period, per channel): nothing.
        assert_eq!(run(&mut d, 20_000, |_| 0.0, &mut noise, &ctx), None);
        let learned_sigma = libm::sqrt(f64::from(d.block_variance(0, 0.0))) as Real;
        // A mean square of 64 blocks (clipped at 3 sigma: 97 % of the variance): within 25 %.
        assert!(
            (learned_sigma / SIGMA - 1.0).abs() < 0.25,
            "{learned_sigma}"
        );
        assert!(!d.holding() && !d.in_run());
    }

    #[test]
    fn a_step_is_declared_once_its_run_has_lasted_the_persistence() {
        let ctx = context(5);
        let mut noise = Noise::new(5);
        let mut d = learned(&mut noise, &ctx);
        // A step of the smallest size (a shift of 10 sigma): declared at the 5th block, with the
        // filter held from the first.
        let shift = GAIN * ctx.step_rad;
        let mut held = 0;
        let mut declared = None;
        for k in 0..10 {
            let b = [
                shift + SIGMA * noise.gaussian() as Real,
                SIGMA * noise.gaussian() as Real,
            ];
            if let Some(alarm) = d.test(0, b, [GAIN, GAIN], &ctx) {
                declared = Some((k, alarm));
                break;
            }
            held += usize::from(d.holding());
            // While it builds up, the 1-sigma of x1 is widened to more than half the step: the
            // error is within 2 sigma.
            assert!(
                d.widening_rad()[0] > 0.5 * ctx.step_rad,
                "{}",
                d.widening_rad()[0]
            );
        }
        let (k, alarm) = declared.expect("declared");
        assert_eq!(k, 4);
        assert_eq!(held, 4);
        assert_eq!(
            alarm,
            Alarm {
                changed: [true, false, false, false],
                run_blocks: 5
            }
        );
    }

    /// The block at which a step of the smallest size, whose blocks in `dips` fall back to a
    /// quarter of its shift, is declared (noise of seed 5, as above).
    fn declared_with_dips(dips: &[usize]) -> Option<usize> {
        let ctx = context(5);
        let mut noise = Noise::new(5);
        let mut d = learned(&mut noise, &ctx);
        let shift = GAIN * ctx.step_rad;
        run(
            &mut d,
            20,
            |k| {
                if dips.contains(&k) {
                    0.25 * shift
                } else {
                    shift
                }
            },
            &mut noise,
            &ctx,
        )
        .map(|(k, _)| k)
    }

    #[test]
    fn a_run_goes_on_through_one_block_short_of_half_the_shift_but_not_two() {
        // Without a dip: the 5th block (as above).
        assert_eq!(declared_with_dips(&[]), Some(4));
        // One block short of half the shift: the run goes on without counting it, declared one
        // block later.
        assert_eq!(declared_with_dips(&[2]), Some(5));
        // Two in a row end the run: a new one starts after them and lasts the persistence.
        assert_eq!(declared_with_dips(&[2, 3]), Some(8));
        // Dips one block apart: each is one alone, the run goes on (declared at 5 blocks of it).
        assert_eq!(declared_with_dips(&[1, 3, 5]), Some(7));
    }

    #[test]
    fn a_change_smaller_than_half_the_step_or_a_passing_one_is_never_declared() {
        let ctx = context(5);
        let mut noise = Noise::new(7);
        let mut d = learned(&mut noise, &ctx);
        // A drift's lag: a persistent shift of 0.4 of the smallest step's.
        let lag = 0.4 * GAIN * ctx.step_rad;
        assert_eq!(run(&mut d, 2_000, |_| lag, &mut noise, &ctx), None);
        // A disturbance of 4 blocks, 100 times the step's shift, every 20 blocks: held while it
        // lasts, never declared.
        let mut d = learned(&mut noise, &ctx);
        let pulse = |k: usize| {
            if k % 20 < 4 {
                100.0 * GAIN * ctx.step_rad
            } else {
                0.0
            }
        };
        assert_eq!(run(&mut d, 2_000, pulse, &mut noise, &ctx), None);
        // The block variance stayed that of the noise: the blocks that held are left out.
        let learned_sigma = libm::sqrt(f64::from(d.block_variance(0, 0.0))) as Real;
        assert!(learned_sigma < 2.0 * SIGMA, "{learned_sigma}");
    }

    #[test]
    fn nothing_is_declared_before_the_variance_is_learned() {
        let mut d = ChangeDetector::NEW;
        let mut ctx = context(5);
        ctx.armed = false;
        let shift = 10.0 * ctx.step_rad;
        let mut noise = Noise::new(9);
        assert_eq!(run(&mut d, 200, |_| shift, &mut noise, &ctx), None);
        // The 1-sigma is widened by tested blocks alone.
        assert_eq!(d.widening_rad(), &[0.0; 4]);
    }

    #[test]
    fn before_the_first_test_a_gross_disturbance_holds_the_filter_no_longer_than_a_passing_one() {
        let mut ctx = context(5);
        ctx.armed = false;
        let mut noise = Noise::new(11);
        let gross = 100.0 * GAIN * ctx.step_rad;
        let block = |noise: &mut Noise, shift: Real| {
            [
                shift + SIGMA * noise.gaussian() as Real,
                SIGMA * noise.gaussian() as Real,
            ]
        };
        // Fewer than `HOLD_FROM_BLOCKS` blocks learned: nothing to hold against yet.
        let mut d = ChangeDetector::NEW;
        for _ in 0..HOLD_FROM_BLOCKS - 1 {
            assert_eq!(d.test(0, block(&mut noise, 0.0), [GAIN, GAIN], &ctx), None);
        }
        assert_eq!(
            d.test(0, block(&mut noise, gross), [GAIN, GAIN], &ctx),
            None
        );
        assert!(!d.holding());
        // Learned from enough blocks: a disturbance of 4 blocks holds the filter while it lasts.
        let mut d = ChangeDetector::NEW;
        for _ in 0..2 * HOLD_FROM_BLOCKS {
            assert_eq!(d.test(0, block(&mut noise, 0.0), [GAIN, GAIN], &ctx), None);
        }
        for _ in 0..4 {
            assert_eq!(
                d.test(0, block(&mut noise, gross), [GAIN, GAIN], &ctx),
                None
            );
            assert!(d.holding());
        }
        assert_eq!(d.test(0, block(&mut noise, 0.0), [GAIN, GAIN], &ctx), None);
        assert!(!d.holding());
        // One that persists holds no longer than the persistence, and is never declared.
        let mut held = 0;
        for _ in 0..50 {
            assert_eq!(
                d.test(0, block(&mut noise, gross), [GAIN, GAIN], &ctx),
                None
            );
            held += usize::from(d.holding());
        }
        assert_eq!(held, ctx.persistence_blocks as usize - 1);
        assert_eq!(d.widening_rad(), &[0.0; 4]);
    }
}
