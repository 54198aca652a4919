//! Compressible neo-Hookean: `W = mu/2 (tr B - 3) - mu ln J + lambda/2 (ln J)^2`,
//! `tau = mu (B - I) + lambda ln(J) I` with `B = F F^T` (2D: `B_zz = F_zz^2`, 1 in plane
//! strain).
//!
//! Everything is written in the displacement gradient `H = F - I`: `B - I = H + H^T + H H^T`
//! and `J - 1` from [`crate::math::det_identity_plus_parts`], so small strains keep full
//! precision in f32.

use super::{Deformation, Model, Params, Stress};
use crate::math::{det_identity_plus_parts, ln_1p, ln_1p_fast, x_minus_ln_1p};
use crate::Real;

/// `ln J` from `J - 1` for the stress: the branch-free log, so that [`Model::kirchhoff`] and
/// [`Model::kirchhoff_lanes`] give a particle bit-identical stress.
#[inline(always)]
fn ln_j(jm1: Real) -> Real {
    ln_1p_fast(jm1.max(-1.0 + Real::EPSILON))
}

/// The compressible neo-Hookean model.
pub(crate) struct NeoHookean;

impl Model for NeoHookean {
    #[inline(always)]
    fn kirchhoff<const D: usize>(p: &Params, f: &Deformation<D>) -> Stress<D> {
        let (h, hzz) = (&f.h, f.hzz);
        let lnj = ln_j(f.jm1);
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
        let zz = if D == 2 {
            p.mu * hzz * (2.0 + hzz) + p.lambda * lnj
        } else {
            0.0
        };
        Stress { m, zz }
    }

    /// `tau / rho0` for `W` particles at once, `h[a][b][lane]`, `hzz[lane]` and `jm1[lane]`, into
    /// `tau[k][lane]` in the stored component order (`crate::phases::sym_pairs`, then `zz` in 2D).
    /// The same formula as [`Model::kirchhoff`], written as loops over lanes that vectorise.
    #[inline(always)]
    fn kirchhoff_lanes<const D: usize, const W: usize>(
        p: &Params,
        h: &[[[Real; W]; D]; D],
        hzz: &[Real; W],
        jm1: &[Real; W],
        tau: &mut [[Real; W]; 6],
    ) {
        let mut lnj = [0.0; W];
        for ln in 0..W {
            lnj[ln] = ln_j(jm1[ln]);
        }
        for (k, &(r, c)) in crate::phases::sym_pairs(D).iter().enumerate() {
            for ln in 0..W {
                let mut hh = 0.0;
                for m in 0..D {
                    hh += h[r][m][ln] * h[c][m][ln];
                }
                let diag = if r == c { p.lambda * lnj[ln] } else { 0.0 };
                tau[k][ln] = (p.mu * (h[r][c][ln] + h[c][r][ln] + hh) + diag) * p.inv_rho0;
            }
        }
        if D == 2 {
            for ln in 0..W {
                tau[3][ln] = (p.mu * hzz[ln] * (2.0 + hzz[ln]) + p.lambda * lnj[ln]) * p.inv_rho0;
            }
        }
    }

    /// `W = mu (tr H - ln J) + mu/2 |H|^2 + lambda/2 (ln J)^2`, the same energy arranged so that no
    /// two first-order terms cancel: `tr H - ln J = -rest + (jm1 - ln(1 + jm1))`, `rest` the
    /// higher-order part of `J - 1` (in 2D with the out-of-plane factor: `J - 1 = j2 + hzz + j2 hzz`
    /// with `j2` the in-plane part).
    fn energy<const D: usize>(p: &Params, f: &Deformation<D>) -> Real {
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
