//! Scalar functions (libm-backed, so the kernel stays `no_std`) and small dense matrices
//! generic over the dimension `D` (2 or 3), stored row-major as `[[Real; D]; D]`.

use crate::Real;

/// A `D x D` matrix, row-major: `m[a][b]` is row a, column b.
pub type Mat<const D: usize> = [[Real; D]; D];

/// Square root.
#[inline(always)]
pub fn sqrt(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::sqrtf(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::sqrt(x)
    }
}

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
pub fn mul<const D: usize>(a: &Mat<D>, b: &Mat<D>) -> Mat<D> {
    let mut c = [[0.0; D]; D];
    for i in 0..D {
        for j in 0..D {
            let mut s = 0.0;
            for k in 0..D {
                s += a[i][k] * b[k][j];
            }
            c[i][j] = s;
        }
    }
    c
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
pub fn det<const D: usize>(m: &Mat<D>) -> Real {
    if D == 2 {
        m[0][0] * m[1][1] - m[0][1] * m[1][0]
    } else {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }
}

/// Inverse transpose `m^-T` from cofactors (D = 2 or 3); the caller guarantees `det != 0`.
#[inline(always)]
fn inverse_transpose<const D: usize>(m: &Mat<D>) -> Mat<D> {
    let inv_det = 1.0 / det(m);
    let mut c = [[0.0; D]; D];
    if D == 2 {
        c[0][0] = m[1][1] * inv_det;
        c[0][1] = -m[1][0] * inv_det;
        c[1][0] = -m[0][1] * inv_det;
        c[1][1] = m[0][0] * inv_det;
    } else {
        for i in 0..3 {
            for j in 0..3 {
                let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
                let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
                c[i][j] = (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) * inv_det;
            }
        }
    }
    c
}

/// `exp(a)` by its Taylor series up to and including the power `terms`
/// (seeds/000 eq 26: `dF = exp(grad v dt)`).
#[inline(always)]
pub fn exp_series<const D: usize>(a: &Mat<D>, terms: u32) -> Mat<D> {
    let mut result = identity::<D>();
    let mut power = identity::<D>();
    let mut k = 1;
    while k <= terms {
        power = mul(&power, a);
        let inv_k_fact = 1.0 / factorial(k);
        for i in 0..D {
            for j in 0..D {
                result[i][j] += power[i][j] * inv_k_fact;
            }
        }
        k += 1;
    }
    result
}

#[inline(always)]
fn factorial(k: u32) -> Real {
    let mut f = 1.0;
    let mut i = 2;
    while i <= k {
        f *= i as Real;
        i += 1;
    }
    f
}

/// The rotation R of the polar decomposition `F = R U` (det F > 0).
///
/// 2D: closed form from the antisymmetric part. 3D: Higham's scaled Newton iteration
/// `R <- (g R + R^-T / g) / 2`, which converges quadratically; it stops when the change is at
/// round-off or after a fixed number of iterations, so its cost is bounded.
pub fn polar_rotation<const D: usize>(f: &Mat<D>) -> Mat<D> {
    if D == 2 {
        let c = f[0][0] + f[1][1];
        let s = f[1][0] - f[0][1];
        let n = sqrt(c * c + s * s);
        let mut r = identity::<D>();
        if n > 0.0 {
            r[0][0] = c / n;
            r[0][1] = -s / n;
            r[1][0] = s / n;
            r[1][1] = c / n;
        }
        return r;
    }
    let mut r = *f;
    let tol = Real::EPSILON * 16.0;
    for _ in 0..32 {
        let d = det(&r);
        if !(d.is_finite() && d > 0.0) {
            break;
        }
        // Scaling by |det|^(-1/D) speeds up the first iterations (Higham 1986).
        let g = 1.0 / libm_cbrt(d);
        let inv_t = inverse_transpose(&r);
        let mut change: Real = 0.0;
        for i in 0..D {
            for j in 0..D {
                let next = 0.5 * (g * r[i][j] + inv_t[i][j] / g);
                let diff = next - r[i][j];
                change += diff * diff;
                r[i][j] = next;
            }
        }
        if change <= tol * tol * (D as Real) {
            break;
        }
    }
    r
}

#[inline(always)]
fn libm_cbrt(x: Real) -> Real {
    #[cfg(not(feature = "f64"))]
    {
        libm::cbrtf(x)
    }
    #[cfg(feature = "f64")]
    {
        libm::cbrt(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_series_of_zero_is_identity_and_of_diagonal_matches_scalar_exp() {
        let z: Mat<3> = [[0.0; 3]; 3];
        assert_eq!(exp_series(&z, 4), identity::<3>());
        let a: Mat<2> = [[0.1, 0.0], [0.0, -0.2]];
        let e = exp_series(&a, 8);
        assert!((e[0][0] - libm::exp(0.1) as Real).abs() < 1e-6);
        assert!((e[1][1] - libm::exp(-0.2) as Real).abs() < 1e-6);
    }

    #[test]
    fn polar_rotation_recovers_rotation_of_stretched_matrix() {
        // F = R(30 deg about z) * diag(1.5, 0.7, 1.1): the rotation part must come back.
        let (s, c) = (0.5 as Real, (0.75 as Real).sqrt());
        let r: Mat<3> = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let u: Mat<3> = [[1.5, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 1.1]];
        let f = mul(&r, &u);
        let got = polar_rotation(&f);
        for i in 0..3 {
            for j in 0..3 {
                assert!((got[i][j] - r[i][j]).abs() < 1e-5, "{i}{j}");
            }
        }
        let f2: Mat<2> = [[c * 1.5, -s * 0.7], [s * 1.5, c * 0.7]];
        let got2 = polar_rotation(&f2);
        assert!((got2[0][0] - c).abs() < 1e-6 && (got2[1][0] - s).abs() < 1e-6);
    }
}
