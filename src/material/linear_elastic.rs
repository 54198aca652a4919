//! Isotropic linear elasticity (small strain) in the corotated frame: `F = R U`, `e = U - I`,
//! `sigma_rot = lambda tr(e) I + 2 mu e`, `tau = J R sigma_rot R^T`. For small strain and no
//! rotation this is classic linear elasticity; a rigid rotation gives exactly zero strain.
//! Plane strain: `e_zz = 0`, so `sigma_zz = lambda tr(e)`.

use super::{Params, Stress};
use crate::math::{mul, polar_rotation, transpose, Mat};
use crate::Real;

/// Small strain `e = R^T F - I` of the corotated frame, and R.
#[inline(always)]
fn corotated_strain<const D: usize>(f: &Mat<D>) -> (Mat<D>, Mat<D>) {
    let r = polar_rotation(f);
    let mut e = mul(&transpose(&r), f);
    // U is symmetric in exact arithmetic; symmetrise the round-off away.
    for a in 0..D {
        for b in a + 1..D {
            let s = 0.5 * (e[a][b] + e[b][a]);
            e[a][b] = s;
            e[b][a] = s;
        }
        e[a][a] -= 1.0;
    }
    (e, r)
}

#[inline(always)]
pub(super) fn kirchhoff<const D: usize>(p: &Params, f: &Mat<D>, j: Real) -> Stress<D> {
    let (e, r) = corotated_strain(f);
    let mut tr = 0.0;
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
    let mut m = mul(&mul(&r, &s), &transpose(&r));
    for row in m.iter_mut() {
        for v in row.iter_mut() {
            *v *= j;
        }
    }
    let zz = if D == 2 { j * p.lambda * tr } else { 0.0 };
    Stress { m, zz }
}

pub(super) fn energy<const D: usize>(p: &Params, f: &Mat<D>) -> Real {
    let (e, _) = corotated_strain(f);
    let mut tr = 0.0;
    let mut ee = 0.0;
    for a in 0..D {
        tr += e[a][a];
        for b in 0..D {
            ee += e[a][b] * e[a][b];
        }
    }
    p.mu * ee + 0.5 * p.lambda * tr * tr
}
