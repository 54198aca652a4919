//! Constitutive models: F in, Kirchhoff stress over initial density `tau / rho0` out
//! (seeds/000 eq 18), plus the strain energy per unit initial volume for energy checks.
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

/// `tau / rho0` from F (det F = j > 0).
#[inline(always)]
pub(crate) fn kirchhoff_over_rho0<const D: usize>(
    model: MaterialModel,
    p: &Params,
    f: &Mat<D>,
    j: Real,
) -> Stress<D> {
    let mut s = match model {
        MaterialModel::NeoHookean => neo_hookean::kirchhoff(p, f, j),
        MaterialModel::LinearElastic => linear_elastic::kirchhoff(p, f, j),
    };
    for row in s.m.iter_mut() {
        for v in row.iter_mut() {
            *v *= p.inv_rho0;
        }
    }
    s.zz *= p.inv_rho0;
    s
}

/// Strain energy per unit initial volume, J/m^3.
pub(crate) fn energy_density<const D: usize>(
    model: MaterialModel,
    p: &Params,
    f: &Mat<D>,
    j: Real,
) -> Real {
    match model {
        MaterialModel::NeoHookean => neo_hookean::energy(p, f, j),
        MaterialModel::LinearElastic => linear_elastic::energy(p, f),
    }
}
