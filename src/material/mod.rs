//! Constitutive models: the displacement gradient `H = F - I` and `J - 1` in, Kirchhoff stress
//! over initial density `tau / rho0` out (seeds/000 eq 18), plus the strain energy per unit
//! initial volume for energy checks.
//!
//! In 2D the out-of-plane stretch is given separately ([`Deformation::hzz`]: 0 in plane strain,
//! `F_thetatheta - 1` in the axisymmetric form) and the out-of-plane stress is returned
//! separately as `zz` (`tau_thetatheta` when axisymmetric).
//!
//! An isotropic eigenstrain (thermal expansion, swelling: `F_0 = (1 + d) I`) is taken out of the
//! deformation before the model sees it ([`elastic_part`]), so the models know nothing of it.

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

/// The deformation a model sees: `H = F - I` in the plane of the D axes, the out-of-plane
/// `F_zz - 1` (2D only; ignored in 3D) and `J - 1 = det F - 1` of the whole 3 x 3 `F`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Deformation<const D: usize> {
    pub h: Mat<D>,
    pub hzz: Real,
    pub jm1: Real,
}

impl<const D: usize> Deformation<D> {
    /// From `H` and the out-of-plane `F_zz - 1` (0 in plane strain and in 3D).
    #[inline(always)]
    pub fn new(h: Mat<D>, hzz: Real) -> Self {
        let j2 = crate::math::det_identity_plus_minus_one(&h);
        let jm1 = if D == 2 { j2 + hzz + j2 * hzz } else { j2 };
        Deformation { h, hzz, jm1 }
    }
}

/// The elastic part `F_e = F / (1 + d)` of a deformation carrying the isotropic eigenstrain
/// `F_0 = (1 + d) I` (thermal expansion `d = alpha (T - T_0)`, swelling `d = beta (c - c_0)`),
/// and the factor `J / J_e = (1 + d)^3` that turns the Kirchhoff stress of `F_e` into that of
/// `F` (`tau = J sigma`). Written in `H` and `d` so that small strains keep their precision:
/// `H_e = (H - d I) / (1 + d)`. In 2D the out-of-plane axis carries the eigenstrain too (a
/// clamped plane-strain block heated is stressed along z).
#[inline(always)]
pub(crate) fn elastic_part<const D: usize>(f: &Deformation<D>, d: Real) -> (Deformation<D>, Real) {
    let inv = 1.0 / (1.0 + d);
    let mut h = f.h;
    for (a, row) in h.iter_mut().enumerate() {
        row[a] -= d;
        for v in row.iter_mut() {
            *v *= inv;
        }
    }
    // (1 + d)^3 - 1 without cancellation.
    let cube_m1 = d * (3.0 + d * (3.0 + d));
    let cube = 1.0 + cube_m1;
    let e = Deformation {
        h,
        hzz: (f.hzz - d) * inv,
        jm1: (f.jm1 - cube_m1) / cube,
    };
    (e, cube)
}

/// The part of the isotropic eigenstrain `d` (`F_0 = (1 + d) I`) of a particle of material
/// `r` that transported field `field` gives at the grid value `value` there: thermal expansion
/// `alpha (T - T_0)` for heat (0), swelling `beta (c - c_0)` for diffusion (1).
#[inline(always)]
pub(crate) fn eigenstrain_part(r: &MaterialRecord, field: usize, value: Real) -> Real {
    if field == 0 {
        r.thermal_expansion * (value - r.reference_temperature)
    } else {
        r.swelling * (value - r.reference_concentration)
    }
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

/// `tau / rho0` of a deformation with `jm1 = det F - 1 > -1`.
#[inline(always)]
pub(crate) fn kirchhoff_over_rho0<const D: usize>(
    model: MaterialModel,
    p: &Params,
    f: &Deformation<D>,
) -> Stress<D> {
    let mut s = match model {
        MaterialModel::NeoHookean => neo_hookean::kirchhoff(p, f),
        MaterialModel::LinearElastic => linear_elastic::kirchhoff(p, f),
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
/// stress update): `h[a][b][lane]`, out-of-plane `hzz[lane]` (2D) and `jm1[lane]`; see
/// [`neo_hookean`].
#[inline(always)]
pub(crate) fn neo_hookean_lanes<const D: usize, const W: usize>(
    p: &Params,
    h: &[[[Real; W]; D]; D],
    hzz: &[Real; W],
    jm1: &[Real; W],
    tau: &mut [[Real; W]; 6],
) {
    neo_hookean::kirchhoff_lanes(p, h, hzz, jm1, tau);
}

/// Strain energy per unit initial volume, J/m^3, of a deformation.
pub(crate) fn energy_density<const D: usize>(
    model: MaterialModel,
    p: &Params,
    f: &Deformation<D>,
) -> Real {
    match model {
        MaterialModel::NeoHookean => neo_hookean::energy(p, f),
        MaterialModel::LinearElastic => linear_elastic::energy(p, f),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
                    let f = Deformation::new(rotation_minus_identity(angle, axis), 0.0);
                    let s = kirchhoff_over_rho0(model, &p, &f);
                    // tau/rho0 scale of a unit strain is (lambda + 2 mu)/rho0 = 1300; round-off
                    // of order 1e-6 of it is what f32 leaves.
                    let bound = 1.0e-5 * 1300.0;
                    assert!(
                        s.m.iter().flatten().all(|v| v.abs() < bound),
                        "{model:?} {angle} {axis}: {:?}",
                        s.m
                    );
                    assert!(energy_density(model, &p, &f).abs() < 1.0e-5 * 1.3e6);
                }
                let (s2, c2) = (
                    libm::sin(angle as f64) as Real,
                    libm::cos(angle as f64) as Real,
                );
                let h2: Mat<2> = [[c2 - 1.0, -s2], [s2, c2 - 1.0]];
                let s = kirchhoff_over_rho0(model, &p, &Deformation::new(h2, 0.0));
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
        let f = Deformation::<3>::new([[eps, 0.0, 0.0], [0.0; 3], [0.0; 3]], 0.0);
        for model in [MaterialModel::NeoHookean, MaterialModel::LinearElastic] {
            let s = kirchhoff_over_rho0(model, &p, &f);
            let xx = (p.lambda + 2.0 * p.mu) * eps;
            let yy = p.lambda * eps;
            assert!((s.m[0][0] - xx).abs() < 2.0 * eps * xx + 1e-3, "{model:?}");
            assert!((s.m[1][1] - yy).abs() < 2.0 * eps * xx + 1e-3, "{model:?}");
            // Energy (lambda + 2 mu) eps^2 / 2.
            let w = energy_density(model, &p, &f);
            let expect = 0.5 * (p.lambda + 2.0 * p.mu) * eps * eps;
            assert!((w - expect).abs() < 1e-3 * expect, "{model:?} {w} {expect}");
        }
    }

    /// The 2D form with an out-of-plane stretch (`hzz`: the hoop stretch of the axisymmetric
    /// form) is the 3D form with `H = diag(H2, hzz)`: same stress components and energy, for
    /// both models, at small and large strain.
    #[test]
    fn out_of_plane_stretch_matches_the_3d_model() {
        let p = Params {
            lambda: 5.0e5,
            mu: 4.0e5,
            inv_rho0: 1.0e-3,
        };
        for (scale, hzz) in [(1.0e-4, -3.0e-5), (0.2, 0.3), (0.3, -0.4)] {
            let h2: Mat<2> = [[0.5 * scale, -0.3 * scale], [0.2 * scale, -0.4 * scale]];
            let h3: Mat<3> = [
                [h2[0][0], h2[0][1], 0.0],
                [h2[1][0], h2[1][1], 0.0],
                [0.0, 0.0, hzz],
            ];
            let (f2, f3) = (Deformation::new(h2, hzz), Deformation::new(h3, 0.0));
            assert!((f2.jm1 - f3.jm1).abs() <= 4.0 * Real::EPSILON * (1.0 + f3.jm1.abs()));
            for model in [MaterialModel::NeoHookean, MaterialModel::LinearElastic] {
                let (s2, s3) = (
                    kirchhoff_over_rho0(model, &p, &f2),
                    kirchhoff_over_rho0(model, &p, &f3),
                );
                let tol = 1.0e-5 * 1300.0 * scale.max(hzz.abs()).max(1e-3);
                for (a, b) in [(0, 0), (1, 1), (0, 1)] {
                    assert!(
                        (s2.m[a][b] - s3.m[a][b]).abs() < tol,
                        "{model:?} {scale} {a}{b}"
                    );
                }
                assert!((s2.zz - s3.m[2][2]).abs() < tol, "{model:?} {scale} zz");
                let (w2, w3) = (
                    energy_density(model, &p, &f2),
                    energy_density(model, &p, &f3),
                );
                assert!(
                    (w2 - w3).abs() <= 1.0e-4 * w3.abs() + 1.0e-6,
                    "{model:?} {w2} {w3}"
                );
            }
        }
    }

    /// A deformation that is exactly the eigenstrain, `F = (1 + d) I` (in 2D with the
    /// out-of-plane stretch too), leaves no elastic part: zero stress and energy, both models.
    #[test]
    fn a_free_eigenstrain_is_stress_free() {
        let p = Params {
            lambda: 5.0e5,
            mu: 4.0e5,
            inv_rho0: 1.0e-3,
        };
        for d in [1.0e-4, -2.0e-3, 0.05, -0.3] {
            let f2 = Deformation::<2>::new([[d, 0.0], [0.0, d]], d);
            let f3 = Deformation::<3>::new([[d, 0.0, 0.0], [0.0, d, 0.0], [0.0, 0.0, d]], 0.0);
            let (e2, k2) = elastic_part(&f2, d);
            let (e3, k3) = elastic_part(&f3, d);
            let cube = (1.0 + d) * (1.0 + d) * (1.0 + d);
            assert!(
                (k2 - cube).abs() < 8.0 * Real::EPSILON && (k3 - cube).abs() < 8.0 * Real::EPSILON
            );
            for model in [MaterialModel::NeoHookean, MaterialModel::LinearElastic] {
                let bound = 16.0 * Real::EPSILON * 1300.0;
                let s2 = kirchhoff_over_rho0(model, &p, &e2);
                let s3 = kirchhoff_over_rho0(model, &p, &e3);
                assert!(s2.m.iter().flatten().all(|v| v.abs() < bound) && s2.zz.abs() < bound);
                assert!(
                    s3.m.iter().flatten().all(|v| v.abs() < bound),
                    "{model:?} {d}"
                );
                assert!(energy_density(model, &p, &e3).abs() < bound * 1.0e3);
            }
        }
    }
}
