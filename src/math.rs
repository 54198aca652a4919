//! Scalar functions (libm-backed, so the kernel stays `no_std`) and small dense matrices
//! generic over the dimension `D` (2 or 3), stored row-major as `[[Real; D]; D]`.

pub use crate::num::sqrt;
use crate::num::{matrix, MatOf, Num, Truth};
use crate::Real;

/// A `D x D` matrix, row-major: `m[a][b]` is row a, column b.
pub type Mat<const D: usize> = [[Real; D]; D];

/// Natural logarithm.
#[inline(always)]
pub fn ln(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::logf(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::log(x)
    }
}

/// `exp(x) - 1`, accurate for small x.
#[inline(always)]
pub fn exp_m1(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::expm1f(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::expm1(x)
    }
}

/// `ln(1 + x)`, accurate for small x.
#[inline(always)]
pub fn ln_1p(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::log1pf(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::log1p(x)
    }
}

/// `ln(1 + x)` for `x > -1`, written without calls or branches so that a loop over particles
/// that uses it vectorises: `ln(1 + x) = ln(u) x / (u - 1)` with `u = 1 + x` (Goldberg's trick,
/// exact where `u` rounds to 1), and `ln(u) = e ln 2 + 2 atanh((m - 1) / (m + 1))` from the
/// float's exponent e and mantissa m in [sqrt(1/2), sqrt(2)). Relative error a few ulps.
#[inline(always)]
pub fn ln_1p_fast(x: Real) -> Real {
    let u = 1.0 + x;
    #[cfg(not(feature = "f64"))]
    let (e, m) = {
        let bits = u.to_bits();
        let mut e = ((bits >> 23) & 0xff) as i32 - 127;
        let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
        let big = m > core::f32::consts::SQRT_2;
        m = if big { 0.5 * m } else { m };
        e += big as i32;
        (e as Real, m)
    };
    #[cfg(feature = "f64")]
    let (e, m) = {
        let bits = u.to_bits();
        let mut e = ((bits >> 52) & 0x7ff) as i64 - 1023;
        let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
        let big = m > core::f64::consts::SQRT_2;
        m = if big { 0.5 * m } else { m };
        e += big as i64;
        (e as Real, m)
    };
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    // atanh series in t^2, |t| <= 0.1716: f32 needs terms to t^9, f64 to t^21.
    #[cfg(not(feature = "f64"))]
    let series = 1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0))));
    #[cfg(feature = "f64")]
    let series = {
        let mut acc = 1.0 / 21.0;
        let mut k = 19.0;
        while k >= 1.0 {
            acc = 1.0 / k + t2 * acc;
            k -= 2.0;
        }
        acc
    };
    let ln_u = e * core::f64::consts::LN_2 as Real + 2.0 * t * series;
    let exact = u == 1.0;
    let denom = if exact { 1.0 } else { u - 1.0 };
    if exact {
        x
    } else {
        ln_u * x / denom
    }
}

/// `exp(x) - 1`, written without calls or branches so that a loop over particles that uses it
/// vectorises, as [`ln_1p_fast`]: `x = k ln 2 + r` with the integer `k` nearest `x / ln 2` and
/// `|r| <= ln 2 / 2` (Cody and Waite: `ln 2` in two parts, the first with few enough bits that
/// `k` times it is exact), then `exp(x) - 1 = 2^k (exp(r) - 1) + (2^k - 1)`, with `exp(r) - 1`
/// from its Taylor series and `2^k` built from its bits. Where `k = 0` that is the series
/// itself, so small x keep their relative precision. Relative error within 2 eps (tested).
/// `x` is clamped to [-32, 88] in f32, [-64, 709] in f64: below, the result is -1 anyway;
/// above, it stays `exp_m1_fast` of the bound, finite. A NaN stays a NaN.
#[inline(always)]
pub fn exp_m1_fast(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    const BITS: u32 = 23;
    #[cfg(feature = "f64")]
    const BITS: u32 = 52;
    // 1.5 2^BITS: adding it rounds a real of magnitude below 2^(BITS - 1) to an integer, held
    // in the low bits of the sum's mantissa.
    const SHIFT: Real = (3u64 << (BITS - 1)) as Real;
    // ln 2 = ln2_hi + ln2_lo; f32's ln2_hi is 355 / 512, 9 bits, f64's has 32.
    #[cfg(not(feature = "f64"))]
    let (lo, hi, ln2_hi, ln2_lo) = (-32.0, 88.0, 355.0 / 512.0, -2.121_944_4e-4);
    #[cfg(feature = "f64")]
    let (lo, hi, ln2_hi, ln2_lo) = (
        -64.0,
        709.0,
        6.931_471_803_691_238e-1,
        1.908_214_929_270_587_7e-10,
    );
    // Comparisons, not `max`/`min`, so that a NaN goes through.
    let x = if x > hi { hi } else { x };
    let x = if x < lo { lo } else { x };
    let t = x * core::f64::consts::LOG2_E as Real + SHIFT;
    let k = t - SHIFT;
    let r = (x - k * ln2_hi) - k * ln2_lo;
    // 2^k: the biased exponent k + bias into the exponent field; the low bits of t hold k, and
    // the shift drops the rest of t.
    #[cfg(not(feature = "f64"))]
    let two_k = Real::from_bits(t.to_bits().wrapping_add(127) << BITS);
    #[cfg(feature = "f64")]
    let two_k = Real::from_bits(t.to_bits().wrapping_add(1023) << BITS);
    // exp(r) - 1 = r + r^2 (1/2! + r/3! + ...): f32 to r^7, f64 to r^13 (the first omitted term
    // is below half an ulp of r for |r| <= ln 2 / 2).
    #[cfg(not(feature = "f64"))]
    const TERMS: usize = 7;
    #[cfg(feature = "f64")]
    const TERMS: usize = 13;
    let mut q = 0.0;
    let mut j = TERMS;
    while j >= 2 {
        q = q * r + INV_FACTORIAL[j];
        j -= 1;
    }
    let em1_r = r + r * r * q;
    two_k * em1_r + (two_k - 1.0)
}

/// `1 / j!` for `j` up to 13 (the terms of [`exp_m1_fast`]'s series).
const INV_FACTORIAL: [Real; 14] = {
    let mut f = [1.0; 14];
    let mut fact = 1.0f64;
    let mut j = 1;
    while j < 14 {
        fact *= j as f64;
        f[j] = (1.0 / fact) as Real;
        j += 1;
    }
    f
};

/// Rounds up to the next integer.
#[inline(always)]
pub fn ceil(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::ceilf(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::ceil(x)
    }
}

/// Rounds down to the previous integer.
#[inline(always)]
pub fn floor(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::floorf(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::floor(x)
    }
}

/// The identity matrix.
#[inline(always)]
pub fn identity<const D: usize>() -> Mat<D> {
    let mut m = [[0.0; D]; D];
    for (a, row) in m.iter_mut().enumerate() {
        row[a] = 1.0;
    }
    m
}

/// Matrix product `a b`.
#[inline(always)]
pub fn mul<T: Num, const D: usize>(a: &MatOf<T, D>, b: &MatOf<T, D>) -> MatOf<T, D> {
    matrix(|i, j| {
        let mut s = T::splat(0.0);
        for k in 0..D {
            s += a[i][k] * b[k][j];
        }
        s
    })
}

/// Transpose.
#[inline(always)]
pub fn transpose<const D: usize>(a: &Mat<D>) -> Mat<D> {
    let mut t = [[0.0; D]; D];
    for i in 0..D {
        for j in 0..D {
            t[i][j] = a[j][i];
        }
    }
    t
}

/// Determinant (D = 2 or 3).
#[inline(always)]
pub fn det<T: Num, const D: usize>(m: &MatOf<T, D>) -> T {
    if D == 2 {
        m[0][0] * m[1][1] - m[0][1] * m[1][0]
    } else {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }
}

/// `det(I + h) - 1 = tr h + rest`, returned as `(tr h, rest)` without forming `I + h`, so
/// that small strains keep their precision (`rest` is the sum of the principal minors of
/// order >= 2: `det h` in 2D; the 2 x 2 minors plus `det h` in 3D).
#[inline(always)]
pub fn det_identity_plus_parts<T: Num, const D: usize>(h: &MatOf<T, D>) -> (T, T) {
    if D == 2 {
        (h[0][0] + h[1][1], det(h))
    } else {
        let tr = h[0][0] + h[1][1] + h[2][2];
        let minors = h[0][0] * h[1][1] - h[0][1] * h[1][0] + h[0][0] * h[2][2] - h[0][2] * h[2][0]
            + h[1][1] * h[2][2]
            - h[1][2] * h[2][1];
        (tr, minors + det(h))
    }
}

/// `det(I + h) - 1`.
#[inline(always)]
pub fn det_identity_plus_minus_one<T: Num, const D: usize>(h: &MatOf<T, D>) -> T {
    let (tr, rest) = det_identity_plus_parts(h);
    tr + rest
}

/// `x - ln(1 + x)`, accurate for small x (where the difference would cancel).
#[inline(always)]
pub fn x_minus_ln_1p(x: Real) -> Real {
    if x.abs() < 1.0e-2 {
        // Alternating series; the first omitted term is x^6 / 6 < 2e-13, below round-off.
        x * x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * 0.2)))
    } else {
        x - ln_1p(x)
    }
}

/// Inverse transpose `m^-T` from cofactors (D = 2 or 3); the caller guarantees `det != 0`.
#[inline(always)]
pub(crate) fn inverse_transpose<T: Num, const D: usize>(m: &MatOf<T, D>) -> MatOf<T, D> {
    let inv_det = T::splat(1.0) / det(m);
    matrix(|i, j| {
        if D == 2 {
            // The cofactor of (i, j): the opposite corner, negated off the diagonal.
            let c = m[1 - i][1 - j];
            (if i == j { c } else { -c }) * inv_det
        } else {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
            (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) * inv_det
        }
    })
}

/// `exp(A) - I` to `n` terms (E31: `dF = exp(L dt)` with `A = L dt`), by Horner:
/// `Q = A / n`, then `Q <- (A + A Q) / k` for `k = n - 1` down to 1 (the division by 1
/// skipped). The identity is left out so that a small increment keeps its precision. Written
/// once on `Num` (a real, or a vector of the particle pass's instance); `n` in 1..=8.
#[inline(always)]
pub fn exp_series_minus_identity<T: Num, const D: usize>(a: &MatOf<T, D>, n: usize) -> MatOf<T, D> {
    let mut q = *a;
    for (row, a) in q.iter_mut().zip(a) {
        for (v, &a) in row.iter_mut().zip(a) {
            *v = a * INV[n];
        }
    }
    for k in (1..n).rev() {
        let mut next = *a;
        for r in 0..D {
            for c in 0..D {
                for m in 0..D {
                    next[r][c] += a[r][m] * q[m][c];
                }
                if k > 1 {
                    next[r][c] = next[r][c] * INV[k];
                }
            }
        }
        q = next;
    }
    q
}

/// `1 / k` for the series terms (index 0 unused).
pub(crate) const INV: [Real; 9] = [
    0.0,
    1.0,
    1.0 / 2.0,
    1.0 / 3.0,
    1.0 / 4.0,
    1.0 / 5.0,
    1.0 / 6.0,
    1.0 / 7.0,
    1.0 / 8.0,
];

/// `Q = R - I`, where R is the rotation of the polar decomposition `F = R U` of `F = I + h`
/// (det F > 0), for one matrix (`T = Real`) or a vector of them (each lane gets the bits it
/// would get alone). Working with `R - I` keeps small rotations at full precision.
///
/// 2D: closed form from the angle. 3D: Newton's iteration `R <- (R + R^-T) / 2` written for
/// `Q`: `Q <- (Q - (I + Q)^-T Q^T) / 2`, which converges quadratically near a rotation; a lane
/// stops at round-off, at a non-positive determinant or after a fixed number of iterations (so
/// the cost is bounded), and the loop runs until every lane has stopped.
#[inline(always)]
pub fn polar_rotation_minus_identity<T: Num, const D: usize>(h: &MatOf<T, D>) -> MatOf<T, D> {
    let zero = T::splat(0.0);
    if D == 2 {
        // R = [[c, -s], [s, c]] / n with c = 2 + tr h, s = h10 - h01.
        let c = h[0][0] + h[1][1] + 2.0;
        let s = h[1][0] - h[0][1];
        let n = (c * c + s * s).sqrt();
        // cos - 1 = c/n - 1 = -s^2 / (n (c + n)): the second form has no cancellation where it
        // matters (small angles, c > 0); the first is exact enough elsewhere.
        let cos_m1 = T::select(c.ge(zero), -s * s / (n * (c + n)), c / n - 1.0);
        let turns = n.gt(zero);
        let sin = T::select(turns, s / n, zero);
        let cos_m1 = T::select(turns, cos_m1, zero);
        return matrix(|a, b| match (a, b) {
            (0, 1) => -sin,
            (1, 0) => sin,
            _ => cos_m1,
        });
    }
    // 3D: a lane goes on while the last round stepped and did not converge.
    let inf = T::splat(Real::INFINITY);
    let tol = Real::EPSILON * 4.0;
    let mut q = *h;
    let mut going = zero.ge(zero);
    for _ in 0..32 {
        let mut r = q;
        for (i, row) in r.iter_mut().enumerate() {
            row[i] = row[i] + 1.0;
        }
        let qt: MatOf<T, D> = matrix(|i, j| q[j][i]);
        let d = det(&r);
        let valid = d.gt(zero) & inf.gt(d);
        let corr = mul(&inverse_transpose(&r), &qt);
        let (mut change, mut size) = (zero, zero);
        let mut next = q;
        for i in 0..D {
            for j in 0..D {
                next[i][j] = (q[i][j] - corr[i][j]) * 0.5;
                let diff = next[i][j] - q[i][j];
                change += diff * diff;
                size += next[i][j] * next[i][j];
            }
        }
        let step = going & valid;
        for i in 0..D {
            for j in 0..D {
                q[i][j] = T::select(step, next[i][j], q[i][j]);
            }
        }
        // Not `change > ...`: a NaN change goes on.
        let converged = ((size + 1.0) * (tol * tol)).ge(change);
        going = step.and_not(converged);
        if !going.any() {
            break;
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_series_of_zero_is_zero_and_of_diagonal_matches_scalar_exp() {
        let z: Mat<3> = [[0.0; 3]; 3];
        assert_eq!(exp_series_minus_identity(&z, 4), z);
        let a: Mat<2> = [[0.1, 0.0], [0.0, -0.2]];
        let e = exp_series_minus_identity(&a, 8);
        assert!((e[0][0] - libm::expm1(0.1) as Real).abs() < 1e-6);
        assert!((e[1][1] - libm::expm1(-0.2) as Real).abs() < 1e-6);
    }

    #[test]
    fn polar_rotation_recovers_rotation_of_stretched_matrix() {
        // F = R(30 deg about z) * diag(1.5, 0.7, 1.1): the rotation part must come back.
        let (s, c) = (0.5 as Real, (0.75 as Real).sqrt());
        let r: Mat<3> = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let u: Mat<3> = [[1.5, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 1.1]];
        let mut h = mul(&r, &u);
        for (a, row) in h.iter_mut().enumerate() {
            row[a] -= 1.0;
        }
        let q = polar_rotation_minus_identity(&h);
        for i in 0..3 {
            for j in 0..3 {
                let expect = r[i][j] - if i == j { 1.0 } else { 0.0 };
                assert!((q[i][j] - expect).abs() < 1e-5, "{i}{j}");
            }
        }
        let h2: Mat<2> = [[c * 1.5 - 1.0, -s * 0.7], [s * 1.5, c * 0.7 - 1.0]];
        let q2 = polar_rotation_minus_identity(&h2);
        assert!((q2[0][0] - (c - 1.0)).abs() < 1e-6 && (q2[1][0] - s).abs() < 1e-6);
    }

    #[test]
    fn ln_1p_fast_matches_libm_over_many_decades() {
        let mut x: f64 = -0.999;
        while x < 1.0e3 {
            let got = ln_1p_fast(x as Real) as f64;
            let want = libm::log1p((x as Real) as f64);
            assert!(
                (got - want).abs() <= 8.0 * Real::EPSILON as f64 * want.abs().max(1e-30),
                "{x}: {got} vs {want}"
            );
            x = if x < 0.0 {
                x * 0.9 + if x > -1e-12 { 1e-12 } else { 0.0 }
            } else {
                x * 1.1 + 1e-12
            };
        }
        assert_eq!(ln_1p_fast(0.0), 0.0);
        assert_eq!(ln_1p_fast(1.0e-30), 1.0e-30);
    }

    /// [`exp_m1_fast`] is within 2 `Real::EPSILON` of libm's `expm1` in f64, relative, over x
    /// from -40 to 100 (through the clamps) and from 1e-30 to 1 in magnitude, each step 1e-4 of
    /// the last (worst found: 1.06 in f32, also over every f32 in [-40, 100]; 1.21 in f64), and
    /// keeps 0, a tiny x and a NaN.
    #[test]
    fn exp_m1_fast_matches_libm_over_its_range() {
        let mut worst: f64 = 0.0;
        let mut check = |x: Real| {
            let got = exp_m1_fast(x) as f64;
            #[cfg(not(feature = "f64"))]
            let clamped = (x as f64).min(88.0);
            #[cfg(feature = "f64")]
            let clamped = (x as f64).min(709.0);
            let want = libm::expm1(clamped);
            let err = (got - want).abs() / want.abs() / Real::EPSILON as f64;
            assert!(got.is_finite(), "{x}: {got}");
            worst = worst.max(err);
        };
        let mut x: f64 = 1.0e-30;
        while x < 1.0 {
            check(x as Real);
            check(-x as Real);
            x *= 1.0001;
        }
        let mut x: f64 = -40.0;
        while x < 100.0 {
            check(x as Real);
            x += 1.0e-4 * x.abs().max(1.0e-3);
        }
        check(1.0e30);
        check(-1.0e30);
        assert!(worst <= 2.0, "{worst} eps");
        assert_eq!(exp_m1_fast(0.0), 0.0);
        assert_eq!(exp_m1_fast(1.0e-30), 1.0e-30);
        assert!(exp_m1_fast(Real::NAN).is_nan());
    }

    #[test]
    fn exp_series_matches_power_sum_for_every_term_count() {
        let a: Mat<3> = [
            [0.01, -0.02, 0.005],
            [0.03, -0.01, 0.0],
            [0.002, 0.004, 0.02],
        ];
        for terms in 1..=8u32 {
            // Reference: sum of A^k / k! for k = 1..=terms.
            let mut want = [[0.0; 3]; 3];
            let mut power = identity::<3>();
            let mut fact = 1.0;
            for k in 1..=terms {
                power = mul(&power, &a);
                fact *= k as Real;
                for i in 0..3 {
                    for j in 0..3 {
                        want[i][j] += power[i][j] / fact;
                    }
                }
            }
            let got = exp_series_minus_identity(&a, terms as usize);
            for i in 0..3 {
                for j in 0..3 {
                    assert!((got[i][j] - want[i][j]).abs() < 1e-7, "{terms} {i}{j}");
                }
            }
        }
    }

    #[test]
    fn det_identity_plus_minus_one_matches_det() {
        let h: Mat<3> = [[0.1, 0.02, -0.03], [0.04, -0.2, 0.01], [0.0, 0.05, 0.3]];
        let mut f = h;
        for (a, row) in f.iter_mut().enumerate() {
            row[a] += 1.0;
        }
        assert!((det_identity_plus_minus_one(&h) - (det(&f) - 1.0)).abs() < 1e-6);
        let h2: Mat<2> = [[0.1, 0.02], [0.04, -0.2]];
        let f2: Mat<2> = [[1.1, 0.02], [0.04, 0.8]];
        assert!((det_identity_plus_minus_one(&h2) - (det(&f2) - 1.0)).abs() < 1e-6);
    }
}
