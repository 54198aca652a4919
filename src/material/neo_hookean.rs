//! Compressible neo-Hookean: `W = mu/2 (tr B - 3) - mu ln J + lambda/2 (ln J)^2`,
//! `tau = mu (B - I) + lambda ln(J) I` with `B = F F^T` (plane strain: `B_zz = 1`).

use super::{Params, Stress};
use crate::math::{ln, Mat};
use crate::Real;

#[inline(always)]
pub(super) fn kirchhoff<const D: usize>(p: &Params, f: &Mat<D>, j: Real) -> Stress<D> {
    let lnj = ln(j);
    let mut m = [[0.0; D]; D];
    for a in 0..D {
        for b in 0..D {
            let mut bab = 0.0;
            for k in 0..D {
                bab += f[a][k] * f[b][k];
            }
            m[a][b] = p.mu * bab;
        }
        m[a][a] += p.lambda * lnj - p.mu;
    }
    let zz = if D == 2 { p.lambda * lnj } else { 0.0 };
    Stress { m, zz }
}

pub(super) fn energy<const D: usize>(p: &Params, f: &Mat<D>, j: Real) -> Real {
    let lnj = ln(j);
    let mut tr_b = if D == 2 { 1.0 } else { 0.0 };
    for row in f.iter() {
        for v in row.iter() {
            tr_b += v * v;
        }
    }
    0.5 * p.mu * (tr_b - 3.0) - p.mu * lnj + 0.5 * p.lambda * lnj * lnj
}
