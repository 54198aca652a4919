//! Principal logarithmic strains of a deformation and a change of them (E37, E38): what the
//! Hencky models ([`super::von_mises`], [`super::drucker_prager`]) and snow's clamp
//! ([`super::snow`]) work in. The Hencky models share their [`Model`] ([`HenckyReturn`]): each
//! gives only its parameters and its return.
//!
//! With `F = V S R` (left stretch `V`, rotation `R`), `b = F F^T = V^2` has the eigenvectors
//! `n_i` and eigenvalues `s_i^2`; the principal log strains are `eps_i = ln s_i`. A return
//! mapping that changes them to `eps_i + delta_i` along the same directions gives
//! `F' = M F` with `M = sum_i exp(delta_i) n_i n_i^T`. Everything is written in `H = F - I` and
//! `b - I = H + H^T + H H^T`, so that small strains keep their precision in f32, and on
//! [`Num`], with a fixed number of Jacobi rotations and no branch, so that the lanes of a vector
//! run it in step.
//!
//! In 2D the out-of-plane axis is always principal: its strain is `ln(1 + hzz)`, the hoop
//! stretch when axisymmetric, 0 in plane strain, where a return leaves it alone (the 2D form
//! of the plastic models: their flow is in the plane).

use super::model::{Deformation, Lame, Model, Stress};
use crate::layout::MaterialRecord;
use crate::math::{exp_m1_fast, ln_1p_fast};
use crate::num::{matrix, vector, MatOf, Num};
use crate::Real;

/// Sweeps of cyclic Jacobi rotations in 3D: convergence is quadratic, and four sweeps
/// reconstruct any symmetric 3 x 3 matrix to 64 eps of its largest entry in f32 and f64
/// (tested over 2000 random matrices; three sweeps fail that in f64); one rotation is exact in
/// 2D.
const SWEEPS_3D: usize = 4;

/// `|x|`.
#[inline(always)]
pub(crate) fn abs<T: Num>(x: T) -> T {
    x.map(|v| v.abs())
}

/// The eigen decomposition of the symmetric `a`: eigenvalues and the matrix whose columns are
/// the eigenvectors (`a = V diag(lambda) V^T`), by cyclic Jacobi rotations.
#[inline(always)]
pub(crate) fn eigen_symmetric<T: Num, const D: usize>(a: &MatOf<T, D>) -> ([T; D], MatOf<T, D>) {
    let mut a = *a;
    let mut v: MatOf<T, D> = matrix(|r, c| T::splat(if r == c { 1.0 } else { 0.0 }));
    let sweeps = if D == 2 { 1 } else { SWEEPS_3D };
    let zero = T::splat(0.0);
    for _ in 0..sweeps {
        for p in 0..D {
            for q in p + 1..D {
                let apq = a[p][q];
                let d = a[q][q] - a[p][p];
                // tan of the rotation angle, the smaller root: sign(d) 2 a_pq / (|d| +
                // sqrt(d^2 + 4 a_pq^2)); the smallest positive real keeps a_pq = d = 0 at 0.
                let sign = T::select(d.ge(zero), T::splat(1.0), T::splat(-1.0));
                let root = (d * d + apq * apq * 4.0).sqrt();
                let t = sign * apq * 2.0 / (abs(d) + root + Real::MIN_POSITIVE);
                let c = T::splat(1.0) / (t * t + 1.0).sqrt();
                let s = t * c;
                a[p][p] -= t * apq;
                a[q][q] += t * apq;
                a[p][q] = zero;
                a[q][p] = zero;
                for r in 0..D {
                    if r != p && r != q {
                        let (arp, arq) = (a[r][p], a[r][q]);
                        a[r][p] = c * arp - s * arq;
                        a[p][r] = a[r][p];
                        a[r][q] = s * arp + c * arq;
                        a[q][r] = a[r][q];
                    }
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    (vector(|i| a[i][i]), v)
}

/// The principal directions and log strains of a deformation: `n[a][i]` is component a of
/// direction i (in the plane in 2D), `eps[i]` for i < D, and `eps[2]` the out-of-plane strain
/// in 2D (`ln(1 + hzz)`).
#[derive(Clone, Copy)]
pub(crate) struct Principal<const D: usize, T> {
    pub n: MatOf<T, D>,
    pub eps: [T; 3],
    /// The principal stretches less 1, `exp(eps_i) - 1`.
    pub s_m1: [T; 3],
}

/// `ln(1 + x)` for `x > -1`, on any [`Num`].
#[inline(always)]
fn ln_1p<T: Num>(x: T) -> T {
    x.map(|v| ln_1p_fast(v.max(-1.0 + Real::EPSILON)))
}

impl<const D: usize, T: Num> Principal<D, T> {
    /// The principal log strains of `f`.
    #[inline(always)]
    pub fn of(f: &Deformation<D, T>) -> Self {
        let h = &f.h;
        // b - I = H + H^T + H H^T
        let bm1: MatOf<T, D> = matrix(|a, b| {
            let mut hh = h[a][b] + h[b][a];
            for k in 0..D {
                hh += h[a][k] * h[b][k];
            }
            hh
        });
        let (lam, n) = eigen_symmetric(&bm1);
        let (mut eps, mut s_m1) = ([T::splat(0.0); 3], [T::splat(0.0); 3]);
        for i in 0..D {
            eps[i] = ln_1p(lam[i]) * 0.5;
            // s - 1 = (s^2 - 1) / (s + 1), without cancellation.
            s_m1[i] = lam[i] / ((lam[i] + 1.0).sqrt() + 1.0);
        }
        if D == 2 {
            eps[2] = ln_1p(f.hzz);
            s_m1[2] = f.hzz;
        }
        Principal { n, eps, s_m1 }
    }

    /// The Kirchhoff stress of Hencky elasticity, `tau = sum_i (2 mu eps_i + lambda tr eps)
    /// n_i n_i^T` (with the out-of-plane `2 mu eps_zz + lambda tr eps` in 2D).
    #[inline(always)]
    pub fn hencky(&self, mu: T, lambda: T) -> Stress<D, T> {
        let tr = self.eps[0] + self.eps[1] + self.eps[2];
        let t: [T; 3] = vector(|i| self.eps[i] * mu * 2.0 + lambda * tr);
        let m = matrix(|a, b| {
            let mut s = T::splat(0.0);
            for i in 0..D {
                s += self.n[a][i] * self.n[b][i] * t[i];
            }
            s
        });
        let zz = if D == 2 { t[2] } else { T::splat(0.0) };
        Stress { m, zz }
    }

    /// `f` with its principal log strains changed by `delta` (`delta[2]` the out-of-plane one in
    /// 2D): `F' = M F`, `M - I = sum_i (exp(delta_i) - 1) n_i n_i^T`, so `H' = H + (M - I)(I +
    /// H)`; `J - 1` follows. Also the principal strains of the result: the axes are the same
    /// (`b' = M b M^T`, M sharing b's axes), each log strain moves by its `delta` and each
    /// stretch is multiplied by `exp(delta_i)`. A return takes the stress from these rather
    /// than decomposing the new deformation again.
    ///
    /// Only the first `n` deltas may be other than zero ([`plastic_axes`]): the others are
    /// their own `exp - 1`, and the out-of-plane one of plane strain costs no exponential.
    #[inline(always)]
    pub fn change(
        &self,
        f: &Deformation<D, T>,
        delta: &[T; 3],
        n: usize,
    ) -> (Deformation<D, T>, Principal<D, T>) {
        // A loop, not `vector` (whose closure this size was left out of line).
        let mut g = *delta;
        for (g, d) in g.iter_mut().zip(delta).take(n) {
            *g = d.map(exp_m1_fast);
        }
        let mm1: MatOf<T, D> = matrix(|a, b| {
            let mut s = T::splat(0.0);
            for i in 0..D {
                s += self.n[a][i] * self.n[b][i] * g[i];
            }
            s
        });
        let h = matrix(|a, b| {
            let mut s = f.h[a][b] + mm1[a][b];
            for k in 0..D {
                s += mm1[a][k] * f.h[k][b];
            }
            s
        });
        let hzz = if D == 2 {
            f.hzz + (f.hzz + 1.0) * g[2]
        } else {
            f.hzz
        };
        let changed = Principal {
            n: self.n,
            eps: vector(|i| self.eps[i] + delta[i]),
            s_m1: vector(|i| self.s_m1[i] + (self.s_m1[i] + 1.0) * g[i]),
        };
        (Deformation::with_plastic(h, hzz, f.plastic), changed)
    }

    /// The fixed-corotated Kirchhoff stress (E36) in the principal axes of `V` (`F = V R`,
    /// stretches `s_i = exp(eps_i)`): `(F - R) F^T = (V - I) V`, so `tau = sum_i 2 mu (s_i -
    /// 1) s_i n_i n_i^T + lambda (J - 1) J I`, with `jm1 = J - 1` of the deformation.
    #[inline(always)]
    pub fn corotated(&self, mu: T, lambda: T, jm1: T) -> Stress<D, T> {
        let vol = lambda * jm1 * (jm1 + 1.0);
        let t: [T; 3] = vector(|i| self.s_m1[i] * (self.s_m1[i] + 1.0) * mu * 2.0);
        let m = matrix(|a, b| {
            let mut s = T::splat(0.0);
            for i in 0..D {
                s += self.n[a][i] * self.n[b][i] * t[i];
            }
            if a == b {
                s + vol
            } else {
                s
            }
        });
        let zz = if D == 2 { t[2] + vol } else { T::splat(0.0) };
        Stress { m, zz }
    }
}

/// The volumetric and deviatoric parts of the first `n` principal strains.
#[derive(Clone, Copy)]
pub(crate) struct Split<T> {
    /// Their trace.
    pub trace: T,
    /// Each less the mean (0 past `n`).
    pub dev: [T; 3],
    /// The deviator's norm.
    pub norm: T,
}

impl<const D: usize, T: Num> Principal<D, T> {
    /// The split of the first `n` principal strains ([`plastic_axes`]).
    #[inline(always)]
    pub fn split(&self, n: usize) -> Split<T> {
        let mut trace = T::splat(0.0);
        for i in 0..n {
            trace += self.eps[i];
        }
        let mean = trace * (1.0 / n as Real);
        let dev: [T; 3] = vector(|i| {
            if i < n {
                self.eps[i] - mean
            } else {
                T::splat(0.0)
            }
        });
        let norm = (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]).sqrt();
        Split { trace, dev, norm }
    }
}

/// Hencky strain energy `mu |eps|^2 + lambda/2 (tr eps)^2` in the principal log strains, with
/// the Lamé constants `lambda`, `mu`.
pub(crate) fn hencky_energy<const D: usize>(lambda: Real, mu: Real, f: &Deformation<D>) -> Real {
    let e = Principal::<D, Real>::of(f).eps;
    let tr = e[0] + e[1] + e[2];
    mu * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) + 0.5 * lambda * tr * tr
}

/// How many principal strains a return acts on: 3 in 3D and axisymmetric, the 2 in-plane ones
/// in plane strain (the out-of-plane stretch stays 1).
#[inline(always)]
pub(crate) fn plastic_axes(d: usize, hoop: bool) -> usize {
    if d == 3 || hoop {
        3
    } else {
        2
    }
}

/// A plastic model on Hencky elasticity (E37) whose return map acts on the principal log
/// strains of the trial `F_e`: von Mises (E39) and Drucker-Prager (E40, E41). Its [`Model`]
/// is the same frame for all: the Hencky stress and energy of `F_e`, and an inelastic part
/// that decomposes the trial `F_e` once, splits its first `n` principal strains
/// ([`plastic_axes`]), lets the model's return say how they change, changes `F_e` by that
/// ([`Principal::change`]) and takes the Hencky stress from the changed principal strains.
/// The model gives its parameters, their Lamé constants and the return.
pub(crate) trait HenckyReturn {
    /// The parameters the model reads ([`Model::Params`]).
    type Params: Copy;

    /// The parameters of material `r` ([`Model::params`]).
    fn params(r: &MaterialRecord) -> Self::Params;

    /// Hencky elasticity's Lamé constants among the parameters.
    fn lame(p: &Self::Params) -> Lame;

    /// The return: from the principal strains `pr` of the trial `F_e`, the split `split` of
    /// their first `n` and the history `plastic`, the change `delta` of the principal strains
    /// (0 past `n`) and the new history. Written on [`Num`] without branches.
    fn principal_return<const D: usize, T: Num>(
        p: &Self::Params,
        pr: &Principal<D, T>,
        split: Split<T>,
        n: usize,
        plastic: T,
    ) -> ([T; 3], T);
}

impl<M: HenckyReturn> Model for M {
    type Params = M::Params;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> M::Params {
        <M as HenckyReturn>::params(r)
    }

    const INELASTIC: bool = true;

    /// On vectors: its stress takes logarithms, exponentials or a Jacobi decomposition, which a
    /// loop over lanes ran 4 times as long (measured, von Mises 3D).
    #[inline(always)]
    fn on_vectors(_d: usize) -> bool {
        true
    }

    #[inline(always)]
    fn kirchhoff<const D: usize, T: Num>(p: &M::Params, f: &Deformation<D, T>) -> Stress<D, T> {
        let l = M::lame(p);
        Principal::of(f).hencky(T::splat(l.mu), T::splat(l.lambda))
    }

    fn energy<const D: usize>(p: &M::Params, f: &Deformation<D>) -> Real {
        let l = M::lame(p);
        hencky_energy(l.lambda, l.mu, f)
    }

    /// The accumulated plastic strain never decreases from 0.
    fn history_in_range(plastic: Real) -> bool {
        plastic >= 0.0
    }

    /// The return, and the stress from its principal strains.
    #[inline(always)]
    fn inelastic<const D: usize, T: Num>(
        p: &M::Params,
        f: &Deformation<D, T>,
        hoop: bool,
    ) -> (Deformation<D, T>, Stress<D, T>) {
        let pr = Principal::of(f);
        let n = plastic_axes(D, hoop);
        let (delta, plastic) = M::principal_return(p, &pr, pr.split(n), n, f.plastic);
        let (mut g, changed) = pr.change(f, &delta, n);
        g.plastic = plastic;
        let l = M::lame(p);
        let tau = changed.hencky(T::splat(l.mu), T::splat(l.lambda));
        (g, tau)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat;

    /// Over many random symmetric matrices (entries from 1e-6 to 10, 2D and 3D), the Jacobi
    /// decomposition reproduces the matrix (`V diag V^T`) to 64 eps of its largest entry and
    /// its vectors are orthonormal to 16 eps.
    #[test]
    fn jacobi_decomposes_symmetric_matrices() {
        let mut state = 99u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f64 / (1u64 << 24) as f64) as Real - 0.5
        };
        fn check<const D: usize>(a: &Mat<D>) {
            let (lam, v) = eigen_symmetric(a);
            let scale = a.iter().flatten().fold(0.0 as Real, |m, x| m.max(x.abs()));
            for r in 0..D {
                for c in 0..D {
                    let mut back = 0.0;
                    let mut dot = 0.0;
                    for i in 0..D {
                        back += v[r][i] * v[c][i] * lam[i];
                        dot += v[i][r] * v[i][c];
                    }
                    let eye = if r == c { 1.0 } else { 0.0 };
                    assert!(
                        (back - a[r][c]).abs() <= 64.0 * Real::EPSILON * scale,
                        "{a:?}"
                    );
                    assert!((dot - eye).abs() <= 16.0 * Real::EPSILON, "{a:?}");
                }
            }
        }
        for k in 0..2000 {
            let scale = [1.0e-6, 1.0e-2, 1.0, 10.0][k % 4];
            let mut a3: Mat<3> = [[0.0; 3]; 3];
            for r in 0..3 {
                for c in r..3 {
                    a3[r][c] = next() * scale;
                    a3[c][r] = a3[r][c];
                }
            }
            if k % 7 == 0 {
                a3[0][1] = 0.0;
                a3[1][0] = 0.0;
                a3[1][1] = a3[0][0];
            }
            check(&a3);
            check(&[[a3[0][0], a3[0][1]], [a3[1][0], a3[1][1]]]);
        }
        check(&[[0.0; 3]; 3]);
    }

    /// A deformation with known principal stretches (a rotated diagonal stretch) gives their
    /// logs, and changing them by `delta` gives the stretches times `exp(delta)` in the same
    /// directions.
    #[test]
    fn principal_strains_of_a_rotated_stretch() {
        let (c, s) = (0.8 as Real, 0.6 as Real);
        let rot: Mat<3> = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let st = [1.2 as Real, 0.9, 1.05];
        // F = Q diag(st) Q^T, H = F - I
        let f: Mat<3> = matrix(|a, b| {
            let mut v = 0.0;
            for i in 0..3 {
                v += rot[a][i] * st[i] * rot[b][i];
            }
            v - if a == b { 1.0 } else { 0.0 }
        });
        let def = Deformation::new(f, 0.0);
        let p = Principal::of(&def);
        let mut got = p.eps;
        got.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut want = st.map(|x| x.ln());
        want.sort_by(|a, b| a.partial_cmp(b).unwrap());
        for i in 0..3 {
            assert!((got[i] - want[i]).abs() < 1e-5, "{got:?} {want:?}");
        }
        let delta = [0.01 as Real, -0.02, 0.03];
        let (g, changed) = p.change(&def, &delta, 3);
        for i in 0..3 {
            // Each direction of `p` is still principal with strain eps_i + delta_i.
            let mut bn = [0.0 as Real; 3];
            for a in 0..3 {
                for b in 0..3 {
                    let mut bab = 0.0;
                    for k in 0..3 {
                        let fa = g.h[a][k] + if a == k { 1.0 } else { 0.0 };
                        let fb = g.h[b][k] + if b == k { 1.0 } else { 0.0 };
                        bab += fa * fb;
                    }
                    bn[a] += bab * p.n[b][i];
                }
            }
            let want = libm::exp(2.0 * (p.eps[i] + delta[i]) as f64) as Real;
            for a in 0..3 {
                assert!((bn[a] - want * p.n[a][i]).abs() < 1e-5, "{i} {bn:?}");
            }
            // The principal strains `change` gives (what a return takes its stress from) are
            // those of its result: log strain and stretch less 1.
            let stretch = libm::exp((p.eps[i] + delta[i]) as f64);
            assert!((changed.eps[i] as f64 - (p.eps[i] + delta[i]) as f64).abs() < 1e-6);
            assert!((changed.s_m1[i] as f64 - (stretch - 1.0)).abs() < 1e-5 * stretch);
            assert_eq!(changed.n[i], p.n[i]);
        }
        // And the stress from them is the stress of the result decomposed anew.
        let (mu, lambda) = (1.0e6 as Real, 2.0e6 as Real);
        let (shared, anew) = (
            changed.hencky(mu, lambda),
            Principal::of(&g).hencky(mu, lambda),
        );
        // The fixed-corotated stress in principal form is the polar decomposition's (E36).
        let corotated = changed.corotated(mu, lambda, g.jm1);
        let polar = crate::material::fixed_corotated::stress(&g, mu, lambda);
        for a in 0..3 {
            for b in 0..3 {
                assert!((shared.m[a][b] - anew.m[a][b]).abs() < 1e-5 * mu, "{a}{b}");
                assert!(
                    (corotated.m[a][b] - polar.m[a][b]).abs() < 1e-5 * mu,
                    "{a}{b}"
                );
            }
        }
    }
}
