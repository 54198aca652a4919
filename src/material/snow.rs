//! Snow (Stomakhin et al. 2013, "A material point method for snow simulation"; E42, E43):
//! fixed-corotated elasticity of `F_e` ([`super::fixed_corotated`]) with the moduli hardened
//! by `exp(xi (1 - J_p))`, and a return that clamps the singular values of the trial `F_e`
//! to `[1 - theta_c, 1 + theta_s]` (critical compression and stretch), the clamped part
//! going to `F_p`. The
//! history is `J_p - 1`: `J_p` gains the trial's volume the clamp removes, `J_p' = J_p J_e /
//! J_e'`. The clamp acts on the principal log strains (singular values `exp(eps_i)`).

use super::fixed_corotated;
use super::model::{Deformation, Model, Stress};
use super::principal::{plastic_axes, Principal};
use crate::layout::MaterialRecord;
use crate::math::exp_m1_fast;
use crate::num::Num;
use crate::Real;

/// Snow's parameters: the fixed-corotated Lamé constants before hardening (E36, E42) and the
/// clamp's bounds (E43), derived from the critical compression and stretch when the material
/// was added.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SnowParams {
    /// Lamé's lambda at `J_p = 1`, Pa.
    pub lambda: Real,
    /// The shear modulus mu at `J_p = 1`, Pa.
    pub mu: Real,
    /// `ln(1 - theta_c)`, the least principal log strain of `F_e`.
    pub log_compression: Real,
    /// `ln(1 + theta_s)`, the greatest.
    pub log_stretch: Real,
    /// The hardening coefficient xi.
    pub hardening_coefficient: Real,
}

/// The hardening factor `exp(xi (1 - J_p)) = exp(-xi plastic)` of a particle.
#[inline(always)]
pub(crate) fn hardening<T: Num>(p: &SnowParams, plastic: T) -> T {
    (plastic * -p.hardening_coefficient).map(|x| exp_m1_fast(x) + 1.0)
}

/// Snow.
pub(crate) struct Snow;

impl Model for Snow {
    type Params = SnowParams;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> SnowParams {
        SnowParams {
            lambda: r.lambda,
            mu: r.mu,
            log_compression: r.log_compression,
            log_stretch: r.log_stretch,
            hardening_coefficient: r.hardening_coefficient,
        }
    }

    const INELASTIC: bool = true;

    /// On vectors: its return and stress take logarithms, exponentials and an eigen
    /// decomposition, which vectorise only there.
    #[inline(always)]
    fn on_vectors(_d: usize) -> bool {
        true
    }

    #[inline(always)]
    fn kirchhoff<const D: usize, T: Num>(p: &SnowParams, f: &Deformation<D, T>) -> Stress<D, T> {
        let k = hardening(p, f.plastic);
        fixed_corotated::stress(f, k * p.mu, k * p.lambda)
    }

    fn energy<const D: usize>(p: &SnowParams, f: &Deformation<D>) -> Real {
        let k = hardening(p, f.plastic);
        fixed_corotated::energy(f, k * p.mu, k * p.lambda)
    }

    /// `J_p - 1 > -1`: the plastic volume ratio stays positive.
    fn history_in_range(plastic: Real) -> bool {
        plastic > -1.0
    }

    /// `J_e J_p - 1`: the history holds the plastic volume change.
    fn volume_ratio_minus_one(jm1: Real, plastic: Real) -> Real {
        jm1 + plastic + jm1 * plastic
    }

    fn hardens(r: &MaterialRecord) -> bool {
        r.hardening_coefficient > 0.0
    }

    /// Hardened as the moduli: `c sqrt(exp(xi (1 - J_p)))`, falling as `J_p - 1` grows (`xi >
    /// 0` where it hardens).
    fn wave_speed(r: &MaterialRecord, plastic: Real) -> f64 {
        let k = libm::exp(-(r.hardening_coefficient as f64) * plastic as f64);
        r.wave_speed as f64 * libm::sqrt(k)
    }

    /// The clamp, and the hardened fixed-corotated stress from its principal strains
    /// (`Principal::corotated`), not from a polar decomposition of the result.
    #[inline(always)]
    fn inelastic<const D: usize, T: Num>(
        p: &SnowParams,
        f: &Deformation<D, T>,
        hoop: bool,
    ) -> (Deformation<D, T>, Stress<D, T>) {
        let n = plastic_axes(D, hoop);
        let pr = Principal::of(f);
        let (lo, hi) = (T::splat(p.log_compression), T::splat(p.log_stretch));
        let mut removed = T::splat(0.0);
        // A loop, not `vector` (whose closure this size was left out of line).
        let mut delta = [T::splat(0.0); 3];
        for i in 0..n {
            let e = pr.eps[i];
            let clamped = T::select(e.gt(hi), hi, T::select(lo.gt(e), lo, e));
            delta[i] = clamped - e;
            removed += delta[i];
        }
        let (mut g, changed) = pr.change(f, &delta, n);
        // J_p' = J_p exp(-sum delta): J_p' - 1 = plastic + (1 + plastic) (exp(-sum delta) - 1)
        g.plastic = f.plastic + (f.plastic + 1.0) * (-removed).map(exp_m1_fast);
        let k = hardening(p, g.plastic);
        let tau = changed.corotated(k * p.mu, k * p.lambda, g.jm1);
        (g, tau)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::principal::eigen_symmetric;
    use crate::math::Mat;
    use crate::{MaterialDef, MaterialModel};

    /// Over 5000 random deformations (stretches 0.5 to 1.5 in random directions, with a random
    /// rotation), in 3D, axisymmetric and plane strain, the return leaves every singular value
    /// of `F_e` within `[1 - theta_c, 1 + theta_s]` (to 32 ulps), keeps `J_e J_p = J_trial
    /// J_p,old` (relative 1e-5), and leaves a deformation already inside the bounds unchanged
    /// but for round-off.
    #[test]
    fn the_clamp_keeps_singular_values_in_bounds_and_volume_in_j_p() {
        let snow = MaterialDef {
            model: MaterialModel::Snow,
            ..MaterialDef::DEFAULT
        };
        let p = Snow::params(&crate::material::material_record(&snow).unwrap());
        let (lo, hi) = (1.0 - snow.critical_compression, 1.0 + snow.critical_stretch);
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f64 / (1u64 << 24) as f64) as Real
        };
        let tol = 32.0 * Real::EPSILON;
        for k in 0..5000 {
            // F = Q diag(s) with Q from a random symmetric matrix's eigenvectors.
            let scale = if k % 3 == 0 { 0.01 } else { 0.5 };
            let s: [Real; 3] = core::array::from_fn(|_| 1.0 + scale * (2.0 * next() - 1.0));
            let mut a: Mat<3> = [[0.0; 3]; 3];
            for r in 0..3 {
                for c in r..3 {
                    a[r][c] = next() - 0.5;
                    a[c][r] = a[r][c];
                }
            }
            let (_, q) = eigen_symmetric(&a);
            let h3: Mat<3> = core::array::from_fn(|r| {
                core::array::from_fn(|c| q[r][c] * s[c] - if r == c { 1.0 } else { 0.0 })
            });
            let old = 0.1 * (next() - 0.5);
            let f3 = Deformation::with_plastic(h3, 0.0, old);
            let h2: Mat<2> = [[s[0] - 1.0, 0.0], [0.0, s[1] - 1.0]];
            let f2 = Deformation::with_plastic(h2, s[2] - 1.0, old);
            let check = |before: Real, g_jm1: Real, g_plastic: Real, sv: &[Real]| {
                for &v in sv {
                    assert!(v >= lo * (1.0 - tol) && v <= hi * (1.0 + tol), "{v} {s:?}");
                }
                let j = (1.0 + g_jm1) * (1.0 + g_plastic);
                let want = (1.0 + before) * (1.0 + old);
                assert!((j - want).abs() < 1e-5 * want, "{j} {want}");
            };
            let g = Snow::inelastic(&p, &f3, false).0;
            let bm1: Mat<3> = core::array::from_fn(|r| {
                core::array::from_fn(|c| {
                    let mut v = g.h[r][c] + g.h[c][r];
                    for m in 0..3 {
                        v += g.h[r][m] * g.h[c][m];
                    }
                    v
                })
            });
            let (lam, _) = eigen_symmetric(&bm1);
            check(f3.jm1, g.jm1, g.plastic, &lam.map(|l| (1.0 + l).sqrt()));
            if s.iter().all(|&v| v > lo && v < hi) {
                for r in 0..3 {
                    for c in 0..3 {
                        assert!((g.h[r][c] - h3[r][c]).abs() < 8.0 * Real::EPSILON);
                    }
                }
            }
            for hoop in [true, false] {
                let g = Snow::inelastic(&p, &f2, hoop).0;
                let sv = [1.0 + g.h[0][0], 1.0 + g.h[1][1], 1.0 + g.hzz];
                if !hoop {
                    assert_eq!(g.hzz, f2.hzz, "plane strain keeps F_zz");
                }
                check(f2.jm1, g.jm1, g.plastic, &sv[..if hoop { 3 } else { 2 }]);
            }
        }
    }
}
