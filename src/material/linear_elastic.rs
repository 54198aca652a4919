//! Isotropic linear elasticity (small strain) in the corotated frame: `F = R U`, `e = U - I`,
//! `sigma_rot = lambda tr(e) I + 2 mu e`, `tau = J R sigma_rot R^T`. For small strain and no
//! rotation this is classic linear elasticity; a rigid rotation gives exactly zero strain.
//! In 2D the out-of-plane axis is a principal direction (R turns in the plane only), so
//! `e_zz = F_zz - 1`: 0 in plane strain (`sigma_zz = lambda tr(e)`), the hoop strain when
//! axisymmetric.
//!
//! Written in `H = F - I` and `Q = R - I`: `e = sym(R^T F) - I = sym(Q^T + H + Q^T H)`.

use super::{Deformation, Model, Params, Stress};
use crate::math::{polar_rotation_minus_identity_lanes, Mat};
use crate::Real;

/// Lanes of `D x D` matrices, `m[a][b][lane]`.
type Lanes<const D: usize, const W: usize> = [[[Real; W]; D]; D];

/// Small strain `e = sym(R^T F) - I` of the corotated frame, and `Q = R - I`, of each lane.
#[inline(always)]
fn corotated_strain<const D: usize, const W: usize>(h: &Lanes<D, W>) -> (Lanes<D, W>, Lanes<D, W>) {
    let q = polar_rotation_minus_identity_lanes(h);
    let mut e = [[[0.0; W]; D]; D];
    for a in 0..D {
        for b in 0..D {
            for ln in 0..W {
                // (R^T F - I)[a][b] = Q[b][a] + H[a][b] + sum_k Q[k][a] H[k][b]
                let mut qh = 0.0;
                for k in 0..D {
                    qh += q[k][a][ln] * h[k][b][ln];
                }
                e[a][b][ln] = q[b][a][ln] + h[a][b][ln] + qh;
            }
        }
    }
    // U is symmetric in exact arithmetic; symmetrise the round-off away.
    for a in 0..D {
        for b in a + 1..D {
            for ln in 0..W {
                let s = 0.5 * (e[a][b][ln] + e[b][a][ln]);
                e[a][b][ln] = s;
                e[b][a][ln] = s;
            }
        }
    }
    (e, q)
}

/// One particle's `H` as a single lane.
fn one_lane<const D: usize>(h: &Mat<D>) -> Lanes<D, 1> {
    core::array::from_fn(|a| core::array::from_fn(|b| [h[a][b]]))
}

/// Corotated linear elasticity. The formula is written once, on lanes
/// ([`Model::kirchhoff_lanes`]: loops over lanes that vectorise); one particle is one lane.
pub(crate) struct LinearElastic;

impl Model for LinearElastic {
    #[inline(always)]
    fn kirchhoff_lanes<const D: usize, const W: usize>(
        p: &Params,
        h: &[[[Real; W]; D]; D],
        hzz: &[Real; W],
        jm1: &[Real; W],
        tau: &mut [[Real; W]; 6],
    ) {
        let (e, q) = corotated_strain(h);
        // tr(e) with the out-of-plane e_zz, and s = lambda tr(e) I + 2 mu e.
        let mut tr = [0.0; W];
        for ln in 0..W {
            tr[ln] = if D == 2 { hzz[ln] } else { 0.0 };
            for a in 0..D {
                tr[ln] += e[a][a][ln];
            }
        }
        let mut s = [[[0.0; W]; D]; D];
        for a in 0..D {
            for b in 0..D {
                for ln in 0..W {
                    s[a][b][ln] = 2.0 * p.mu * e[a][b][ln];
                }
            }
            for ln in 0..W {
                s[a][a][ln] += p.lambda * tr[ln];
            }
        }
        // J R s R^T with R = I + Q: (R s)[i][k], then (R s R^T)[i][j] = sum_k (R s)[i][k] R[j][k].
        let mut r = q;
        for a in 0..D {
            for ln in 0..W {
                r[a][a][ln] += 1.0;
            }
        }
        let mut rs = [[[0.0; W]; D]; D];
        for i in 0..D {
            for j in 0..D {
                for ln in 0..W {
                    let mut sum = 0.0;
                    for k in 0..D {
                        sum += r[i][k][ln] * s[k][j][ln];
                    }
                    rs[i][j][ln] = sum;
                }
            }
        }
        for (k, &(i, j)) in crate::phases::sym_pairs(D).iter().enumerate() {
            for ln in 0..W {
                let mut sum = 0.0;
                for m in 0..D {
                    sum += rs[i][m][ln] * r[j][m][ln];
                }
                tau[k][ln] = sum * (1.0 + jm1[ln]) * p.inv_rho0;
            }
        }
        if D == 2 {
            for ln in 0..W {
                let j = 1.0 + jm1[ln];
                tau[3][ln] = j * (p.lambda * tr[ln] + 2.0 * p.mu * hzz[ln]) * p.inv_rho0;
            }
        }
    }

    /// The chunk path on one lane (with `1 / rho0 = 1`: `x * 1` is `x`, so
    /// [`super::kirchhoff_over_rho0`] gives the chunk path's bits); the stress is symmetric.
    #[inline(always)]
    fn kirchhoff<const D: usize>(p: &Params, f: &Deformation<D>) -> Stress<D> {
        let unscaled = Params {
            inv_rho0: 1.0,
            ..*p
        };
        let mut tau = [[0.0; 1]; 6];
        Self::kirchhoff_lanes(&unscaled, &one_lane(&f.h), &[f.hzz], &[f.jm1], &mut tau);
        let mut m = [[0.0; D]; D];
        for (k, &(r, c)) in crate::phases::sym_pairs(D).iter().enumerate() {
            m[r][c] = tau[k][0];
            m[c][r] = tau[k][0];
        }
        let zz = if D == 2 { tau[3][0] } else { 0.0 };
        Stress { m, zz }
    }

    fn energy<const D: usize>(p: &Params, f: &Deformation<D>) -> Real {
        let (e, _) = corotated_strain(&one_lane(&f.h));
        let ezz = if D == 2 { f.hzz } else { 0.0 };
        let mut tr = ezz;
        let mut ee = ezz * ezz;
        for a in 0..D {
            tr += e[a][a][0];
            for b in 0..D {
                ee += e[a][b][0] * e[a][b][0];
            }
        }
        p.mu * ee + 0.5 * p.lambda * tr * tr
    }
}
