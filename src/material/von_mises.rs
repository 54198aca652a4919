//! Metal: J2 (von Mises) plasticity with linear isotropic hardening (E39) on Hencky elasticity
//! (E37), `F = F_e F_p`. The stored deformation is `F_e`; the history is the equivalent
//! plastic strain `eps_p`. The return (Simo and Hughes 1998, section 9.2) is the radial return
//! in principal logarithmic strains of the trial `F_e`: with the deviatoric strain `e` (norm
//! `|e|`), the deviatoric Kirchhoff stress is `2 mu e`, and where `f = 2 mu |e| - sqrt(2/3)
//! (sigma_y + H eps_p) > 0` the plastic multiplier `dgamma = f / (2 mu + 2 H / 3)` takes `e`
//! back to the yield surface along itself, `eps_p += sqrt(2/3) dgamma`. The flow is
//! isochoric: `J_p = 1`.
//! Under uniaxial stress this is `sigma = sigma_y + H eps_p` in Kirchhoff stress and
//! logarithmic strain (`sigma_y` the initial yield stress, H the hardening modulus).
//!
//! In plane strain the return acts on the two in-plane strains with the deviator taken over
//! them (the 2D form; see [`super::principal`]).

use super::model::Lame;
use super::principal::{abs, HenckyReturn, Principal, Split};
use crate::layout::MaterialRecord;
use crate::num::{vector, Num};
use crate::Real;

/// `sqrt(2/3)`.
const SQRT_2_3: Real = 0.816_496_580_927_726_f64 as Real;

/// Von Mises' parameters: Hencky elasticity's Lamé constants (E37) and the linear hardening's
/// (E39).
#[derive(Clone, Copy, Debug)]
pub(crate) struct VonMisesParams {
    /// Hencky elasticity's Lamé constants.
    pub lame: Lame,
    /// The initial yield stress `sigma_y`, Pa.
    pub yield_stress: Real,
    /// The hardening modulus H, Pa.
    pub hardening_modulus: Real,
}

/// J2 plasticity with linear isotropic hardening.
pub(crate) struct VonMises;

impl HenckyReturn for VonMises {
    type Params = VonMisesParams;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> VonMisesParams {
        VonMisesParams {
            lame: Lame::of(r),
            yield_stress: r.yield_stress,
            hardening_modulus: r.hardening_modulus,
        }
    }

    #[inline(always)]
    fn lame(p: &VonMisesParams) -> Lame {
        p.lame
    }

    /// The radial return (E39): `e` back to the yield surface along itself.
    #[inline(always)]
    fn principal_return<const D: usize, T: Num>(
        p: &VonMisesParams,
        _pr: &Principal<D, T>,
        split: Split<T>,
        _n: usize,
        plastic: T,
    ) -> ([T; 3], T) {
        let Split { dev: e, norm, .. } = split;
        let yield_radius = (plastic * p.hardening_modulus + p.yield_stress) * SQRT_2_3;
        let excess = norm * (2.0 * p.lame.mu) - yield_radius;
        let zero = T::splat(0.0);
        let dgamma = T::select(excess.gt(zero), excess, zero)
            * (1.0 / (2.0 * p.lame.mu + 2.0 / 3.0 * p.hardening_modulus));
        // e's direction; dgamma is 0 where the norm is (no excess), so the tiny real only keeps
        // 0 / 0 away.
        let along = dgamma / (norm + Real::MIN_POSITIVE);
        let delta: [T; 3] = vector(|i| -(e[i] * along));
        (delta, plastic + abs(dgamma) * SQRT_2_3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Deformation, Model};
    use crate::{MaterialDef, MaterialModel};

    /// The plastic work equals the dissipation: along a strain path with fixed principal axes
    /// (tension to a log strain of 6 %, back to 1 %, then compression to -4 % along x, the
    /// other axes following at -0.3 and -0.2 of it), the work `int tau : d eps` per unit
    /// reference volume (trapezoid over 6000 increments) less the elastic energy stored in
    /// `F_e` at the end is `int sigma_Y d eps_p = sigma_y eps_p + H eps_p^2 / 2`, within 1e-3
    /// (the trapezoid's error on the corners of the path). Both are about 40 times the stored
    /// energy, so a return that loses or invents work fails by far.
    #[test]
    fn plastic_work_equals_the_dissipation() {
        let metal = MaterialDef {
            model: MaterialModel::VonMises,
            youngs_modulus: 2.0e7,
            poisson_ratio: 0.3,
            yield_stress: 1.0e5,
            hardening_modulus: 2.0e6,
            ..MaterialDef::DEFAULT
        };
        let p = <VonMises as Model>::params(&crate::material::material_record(&metal).unwrap());
        let mut f = Deformation::<3>::new([[0.0; 3]; 3], 0.0);
        let (mut eps, mut work) = (0.0f64, 0.0f64);
        let mut tau_old = [0.0f64; 3];
        let legs = [(0.06, 2000), (0.01, 1000), (-0.04, 3000)];
        for (target, n) in legs {
            let de = (target - eps) / n as f64;
            for _ in 0..n {
                let d = [de, -0.3 * de, -0.2 * de];
                // F_e <- dF F_e with dF = diag(exp(d)), then the return.
                let trial = Deformation::new(
                    core::array::from_fn(|a| {
                        core::array::from_fn(|b| {
                            let g = libm::expm1(d[a]) as Real;
                            f.h[a][b] + g * (f.h[a][b] + if a == b { 1.0 } else { 0.0 })
                        })
                    }),
                    0.0,
                );
                let trial = Deformation::with_plastic(trial.h, 0.0, f.plastic);
                f = VonMises::inelastic(&p, &trial, false).0;
                let s = VonMises::kirchhoff(&p, &f);
                let tau = [s.m[0][0] as f64, s.m[1][1] as f64, s.m[2][2] as f64];
                for a in 0..3 {
                    work += 0.5 * (tau[a] + tau_old[a]) * d[a];
                }
                tau_old = tau;
                eps += de;
            }
        }
        let stored = VonMises::energy(&p, &f) as f64;
        let ep = f.plastic as f64;
        let (sy, hard) = (metal.yield_stress as f64, metal.hardening_modulus as f64);
        let dissipated = sy * ep + 0.5 * hard * ep * ep;
        assert!(ep > 0.08, "eps_p {ep}");
        assert!(
            (work - stored - dissipated).abs() < 1e-3 * dissipated,
            "work {work} stored {stored} dissipated {dissipated}"
        );
    }
}
