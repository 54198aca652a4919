//! Constitutive models: the displacement gradient `H = F - I` and `J - 1` in, Kirchhoff stress
//! over initial density `tau / rho0` out (seeds/000 eq 18), plus the strain energy per unit
//! initial volume for energy checks.
//!
//! In 2D (plane strain) `F_zz = 1` and the out-of-plane stress is returned separately as `zz`.

mod linear_elastic;
mod neo_hookean;

use crate::layout::MaterialRecord;
use crate::math::Mat;
use crate::{MaterialModel, Real};

/// Stress as a D x D matrix plus the plane-strain `zz` component (0 in 3D).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stress<const D: usize> {
    pub m: Mat<D>,
    pub zz: Real,
}

/// Parameters the models need, taken from a material record once per step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Params {
    pub lambda: Real,
    pub mu: Real,
    pub inv_rho0: Real,
}

impl Params {
    pub fn of(r: &MaterialRecord) -> Params {
        Params {
            lambda: r.lambda,
            mu: r.mu,
            inv_rho0: 1.0 / r.density,
        }
    }
}

/// The model stored in a record.
pub(crate) fn model_of(r: &MaterialRecord) -> MaterialModel {
    if r.model == MaterialModel::LinearElastic as u32 as Real {
        MaterialModel::LinearElastic
    } else {
        MaterialModel::NeoHookean
    }
}

/// `tau / rho0` from `H = F - I` and `jm1 = det F - 1 > -1`.
#[inline(always)]
pub(crate) fn kirchhoff_over_rho0<const D: usize>(
    model: MaterialModel,
    p: &Params,
    h: &Mat<D>,
    jm1: Real,
) -> Stress<D> {
    let mut s = match model {
        MaterialModel::NeoHookean => neo_hookean::kirchhoff(p, h, jm1),
        MaterialModel::LinearElastic => linear_elastic::kirchhoff(p, h, jm1),
    };
    for row in s.m.iter_mut() {
        for v in row.iter_mut() {
            *v *= p.inv_rho0;
        }
    }
    s.zz *= p.inv_rho0;
    s
}

/// Neo-Hookean `tau / rho0` for `W` particles sharing one material (the vectorised path of the
/// stress update); see [`neo_hookean`].
#[inline(always)]
pub(crate) fn neo_hookean_lanes<const D: usize, const W: usize>(
    p: &Params,
    h: &[[[Real; W]; D]; D],
    jm1: &[Real; W],
    tau: &mut [[Real; W]; 6],
) {
    neo_hookean::kirchhoff_lanes(p, h, jm1, tau);
}

/// Strain energy per unit initial volume, J/m^3, from `H = F - I` and `jm1 = det F - 1`.
pub(crate) fn energy_density<const D: usize>(
    model: MaterialModel,
    p: &Params,
    h: &Mat<D>,
    jm1: Real,
) -> Real {
    match model {
        MaterialModel::NeoHookean => neo_hookean::energy(p, h, jm1),
        MaterialModel::LinearElastic => linear_elastic::energy(p, h),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::det_identity_plus_minus_one;

    fn rotation_minus_identity(angle: Real, axis: usize) -> Mat<3> {
        let (s, c) = (
            libm::sin(angle as f64) as Real,
            libm::cos(angle as f64) as Real,
        );
        let (i, j) = [(1, 2), (2, 0), (0, 1)][axis];
        let mut q = [[0.0; 3]; 3];
        q[i][i] = c - 1.0;
        q[j][j] = c - 1.0;
        q[i][j] = -s;
        q[j][i] = s;
        q
    }

    /// Objectivity: a rigid rotation (F = R, so H = R - I) gives zero stress and zero energy
    /// in both models, to round-off, for many angles about every axis, in 3D and 2D.
    #[test]
    fn rigid_rotation_gives_zero_stress_and_energy() {
        let p = Params {
            lambda: 5.0e5,
            mu: 4.0e5,
            inv_rho0: 1.0e-3,
        };
        for model in [MaterialModel::NeoHookean, MaterialModel::LinearElastic] {
            for k in 0..64 {
                let angle = -3.0 + 6.0 * k as Real / 63.0;
                for axis in 0..3 {
                    let h = rotation_minus_identity(angle, axis);
                    let jm1 = det_identity_plus_minus_one(&h);
                    let s = kirchhoff_over_rho0(model, &p, &h, jm1);
                    // tau/rho0 scale of a unit strain is (lambda + 2 mu)/rho0 = 1300; round-off
                    // of order 1e-6 of it is what f32 leaves.
                    let bound = 1.0e-5 * 1300.0;
                    assert!(
                        s.m.iter().flatten().all(|v| v.abs() < bound),
                        "{model:?} {angle} {axis}: {:?}",
                        s.m
                    );
                    assert!(energy_density(model, &p, &h, jm1).abs() < 1.0e-5 * 1.3e6);
                }
                let (s2, c2) = (
                    libm::sin(angle as f64) as Real,
                    libm::cos(angle as f64) as Real,
                );
                let h2: Mat<2> = [[c2 - 1.0, -s2], [s2, c2 - 1.0]];
                let jm1 = det_identity_plus_minus_one(&h2);
                let s = kirchhoff_over_rho0(model, &p, &h2, jm1);
                assert!(s.m.iter().flatten().all(|v| v.abs() < 1.0e-5 * 1300.0));
                assert!(s.zz.abs() < 1.0e-5 * 1300.0);
            }
        }
    }

    /// Uniaxial small strain (H = diag(eps, 0, 0)): both models give the linear-elastic stress
    /// `tau_xx = (lambda + 2 mu) eps`, `tau_yy = lambda eps` to first order (relative 2 eps).
    #[test]
    fn small_uniaxial_strain_matches_linear_elasticity() {
        let p = Params {
            lambda: 5.0e5,
            mu: 4.0e5,
            inv_rho0: 1.0,
        };
        let eps = 1.0e-4;
        let h: Mat<3> = [[eps, 0.0, 0.0], [0.0; 3], [0.0; 3]];
        for model in [MaterialModel::NeoHookean, MaterialModel::LinearElastic] {
            let s = kirchhoff_over_rho0(model, &p, &h, det_identity_plus_minus_one(&h));
            let xx = (p.lambda + 2.0 * p.mu) * eps;
            let yy = p.lambda * eps;
            assert!((s.m[0][0] - xx).abs() < 2.0 * eps * xx + 1e-3, "{model:?}");
            assert!((s.m[1][1] - yy).abs() < 2.0 * eps * xx + 1e-3, "{model:?}");
            // Energy (lambda + 2 mu) eps^2 / 2.
            let w = energy_density(model, &p, &h, det_identity_plus_minus_one(&h));
            let expect = 0.5 * (p.lambda + 2.0 * p.mu) * eps * eps;
            assert!((w - expect).abs() < 1e-3 * expect, "{model:?} {w} {expect}");
        }
    }
}
