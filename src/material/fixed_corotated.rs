//! Fixed-corotated elasticity (Stomakhin et al. 2012; E36): with the polar decomposition
//! `F = R S`, `W = mu |F - R|^2 + lambda/2 (J - 1)^2` and
//! `tau = 2 mu (F - R) F^T + lambda (J - 1) J I`. A rotation (`F = R`) is stress-free exactly;
//! unlike the corotated linear model it stays well posed at large stretch, and unlike
//! neo-Hookean its stress stays finite as `J -> 0`.
//!
//! Written in `H = F - I` and `Q = R - I`: `F - R = H - Q`. In 2D the out-of-plane axis is
//! principal (R turns in the plane only): `(F - R)_zz = hzz`.
//! [`super::snow`] is this model with moduli that harden.

use super::model::{Deformation, Lame, Model, Stress};
use crate::layout::MaterialRecord;
use crate::math::polar_rotation_minus_identity;
use crate::num::{matrix, MatOf, Num};
use crate::Real;

/// The fixed-corotated Kirchhoff stress of `f` with the moduli `mu`, `lambda` (per lane).
#[inline(always)]
pub(crate) fn stress<const D: usize, T: Num>(
    f: &Deformation<D, T>,
    mu: T,
    lambda: T,
) -> Stress<D, T> {
    let h = &f.h;
    let q = polar_rotation_minus_identity(h);
    let fr: MatOf<T, D> = matrix(|a, b| h[a][b] - q[a][b]);
    let j = f.jm1 + 1.0;
    let vol = lambda * f.jm1 * j;
    // (F - R) F^T = (H - Q)(I + H)^T
    let m = matrix(|a, b| {
        let mut s = fr[a][b];
        for k in 0..D {
            s += fr[a][k] * h[b][k];
        }
        let s = s * mu * 2.0;
        if a == b {
            s + vol
        } else {
            s
        }
    });
    let zz = if D == 2 {
        f.hzz * (f.hzz + 1.0) * mu * 2.0 + vol
    } else {
        T::splat(0.0)
    };
    Stress { m, zz }
}

/// `W = mu |F - R|^2 + lambda/2 (J - 1)^2` with the moduli `mu`, `lambda`.
pub(crate) fn energy<const D: usize>(f: &Deformation<D>, mu: Real, lambda: Real) -> Real {
    let q = polar_rotation_minus_identity(&f.h);
    let mut fr2 = if D == 2 { f.hzz * f.hzz } else { 0.0 };
    for a in 0..D {
        for b in 0..D {
            let d = f.h[a][b] - q[a][b];
            fr2 += d * d;
        }
    }
    mu * fr2 + 0.5 * lambda * f.jm1 * f.jm1
}

/// The fixed-corotated model.
pub(crate) struct FixedCorotated;

impl Model for FixedCorotated {
    type Params = Lame;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> Lame {
        Lame::of(r)
    }

    /// As the corotated linear model: the 3D polar iteration vectorises only on vectors.
    #[inline(always)]
    fn on_vectors(d: usize) -> bool {
        d == 3
    }

    #[inline(always)]
    fn kirchhoff<const D: usize, T: Num>(p: &Lame, f: &Deformation<D, T>) -> Stress<D, T> {
        stress(f, T::splat(p.mu), T::splat(p.lambda))
    }

    fn energy<const D: usize>(p: &Lame, f: &Deformation<D>) -> Real {
        energy(f, p.mu, p.lambda)
    }
}
