//! The fill's weights: Lagrange's interpolation at 0 from the present neighbours at offsets
//! -5..=5 ([`NEIGHBOURS`] on each side). The usual patterns (every neighbour present, or the one
//! after or before lost too) are constants formed at build time as exact rationals; any other set
//! of present neighbours is formed at run time in integers and divided once
//! ([`lagrange_at_zero`]). Why a polynomial of this order, and not a straight line: the module doc
//! of [`super`].

use super::NEIGHBOURS;
use crate::Real;

/// Lagrange weights at 0 for the nodes -5..=5 without 0 and without `skip` (0: none), in order,
/// computed at build time as exact rationals (the fills of the usual patterns, one lost row or
/// two in a row, need no weights at run time).
const fn weights_without(skip: i64) -> [Real; 2 * NEIGHBOURS] {
    let mut nodes = [0i64; 2 * NEIGHBOURS];
    let mut n = 0;
    let mut x = -(NEIGHBOURS as i64);
    while x <= NEIGHBOURS as i64 {
        if x != 0 && x != skip {
            nodes[n] = x;
            n += 1;
        }
        x += 1;
    }
    let mut w = [0.0; 2 * NEIGHBOURS];
    let mut j = 0;
    while j < n {
        let (mut num, mut den) = (1i64, 1i64);
        let mut m = 0;
        while m < n {
            if m != j {
                num *= -nodes[m];
                den *= nodes[j] - nodes[m];
            }
            m += 1;
        }
        w[j] = (num as f64 / den as f64) as Real;
        j += 1;
    }
    w
}

/// Fill weights with every neighbour present, and with the one after or before lost (two lost in
/// a row).
pub(super) const ALL_NEIGHBOURS: [Real; 2 * NEIGHBOURS] = weights_without(0);
pub(super) const WITHOUT_NEXT: [Real; 2 * NEIGHBOURS] = weights_without(1);
pub(super) const WITHOUT_PREVIOUS: [Real; 2 * NEIGHBOURS] = weights_without(-1);
/// [`ALL_NEIGHBOURS`] with a 0 for the sample itself in the middle (offsets -5 to 5).
pub(super) const CENTRED_WEIGHTS: [Real; 2 * NEIGHBOURS + 1] = {
    let mut w = [0.0; 2 * NEIGHBOURS + 1];
    let mut i = 0;
    while i < 2 * NEIGHBOURS {
        w[if i < NEIGHBOURS { i } else { i + 1 }] = ALL_NEIGHBOURS[i];
        i += 1;
    }
    w
};

/// Lagrange weights at 0 for the first `n` integer nodes (all distinct, non-zero, within
/// +-[`NEIGHBOURS`]): `w_i = prod_{m != i} (-x_m) / prod_{m != i} (x_i - x_m)`. Numerator and
/// denominator are formed in integers (exact: at most 5!^2 and 10!/... below 2^24, so exact in
/// f32 too, the same values the f32 products gave) and divided once.
///
/// Formed from the full set's products (every offset -5 to 5 but 0), divided by the factors of
/// the offsets missing: exact integer divisions (each a factor of the product), so the same
/// integers as the products over the nodes present, in `n` times the missing offsets' work
/// instead of `n^2` (the costliest fill, a neighbour lost beside a filled row, is a step's worst).
#[inline(never)]
pub(super) fn lagrange_at_zero(nodes: &[i32; 2 * NEIGHBOURS], n: usize) -> [Real; 2 * NEIGHBOURS] {
    const SPAN: i32 = NEIGHBOURS as i32;
    // The full set's numerator (the product of -y over every offset y) and, for each offset x,
    // the product of x - y over every other offset y, indexed by x + SPAN.
    const FULL: (i32, [i32; 2 * NEIGHBOURS + 1]) = {
        let mut num = 1;
        let mut y = -SPAN;
        while y <= SPAN {
            if y != 0 {
                num *= -y;
            }
            y += 1;
        }
        let mut den = [1; 2 * NEIGHBOURS + 1];
        let mut x = -SPAN;
        while x <= SPAN {
            let mut y = -SPAN;
            while y <= SPAN {
                if y != 0 && y != x {
                    den[(x + SPAN) as usize] *= x - y;
                }
                y += 1;
            }
            x += 1;
        }
        (num, den)
    };
    let mut present = 0u32;
    for &x in nodes.iter().take(n) {
        present |= 1 << (x + SPAN);
    }
    // The offsets missing, and the product of -y over them (never 0: 0 is no offset).
    let mut missing = [0i32; 2 * NEIGHBOURS];
    let mut k = 0;
    let mut missing_num = 1i32;
    for y in -SPAN..=SPAN {
        if y != 0 && present & (1 << (y + SPAN)) == 0 && k < missing.len() {
            missing[k] = y;
            k += 1;
            missing_num *= -y;
        }
    }
    let num_all = FULL.0.checked_div(missing_num).unwrap_or(0);
    let mut w = [0.0; 2 * NEIGHBOURS];
    // Every divisor below is a product of non-zero offsets and differences of distinct ones, never
    // 0, and every offset within +-SPAN; written with `checked_div` and `get`, the code has no panic
    // path for the compiler to keep (a weight it cannot form stays 0).
    for (wi, &x) in w.iter_mut().zip(nodes.iter()).take(n) {
        // The product of x - y over the missing offsets (never 0: x is present).
        let mut missing_den = 1i32;
        for &y in missing.iter().take(k) {
            missing_den *= x - y;
        }
        let full_den = FULL.1.get((x + SPAN) as usize).copied().unwrap_or(0);
        if let (Some(num), Some(den)) = (num_all.checked_div(-x), full_den.checked_div(missing_den))
        {
            *wi = num as Real / den as Real;
        }
    }
    w
}
