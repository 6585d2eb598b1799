//! Changes of the installation errors, detected from the filter's residuals.
//!
//! A re-installation or a shock moves the errors by a step `D`. The filter, whose memory grows
//! without bound while the errors look constant, barely moves; the step shows in its post-fit
//! residuals `e = z - H x`, ramping over one window to `H D` and staying there. This detector
//! decides from those residuals that the errors have changed, and which, so that
//! [`super::Windowed`] can learn them again. What holds (the derivation, with the false-alarm
//! bound, is in docs/method.md, "The change detector"; what logs show, in docs/uncertainty.md,
//! "Changes of the errors"):
//!
//! - **Blocks**: each pair's residuals are averaged over blocks of half a period, or a quarter, an
//!   eighth... at long periods, at most [`MAX_BLOCK_S`] ([`block_entries`]): a block mean weighs
//!   the products with a trapezoid that takes the sway down far below a window's residual.
//! - **Variance**: a block mean's variance `s^2` is learned from the blocks (clipped at
//!   [`WINSOR_SIGMAS`], over [`VARIANCE_BLOCKS`]), never below the model's
//!   ([`block_variance_factor`]); with the learned lag-one correlation `rho` the run's variance is
//!   the AR(1) long-run one, `s^2 (1 + rho) / (1 - rho)`.
//! - **Test**: the log-likelihood ratio between no change and a change of the smallest size
//!   (`Config::change_detection_step_rad` times the channel's gain) is summed over a run of blocks
//!   beyond half that shift, through at most one dip at a time. A change is declared when the sum
//!   reaches [`LLR_THRESHOLD`] and the run has lasted [`persistence_blocks`], longer than a passing
//!   disturbance can make it. By Markov's inequality a run reaches the threshold `h` with
//!   probability at most `exp(-h)` per block, channel and direction.
//! - **Hold**: a block in a run and beyond [`HOLD_SIGMAS`] holds the filter's updates, and the
//!   block's excess widens the 1-sigma, until the change is declared or the run ends; before the
//!   first test ([`MIN_VARIANCE_BLOCKS`]) only a block beyond [`UNTESTED_HOLD_SIGMAS`] holds, from
//!   [`HOLD_FROM_BLOCKS`] on, and nothing is declared.
//!
//! Per update the detector costs two additions; per block and channel three divisions, a root
//! and two dozen multiply-adds.

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
/// variance learned so far holds the filter (docs/method.md, "Before the first test").
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
    /// beyond [`HOLD_SIGMAS`] standard deviations (docs/method.md, "While a change builds up").
    pub fn holding(&self) -> bool {
        self.holding.iter().any(|h| *h)
    }

    /// The learned lag-one correlation of each channel's block means (docs/method.md, "Correlated
    /// blocks").
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
        // Before that, a gross disturbance still holds the filter (docs/method.md, "Before the
        // first test").
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
                declared |= self.extend_runs(ch, b, gains[k] * ctx.step_rad, var, testing, ctx);
                self.hold_and_widen(ch, b, gains[k], var, testing, ctx);
            }
            // A block that holds the filter is a disturbance or a change, not the blocks' noise;
            // before the first test, one that holds is learned from all the same (clipped), see
            // docs/method.md, "Before the first test".
            if ctx.settled && !(testing && self.holding[ch]) {
                self.learn_block(ch, b, var, learned, weight);
            }
            self.previous_block_rad[ch] = b;
        }
        if ctx.settled && !(testing && (self.holding[2 * pair] || self.holding[2 * pair + 1])) {
            self.learned_blocks[pair] = count;
        }
        if !declared {
            return None;
        }
        Some(self.alarm())
    }

    /// Adds block mean `b` of channel `ch` (of variance `var`) to the channel's runs, a rise and
    /// a fall of the smallest shift `a`: a block beyond `a / 2` extends the run, one short of it is
    /// a dip (`testing` only) or ends it. Before the first test (`testing` false) runs are counted
    /// for the hold alone. Returns whether a run is now long enough and its sum high enough for a
    /// change to be declared.
    // Called once, on the step's path.
    #[inline(always)]
    fn extend_runs(
        &mut self,
        ch: usize,
        b: Real,
        a: Real,
        var: Real,
        testing: bool,
        ctx: &BlockContext,
    ) -> bool {
        let mut declared = false;
        // The run's blocks are not independent: the long-run variance of an AR(1) of the learned
        // lag-one correlation (docs/method.md, "Correlated blocks").
        let rho = (self.lag_product_rad2[ch] / var).clamp(0.0, MAX_BLOCK_CORRELATION);
        let run_var = var * (1.0 + rho) / (1.0 - rho);
        for dir in 0..2 {
            // A rise (0) or a fall (1) of the smallest size: at most one direction gains, the one
            // of the block's sign, when |b| > a / 2.
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
                // A dip (docs/method.md, "A dip in a run"): the run goes on, its sum takes the
                // block's ratio, its length does not count the block.
                self.llr[ch][dir] += llr;
                self.dipped[ch][dir] = true;
            } else {
                self.llr[ch][dir] = 0.0;
                self.run[ch][dir] = 0;
                self.dipped[ch][dir] = false;
            }
        }
        declared
    }

    /// Whether channel `ch`'s block `b` (of variance `var`, channel gain `gain`) holds the filter,
    /// and by how much it widens the error's 1-sigma (`testing` only): held while the run is
    /// shorter than a passing disturbance can make it; a longer one is a change (declared) or an
    /// inconsistency the filter must work through.
    // Called once, on the step's path.
    #[inline(always)]
    fn hold_and_widen(
        &mut self,
        ch: usize,
        b: Real,
        gain: Real,
        var: Real,
        testing: bool,
        ctx: &BlockContext,
    ) {
        let run = self.run[ch][0].max(self.run[ch][1]);
        let hold_sigmas = if testing {
            HOLD_SIGMAS
        } else {
            UNTESTED_HOLD_SIGMAS
        };
        self.holding[ch] =
            run > 0 && run < ctx.persistence_blocks && b * b > hold_sigmas * hold_sigmas * var;
        self.widening_rad[ch] = if testing && b * b > 4.0 * var && gain > 1e-6 {
            ((b.abs() - 2.0 * sqrt(var)) / gain).smaller(ctx.max_widening_rad)
        } else {
            0.0
        };
    }

    /// Learns block mean `b` of channel `ch` into its variance and its lag-one covariance, each a
    /// running mean of weight `weight`, clipped at [`WINSOR_SIGMAS`] of the variance `var` once
    /// `learned` blocks are in it.
    // Called once, on the step's path.
    #[inline(always)]
    fn learn_block(&mut self, ch: usize, b: Real, var: Real, learned: u32, weight: Real) {
        // The first block has no variance to be clipped against yet.
        let b2 = if learned == 0 {
            b * b
        } else {
            (b * b).smaller(WINSOR_SIGMAS * WINSOR_SIGMAS * var)
        };
        self.mean_square_rad2[ch] += (b2 - self.mean_square_rad2[ch]) * weight;
        // The product with the previous block, both clipped alike: the lag-one covariance.
        if learned > 0 {
            // max/min, not clamp: clamp's bounds come from a learned value here, and its check of
            // them is a panic that formats floats, which the firmware's flash has no room for.
            let bound = WINSOR_SIGMAS * WINSOR_SIGMAS * var;
            let product = (b * self.previous_block_rad[ch])
                .larger(-bound)
                .smaller(bound);
            self.lag_product_rad2[ch] += (product - self.lag_product_rad2[ch]) * weight;
        }
    }

    /// The change declared: the errors whose channels are in a run, and the longest run.
    // Called once, on the step's path.
    #[inline(always)]
    fn alarm(&self) -> Alarm {
        let mut alarm = Alarm {
            changed: [false; 4],
            run_blocks: 0,
        };
        for ch in 0..4 {
            let run = self.run[ch][0].max(self.run[ch][1]);
            alarm.changed[ch] = run > 0;
            alarm.run_blocks = alarm.run_blocks.max(run);
        }
        alarm
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
