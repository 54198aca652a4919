//! Isotropic linear elasticity (small strain) in the corotated frame: `F = R U`, `e = U - I`,
//! `sigma_rot = lambda tr(e) I + 2 mu e`, `tau = J R sigma_rot R^T`. For small strain and no
//! rotation this is classic linear elasticity; a rigid rotation gives exactly zero strain.
//! In 2D the out-of-plane axis is a principal direction (R turns in the plane only), so
//! `e_zz = F_zz - 1`: 0 in plane strain (`sigma_zz = lambda tr(e)`), the hoop strain when
//! axisymmetric.
//!
//! Written in `H = F - I` and `Q = R - I`: `e = sym(R^T F) - I = sym(Q^T + H + Q^T H)`.

use super::{Deformation, Model, Params, Stress};
use crate::math::{mul, polar_rotation_minus_identity, polar_rotation_minus_identity_lanes, Mat};
use crate::Real;

/// Small strain `e` of the corotated frame, and `Q = R - I`.
#[inline(always)]
fn corotated_strain<const D: usize>(h: &Mat<D>) -> (Mat<D>, Mat<D>) {
    let q = polar_rotation_minus_identity(h);
    let mut e = [[0.0; D]; D];
    for a in 0..D {
        for b in 0..D {
            // (R^T F - I)[a][b] = Q[b][a] + H[a][b] + sum_k Q[k][a] H[k][b]
            let mut qh = 0.0;
            for k in 0..D {
                qh += q[k][a] * h[k][b];
            }
            e[a][b] = q[b][a] + h[a][b] + qh;
        }
    }
    // U is symmetric in exact arithmetic; symmetrise the round-off away.
    for a in 0..D {
        for b in a + 1..D {
            let s = 0.5 * (e[a][b] + e[b][a]);
            e[a][b] = s;
            e[b][a] = s;
        }
    }
    (e, q)
}

/// Corotated linear elasticity.
pub(crate) struct LinearElastic;

impl Model for LinearElastic {
    /// [`Model::kirchhoff`]'s operations, in its order, as loops over lanes that vectorise
    /// (the formula lane by lane took 1.8 times the neo-Hookean step).
    #[inline(always)]
    fn kirchhoff_lanes<const D: usize, const W: usize>(
        p: &Params,
        h: &[[[Real; W]; D]; D],
        hzz: &[Real; W],
        jm1: &[Real; W],
        tau: &mut [[Real; W]; 6],
    ) {
        let q = polar_rotation_minus_identity_lanes(h);
        // e = sym(R^T F - I) (see `corotated_strain`), its trace with the out-of-plane e_zz,
        // and s = lambda tr(e) I + 2 mu e.
        let mut e = [[[0.0; W]; D]; D];
        for a in 0..D {
            for b in 0..D {
                for ln in 0..W {
                    let mut qh = 0.0;
                    for k in 0..D {
                        qh += q[k][a][ln] * h[k][b][ln];
                    }
                    e[a][b][ln] = q[b][a][ln] + h[a][b][ln] + qh;
                }
            }
        }
        for a in 0..D {
            for b in a + 1..D {
                for ln in 0..W {
                    let s = 0.5 * (e[a][b][ln] + e[b][a][ln]);
                    e[a][b][ln] = s;
                    e[b][a][ln] = s;
                }
            }
        }
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

    #[inline(always)]
    fn kirchhoff<const D: usize>(p: &Params, f: &Deformation<D>) -> Stress<D> {
        let (e, q) = corotated_strain(&f.h);
        let ezz = if D == 2 { f.hzz } else { 0.0 };
        let mut tr = ezz;
        for (a, row) in e.iter().enumerate() {
            tr += row[a];
        }
        let mut s = [[0.0; D]; D];
        for a in 0..D {
            for b in 0..D {
                s[a][b] = 2.0 * p.mu * e[a][b];
            }
            s[a][a] += p.lambda * tr;
        }
        // R s R^T with R = I + Q.
        let mut r = q;
        for (a, row) in r.iter_mut().enumerate() {
            row[a] += 1.0;
        }
        let mut rt = [[0.0; D]; D];
        for a in 0..D {
            for b in 0..D {
                rt[a][b] = r[b][a];
            }
        }
        let j = 1.0 + f.jm1;
        let mut m = mul(&mul(&r, &s), &rt);
        for row in m.iter_mut() {
            for v in row.iter_mut() {
                *v *= j;
            }
        }
        let zz = if D == 2 {
            j * (p.lambda * tr + 2.0 * p.mu * ezz)
        } else {
            0.0
        };
        Stress { m, zz }
    }

    fn energy<const D: usize>(p: &Params, f: &Deformation<D>) -> Real {
        let (e, _) = corotated_strain(&f.h);
        let ezz = if D == 2 { f.hzz } else { 0.0 };
        let mut tr = ezz;
        let mut ee = ezz * ezz;
        for a in 0..D {
            tr += e[a][a];
            for b in 0..D {
                ee += e[a][b] * e[a][b];
            }
        }
        p.mu * ee + 0.5 * p.lambda * tr * tr
    }
}
