//! Compressible neo-Hookean: `W = mu/2 (tr B - 3) - mu ln J + lambda/2 (ln J)^2`,
//! `tau = mu (B - I) + lambda ln(J) I` with `B = F F^T` (plane strain: `B_zz = 1`).
//!
//! Everything is written in the displacement gradient `H = F - I`: `B - I = H + H^T + H H^T`
//! and `J - 1` from [`crate::math::det_identity_plus_parts`], so small strains keep full
//! precision in f32.

use super::{Params, Stress};
use crate::math::{det_identity_plus_parts, ln_1p, x_minus_ln_1p, Mat};
use crate::Real;

#[inline(always)]
pub(super) fn kirchhoff<const D: usize>(p: &Params, h: &Mat<D>, jm1: Real) -> Stress<D> {
    let lnj = ln_1p(jm1);
    let mut m = [[0.0; D]; D];
    for a in 0..D {
        for b in 0..D {
            let mut hh = 0.0;
            for k in 0..D {
                hh += h[a][k] * h[b][k];
            }
            m[a][b] = p.mu * (h[a][b] + h[b][a] + hh);
        }
        m[a][a] += p.lambda * lnj;
    }
    let zz = if D == 2 { p.lambda * lnj } else { 0.0 };
    Stress { m, zz }
}

/// `W = mu (tr H - ln J) + mu/2 |H|^2 + lambda/2 (ln J)^2`, the same energy arranged so that no
/// two first-order terms cancel: `tr H - ln J = -rest + (jm1 - ln(1 + jm1))`.
pub(super) fn energy<const D: usize>(p: &Params, h: &Mat<D>, jm1: Real) -> Real {
    let (_, rest) = det_identity_plus_parts(h);
    let lnj = ln_1p(jm1);
    let mut hh = 0.0;
    for row in h.iter() {
        for v in row.iter() {
            hh += v * v;
        }
    }
    p.mu * (x_minus_ln_1p(jm1) - rest) + 0.5 * p.mu * hh + 0.5 * p.lambda * lnj * lnj
}
