//! Constitutive models: the displacement gradient `H = F - I` and `J - 1` in, Kirchhoff stress
//! over initial density `tau / rho0` out (E3), plus the strain energy per unit
//! initial volume for energy checks. The elastic models (corotated linear, neo-Hookean,
//! fixed-corotated) are that alone; the fluid and the plastic models (von Mises, Drucker-Prager,
//! snow) first change the deformation each step ([`Model::inelastic`]) and keep `F_e` in `H`.
//! Any material may add a Newtonian viscous stress (E46, [`add_viscous_lanes`]).
//!
//! In 2D the out-of-plane stretch is given separately ([`Deformation::hzz`]: 0 in plane strain,
//! `F_thetatheta - 1` in the axisymmetric form) and the out-of-plane stress is returned
//! separately as `zz` (`tau_thetatheta` when axisymmetric).
//!
//! An isotropic eigenstrain (thermal expansion, swelling: `F_0 = (1 + d) I`) is taken out of the
//! deformation before the model sees it (E47, [`elastic_part`]), so the models know nothing of
//! it.
//!
//! # Adding a material
//!
//! A model with its own parameters touches, and nothing else should:
//! 1. `src/material/<model>.rs`: its parameters' struct (or `Lame`), the `Model` impl (`params`
//!    from the record, stress, inelastic part, energy; wave speed and history range where they
//!    differ from the defaults; a return's stress from its own decomposition) and its tests;
//!    a plastic model on Hencky elasticity implements `HenckyReturn` (`material/principal.rs`)
//!    instead: its parameters, their Lamé constants and its return in principal strains;
//! 2. one arm of `by_model!` (`material/mod.rs`) and of `MaterialModel` with its fields and
//!    defaults in `MaterialDef` (`def/mod.rs`); `MaterialRecord` (`layout.rs`) and its checks
//!    and derived values (`material/record.rs`);
//! 3. `ffi/src/defs.rs`: the C enum arm and `MpmMaterialDef` fields (header regenerated); the C
//!    tests `layout.c` and `misuse.c`; the fuzz target;
//! 4. the model in `tests/kernel/reference.rs`.

mod drucker_prager;
mod fixed_corotated;
mod fluid;
mod linear_elastic;
mod model;
mod neo_hookean;
mod principal;
mod record;
mod snow;
mod viscous;
mod von_mises;

pub(crate) use model::{Deformation, Model, Stress};
pub(crate) use record::{explicit_diffusivity, material_record, material_resolvable};
pub(crate) use viscous::add_viscous_lanes;

use crate::layout::MaterialRecord;
use crate::num::{matrix, Num};
use crate::simd::rows::Compare;
use crate::simd::wide::Wide;
use crate::{MaterialModel, Real};

/// The elastic part `F_e = F / (1 + d)` (E47) of a deformation carrying the isotropic
/// eigenstrain `F_0 = (1 + d) I` (thermal expansion `d = alpha (T - T_0)`, swelling
/// `d = beta (c - c_0)`), and the factor `J / J_e = (1 + d)^3` that turns the Kirchhoff stress
/// of `F_e` into that of `F` (`tau = J sigma`). Written in `H` and `d` so that small strains
/// keep their precision: `H_e = (H - d I) / (1 + d)`. In 2D the out-of-plane axis carries the
/// eigenstrain too (a clamped plane-strain block heated is stressed along z).
#[inline(always)]
pub(crate) fn elastic_part<const D: usize, T: Num>(
    f: &Deformation<D, T>,
    d: T,
) -> (Deformation<D, T>, T) {
    let inv = T::splat(1.0) / (d + 1.0);
    let mut h = f.h;
    for (a, row) in h.iter_mut().enumerate() {
        row[a] -= d;
        for v in row.iter_mut() {
            *v *= inv;
        }
    }
    let cube_m1 = cube_minus_one(d);
    let cube = cube_m1 + 1.0;
    let e = Deformation {
        h,
        hzz: (f.hzz - d) * inv,
        jm1: (f.jm1 - cube_m1) / cube,
        plastic: f.plastic,
    };
    (e, cube)
}

/// `(1 + d)^3 - 1` without cancellation: the volume change of the eigenstrain `d`.
#[inline(always)]
fn cube_minus_one<T: Num>(d: T) -> T {
    d * ((d + 3.0) * d + 3.0)
}

/// The deformation `F = (1 + d) F_e` of the elastic part `e` carrying the isotropic
/// eigenstrain `d` back: the inverse of [`elastic_part`], `H = (1 + d) H_e + d I`.
#[inline(always)]
pub(crate) fn with_eigenstrain<const D: usize, T: Num>(
    e: &Deformation<D, T>,
    d: T,
) -> Deformation<D, T> {
    let scale = d + 1.0;
    let mut h = e.h;
    for (a, row) in h.iter_mut().enumerate() {
        for v in row.iter_mut() {
            *v *= scale;
        }
        row[a] += d;
    }
    let cube_m1 = cube_minus_one(d);
    Deformation {
        h,
        hzz: e.hzz * scale + d,
        jm1: e.jm1 * (cube_m1 + 1.0) + cube_m1,
        plastic: e.plastic,
    }
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

/// The isotropic eigenstrain `d` of a particle of material `r` whose transported fields have
/// the grid values `values` there (heat, diffusion; `None` for a field not declared): the sum
/// of their [`eigenstrain_part`]s.
#[inline(always)]
pub(crate) fn eigenstrain_at(r: &MaterialRecord, values: [Option<Real>; 2]) -> Real {
    let mut d = 0.0;
    for (field, value) in values.into_iter().enumerate() {
        if let Some(v) = value {
            d += eigenstrain_part(r, field, v);
        }
    }
    d
}

/// The model stored in a record.
pub(crate) fn model_of(r: &MaterialRecord) -> MaterialModel {
    // A stored record holds a valid code (`add_material` wrote it, `World::open` checks it);
    // anything else reads as the default model, which then fails that check.
    MaterialModel::from_code(r.model as u32).unwrap_or(MaterialModel::NeoHookean)
}

/// Evaluates `$e` with `$m` naming the [`Model`] type of `$model` (a [`MaterialModel`]): the
/// one place that maps the enum to the models.
macro_rules! by_model {
    ($model:expr, $m:ident => $e:expr) => {
        match $model {
            MaterialModel::NeoHookean => {
                type $m = neo_hookean::NeoHookean;
                $e
            }
            MaterialModel::LinearElastic => {
                type $m = linear_elastic::LinearElastic;
                $e
            }
            MaterialModel::FixedCorotated => {
                type $m = fixed_corotated::FixedCorotated;
                $e
            }
            MaterialModel::Fluid => {
                type $m = fluid::Fluid;
                $e
            }
            MaterialModel::VonMises => {
                type $m = von_mises::VonMises;
                $e
            }
            MaterialModel::DruckerPrager => {
                type $m = drucker_prager::DruckerPrager;
                $e
            }
            MaterialModel::Snow => {
                type $m = snow::Snow;
                $e
            }
        }
    };
}

/// [`Model::history_in_range`] of material `r`'s model.
pub(crate) fn history_in_range(r: &MaterialRecord, plastic: Real) -> bool {
    by_model!(model_of(r), M => M::history_in_range(plastic))
}

/// [`Model::hardens`] of material `r`'s model.
pub(crate) fn hardens(r: &MaterialRecord) -> bool {
    by_model!(model_of(r), M => M::hardens(r))
}

/// [`Model::volume_ratio_minus_one`] of material `r`'s model.
pub(crate) fn volume_ratio_minus_one(r: &MaterialRecord, jm1: Real, plastic: Real) -> Real {
    by_model!(model_of(r), M => M::volume_ratio_minus_one(jm1, plastic))
}

/// [`Model::wave_speed`] of material `r`'s model.
pub(crate) fn wave_speed(r: &MaterialRecord, plastic: Real) -> f64 {
    by_model!(model_of(r), M => M::wave_speed(r, plastic))
}

/// `tau / rho0` of one particle of material `r` at deformation `f` with the isotropic
/// eigenstrain `d` ([`elastic_part`]; 0 for none, which changes no bit), in the stored component
/// order ([`crate::layout::sym_pairs`], then `zz` in 2D); `None` if `f` or the eigenstrain
/// inverts the material.
#[inline(always)]
pub(crate) fn particle_stress<const D: usize>(
    r: &MaterialRecord,
    f: &Deformation<D>,
    d: Real,
) -> Option<[Real; 6]> {
    by_model!(model_of(r), M => stress_as::<M, D>(r, f, d))
}

/// [`particle_stress`] of a particle of the fluid model alone (material `r` a fluid): what
/// the fluid's volume relaxation (E97) recomputes, without every model's stress compiled in.
pub(crate) fn fluid_stress<const D: usize>(
    r: &MaterialRecord,
    f: &Deformation<D>,
    d: Real,
) -> Option<[Real; 6]> {
    stress_as::<fluid::Fluid, D>(r, f, d)
}

/// [`particle_stress`] with the model `M`.
#[inline(always)]
fn stress_as<M: Model, const D: usize>(
    r: &MaterialRecord,
    f: &Deformation<D>,
    d: Real,
) -> Option<[Real; 6]> {
    // NaN-safe: a NaN is not > -1.
    if !(f.jm1 > -1.0 && d > -1.0) {
        return None;
    }
    Some(stress_of::<M, D, Real>(&M::params(r), 1.0 / r.density, f, Some(d)).stored())
}

/// A chunk's deformation as lane arrays (borrowed within one chunk's update), `h[a][b][lane]`, the out-of-plane `hzz[lane]` (2D),
/// `jm1[lane]` and the plastic history `plastic[lane]`, which the material update changes in
/// place.
pub(crate) struct LaneDeformation<'a, const D: usize, const W: usize> {
    pub h: &'a mut [[[Real; W]; D]; D],
    pub hzz: &'a mut [Real; W],
    pub jm1: &'a mut [Real; W],
    pub plastic: &'a mut [Real; W],
}

/// The material update of the `W` particles of a chunk that share the material `model`: the
/// inelastic part ([`Model::inelastic`]: a return mapping, a fluid's projection) on the lanes'
/// deformation in place, then `tau / rho0` (`tau[k][lane]` out in the stored component order,
/// [`crate::layout::sym_pairs`], then `zz` in 2D). With the isotropic eigenstrain `eigen[lane]`
/// (E47), both act on the elastic part `F / (1 + d)` where the model asks for it
/// ([`Model::ON_ELASTIC_PART`]), and the stress is scaled back by `(1 + d)^3`. `hoop`:
/// axisymmetric.
///
/// On the instance's vectors ([`Wide`], [`crate::simd::rows::Rows::N`] lanes at a time) where the model asks for
/// it ([`Model::on_vectors`]), else lane by lane on [`Real`] in a loop the compiler vectorises.
/// Each lane gets the bits of the one-particle path ([`particle_stress`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn chunk_lanes<I: Compare, const D: usize, const W: usize>(
    rec: &MaterialRecord,
    h: &mut [[[Real; W]; D]; D],
    hzz: &mut [Real; W],
    jm1: &mut [Real; W],
    plastic: &mut [Real; W],
    hoop: bool,
    eigen: Option<&[Real; W]>,
    tau: &mut [[Real; W]; 6],
) {
    // The arrays come as parameters of their own: the compiler knows them apart only so (in
    // a struct of references the lane loop did not vectorise: the step took 1.4 times as
    // long).
    let mut f = LaneDeformation {
        h,
        hzz,
        jm1,
        plastic,
    };
    let inv_rho0 = 1.0 / rec.density;
    // The whole model inside its arm: a stress matrix carried out of the `match` was copied
    // through `memcpy`.
    by_model!(model_of(rec), M => {
        let p = &M::params(rec);
        if M::on_vectors(D) {
            for at in (0..W).step_by(I::N) {
                let ld = |c: &[Real; W]| Wide::<I>::load(c, at);
                let lanes = Deformation::<D, Wide<I>> {
                    h: matrix(|a, b| ld(&f.h[a][b])),
                    hzz: ld(f.hzz),
                    jm1: ld(f.jm1),
                    plastic: ld(f.plastic),
                };
                let d = eigen.map(ld);
                let g = update::<M, D, Wide<I>>(p, inv_rho0, &lanes, hoop, d);
                for a in 0..D {
                    for b in 0..D {
                        g.f.h[a][b].store(&mut f.h[a][b], at);
                    }
                }
                g.f.hzz.store(f.hzz, at);
                g.f.jm1.store(f.jm1, at);
                g.f.plastic.store(f.plastic, at);
                for (k, &(r, c)) in crate::layout::sym_pairs(D).iter().enumerate() {
                    g.tau.m[r][c].store(&mut tau[k], at);
                }
                if D == 2 {
                    g.tau.zz.store(&mut tau[3], at);
                }
            }
        } else {
            // Two loops rather than a test of the eigenstrain per lane, so that each is
            // branch-free and vectorises.
            match eigen {
                None => {
                    for ln in 0..W {
                        lane_update::<M, D, W>(p, inv_rho0, &mut f, hoop, None, tau, ln);
                    }
                }
                Some(d) => {
                    for ln in 0..W {
                        lane_update::<M, D, W>(p, inv_rho0, &mut f, hoop, Some(d[ln]), tau, ln);
                    }
                }
            }
        }
    })
}

/// [`update`] of lane `ln` of a chunk, on [`Real`], in place.
#[inline(always)]
fn lane_update<M: Model, const D: usize, const W: usize>(
    p: &M::Params,
    inv_rho0: Real,
    f: &mut LaneDeformation<'_, D, W>,
    hoop: bool,
    d: Option<Real>,
    tau: &mut [[Real; W]; 6],
    ln: usize,
) {
    let one = Deformation::<D> {
        h: matrix(|a, b| f.h[a][b][ln]),
        hzz: f.hzz[ln],
        jm1: f.jm1[ln],
        plastic: f.plastic[ln],
    };
    let g = update::<M, D, Real>(p, inv_rho0, &one, hoop, d);
    if M::INELASTIC {
        for a in 0..D {
            for b in 0..D {
                f.h[a][b][ln] = g.f.h[a][b];
            }
        }
        (f.hzz[ln], f.jm1[ln], f.plastic[ln]) = (g.f.hzz, g.f.jm1, g.f.plastic);
    }
    for (k, &(r, c)) in crate::layout::sym_pairs(D).iter().enumerate() {
        tau[k][ln] = g.tau.m[r][c];
    }
    if D == 2 {
        tau[3][ln] = g.tau.zz;
    }
}

/// A material update's result: the deformation after the inelastic part and `tau / rho0`.
struct Updated<const D: usize, T> {
    f: Deformation<D, T>,
    tau: Stress<D, T>,
}

/// The material update of one particle or one vector of particles of model `M` (see
/// [`chunk_lanes`]): the inelastic part, on the elastic part under an eigenstrain `d` where
/// the model acts on it, then `tau / rho0`, of the elastic part under an eigenstrain, scaled
/// back by `(1 + d)^3`.
#[inline(always)]
fn update<M: Model, const D: usize, T: Num>(
    p: &M::Params,
    inv_rho0: Real,
    f: &Deformation<D, T>,
    hoop: bool,
    d: Option<T>,
) -> Updated<D, T> {
    let inv_rho0 = T::splat(inv_rho0);
    match d {
        _ if !M::INELASTIC => Updated {
            f: *f,
            tau: stress_of::<M, D, T>(p, inv_rho0, f, d),
        },
        // The return on the elastic part, whose stress it gives, scaled back (E47).
        Some(d) if M::ON_ELASTIC_PART => {
            let (e, scale) = elastic_part(f, d);
            let (g, tau) = M::inelastic(p, &e, hoop);
            Updated {
                f: with_eigenstrain(&g, d),
                tau: per_rho0(tau, inv_rho0, Some(scale)),
            }
        }
        Some(_) => {
            let g = M::inelastic(p, f, hoop).0;
            Updated {
                f: g,
                tau: stress_of::<M, D, T>(p, inv_rho0, &g, d),
            }
        }
        None => {
            let (g, tau) = M::inelastic(p, f, hoop);
            Updated {
                f: g,
                tau: per_rho0(tau, inv_rho0, None),
            }
        }
    }
}

/// `tau / rho0` of model `M` at deformation `f`: with an eigenstrain `d`, the stress of the
/// elastic part scaled back by `(1 + d)^3` (E47).
#[inline(always)]
fn stress_of<M: Model, const D: usize, T: Num>(
    p: &M::Params,
    inv_rho0: T,
    f: &Deformation<D, T>,
    d: Option<T>,
) -> Stress<D, T> {
    match d {
        Some(d) => {
            let (e, scale) = elastic_part(f, d);
            per_rho0(M::kirchhoff(p, &e), inv_rho0, Some(scale))
        }
        None => per_rho0(M::kirchhoff(p, f), inv_rho0, None),
    }
}

/// `tau / rho0` from `tau`, times `scale` where given (`(1 + d)^3` under an eigenstrain).
#[inline(always)]
fn per_rho0<const D: usize, T: Num>(
    mut tau: Stress<D, T>,
    inv_rho0: T,
    scale: Option<T>,
) -> Stress<D, T> {
    // Indexed loops: a flattening iterator was left as a loop the lane loop did not vectorise
    // around.
    let over_rho0 = |v: T| match scale {
        Some(scale) => v * inv_rho0 * scale,
        None => v * inv_rho0,
    };
    for a in 0..D {
        for b in 0..D {
            tau.m[a][b] = over_rho0(tau.m[a][b]);
        }
    }
    tau.zz = over_rho0(tau.zz);
    tau
}

/// Strain energy per unit initial volume, J/m^3, of material `r` at a deformation.
pub(crate) fn energy_density<const D: usize>(r: &MaterialRecord, f: &Deformation<D>) -> Real {
    by_model!(model_of(r), M => M::energy(&M::params(r), f))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat;

    /// `tau / rho0` of material `r` at a deformation with `jm1 = det F - 1 > -1`: one particle,
    /// or a vector of them.
    fn kirchhoff_over_rho0<const D: usize, T: Num>(
        r: &MaterialRecord,
        f: &Deformation<D, T>,
    ) -> Stress<D, T> {
        by_model!(model_of(r), M => stress_of::<M, D, T>(&M::params(r), T::splat(1.0 / r.density), f, None))
    }

    /// The default material's record as `model`, with the given Lamé constants and initial
    /// density `rho0`; lambda is also the fluid's bulk modulus K, as in a fluid's own record
    /// ([`crate::MaterialDef::lame`]).
    fn record(model: MaterialModel, lambda: Real, mu: Real, rho0: Real) -> MaterialRecord {
        let r = crate::material::material_record(&crate::MaterialDef::DEFAULT).unwrap();
        MaterialRecord {
            model: model as u32 as Real,
            lambda,
            mu,
            bulk_modulus: lambda,
            density: rho0,
            ..r
        }
    }

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
        for model in MaterialModel::ALL {
            let r = record(model, 5.0e5, 4.0e5, 1.0e3);
            for k in 0..64 {
                let angle = -3.0 + 6.0 * k as Real / 63.0;
                for axis in 0..3 {
                    let f = Deformation::new(rotation_minus_identity(angle, axis), 0.0);
                    let s = kirchhoff_over_rho0(&r, &f);
                    // tau/rho0 scale of a unit strain is (lambda + 2 mu)/rho0 = 1300; round-off
                    // of order 1e-6 of it is what f32 leaves.
                    let bound = 1.0e-5 * 1300.0;
                    assert!(
                        s.m.iter().flatten().all(|v| v.abs() < bound),
                        "{model:?} {angle} {axis}: {:?}",
                        s.m
                    );
                    assert!(energy_density(&r, &f).abs() < 1.0e-5 * 1.3e6);
                }
                let (s2, c2) = (
                    libm::sin(angle as f64) as Real,
                    libm::cos(angle as f64) as Real,
                );
                let h2: Mat<2> = [[c2 - 1.0, -s2], [s2, c2 - 1.0]];
                let s = kirchhoff_over_rho0(&r, &Deformation::new(h2, 0.0));
                assert!(s.m.iter().flatten().all(|v| v.abs() < 1.0e-5 * 1300.0));
                assert!(s.zz.abs() < 1.0e-5 * 1300.0);
            }
        }
    }

    /// Uniaxial small strain (H = diag(eps, 0, 0)): every solid model gives the linear-elastic stress
    /// `tau_xx = (lambda + 2 mu) eps`, `tau_yy = lambda eps` to first order (relative 2 eps).
    #[test]
    fn small_uniaxial_strain_matches_linear_elasticity() {
        let eps = 1.0e-4;
        let f = Deformation::<3>::new([[eps, 0.0, 0.0], [0.0; 3], [0.0; 3]], 0.0);
        for model in MaterialModel::ALL
            .into_iter()
            .filter(|&m| m != MaterialModel::Fluid)
        {
            let r = record(model, 5.0e5, 4.0e5, 1.0);
            let s = kirchhoff_over_rho0(&r, &f);
            let xx = (r.lambda + 2.0 * r.mu) * eps;
            let yy = r.lambda * eps;
            assert!((s.m[0][0] - xx).abs() < 2.0 * eps * xx + 1e-3, "{model:?}");
            assert!((s.m[1][1] - yy).abs() < 2.0 * eps * xx + 1e-3, "{model:?}");
            // Energy (lambda + 2 mu) eps^2 / 2.
            let w = energy_density(&r, &f);
            let expect = 0.5 * (r.lambda + 2.0 * r.mu) * eps * eps;
            assert!((w - expect).abs() < 1e-3 * expect, "{model:?} {w} {expect}");
        }
    }

    /// The 2D form with an out-of-plane stretch (`hzz`: the hoop stretch of the axisymmetric
    /// form) is the 3D form with `H = diag(H2, hzz)`: same stress components and energy, for
    /// both models, at small and large strain.
    #[test]
    fn out_of_plane_stretch_matches_the_3d_model() {
        for (scale, hzz) in [(1.0e-4, -3.0e-5), (0.2, 0.3), (0.3, -0.4)] {
            let h2: Mat<2> = [[0.5 * scale, -0.3 * scale], [0.2 * scale, -0.4 * scale]];
            let h3: Mat<3> = [
                [h2[0][0], h2[0][1], 0.0],
                [h2[1][0], h2[1][1], 0.0],
                [0.0, 0.0, hzz],
            ];
            let (f2, f3) = (Deformation::new(h2, hzz), Deformation::new(h3, 0.0));
            assert!((f2.jm1 - f3.jm1).abs() <= 4.0 * Real::EPSILON * (1.0 + f3.jm1.abs()));
            for model in MaterialModel::ALL {
                let r = record(model, 5.0e5, 4.0e5, 1.0e3);
                let (s2, s3) = (kirchhoff_over_rho0(&r, &f2), kirchhoff_over_rho0(&r, &f3));
                let tol = 1.0e-5 * 1300.0 * scale.max(hzz.abs()).max(1e-3);
                for (a, b) in [(0, 0), (1, 1), (0, 1)] {
                    assert!(
                        (s2.m[a][b] - s3.m[a][b]).abs() < tol,
                        "{model:?} {scale} {a}{b}"
                    );
                }
                assert!((s2.zz - s3.m[2][2]).abs() < tol, "{model:?} {scale} zz");
                let (w2, w3) = (energy_density(&r, &f2), energy_density(&r, &f3));
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
        for d in [1.0e-4, -2.0e-3, 0.05, -0.3] {
            let f2 = Deformation::<2>::new([[d, 0.0], [0.0, d]], d);
            let f3 = Deformation::<3>::new([[d, 0.0, 0.0], [0.0, d, 0.0], [0.0, 0.0, d]], 0.0);
            let (e2, k2) = elastic_part(&f2, d);
            let (e3, k3) = elastic_part(&f3, d);
            let cube = (1.0 + d) * (1.0 + d) * (1.0 + d);
            assert!(
                (k2 - cube).abs() < 8.0 * Real::EPSILON && (k3 - cube).abs() < 8.0 * Real::EPSILON
            );
            for model in MaterialModel::ALL {
                let r = record(model, 5.0e5, 4.0e5, 1.0e3);
                let bound = 16.0 * Real::EPSILON * 1300.0;
                let s2 = kirchhoff_over_rho0(&r, &e2);
                let s3 = kirchhoff_over_rho0(&r, &e3);
                assert!(s2.m.iter().flatten().all(|v| v.abs() < bound) && s2.zz.abs() < bound);
                assert!(
                    s3.m.iter().flatten().all(|v| v.abs() < bound),
                    "{model:?} {d}"
                );
                assert!(energy_density(&r, &e3).abs() < bound * 1.0e3);
            }
        }
    }

    /// Every model's chunk path ([`chunk_lanes`]), and its update on the instance's vectors
    /// whichever path the chunk takes, gives each lane the bits of the one-particle path (the
    /// inelastic part, on the elastic part under an eigenstrain, then [`kirchhoff_over_rho0`]
    /// of the elastic part scaled by `(1 + d)^3`), in every instance the CPU supports, over
    /// random deformations from small strain to large stretch and rotation and lanes that take
    /// each branch of the polar decomposition, in 2D (with an out-of-plane stretch, plane and
    /// axisymmetric) and 3D, with and without an eigenstrain.
    #[test]
    fn every_model_gives_a_chunk_the_bits_of_one_particle() {
        every_instance::<{ crate::simd::lanes::width(2) }>();
        every_instance::<{ crate::simd::lanes::width(3) }>();
    }

    fn every_instance<const W: usize>() {
        check_instance::<crate::simd::Baseline, W>();
        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        {
            use crate::simd::{Instance, Simd};
            if Simd::Detect.instance() >= Instance::Avx2 {
                check_instance::<crate::simd::Avx2, W>();
            }
            if Simd::Detect.instance() >= Instance::Avx512 {
                check_instance::<crate::simd::Avx512, W>();
            }
        }
    }

    fn check_instance<I: Compare, const W: usize>() {
        let mut state = 12345u64;
        let mut next = |scale: Real| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            scale * (((state >> 40) as f64 / (1u64 << 24) as f64) as Real - 0.5)
        };
        for model in MaterialModel::ALL {
            let r = record(model, 5.0e5, 4.0e5, 1.0e3);
            check::<I, 2, W>(&r, &mut next);
            check::<I, 3, W>(&r, &mut next);
        }
    }

    /// One particle's material update: the path of the reference step, which every lane of a
    /// chunk must match.
    fn one_particle<const D: usize>(
        r: &MaterialRecord,
        f: &Deformation<D>,
        hoop: bool,
        d: Option<Real>,
    ) -> (Deformation<D>, Stress<D>) {
        // The inelastic part (on the elastic part under an eigenstrain, for a return) with the
        // stress of its result, then tau / rho0 scaled back by (1 + d)^3.
        let d0 = d.unwrap_or(0.0);
        let (g, mut s) = by_model!(model_of(r), M => {
            let p = &M::params(r);
            match d {
                _ if !M::INELASTIC => (*f, M::kirchhoff(p, &elastic_part(f, d0).0)),
                Some(d) if M::ON_ELASTIC_PART => {
                    let (g, tau) = M::inelastic(p, &elastic_part(f, d).0, hoop);
                    (with_eigenstrain(&g, d), tau)
                }
                None => M::inelastic(p, f, hoop),
                Some(_) => {
                    let g = M::inelastic(p, f, hoop).0;
                    (g, M::kirchhoff(p, &elastic_part(&g, d0).0))
                }
            }
        });
        let scale = elastic_part(f, d0).1;
        for v in s.m.iter_mut().flatten().chain([&mut s.zz]) {
            *v = *v * (1.0 / r.density) * scale;
        }
        (g, s)
    }

    fn check<I: Compare, const D: usize, const W: usize>(
        rec: &MaterialRecord,
        next: &mut impl FnMut(Real) -> Real,
    ) {
        let model = model_of(rec);
        // Lanes that take each branch of the corotated model's polar decomposition: no
        // deformation, a half turn (F = -I in 2D), turns past a quarter, an inverted F (3D:
        // the iteration stops at once).
        let (c, s) = (libm::cos(3.0) as Real, libm::sin(3.0) as Real);
        let special: [Mat<D>; 4] = [
            [[0.0; D]; D],
            core::array::from_fn(|r| core::array::from_fn(|c| if r == c { -2.0 } else { 0.0 })),
            core::array::from_fn(|r| {
                core::array::from_fn(|k| match (r, k) {
                    (0, 0) | (1, 1) => c - 1.0,
                    (0, 1) => -s,
                    (1, 0) => s,
                    _ => 0.0,
                })
            }),
            core::array::from_fn(|r| {
                core::array::from_fn(|k| match (r, k) {
                    (0, 0) => -1.5,
                    (0, 1) => 0.3,
                    (1, 0) => 2.0,
                    _ => 0.0,
                })
            }),
        ];
        for scale in [1.0e-5, 1.0e-2, 0.6, 0.0] {
            let mut h = [[[0.0; W]; D]; D];
            let (mut hzz, mut jm1, mut plastic, mut d) = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
            let mut each = [Deformation::<D>::new([[0.0; D]; D], 0.0); W];
            for ln in 0..W {
                let m: Mat<D> = if scale == 0.0 {
                    special[ln % special.len()]
                } else {
                    core::array::from_fn(|_| core::array::from_fn(|_| next(scale)))
                };
                let zz = if D == 2 { next(scale) } else { 0.0 };
                each[ln] = Deformation::new(m, zz);
                // A history in the range of the snow model's (J_p > 0) and the others'.
                each[ln].plastic = next(0.2).abs();
                for r in 0..D {
                    for c in 0..D {
                        h[r][c][ln] = m[r][c];
                    }
                }
                (hzz[ln], jm1[ln], plastic[ln]) = (zz, each[ln].jm1, each[ln].plastic);
                d[ln] = next(0.2);
            }
            for hoop in [false, true] {
                for eigen in [None, Some(&d)] {
                    let (mut h2, mut hzz2, mut jm12, mut pl2) = (h, hzz, jm1, plastic);
                    let mut tau = [[0.0; W]; 6];
                    let (h2r, hzz2r, jm12r, pl2r) = (&mut h2, &mut hzz2, &mut jm12, &mut pl2);
                    chunk_lanes::<I, D, W>(rec, h2r, hzz2r, jm12r, pl2r, hoop, eigen, &mut tau);
                    for (ln, f) in each.iter().enumerate() {
                        let dl = eigen.map(|d| d[ln]);
                        let (g, s) = one_particle(rec, f, hoop, dl);
                        // The update on the instance's vectors, whichever path the model takes.
                        let at = ln - ln % I::N;
                        let ld = |c: &[Real; W]| Wide::<I>::load(c, at);
                        let v = Deformation::<D, Wide<I>> {
                            h: matrix(|a, b| ld(&h[a][b])),
                            hzz: ld(&hzz),
                            jm1: ld(&jm1),
                            plastic: ld(&plastic),
                        };
                        let inv_rho0 = 1.0 / rec.density;
                        let w = by_model!(model, M => update::<M, D, Wide<I>>(
                            &M::params(rec), inv_rho0, &v, hoop, eigen.map(ld)
                        ));
                        let lane = |x: Wide<I>| {
                            let mut out = [0.0; W];
                            x.store(&mut out, at);
                            out[ln]
                        };
                        let same = |a: Real, b: Real, what: &str| {
                            assert_eq!(a.to_bits(), b.to_bits(), "{model:?} {D}D {what} {a} {b}")
                        };
                        for r in 0..D {
                            for c in 0..D {
                                same(h2[r][c][ln], g.h[r][c], "h");
                                same(lane(w.f.h[r][c]), g.h[r][c], "h vector");
                            }
                        }
                        same(hzz2[ln], g.hzz, "hzz");
                        same(jm12[ln], g.jm1, "jm1");
                        same(pl2[ln], g.plastic, "plastic");
                        same(lane(w.f.plastic), g.plastic, "plastic vector");
                        for (k, &(r, c)) in crate::layout::sym_pairs(D).iter().enumerate() {
                            same(tau[k][ln], s.m[r][c], "tau");
                            same(lane(w.tau.m[r][c]), s.m[r][c], "tau vector");
                        }
                        if D == 2 {
                            same(tau[3][ln], s.zz, "zz");
                            same(lane(w.tau.zz), s.zz, "zz vector");
                        }
                    }
                }
            }
        }
    }
}
