//! Eq (8): correlating roll and pitch with the rotation angle, and each channel's measurement row.
//!
//! # The four channels
//! Eq (2)'s errors times a reference have a slow part (product-to-sum identities); the rest are
//! harmonics at `2 rho`, `2 rho - s` or `2(rho - s)`, which the one-period average of eq (11)
//! ([`crate::moving_average`]) blocks with the sway of eq (4) and the errors of eq (5):
//!
//! ```text
//! d_pitch sin(rho-s) -> x1/2        d_pitch cos(rho-s) -> -x2/2
//! d_roll sin rho     -> x3 cosL/2 - x1 sinL sin(s)/2 - x2 sinL cos(s)/2
//! d_roll cos rho     -> -x4 cosL/2 - x1 sinL cos(s)/2 + x2 sinL sin(s)/2
//! ```
//!
//! Each channel ([`PITCH_SIN`], [`PITCH_COS`], [`ROLL_SIN`], [`ROLL_COS`]) isolates one error; the
//! roll channels also carry x1, x2 (eq (12)'s leakage), a slow term with known coefficients that
//! the default filter models. The derivation, and eq (12)'s x1 and x2 exchanged: docs/method.md,
//! "Eq (2) and the four channels (eq 8)" and "Where the paper's algebra and the simulation
//! disagree".
//!
//! # Any rotation pattern: a centred, low-passed reference
//! With `c` a channel's reference, `y` its attitude and `h` eq (2)'s row of `y`, over the samples
//! in the window, `z = mean((c - mean c) y)` and its row `mean((c - mean c) h)`: `z = row . x +
//! (sway, noise)` whatever the pattern and whatever is missing, and a constant heel or trim cancels
//! exactly. `c` is low-passed ([`ReferenceFilter`], three stages of [`REFERENCE_TIME_CONSTANT_S`])
//! so that a stop-and-go pattern's harmonics do not correlate with the sway; `z` and its row use
//! the same `c`, so nothing is biased. Derivation: docs/method.md, "Any rotation pattern".
//!
//! # Heel in turns
//! Roll also holds the heel `k u`, `k` the state [`HEEL_STATE`] and `u` the rate of turn (the
//! heading less eq (2)'s heading oscillation of the estimate): the roll rows' fifth column is
//! `mean((c - mean c) u)`, and the turn channel correlates roll with the low-passed `u` as its
//! reference. When `k` is learned: [`crate::methods::windowed::heel`].
//!
//! # Exact running sums
//! The window keeps the sums of these products ([`CorrelationSums`]), each sample in fixed point
//! ([`QuantizedSample`]: attitude 2^30 counts per rad, sines and cosines 2^14) and every product
//! formed in integers: a sample subtracted leaves the sums exactly as before it was added (no
//! drift; host and target bit for bit), and `z` and its row use the same quantized reference.

use crate::installation::Angles;
use crate::math::round_to_i32;
use crate::sample::Attitude;
use crate::Real;

/// Index of the channel that isolates x1: pitch * sin(rho - s).
pub const PITCH_SIN: usize = 0;
/// Index of the channel that isolates x2: pitch * cos(rho - s).
pub const PITCH_COS: usize = 1;
/// Index of the channel that isolates x3: roll * sin(rho).
pub const ROLL_SIN: usize = 2;
/// Index of the channel that isolates x4: roll * cos(rho).
pub const ROLL_COS: usize = 3;
/// The pitch channels (x1, x2), as a pair the filter takes in turn with [`ROLL_PAIR`].
pub const PITCH_PAIR: usize = 0;
/// The roll channels (x3, x4 and the leakage of x1, x2).
pub const ROLL_PAIR: usize = 1;

/// States of the windowed method's filter: x1..x4 and the heel per rate of turn
/// ([`HEEL_STATE`]).
pub const STATES: usize = 5;

/// Index of the state of the heel in turns: the roll the ship takes at a rate of turn of
/// [`TURN_RATE_UNIT_RAD_S`], rad (see "Heel in turns" in the module doc).
pub const HEEL_STATE: usize = 4;

/// The rate of turn the heel state is the heel at, rad/s (0.057 deg/s): a ship heeling 6 deg per
/// deg/s of turn rate heels 0.006 rad at it.
pub const TURN_RATE_UNIT_RAD_S: Real = 0.001;

/// Fixed-point counts per [`TURN_RATE_UNIT_RAD_S`] of a rate of turn: an `i16` holds rates up to
/// 0.128 rad/s (7.3 deg/s) to 3.9e-6 rad/s.
pub const RATE_COUNTS: f64 = 256.0;

/// The four correlation products of one sample, in channel order (the paper's method uses them
/// as they are).
pub fn products(attitude: &Attitude, angles: &Angles) -> [Real; 4] {
    [
        attitude.pitch_rad * angles.sin_rho_s,
        attitude.pitch_rad * angles.cos_rho_s,
        attitude.roll_rad * angles.sin_rho,
        attitude.roll_rad * angles.cos_rho,
    ]
}

/// Time constant of each of the reference's three low-pass stages, s.
pub const REFERENCE_TIME_CONSTANT_S: f64 = 10.0;

/// The low-passed references `(sin(rho-s), cos(rho-s), sin rho, cos rho)` in channel order, and
/// the turn channel's, the rate of turn in units of [`TURN_RATE_UNIT_RAD_S`]: three one-pole stages
/// in series (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReferenceFilter {
    /// Each stage's output per reference; meaningless until `started`.
    stages: [[Real; 5]; 3],
    started: bool,
}

/// The references of one sample: the four channels' and the turn channel's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct References {
    /// The low-passed references of the four channels (`sin(rho-s)`, `cos(rho-s)`, `sin rho`,
    /// `cos rho`), in channel order.
    pub channels: [Real; 4],
    /// The rate of turn, low-passed, in units of [`TURN_RATE_UNIT_RAD_S`].
    pub turn: Real,
}

impl ReferenceFilter {
    /// Not started.
    pub const NEW: ReferenceFilter = ReferenceFilter {
        stages: [[0.0; 5]; 3],
        started: false,
    };

    /// The stage gain for a sample interval: `1 - exp(-dt / tau)`.
    pub fn alpha(interval_s: f64) -> Real {
        (1.0 - libm::exp(-interval_s / REFERENCE_TIME_CONSTANT_S)) as Real
    }

    /// Filters one sample's references with stage gain `alpha`; the first sample starts every
    /// stage at its value. `turn_rate` in units of [`TURN_RATE_UNIT_RAD_S`].
    pub fn filter(&mut self, angles: &Angles, turn_rate: Real, alpha: Real) -> References {
        let c = [
            angles.sin_rho_s,
            angles.cos_rho_s,
            angles.sin_rho,
            angles.cos_rho,
            turn_rate,
        ];
        let out = if !self.started {
            self.stages = [c; 3];
            self.started = true;
            c
        } else {
            let mut input = c;
            for stage in &mut self.stages {
                for ch in 0..5 {
                    stage[ch] += alpha * (input[ch] - stage[ch]);
                }
                input = *stage;
            }
            input
        };
        References {
            channels: [out[0], out[1], out[2], out[3]],
            turn: out[4],
        }
    }
}

/// Fixed-point counts per rad of roll and pitch.
pub const ATTITUDE_COUNTS: f64 = (1u64 << 30) as f64;
/// Fixed-point counts per unit of a sine or cosine.
pub const TRIG_COUNTS: f64 = (1u64 << 14) as f64;

/// One sample's inputs to the sums, in fixed point: the attitude, the angles' sines and cosines
/// (for eq (2)'s rows) and the low-passed references.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QuantizedSample {
    /// Roll, [`ATTITUDE_COUNTS`] per rad.
    pub roll: i32,
    /// Pitch, [`ATTITUDE_COUNTS`] per rad.
    pub pitch: i32,
    /// `sin rho`, [`TRIG_COUNTS`] per unit.
    pub sin_rho: i16,
    /// `cos rho`, [`TRIG_COUNTS`] per unit.
    pub cos_rho: i16,
    /// `sin(rho-s)`, [`TRIG_COUNTS`] per unit.
    pub sin_rho_s: i16,
    /// `cos(rho-s)`, [`TRIG_COUNTS`] per unit.
    pub cos_rho_s: i16,
    /// `sin L`, [`TRIG_COUNTS`] per unit.
    pub sin_lat: i16,
    /// `cos L`, [`TRIG_COUNTS`] per unit.
    pub cos_lat: i16,
    /// The references of the four channels, low-passed ([`ReferenceFilter`]), in channel order.
    pub reference: [i16; 4],
    /// The rate of turn in [`RATE_COUNTS`] per [`TURN_RATE_UNIT_RAD_S`] (saturating).
    pub turn_rate: i16,
    /// The turn channel's reference, the low-passed rate of turn, in the same counts.
    pub turn_reference: i16,
}

/// A sine, cosine or reference in fixed point ([`TRIG_COUNTS`] per unit), clamped to +-1; NaN
/// gives 0.
pub fn trig_count(v: Real) -> i16 {
    round_to_i32(v * TRIG_COUNTS as Real).clamp(-MAX_TRIG_COUNT, MAX_TRIG_COUNT) as i16
}

/// Largest count of a quantized sine, cosine or reference (1 in [`TRIG_COUNTS`]).
const MAX_TRIG_COUNT: i32 = 1 << 14;

impl QuantizedSample {
    /// Rounds a sample's roll, pitch, trigonometry and references to fixed point.
    ///
    /// No floating-point clamp: the conversion to `i32` saturates and takes NaN to 0, so an
    /// attitude beyond +-2 rad (impossible: roll and pitch are checked to within 90 deg) stays at
    /// +-2^31 counts, and a sine, cosine or reference is clamped to +-1 in integers (one `ssat`
    /// on the Cortex-M4F, where a float clamp is two library calls or four compares a value).
    pub fn new(
        roll_rad: Real,
        pitch_rad: Real,
        angles: &Angles,
        reference: &References,
        turn_rate: Real,
    ) -> QuantizedSample {
        let att = |v: Real| round_to_i32(v * ATTITUDE_COUNTS as Real);
        let rate = |u: Real| {
            round_to_i32(u * RATE_COUNTS as Real).clamp(i32::from(i16::MIN), i32::from(i16::MAX))
                as i16
        };
        QuantizedSample {
            roll: att(roll_rad),
            pitch: att(pitch_rad),
            sin_rho: trig_count(angles.sin_rho),
            cos_rho: trig_count(angles.cos_rho),
            sin_rho_s: trig_count(angles.sin_rho_s),
            cos_rho_s: trig_count(angles.cos_rho_s),
            sin_lat: trig_count(angles.sin_lat),
            cos_lat: trig_count(angles.cos_lat),
            reference: reference.channels.map(trig_count),
            turn_rate: rate(turn_rate),
            turn_reference: rate(reference.turn),
        }
    }

    /// The products summed by the window, in the order of [`CorrelationSums::sums`] (see there),
    /// each times the weight `w` (0 to [`FULL_WEIGHT`]). The weight is folded into the factors
    /// before the products are formed (into the references, and into the terms without a
    /// reference), so that weighting costs a dozen small integer products rather than one 64-bit
    /// product a term.
    pub fn terms(&self, w: u8) -> [i64; SUMS] {
        self.signed_terms(i32::from(w.min(FULL_WEIGHT)))
    }

    /// [`QuantizedSample::terms`] for a weight `w` of either sign (-[`FULL_WEIGHT`] to
    /// [`FULL_WEIGHT`]). Each product has exactly one factor that carries the weight, so the
    /// terms for `-w` are exactly those for `w` negated: an entry is taken out of the sums by
    /// adding its terms for `-w` ([`CorrelationSums::replace`]).
    // On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
    #[inline(always)]
    fn signed_terms(&self, w: i32) -> [i64; SUMS] {
        let (sr, cr, ss, cs) = (
            i32::from(self.sin_rho),
            i32::from(self.cos_rho),
            i32::from(self.sin_rho_s),
            i32::from(self.cos_rho_s),
        );
        let (sl, cl) = (i32::from(self.sin_lat), i32::from(self.cos_lat));
        // The references times the weight: within 2^14 x 2^6.
        let [c0, c1, c2, c3] = self.reference.map(|c| i32::from(c) * w);
        let (r, p) = (i64::from(self.roll), i64::from(self.pitch));
        let u = i32::from(self.turn_rate);
        let uf = i32::from(self.turn_reference) * w;
        let w64 = i64::from(w);
        // eq (2)'s roll row without its signs: sinL cos(rho-s), sinL sin(rho-s), cosL sin rho, cosL cos rho.
        let (h0, h1, h2, h3) = (sl * cs, sl * ss, cl * sr, cl * cr);
        let m = |a: i32, b: i32| i64::from(a) * i64::from(b);
        [
            i64::from(c0),
            i64::from(c1),
            i64::from(c2),
            i64::from(c3),
            i64::from(ss * w),
            i64::from(cs * w),
            r * w64,
            p * w64,
            p * i64::from(c0),
            p * i64::from(c1),
            r * i64::from(c2),
            r * i64::from(c3),
            m(c0, ss),
            m(c0, cs),
            m(c1, ss),
            m(c1, cs),
            i64::from(h0) * w64,
            i64::from(h1) * w64,
            i64::from(h2) * w64,
            i64::from(h3) * w64,
            m(c2, h0),
            m(c2, h1),
            m(c2, h2),
            m(c2, h3),
            m(c3, h0),
            m(c3, h1),
            m(c3, h2),
            m(c3, h3),
            i64::from(u * w),
            m(c2, u),
            m(c3, u),
            // The turn channel: the low-passed rate of turn as the reference of roll.
            i64::from(uf),
            r * i64::from(uf),
            m(uf, h0),
            m(uf, h1),
            m(uf, h2),
            m(uf, h3),
            m(uf, u),
        ]
    }
}

/// Number of running sums.
pub const SUMS: usize = 38;

/// The weight of an entry that counts in full (see [`CorrelationSums`]); a sample next to a run of
/// lost rows counts less ([`crate::gap_fill`]).
pub const FULL_WEIGHT: u8 = 64;

/// The window's exact running sums.
///
/// Each entry is added with its weight `w` (0 to [`FULL_WEIGHT`]): the sums are of `w` times the
/// products, and the means divide by the sum of the weights, so a weighted mean of every product
/// and `z = row . x` holds for any weights. With `w` at most 64 (2^6) and at most 2^46 per product,
/// a window of up to 2^11 entries stays within `i64`.
///
/// `sums`, in fixed-point counts (T = 2^14 per unit of a sine or cosine, A = 2^30 per rad), with
/// `c0..c3` the channels' low-passed references (of `sin(rho-s)`, `cos(rho-s)`, `sin rho`,
/// `cos rho`): 0-3 `c0..c3` (T); 4-5 `sin(rho-s)`, `cos(rho-s)` (T); 6-7 roll, pitch (A); 8-11
/// the channel products pitch `c0`, pitch `c1`, roll `c2`, roll `c3` (A T); 12-15 `c0 sin(rho-s)`,
/// `c0 cos(rho-s)`, `c1 sin(rho-s)`, `c1 cos(rho-s)` (T^2); 16-19 the roll row's terms
/// `sinL cos(rho-s)`, `sinL sin(rho-s)`, `cosL sin rho`, `cosL cos rho` (T^2); 20-23 `c2` times
/// each of those, 24-27 `c3` times each (T^3). Magnitudes: at most 2^46 per sample, so `i64`
/// holds more than 2^16 samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CorrelationSums {
    /// Samples (window entries) summed.
    pub count: u32,
    /// The [`SUMS`] sums of the weighted products, in fixed-point counts, in the order above.
    pub sums: [i64; SUMS],
    /// Sum of the entries' fill weights (see [`crate::gap_fill`]).
    pub fill_weight: u32,
    /// Sum of the entries' weights (a full-weight entry counts [`FULL_WEIGHT`]).
    pub weight: u32,
}

impl CorrelationSums {
    /// Nothing summed.
    pub const ZERO: CorrelationSums = CorrelationSums {
        count: 0,
        sums: [0; SUMS],
        fill_weight: 0,
        weight: 0,
    };
}

impl Default for CorrelationSums {
    fn default() -> Self {
        Self::ZERO
    }
}

/// An exact sum in the step's float type: its high and low 32 bits converted apart (one FPU
/// instruction each on the Cortex-M4F, against a library call of dozens for a 64-bit integer)
/// and added. Rounds twice, within 2 ulp; IEEE operations only, so every target agrees.
fn to_real(v: i64) -> Real {
    let high = (v >> 32) as i32;
    let low = v as u32;
    high as Real * 4_294_967_296.0 + low as Real
}

/// A window's measurement: the four channels and their rows (`z = rows x`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// The four channels' centred means, rad, in channel order.
    pub z: [Real; 4],
    /// Each channel's row: the coefficients of the [`STATES`] states in its `z`.
    pub rows: [[Real; STATES]; 4],
    /// The turn channel (roll with the rate of turn as its reference; with the roll pair only):
    /// its measurement and row.
    pub turn_z: Real,
    /// The turn channel's row: the coefficients of the [`STATES`] states in `turn_z`.
    pub turn_row: [Real; STATES],
}

impl CorrelationSums {
    /// Adds one entry of weight `weight` (at most [`FULL_WEIGHT`]) and fill weight `fill_weight`.
    pub fn add(&mut self, q: &QuantizedSample, fill_weight: u32, weight: u8) {
        let t = q.terms(weight);
        for i in 0..SUMS {
            self.sums[i] += t[i];
        }
        self.count += 1;
        self.fill_weight = self.fill_weight.saturating_add(fill_weight);
        self.weight += u32::from(weight.min(FULL_WEIGHT));
    }

    /// Subtracts an entry added before: exactly undoes [`CorrelationSums::add`].
    pub fn subtract(&mut self, q: &QuantizedSample, fill_weight: u32, weight: u8) {
        let t = q.terms(weight);
        for i in 0..SUMS {
            self.sums[i] -= t[i];
        }
        self.count = self.count.saturating_sub(1);
        self.fill_weight = self.fill_weight.saturating_sub(fill_weight);
        self.weight = self
            .weight
            .saturating_sub(u32::from(weight.min(FULL_WEIGHT)));
    }

    /// Subtracts the entry `old` and adds `new`: the same sums as [`CorrelationSums::subtract`]
    /// then [`CorrelationSums::add`] (integers: exact in any order), what a window does every
    /// sample once it is full. Both are one pass of the same out-of-line code over the sums
    /// (`CorrelationSums::add_signed_terms`), the old entry's with its weight negated: one copy
    /// of the products' code in the image, each product multiply-accumulated into its sum.
    pub fn replace(
        &mut self,
        old: &QuantizedSample,
        old_fill_weight: u32,
        old_weight: u8,
        new: &QuantizedSample,
        fill_weight: u32,
        weight: u8,
    ) {
        // An entry of weight 0 adds nothing (every term carries the weight): not run.
        for (q, w) in [
            (new, i32::from(weight.min(FULL_WEIGHT))),
            (old, -i32::from(old_weight.min(FULL_WEIGHT))),
        ] {
            if w != 0 {
                self.add_signed_terms(q, w);
            }
        }
        self.fill_weight = self
            .fill_weight
            .saturating_sub(old_fill_weight)
            .saturating_add(fill_weight);
        self.weight = self
            .weight
            .saturating_sub(u32::from(old_weight.min(FULL_WEIGHT)))
            + u32::from(weight.min(FULL_WEIGHT));
    }

    /// Adds the terms of `q` for the weight `w` (either sign: [`QuantizedSample::signed_terms`]),
    /// written out sum by sum rather than looped, so that each product is formed next to its sum
    /// and accumulated into it, not the whole list stored on the stack first and read back. Out
    /// of line: [`CorrelationSums::replace`] runs it for the entry going and the one coming.
    #[inline(never)]
    fn add_signed_terms(&mut self, q: &QuantizedSample, w: i32) {
        let t = q.signed_terms(w);
        macro_rules! each_sum {
            ($($i:literal)*) => {
                const _: () = assert!([$($i),*].len() == SUMS);
                $(self.sums[$i] += t[$i];)*
            };
        }
        each_sum!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32 33 34 35 36 37);
    }

    /// The centred measurement of the module doc, or `None` for an empty window.
    pub fn measurement(&self) -> Option<Measurement> {
        let pitch = self.measurement_of(PITCH_PAIR)?;
        let roll = self.measurement_of(ROLL_PAIR)?;
        Some(Measurement {
            z: [pitch.z[0], pitch.z[1], roll.z[2], roll.z[3]],
            rows: [pitch.rows[0], pitch.rows[1], roll.rows[2], roll.rows[3]],
            turn_z: roll.turn_z,
            turn_row: roll.turn_row,
        })
    }

    /// The measurement of one channel pair only ([`PITCH_PAIR`] or [`ROLL_PAIR`]; the other
    /// pair's channels are left zero), from only the sums it needs: the filter takes one pair a
    /// step, and the conversion of the sums is most of the measurement's cost. The same values as
    /// [`CorrelationSums::measurement`], bit for bit.
    #[inline(always)]
    pub fn measurement_of(&self, pair: usize) -> Option<Measurement> {
        if self.count == 0 || self.weight == 0 {
            return None;
        }
        // The sums are of weighted products: their means divide by the sum of the weights. The
        // scales are powers of two: exact in f32, and no software f64 on the Cortex-M4F.
        let inv_n = 1.0 / self.weight as Real;
        let t = inv_n / TRIG_COUNTS as Real;
        let tt = t / TRIG_COUNTS as Real;
        let ttt = tt / TRIG_COUNTS as Real;
        let a = inv_n / ATTITUDE_COUNTS as Real;
        let at = a / TRIG_COUNTS as Real;
        let m = |i: usize, scale: Real| to_real(self.sums[i]) * scale;
        let cov = |mean_product: Real, a: Real, b: Real| mean_product - a * b;
        let mut out = Measurement {
            z: [0.0; 4],
            rows: [[0.0; STATES]; 4],
            turn_z: 0.0,
            turn_row: [0.0; STATES],
        };
        if pair == PITCH_PAIR {
            let (c0, c1, ss, cs, pitch) = (m(0, t), m(1, t), m(4, t), m(5, t), m(7, a));
            out.z[0] = cov(m(8, at), pitch, c0);
            out.z[1] = cov(m(9, at), pitch, c1);
            out.rows[0] = [
                cov(m(12, tt), c0, ss),
                -cov(m(13, tt), c0, cs),
                0.0,
                0.0,
                0.0,
            ];
            out.rows[1] = [
                cov(m(14, tt), c1, ss),
                -cov(m(15, tt), c1, cs),
                0.0,
                0.0,
                0.0,
            ];
        } else {
            let (c2, c3, roll) = (m(2, t), m(3, t), m(6, a));
            let h = [m(16, tt), m(17, tt), m(18, tt), m(19, tt)];
            // The rate of turn in units of the heel state's rate.
            let tu = t / RATE_COUNTS as Real;
            let rate = m(28, inv_n / RATE_COUNTS as Real);
            out.z[2] = cov(m(10, at), roll, c2);
            out.z[3] = cov(m(11, at), roll, c3);
            out.rows[2] = [
                -cov(m(20, ttt), c2, h[0]),
                -cov(m(21, ttt), c2, h[1]),
                cov(m(22, ttt), c2, h[2]),
                -cov(m(23, ttt), c2, h[3]),
                cov(m(29, tu), c2, rate),
            ];
            out.rows[3] = [
                -cov(m(24, ttt), c3, h[0]),
                -cov(m(25, ttt), c3, h[1]),
                cov(m(26, ttt), c3, h[2]),
                -cov(m(27, ttt), c3, h[3]),
                cov(m(30, tu), c3, rate),
            ];
            let ut = ttt * (TRIG_COUNTS / RATE_COUNTS) as Real;
            let turn_ref = m(31, inv_n / RATE_COUNTS as Real);
            out.turn_z = cov(m(32, a / RATE_COUNTS as Real), roll, turn_ref);
            out.turn_row = [
                -cov(m(33, ut), turn_ref, h[0]),
                -cov(m(34, ut), turn_ref, h[1]),
                cov(m(35, ut), turn_ref, h[2]),
                -cov(m(36, ut), turn_ref, h[3]),
                cov(
                    m(37, inv_n / (RATE_COUNTS * RATE_COUNTS) as Real),
                    turn_ref,
                    rate,
                ),
            ];
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sin_cos;

    fn angles(rho: f64, s: f64, lat: f64) -> Angles {
        Angles::new(rho as Real, s as Real, sin_cos(lat as Real))
    }

    /// A sample whose references are the unfiltered sines and cosines.
    fn quantized(roll: Real, pitch: Real, a: &Angles) -> QuantizedSample {
        QuantizedSample::new(
            roll,
            pitch,
            a,
            &References {
                channels: [a.sin_rho_s, a.cos_rho_s, a.sin_rho, a.cos_rho],
                turn: 0.0,
            },
            0.0,
        )
    }

    #[test]
    fn rows_of_a_uniform_rotation_are_the_derived_slow_parts() {
        let (lat, s) = (0.7f64, 1.3f64);
        let mut sums = CorrelationSums::default();
        for k in 0..480 {
            let rho = 0.2 + 2.0 * core::f64::consts::PI * k as f64 / 480.0;
            sums.add(&quantized(0.0, 0.0, &angles(rho, s, lat)), 0, FULL_WEIGHT);
        }
        let rows = sums.measurement().unwrap().rows;
        let (sl, cl) = (lat.sin() as Real, lat.cos() as Real);
        let (ssn, scs) = (s.sin() as Real, s.cos() as Real);
        let expected = [
            [0.5, 0.0, 0.0, 0.0],
            [0.0, -0.5, 0.0, 0.0],
            [-0.5 * sl * ssn, -0.5 * sl * scs, 0.5 * cl, 0.0],
            [-0.5 * sl * scs, 0.5 * sl * ssn, 0.0, -0.5 * cl],
        ];
        for i in 0..4 {
            for j in 0..4 {
                assert!(
                    (rows[i][j] - expected[i][j]).abs() < 2e-4,
                    "row {i} col {j}: {} vs {}",
                    rows[i][j],
                    expected[i][j]
                );
            }
        }
    }

    #[test]
    fn subtracting_every_sample_added_returns_exactly_to_zero() {
        let mut sums = CorrelationSums::default();
        let qs: std::vec::Vec<QuantizedSample> = (0..300)
            .map(|k| {
                quantized(
                    0.05 * (k as Real).sin(),
                    -0.02,
                    &angles(k as f64 * 0.7, 0.1, 0.5),
                )
            })
            .collect();
        for (k, q) in qs.iter().enumerate() {
            sums.add(q, 1, (k % 65) as u8);
        }
        for (k, q) in qs.iter().enumerate() {
            sums.subtract(q, 1, (k % 65) as u8);
        }
        assert_eq!(sums, CorrelationSums::default());
    }

    /// One pass of `replace` (the old entry's terms taken out by its negated weight) gives the
    /// sums of `subtract` then `add`, exactly, for every weight and at the largest magnitudes
    /// (roll and pitch at 90 deg, a turn rate at the counts' limit).
    #[test]
    fn replace_is_subtract_then_add_exactly() {
        let sample = |k: usize| {
            let a = angles(k as f64 * 0.9, 0.3 * k as f64, 1.2 - 0.1 * k as f64);
            let r = References {
                channels: [a.sin_rho_s, -a.cos_rho_s, a.sin_rho, a.cos_rho],
                turn: [0.0, 1e9, -1e9, 3.7][k % 4],
            };
            let att = [1.57, -1.57, 0.3, -1e-6][k % 4];
            QuantizedSample::new(att, -att, &a, &r, [1e9, -1e9, -2.5, 0.0][(k + 1) % 4])
        };
        let mut direct = CorrelationSums::default();
        let mut replaced = CorrelationSums::default();
        for k in 0..300usize {
            let (old, new) = (sample(k), sample(k + 1));
            let (ow, nw) = ((k * 7 % 70) as u8, (k * 13 % 70) as u8);
            direct.add(&old, 2, ow);
            replaced.add(&old, 2, ow);
            direct.subtract(&old, 2, ow);
            direct.add(&new, 3, nw);
            replaced.replace(&old, 2, ow, &new, 3, nw);
            assert_eq!(replaced.sums, direct.sums, "entry {k}");
            assert_eq!(replaced.weight, direct.weight, "entry {k}");
            assert_eq!(replaced.fill_weight, direct.fill_weight, "entry {k}");
        }
    }

    #[test]
    fn a_constant_offset_does_not_leak_into_any_channel_whatever_the_pattern() {
        // Four positions with uneven dwells (the reference does not average to zero), 3 deg heel.
        let heel = (3.0f64).to_radians() as Real;
        let mut sums = CorrelationSums::default();
        for k in 0..480 {
            // The positions to four decimals, as an encoder reads them (not the exact constants).
            #[allow(clippy::approx_constant)]
            let rho = [0.0, 1.5708, 3.1416, 4.7124][(k * 7 / 480) % 4];
            sums.add(
                &quantized(heel, -heel, &angles(rho, 0.4, 0.6)),
                0,
                [FULL_WEIGHT, 17, 0, 40][k % 4],
            );
        }
        let z = sums.measurement().unwrap().z;
        for (ch, v) in z.iter().enumerate() {
            // One fixed-point count of a mean product is below 1e-7 arcsec; f32 rounding of the
            // means leaves a few 1e-9 rad.
            assert!(v.abs() < 1e-8, "channel {ch}: {v:e} rad");
        }
    }
}
