//! Sand: Drucker-Prager plasticity (E40, E41) on Hencky elasticity (E37), with the return
//! mapping of Klar et al. 2016 ("Drucker-Prager elastoplasticity for sand animation", section
//! 7.3) extended by a cohesion. In the principal log strains `eps` of the trial `F_e`, with
//! `n` axes, trace `tr` and deviator `e`, the Kirchhoff stress has the deviator `2 mu e` and
//! trace `(2 mu + n lambda) tr`. The yield condition is
//! `|dev tau| + alpha (tr tau - n p_t) <= 0` with `alpha` fitted to the friction angle phi as
//! [`crate::FrictionFit`] says (E40; Klar's `sqrt(2/3) 2 sin(phi) / (3 - sin(phi))` by
//! default, Mohr-Coulomb's in plane strain `sin(phi) / sqrt(2)`) and the apex at the mean
//! tension `p_t = c cot(phi)` (c the cohesion; 0 for dry sand). Then:
//! - past the apex (`tr tau >= n p_t`, the material pulled apart): `F_e` returns to the apex,
//!   an isotropic stretch carrying the tension `p_t` (no stress for dry sand);
//! - else `dgamma = |e| + alpha (2 mu + n lambda) / (2 mu) (tr - tr_t)` and, where it is
//!   positive, `e` shrinks by `dgamma` along itself (`tr_t` the apex's strain trace).
//!
//! The history is the accumulated plastic shear (the sum of `dgamma`). No hardening of the
//! friction angle and no volume correction (Tampubolon et al. 2017): the volume a return
//! removes from `F_e` at the apex is not given back.

use super::model::Lame;
use super::principal::{HenckyReturn, Principal, Split};
use crate::layout::MaterialRecord;
use crate::num::Num;
use crate::Real;

/// Drucker-Prager's parameters: Hencky elasticity's Lamé constants (E37) and the yield
/// cone's (E40), derived from the friction angle and cohesion when the material was added.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DruckerPragerParams {
    /// Hencky elasticity's Lamé constants.
    pub lame: Lame,
    /// The cone's `alpha` ([`crate::FrictionFit::alpha`]).
    pub friction: Real,
    /// The apex's mean tension `p_t = c cot(phi)`, Pa.
    pub apex_tension: Real,
}

/// Drucker-Prager plasticity.
pub(crate) struct DruckerPrager;

impl HenckyReturn for DruckerPrager {
    type Params = DruckerPragerParams;

    #[inline(always)]
    fn params(r: &MaterialRecord) -> DruckerPragerParams {
        DruckerPragerParams {
            lame: Lame::of(r),
            friction: r.friction_coefficient,
            apex_tension: r.apex_tension,
        }
    }

    #[inline(always)]
    fn lame(p: &DruckerPragerParams) -> Lame {
        p.lame
    }

    /// Past the apex, to the apex; else `e` shrinks by `dgamma` where it is positive (E41).
    #[inline(always)]
    fn principal_return<const D: usize, T: Num>(
        p: &DruckerPragerParams,
        pr: &Principal<D, T>,
        split: Split<T>,
        n: usize,
        plastic: T,
    ) -> ([T; 3], T) {
        let nr = n as Real;
        let Split {
            trace: tr,
            dev: e,
            norm,
        } = split;
        // The apex: the strain trace that carries the mean tension p_t.
        let bulk = 2.0 * p.lame.mu + nr * p.lame.lambda;
        let tr_apex = nr * p.apex_tension / bulk;
        let zero = T::splat(0.0);
        let beyond = tr.ge(T::splat(tr_apex));
        let dgamma = norm + (tr - tr_apex) * (p.friction * bulk / (2.0 * p.lame.mu));
        let flows = dgamma.gt(zero);
        let along = T::select(flows, dgamma, zero) / (norm + Real::MIN_POSITIVE);
        // A loop, not `vector` (whose closure this size was left out of line).
        let mut delta = [zero; 3];
        for i in 0..n {
            let cone = -(e[i] * along);
            let apex = T::splat(tr_apex / nr) - pr.eps[i];
            delta[i] = T::select(beyond, apex, cone);
        }
        let plastic = plastic + T::select(beyond, norm, T::select(flows, dgamma, zero));
        (delta, plastic)
    }
}
