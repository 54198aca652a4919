//! Compressible neo-Hookean (E35): `W = mu/2 (tr B - 3) - mu ln J + lambda/2 (ln J)^2`,
//! `tau = mu (B - I) + lambda ln(J) I` with `B = F F^T` (2D: `B_zz = F_zz^2`, 1 in plane
//! strain).
//!
//! Everything is written in the displacement gradient `H = F - I`: `B - I = H + H^T + H H^T`
//! and `J - 1` from [`crate::math::det_identity_plus_parts`], so small strains keep full
//! precision in f32.

use super::model::{Deformation, Lame, Model, Stress};
use crate::layout::MaterialRecord;
use crate::math::{det_identity_plus_parts, ln_1p, ln_1p_fast, x_minus_ln_1p};
use crate::num::{matrix, Num};
use crate::Real;

/// `ln J` from `J - 1` for the stress: the branch-free log, so that the lane-by-lane loop
/// vectorises.
#[inline(always)]
fn ln_j(jm1: Real) -> Real {
    ln_1p_fast(jm1.max(-1.0 + Real::EPSILON))
}

/// The compressible neo-Hookean model.
pub(crate) struct NeoHookean;

impl Model for NeoHookean {
    type Params = Lame;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> Lame {
        Lame::of(r)
    }

    #[inline(always)]
    fn kirchhoff<const D: usize, T: Num>(p: &Lame, f: &Deformation<D, T>) -> Stress<D, T> {
        let (h, hzz) = (&f.h, f.hzz);
        let lnj = f.jm1.map(ln_j);
        // tau = mu (H + H^T + H H^T) + lambda ln J I
        let m = matrix(|a, b| {
            let mut hh = T::splat(0.0);
            for k in 0..D {
                hh += h[a][k] * h[b][k];
            }
            let shear = (h[a][b] + h[b][a] + hh) * p.mu;
            if a == b {
                shear + lnj * p.lambda
            } else {
                shear
            }
        });
        // tau_zz = mu (F_zz^2 - 1) + lambda ln J
        let zz = if D == 2 {
            hzz * p.mu * (hzz + 2.0) + lnj * p.lambda
        } else {
            T::splat(0.0)
        };
        Stress { m, zz }
    }

    /// `W = mu (tr H - ln J) + mu/2 |H|^2 + lambda/2 (ln J)^2`, the same energy arranged so that no
    /// two first-order terms cancel: `tr H - ln J = -rest + (jm1 - ln(1 + jm1))`, `rest` the
    /// higher-order part of `J - 1` (in 2D with the out-of-plane factor: `J - 1 = j2 + hzz + j2 hzz`
    /// with `j2` the in-plane part).
    fn energy<const D: usize>(p: &Lame, f: &Deformation<D>) -> Real {
        let (h, jm1) = (&f.h, f.jm1);
        let (tr2, rest2) = det_identity_plus_parts(h);
        let (rest, mut hh) = if D == 2 {
            (rest2 + (tr2 + rest2) * f.hzz, f.hzz * f.hzz)
        } else {
            (rest2, 0.0)
        };
        let lnj = ln_1p(jm1);
        for row in h.iter() {
            for v in row.iter() {
                hh += v * v;
            }
        }
        p.mu * (x_minus_ln_1p(jm1) - rest) + 0.5 * p.mu * hh + 0.5 * p.lambda * lnj * lnj
    }
}
