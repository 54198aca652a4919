//! Weakly compressible fluid (E44): an isotropic pressure from the volume ratio alone, Tait's
//! equation of state `p = K / gamma (J^-gamma - 1)` (K the bulk modulus, gamma the exponent: 7
//! for water), so `tau = -p J I`; no elastic shear stress (a fluid's shear stress is its
//! viscosity's, added by [`super::viscous::add_viscous_lanes`]).
//!
//! Only `J` matters, so the return ([`Model::inelastic`], E45) keeps the deformation as
//! `F = J^(1/n) I` (n = 3, or 2 in plane strain where `F_zz = 1`): `J` is carried exactly as
//! the step's `det dF` makes it, and no shear accumulates in F to lose precision.

use super::model::{Deformation, Model, Stress};
use crate::layout::MaterialRecord;
use crate::math::{exp_m1, exp_m1_fast, ln_1p, ln_1p_fast};
use crate::num::{matrix, Num};
use crate::Real;

/// `ln J` from `J - 1 > -1`, branch-free.
#[inline(always)]
fn ln_j<T: Num>(jm1: T) -> T {
    jm1.map(|x| ln_1p_fast(x.max(-1.0 + Real::EPSILON)))
}

/// The fluid's parameters: Tait's equation of state (E44).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tait {
    /// The bulk modulus K, Pa.
    pub bulk_modulus: Real,
    /// The exponent gamma.
    pub pressure_exponent: Real,
}

/// The weakly compressible fluid.
pub(crate) struct Fluid;

impl Model for Fluid {
    type Params = Tait;

    /// K read as `bulk_modulus`: the record's `lambda` holds the same bits (a fluid's Lamé
    /// constants are `(K, 0)`, [`crate::MaterialDef::lame`]; `World::open` checks a stored
    /// record against its definition's), but names another modulus.
    #[inline(always)]
    fn params(r: &MaterialRecord) -> Tait {
        Tait {
            bulk_modulus: r.bulk_modulus,
            pressure_exponent: r.pressure_exponent,
        }
    }
    const INELASTIC: bool = true;
    const ON_ELASTIC_PART: bool = false;

    /// On vectors: its stress takes logarithms, exponentials or a Jacobi decomposition, which a
    /// loop over lanes ran 4 times as long (measured, von Mises 3D).
    #[inline(always)]
    fn on_vectors(_d: usize) -> bool {
        true
    }

    /// `tau = -p J I = K / gamma (J - J^(1 - gamma)) I`, written as `K / gamma ((J - 1) -
    /// (exp((1 - gamma) ln J) - 1))` so that small compressions keep their precision.
    #[inline(always)]
    fn kirchhoff<const D: usize, T: Num>(p: &Tait, f: &Deformation<D, T>) -> Stress<D, T> {
        let g = p.pressure_exponent;
        let lnj = ln_j(f.jm1);
        let t = (f.jm1 - (lnj * (1.0 - g)).map(exp_m1_fast)) * (p.bulk_modulus / g);
        let zero = T::splat(0.0);
        Stress {
            m: matrix(|a, b| if a == b { t } else { zero }),
            zz: if D == 2 { t } else { zero },
        }
    }

    /// `W = K / gamma ((J^(1 - gamma) - 1) / (gamma - 1) + J - 1)`, whose derivative in J is
    /// `-p` (`K (J - 1 - ln J)` for gamma = 1).
    fn energy<const D: usize>(p: &Tait, f: &Deformation<D>) -> Real {
        let g = p.pressure_exponent;
        let lnj = ln_1p(f.jm1);
        if g == 1.0 {
            return p.bulk_modulus * crate::math::x_minus_ln_1p(f.jm1);
        }
        p.bulk_modulus / g * (exp_m1((1.0 - g) * lnj) / (g - 1.0) + f.jm1)
    }

    /// `F <- J^(1/n) I`, `J` kept.
    #[inline(always)]
    fn inelastic<const D: usize, T: Num>(
        p: &Tait,
        f: &Deformation<D, T>,
        hoop: bool,
    ) -> (Deformation<D, T>, Stress<D, T>) {
        let n = if D == 3 || hoop { 3.0 } else { 2.0 };
        let e = (ln_j(f.jm1) * (1.0 / n)).map(exp_m1_fast);
        let zero = T::splat(0.0);
        let h = matrix(|a, b| if a == b { e } else { zero });
        let hzz = if D == 2 && hoop { e } else { f.hzz };
        let g = Deformation::with_plastic(h, hzz, f.plastic);
        (g, Self::kirchhoff(p, &g))
    }
}
