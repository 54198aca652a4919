//! Isotropic linear elasticity (small strain) in the corotated frame (E34): `F = R U`,
//! `e = U - I`, `sigma_rot = lambda tr(e) I + 2 mu e`, `tau = J R sigma_rot R^T`. For small
//! strain and no rotation this is classic linear elasticity; a rigid rotation gives exactly
//! zero strain.
//! In 2D the out-of-plane axis is a principal direction (R turns in the plane only), so
//! `e_zz = F_zz - 1`: 0 in plane strain (`sigma_zz = lambda tr(e)`), the hoop strain when
//! axisymmetric.
//!
//! Written in `H = F - I` and `Q = R - I`: `e = sym(R^T F) - I = sym(Q^T + H + Q^T H)`.

use super::model::{Deformation, Lame, Model, Stress};
use crate::layout::MaterialRecord;
use crate::math::{mul, polar_rotation_minus_identity};
use crate::num::{matrix, MatOf, Num};
use crate::Real;

/// Small strain `e = sym(R^T F) - I` of the corotated frame, and `Q = R - I`.
#[inline(always)]
fn corotated_strain<T: Num, const D: usize>(h: &MatOf<T, D>) -> (MatOf<T, D>, MatOf<T, D>) {
    let q = polar_rotation_minus_identity(h);
    // (R^T F - I)[a][b] = Q[b][a] + H[a][b] + sum_k Q[k][a] H[k][b]
    let mut e: MatOf<T, D> = matrix(|a, b| {
        let mut qh = T::splat(0.0);
        for k in 0..D {
            qh += q[k][a] * h[k][b];
        }
        q[b][a] + h[a][b] + qh
    });
    // U is symmetric in exact arithmetic; symmetrise the round-off away.
    for a in 0..D {
        for b in a + 1..D {
            let s = (e[a][b] + e[b][a]) * 0.5;
            e[a][b] = s;
            e[b][a] = s;
        }
    }
    (e, q)
}

/// Corotated linear elasticity.
pub(crate) struct LinearElastic;

impl Model for LinearElastic {
    type Params = Lame;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> Lame {
        Lame::of(r)
    }

    /// The 3D polar decomposition iterates until each particle converges: on vectors, the
    /// iteration runs over the lanes (lane by lane it did not vectorise: 6.6 times the
    /// instructions); the 2D closed form vectorises lane by lane.
    #[inline(always)]
    fn on_vectors(d: usize) -> bool {
        d == 3
    }

    #[inline(always)]
    fn kirchhoff<const D: usize, T: Num>(p: &Lame, f: &Deformation<D, T>) -> Stress<D, T> {
        let (e, q) = corotated_strain(&f.h);
        // tr(e) with the out-of-plane e_zz, and s = lambda tr(e) I + 2 mu e.
        let mut tr = if D == 2 { f.hzz } else { T::splat(0.0) };
        for (a, row) in e.iter().enumerate() {
            tr += row[a];
        }
        let mut s: MatOf<T, D> = matrix(|a, b| e[a][b] * (2.0 * p.mu));
        for (a, row) in s.iter_mut().enumerate() {
            row[a] += tr * p.lambda;
        }
        // tau = J R s R^T with R = I + Q.
        let mut r = q;
        for (a, row) in r.iter_mut().enumerate() {
            row[a] += T::splat(1.0);
        }
        let rs = mul(&r, &s);
        let j = f.jm1 + 1.0;
        let m = matrix(|i, k| {
            let mut sum = T::splat(0.0);
            for n in 0..D {
                sum += rs[i][n] * r[k][n];
            }
            sum * j
        });
        let zz = if D == 2 {
            j * (tr * p.lambda + f.hzz * (2.0 * p.mu))
        } else {
            T::splat(0.0)
        };
        Stress { m, zz }
    }

    fn energy<const D: usize>(p: &Lame, f: &Deformation<D>) -> Real {
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
