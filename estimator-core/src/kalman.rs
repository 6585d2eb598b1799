//! Eqs (13)-(18): a Kalman filter for constant states.
//!
//! The paper neglects the state equation because installation errors are constant (eq 18): the
//! prediction step is the identity, optionally plus a small random walk `Q` so that slowly drifting
//! errors can be followed. Measurements are scalar and processed one at a time (sequentially), each
//! with the Joseph-form covariance update
//!
//! ```text
//! K  = P h / (h' P h + r)
//! P+ = (I - K h') P (I - K h')' + r K K'
//! ```
//!
//! which stays symmetric positive definite under rounding, unlike `P - K h' P`. `A = I - K h'` is a
//! rank-one change of the identity, so the products are formed without building `A`:
//! `D = A P = P - K b'` (with `b = P h`), `D h = b - K (h' b)`, then
//! `A P A' + r K K' = D - (D h) K' + r K K'`, term by term
//! `P_ij - K_i b_j - (b_i - K_i h'b) K_j + r K_i K_j`: `O(N^2)` instead of the `O(N^3)` of dense
//! products, in place, for any gain (the Schmidt "consider" update zeroes some of it). Together
//! with the Newton square root of [`crate::math`], this keeps the step on the Cortex-M4F within its
//! instruction budget (checked by `host-sim/tests/qemu/qemu_budgets.rs`; the figures in
//! docs/firmware.md). Only the upper triangle is computed; the lower one is its mirror, so the
//! result is symmetric by construction. A measurement whose innovation variance is not positive
//! and finite, or whose value is not finite, is refused and leaves the filter untouched.
//!
//! In `f32` the ratio of prior variance to measurement variance must stay well below 1/eps
//! (1.7e7): the estimator's is about 2e4 (1000 arcsec prior, 7 arcsec measurement).
//!
//! Generic over the scalar `T` (`f32` or `f64`): the windowed and traditional methods run in
//! [`crate::Real`]; the paper's 3-state filters run in `f64` because their states are nearly
//! collinear for hours (`cos w_e t ~ 1` looks like the constant `x`), a covariance whose condition
//! number exceeds what `f32` can hold.

mod checkpoint;

use nalgebra::{ArrayStorage, RealField, SMatrix, SVector};

/// Whether every value is finite, from one sum (a NaN or an infinity anywhere makes it not
/// finite; finite values whose sum overflows count as not finite too).
fn sum_is_finite<T: RealField + Copy>(values: &[T]) -> bool {
    let mut sum = T::zero();
    for v in values {
        sum += *v;
    }
    sum.is_finite()
}

/// Why a measurement was not applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KalmanError {
    /// The measurement, its row or its noise was not finite, or the noise was negative.
    NonFinite,
    /// `h' P h + r` was not positive.
    Degenerate,
    /// The innovation was beyond the gate ([`ConstantStateKalman::update_gated`]).
    Gated,
}

impl core::fmt::Display for KalmanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            KalmanError::NonFinite => {
                write!(f, "measurement, row or noise not finite, or noise negative")
            }
            KalmanError::Degenerate => write!(f, "innovation variance h' P h + r not positive"),
            KalmanError::Gated => write!(f, "innovation beyond the gate"),
        }
    }
}

impl core::error::Error for KalmanError {}

/// A measurement the filter took: its innovation `z - h x` and the gain `K` it was applied with
/// (0 on the states the update left alone).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Applied<T, const N: usize> {
    /// The innovation `z - h x`, before the update.
    pub innovation: T,
    /// The gain `K`.
    pub gain: [T; N],
}

/// Carries a share `C` of the covariance through an update of row `h` and gain `k` (an
/// [`Applied`]): `C+ = (I - k h') C (I - k h')' + r k k'`, with `r` the measurement's variance when
/// the measurement belongs to the share and 0 when it does not. Joseph's form is linear in `P` and
/// `r`: the covariance after an update is the sum of the shares so carried, each measurement's
/// noise added to its own, the prior and the random walk to none. Term by term, with `u = C h`
/// and `s = h' C h`: `C_ij - k_i u_j - u_i k_j + (s + r) k_i k_j`. Only the upper triangle
/// (`[j][k]`, `j <= k`) is read and written; a variance rounded below 0 is set to 0.
///
/// The last state is left out when the update leaves it alone (its gain +0) and the share holds
/// none of it (its column +0), as the estimator's heel state until it is learned: its row and
/// column stay +0 either way, and the rest is the same to the bit (its terms in `u` and `s`, each
/// added last, are zeros, and adding a zero to a sum that starts at +0 leaves it as it is). The
/// test reads the values' bits (an OR of words, no float compares); the loops stay over the
/// constant `N - 1` leading states (unrolled), the last state's terms behind the test.
pub fn carry_share<T: RealField + Copy + ZeroBits, const N: usize>(
    share: &mut [[T; N]; N],
    h: &[T; N],
    k: &[T; N],
    r: T,
) {
    let Some(last) = N.checked_sub(1) else {
        return;
    };
    let mut bits = k[last].zero_bits();
    for row in share.iter() {
        bits |= row[last].zero_bits();
    }
    let with_last = bits != 0;
    let at = |c: &[[T; N]; N], i: usize, j: usize| if i <= j { c[i][j] } else { c[j][i] };
    let mut u = [T::zero(); N];
    for i in 0..last {
        let mut v = T::zero();
        for j in 0..last {
            v += at(share, i, j) * h[j];
        }
        u[i] = v;
    }
    let s_leading = |u: &[T; N]| {
        let mut s = T::zero();
        for i in 0..last {
            s += h[i] * u[i];
        }
        s
    };
    let s = if with_last {
        for i in 0..last {
            u[i] += share[i][last] * h[last];
        }
        let mut v = T::zero();
        for j in 0..N {
            v += share[j][last] * h[j];
        }
        u[last] = v;
        s_leading(&u) + h[last] * v
    } else {
        s_leading(&u)
    };
    let sr = s + r;
    let carry = |c: T, i: usize, j: usize| c + (-k[i] * u[j] - u[i] * k[j] + sr * k[i] * k[j]);
    // A share is a covariance: its variances are not negative (rounding of a share near 0 can
    // make one a few ulps below).
    let not_negative = |c: T| if c < T::zero() { T::zero() } else { c };
    for i in 0..last {
        for j in i..last {
            share[i][j] = carry(share[i][j], i, j);
        }
        share[i][i] = not_negative(share[i][i]);
    }
    if with_last {
        for i in 0..last {
            share[i][last] = carry(share[i][last], i, last);
        }
        share[last][last] = not_negative(carry(share[last][last], last, last));
    }
}

/// Carries the sensitivity `S = d x / d k` of the estimate to a parameter `k` the filter holds
/// at a fixed value (the last state, left out of its updates) through an update of row `h` and
/// gain `g`: the measurement holds `h_k k`, so `x+ = x + g (z - h' x)` moves with `k` by
/// `S+ = S + g (h_k - h' S)` (the last state's own entry stays 0: the update leaves it alone).
/// Linear in `k`: the estimate's error from a `k` of 1-sigma `s_k` has the covariance
/// `S S' s_k^2`, the "consider" covariance of a Schmidt filter, here without changing the gain.
pub fn carry_sensitivity<T: RealField + Copy, const N: usize>(
    sensitivity: &mut [T; N],
    h: &[T; N],
    g: &[T; N],
) {
    let Some(last) = N.checked_sub(1) else {
        return;
    };
    let mut moved = h[last];
    for j in 0..last {
        moved -= h[j] * sensitivity[j];
    }
    for j in 0..last {
        sensitivity[j] += g[j] * moved;
    }
}

/// A float's bits folded into a word that is 0 exactly when the float is +0 ([`carry_share`]'s
/// test, in integer instructions).
pub trait ZeroBits: Copy {
    /// 0 exactly when `self` is +0.
    fn zero_bits(self) -> u32;
}

impl ZeroBits for f32 {
    #[inline(always)]
    fn zero_bits(self) -> u32 {
        self.to_bits()
    }
}

impl ZeroBits for f64 {
    #[inline(always)]
    fn zero_bits(self) -> u32 {
        let b = self.to_bits();
        b as u32 | (b >> 32) as u32
    }
}

/// State estimate and covariance of `N` constant states.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstantStateKalman<T: RealField + Copy, const N: usize> {
    /// State estimate.
    x: SVector<T, N>,
    /// State covariance.
    p: SMatrix<T, N, N>,
}

impl<T: RealField + Copy, const N: usize> ConstantStateKalman<T, N> {
    /// Zero state with a diagonal prior covariance `sigma^2`.
    pub fn new(prior_sigma: [T; N]) -> Self {
        let mut p = SMatrix::<T, N, N>::zeros();
        for i in 0..N {
            p[(i, i)] = prior_sigma[i] * prior_sigma[i];
        }
        ConstantStateKalman {
            x: SVector::zeros(),
            p,
        }
    }

    /// State `mean` with a diagonal prior covariance `sigma^2`.
    pub fn with_mean(mean: [T; N], prior_sigma: [T; N]) -> Self {
        let mut kf = Self::new(prior_sigma);
        kf.x = SVector::from(mean);
        kf
    }

    /// A filter with states `x` and covariance columns `p` (for constants: the estimator's
    /// unconfigured state, test fixtures).
    pub const fn from_parts(x: [T; N], p: [[T; N]; N]) -> Self {
        ConstantStateKalman {
            x: SVector::from_array_storage(ArrayStorage([x])),
            p: SMatrix::from_array_storage(ArrayStorage(p)),
        }
    }

    /// Prediction: states constant, covariance grows by `q` on the diagonal (a random walk).
    pub fn predict(&mut self, q_diag: &[T; N]) {
        for i in 0..N {
            self.p[(i, i)] += q_diag[i];
        }
    }

    /// Applies one scalar measurement `z = h . x + w`, `var(w) = r`. Returns the innovation.
    pub fn update(&mut self, h: &[T; N], z: T, r: T) -> Result<T, KalmanError> {
        self.update_gated(h, z, r, None)
    }

    /// [`ConstantStateKalman::update`], returning the innovation and the gain.
    pub fn update_with_gain(
        &mut self,
        h: &[T; N],
        z: T,
        r: T,
    ) -> Result<Applied<T, N>, KalmanError> {
        self.update_masked(h, z, r, None, None)
    }

    /// [`ConstantStateKalman::update`], refused ([`KalmanError::Gated`], the filter untouched)
    /// when `gate = Some((spread, g))` and the innovation is beyond `g` times its standard
    /// deviation for a measurement of variance `spread`: `(z - h x)^2 > g^2 (h' P h + spread)`
    /// (innovation gating: a measurement the filter's own uncertainty and the measurements' usual
    /// spread cannot explain is left out).
    pub fn update_gated(
        &mut self,
        h: &[T; N],
        z: T,
        r: T,
        gate: Option<(T, T)>,
    ) -> Result<T, KalmanError> {
        self.update_masked(h, z, r, gate, None)
            .map(|a| a.innovation)
    }

    /// [`ConstantStateKalman::update_gated`] that moves only the states `updated` (all: `None`).
    pub fn update_masked(
        &mut self,
        h: &[T; N],
        z: T,
        r: T,
        gate: Option<(T, T)>,
        updated: Option<&[bool; N]>,
    ) -> Result<Applied<T, N>, KalmanError> {
        self.update_leading::<N>(h, z, r, gate, updated)
    }

    /// [`ConstantStateKalman::update_masked`] on the leading `M` states only: the others
    /// keep their estimates, their variances and their covariances, and enter the innovation
    /// through their estimates alone. For states held at a negligible variance and uncorrelated
    /// with the rest (a model term not yet excited), it is the full update less what rounds
    /// away, at `(M / N)^2` of the cost (`M` a constant: the loops unrolled).
    pub fn update_leading<const M: usize>(
        &mut self,
        h: &[T; N],
        z: T,
        r: T,
        gate: Option<(T, T)>,
        updated: Option<&[bool; N]>,
    ) -> Result<Applied<T, N>, KalmanError> {
        let n = if M < N { M } else { N };
        if !z.is_finite() || !r.is_finite() || r < T::zero() || !sum_is_finite(h) {
            return Err(KalmanError::NonFinite);
        }
        let (ph, hph) = self.projected::<M>(h);
        let s = hph + r;
        if !(s > T::zero()) || !s.is_finite() {
            return Err(KalmanError::Degenerate);
        }
        let mut innovation = z;
        for i in 0..N {
            innovation -= h[i] * self.x[i];
        }
        if let Some((spread, g)) = gate {
            if innovation * innovation > g * g * (hph + spread) {
                return Err(KalmanError::Gated);
            }
        }
        // The states not in `updated` keep their estimates (a Schmidt "consider" update: the
        // Joseph form below is the covariance of any gain).
        let inv_s = T::one() / s;
        let mut k = [T::zero(); N];
        for i in 0..n {
            if updated.is_none_or(|u| u[i]) {
                k[i] = ph[i] * inv_s;
            }
        }
        // Joseph's form for any gain (module doc): D h = b - k (h' b), b = P h = ph (P
        // symmetric); P+ = D - (D h) k' + r k k'. The new estimate first, then the covariance in
        // place: the upper triangle written over the old one (each term reads only its own old
        // value), the lower triangle still the old mirror, so that a result that is not finite
        // (one sum each: a NaN or an infinity anywhere makes it not finite) is undone from it and
        // the filter is left untouched.
        let mut dh = [T::zero(); N];
        for i in 0..n {
            dh[i] = ph[i] - k[i] * hph;
        }
        let mut x = [T::zero(); N];
        let mut x_sum = innovation;
        for i in 0..n {
            x[i] = self.x[i] + k[i] * innovation;
            x_sum += x[i];
        }
        if !x_sum.is_finite() {
            return Err(KalmanError::NonFinite);
        }
        if !self.joseph_upper::<M>(&k, &ph, &dh, r) {
            return Err(KalmanError::NonFinite);
        }
        for i in 0..n {
            self.x[i] = x[i];
            for j in i + 1..n {
                self.p[(j, i)] = self.p[(i, j)];
            }
        }
        Ok(Applied {
            innovation,
            gain: k,
        })
    }

    /// `P h` and `h' P h` on the leading `M` states (the rest of `P h` 0).
    // Called once, on the step's path.
    #[inline(always)]
    fn projected<const M: usize>(&self, h: &[T; N]) -> ([T; N], T) {
        let n = if M < N { M } else { N };
        let mut ph = [T::zero(); N];
        let mut hph = T::zero();
        for i in 0..n {
            let mut v = T::zero();
            for j in 0..n {
                v += self.p[(i, j)] * h[j];
            }
            ph[i] = v;
            hph += h[i] * v;
        }
        (ph, hph)
    }

    /// Joseph's form of the covariance for gain `k` on the leading `M` states, `b = ph`,
    /// `D h = dh`, written over the upper triangle in place (each term reads only its own old
    /// value; the lower triangle is still the old mirror). Returns whether it is finite; when it
    /// is not, the upper triangle is undone from the mirror and the diagonal kept, so that the
    /// filter is left untouched.
    // Called once, on the step's path.
    #[inline(always)]
    fn joseph_upper<const M: usize>(&mut self, k: &[T; N], ph: &[T; N], dh: &[T; N], r: T) -> bool {
        let n = if M < N { M } else { N };
        let mut diagonal = [T::zero(); N];
        let mut p_sum = T::zero();
        for i in 0..n {
            diagonal[i] = self.p[(i, i)];
            for j in i..n {
                let v = self.p[(i, j)] - k[i] * ph[j] - dh[i] * k[j] + r * k[i] * k[j];
                self.p[(i, j)] = v;
                p_sum += v;
            }
        }
        if !p_sum.is_finite() {
            for i in 0..n {
                self.p[(i, i)] = diagonal[i];
                for j in i + 1..n {
                    self.p[(i, j)] = self.p[(j, i)];
                }
            }
            return false;
        }
        true
    }

    /// Forgets what is known of the states `which`: their variance becomes `prior_sigma^2` and their
    /// covariance with every other state 0, their estimates stay as they are (the next measurements
    /// move them as at a cold start); the other states keep their estimates and covariance. The
    /// covariance stays symmetric positive definite: the kept block is a principal submatrix of a
    /// positive definite matrix, and the forgotten states are uncorrelated with it.
    pub fn forget(&mut self, which: &[bool; N], prior_sigma: &[T; N]) {
        for i in 0..N {
            if !which[i] {
                continue;
            }
            for j in 0..N {
                self.p[(i, j)] = T::zero();
                self.p[(j, i)] = T::zero();
            }
            self.p[(i, i)] = prior_sigma[i] * prior_sigma[i];
        }
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }

    /// The state covariance.
    pub fn covariance(&self) -> &SMatrix<T, N, N> {
        &self.p
    }

    /// 1-sigma of state `i`.
    pub fn sigma(&self, i: usize) -> T {
        self.p[(i, i)].max(T::zero()).sqrt()
    }

    /// True when the covariance is symmetric and positive definite (Cholesky succeeds).
    pub fn covariance_is_spd(&self) -> bool {
        for i in 0..N {
            for j in 0..i {
                if self.p[(i, j)] != self.p[(j, i)] {
                    return false;
                }
            }
        }
        nalgebra::linalg::Cholesky::new(self.p).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The sensitivity carried through updates that leave the last state alone is how the
    /// estimate moves with that state's true value: two filters fed the same measurements but for
    /// the last state's part (`h_k k`) end `S k` apart.
    #[test]
    fn carried_sensitivity_is_how_the_estimate_moves_with_the_held_state() {
        const N: usize = 3;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut unit = || (rng.next_u32() as f64 / u32::MAX as f64) * 2.0 - 1.0;
        let (mut without, mut with) = (
            ConstantStateKalman::<f64, N>::new([10.0, 5.0, 1e-9]),
            ConstantStateKalman::<f64, N>::new([10.0, 5.0, 1e-9]),
        );
        let held = [true, true, false];
        let k = 0.7;
        let mut sensitivity = [0.0; N];
        for _ in 0..40 {
            let h = [unit(), unit(), unit()];
            let z = 3.0 * unit();
            without
                .update_masked(&h, z, 0.5, None, Some(&held))
                .unwrap();
            let applied = with
                .update_masked(&h, z + h[2] * k, 0.5, None, Some(&held))
                .unwrap();
            carry_sensitivity(&mut sensitivity, &h, &applied.gain);
        }
        for i in 0..N - 1 {
            let moved = with.state()[i] - without.state()[i];
            assert!(
                (moved - sensitivity[i] * k).abs() < 1e-9,
                "state {i}: moved {moved}, S k = {}",
                sensitivity[i] * k
            );
            assert!(sensitivity[i].abs() > 1e-3, "state {i}: nothing to check");
        }
        assert_eq!(sensitivity[N - 1], 0.0);
    }

    /// The shares carried through every update, each group's noise joining its own and the prior
    /// its own, add up to the filter's covariance after any sequence of updates, masked ones among
    /// them; and the group that measured nothing keeps a share the updates only take down.
    #[test]
    fn carried_shares_add_up_to_the_covariance() {
        const N: usize = 3;
        let mut kf = ConstantStateKalman::<f64, N>::new([10.0, 5.0, 2.0]);
        let mut prior = [[0.0; N]; N];
        for (i, row) in prior.iter_mut().enumerate() {
            row[i] = kf.covariance()[(i, i)];
        }
        let (mut a, mut b) = ([[0.0; N]; N], [[0.0; N]; N]);
        let masked = [true, true, false];
        for step in 0..40 {
            let t = step as f64 * 0.37;
            let h = [t.cos(), t.sin(), 0.3 + 0.1 * t.cos()];
            let (r, group_a) = if step % 3 == 0 {
                (0.5, false)
            } else {
                (0.2, true)
            };
            let mask = (step % 5 == 0).then_some(&masked);
            let applied = kf.update_masked(&h, 0.1 * t, r, None, mask).unwrap();
            carry_share(&mut prior, &h, &applied.gain, 0.0);
            carry_share(&mut a, &h, &applied.gain, if group_a { r } else { 0.0 });
            carry_share(&mut b, &h, &applied.gain, if group_a { 0.0 } else { r });
        }
        let p = kf.covariance();
        for i in 0..N {
            for j in i..N {
                let sum = prior[i][j] + a[i][j] + b[i][j];
                assert!(
                    (sum - p[(i, j)]).abs() <= 1e-12 * p[(i, i)].max(p[(j, j)]),
                    "{i},{j}"
                );
            }
            assert!(a[i][i] > 0.0 && b[i][i] > 0.0 && prior[i][i] > 0.0);
            assert!(prior[i][i] < [10.0f64, 5.0, 2.0][i].powi(2));
        }
    }

    /// [`carry_share`] gives, bit for bit, the plain sum over every state (each row's terms in
    /// state order), whether the last state takes part or is left out (its gain and its column
    /// of the share +0, as the heel state's until it is learned), in `f32` and `f64`.
    #[test]
    fn carry_share_is_the_plain_sum_bit_for_bit() {
        fn plain<T: RealField + Copy, const N: usize>(
            share: &mut [[T; N]; N],
            h: &[T; N],
            k: &[T; N],
            r: T,
        ) {
            let at = |c: &[[T; N]; N], i: usize, j: usize| if i <= j { c[i][j] } else { c[j][i] };
            let mut u = [T::zero(); N];
            let mut s = T::zero();
            for i in 0..N {
                let mut v = T::zero();
                for j in 0..N {
                    v += at(share, i, j) * h[j];
                }
                u[i] = v;
                s += h[i] * v;
            }
            let sr = s + r;
            for i in 0..N {
                for j in i..N {
                    share[i][j] += -k[i] * u[j] - u[i] * k[j] + sr * k[i] * k[j];
                }
                if share[i][i] < T::zero() {
                    share[i][i] = T::zero();
                }
            }
        }
        fn check<T: RealField + Copy + ZeroBits + From<f32>>(rng: &mut ChaCha8Rng) {
            let mut v = || T::from((rng.next_u32() as f32 / u32::MAX as f32 - 0.5) * 1e-6);
            for round in 0..200 {
                // The last state left out (its gain and column +0), or taking part.
                let heel = round % 2 == 1;
                let mut share = [[T::zero(); 5]; 5];
                let (mut h, mut k) = ([T::zero(); 5], [T::zero(); 5]);
                for i in 0..5 {
                    for j in i..5 {
                        share[i][j] = if j < 4 || heel { v() } else { T::zero() };
                    }
                    share[i][i] = share[i][i].abs();
                    h[i] = v();
                    k[i] = if i < 4 || heel { v() } else { T::zero() };
                }
                let r = v().abs();
                let mut expected = share;
                plain(&mut expected, &h, &k, r);
                carry_share(&mut share, &h, &k, r);
                for i in 0..5 {
                    for j in i..5 {
                        assert_eq!(
                            share[i][j].zero_bits(),
                            expected[i][j].zero_bits(),
                            "round {round}, [{i}][{j}]"
                        );
                        assert!(share[i][j] == expected[i][j], "round {round}, [{i}][{j}]");
                    }
                }
            }
        }
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        check::<f32>(&mut rng);
        check::<f64>(&mut rng);
    }

    /// A known linear system: two constants observed through rotating rows with white noise. The
    /// filter must match batch least squares (what a constant-state Kalman filter with a weak prior is).
    fn matches_batch_least_squares<T: RealField + Copy + Into<f64>>(
        prior_sigma: f64,
        tolerance: f64,
    ) {
        let c = |v: f64| nalgebra::convert::<f64, T>(v);
        let truth = [0.3, -0.7];
        let mut kf = ConstantStateKalman::<T, 2>::new([c(prior_sigma), c(prior_sigma)]);
        let mut ata = [[0.0f64; 2]; 2];
        let mut atb = [0.0f64; 2];
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for k in 0..2000 {
            let noise = ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02;
            let h = [libm::cos(k as f64 * 0.1), libm::sin(k as f64 * 0.1) + 0.2];
            let z = h[0] * truth[0] + h[1] * truth[1] + noise;
            kf.update(&[c(h[0]), c(h[1])], c(z), c(1e-4)).unwrap();
            for i in 0..2 {
                atb[i] += h[i] * z;
                for j in 0..2 {
                    ata[i][j] += h[i] * h[j];
                }
            }
        }
        let det = ata[0][0] * ata[1][1] - ata[0][1] * ata[1][0];
        let ls = [
            (ata[1][1] * atb[0] - ata[0][1] * atb[1]) / det,
            (ata[0][0] * atb[1] - ata[1][0] * atb[0]) / det,
        ];
        for i in 0..2 {
            let xi: f64 = kf.x[i].into();
            assert!(
                (xi - ls[i]).abs() < tolerance,
                "state {i}: {xi} vs {}",
                ls[i]
            );
            assert!((xi - truth[i]).abs() < 2e-3);
        }
        // Posterior covariance of least squares: r (A'A)^-1.
        let p00 = 1e-4 * ata[1][1] / det;
        let kp00: f64 = kf.p[(0, 0)].into();
        assert!((kp00 / p00 - 1.0).abs() < 1e-2);
        assert!(kf.covariance_is_spd());
    }

    #[test]
    fn f32_filter_matches_batch_least_squares() {
        // Prior variance / measurement variance = 1e4, as in the estimator (about 2e4). In f32 the
        // first updates lose all precision once that ratio nears 1/eps = 1.7e7.
        matches_batch_least_squares::<f32>(1.0, 2e-5);
    }

    #[test]
    fn f64_filter_matches_batch_least_squares() {
        matches_batch_least_squares::<f64>(1e3, 1e-9);
    }

    #[test]
    fn forgetting_states_keeps_the_others_and_the_covariance_positive_definite() {
        let mut kf = ConstantStateKalman::<f32, 4>::new([1.0; 4]);
        for k in 0..40 {
            let a = k as f32 * 0.3;
            kf.update(
                &[libm::cosf(a), libm::sinf(a), 0.3, 0.2 * libm::cosf(2.0 * a)],
                0.1 * k as f32,
                1e-3,
            )
            .unwrap();
        }
        let before = kf.clone();
        kf.forget(&[true, false, true, false], &[2.0; 4]);
        assert!(kf.covariance_is_spd());
        assert_eq!(kf.state(), before.state());
        for i in 0..4 {
            for j in 0..4 {
                let expected = match (i % 2 == 0, j % 2 == 0) {
                    (true, _) | (_, true) if i == j => 4.0,
                    (true, _) | (_, true) => 0.0,
                    _ => before.covariance()[(i, j)],
                };
                assert_eq!(kf.covariance()[(i, j)], expected, "({i}, {j})");
            }
        }
    }

    #[test]
    fn a_gated_update_refuses_an_innovation_beyond_the_gate_and_leaves_the_state() {
        let mut kf = ConstantStateKalman::<f32, 2>::new([1.0, 1.0]);
        kf.update(&[1.0, 0.0], 0.5, 0.01).unwrap();
        let before = kf.clone();
        // h' P h is about 0.01 here; with a spread of 0.01 the 3-sigma gate is about 0.42.
        let hph = kf.covariance()[(0, 0)];
        let gate = 3.0 * libm::sqrtf(hph + 0.01);
        assert_eq!(
            kf.update_gated(
                &[1.0, 0.0],
                kf.state()[0] + 1.01 * gate,
                0.01,
                Some((0.01, 3.0))
            ),
            Err(KalmanError::Gated)
        );
        assert_eq!(kf, before);
        assert!(kf
            .update_gated(
                &[1.0, 0.0],
                kf.state()[0] + 0.99 * gate,
                0.01,
                Some((0.01, 3.0))
            )
            .is_ok());
        assert_ne!(kf, before);
    }

    #[test]
    fn refuses_bad_measurements_and_leaves_state_untouched() {
        let mut kf = ConstantStateKalman::<f32, 2>::new([1.0, 1.0]);
        kf.update(&[1.0, 0.0], 0.5, 0.1).unwrap();
        let before = kf.clone();
        assert_eq!(
            kf.update(&[1.0, 0.0], f32::NAN, 0.1),
            Err(KalmanError::NonFinite)
        );
        assert_eq!(
            kf.update(&[f32::INFINITY, 0.0], 0.0, 0.1),
            Err(KalmanError::NonFinite)
        );
        assert_eq!(
            kf.update(&[1.0, 0.0], 0.0, -1.0),
            Err(KalmanError::NonFinite)
        );
        assert_eq!(
            kf.update(&[0.0, 0.0], 0.0, 0.0),
            Err(KalmanError::Degenerate)
        );
        assert_eq!(kf, before);
    }
}
