//! Damping's terms (E48-E53): the damping acceleration the particle update subtracts (E24,
//! with the per-particle rates of E53) and the nodal damping the grid update subtracts
//! (E49-E51: the grid rate on the force, and the zones of space that damp). The declaration
//! is [`crate::Damping`]; the thermostat's update and the per-particle rates' setter are
//! [`crate::World`]'s.

use crate::def::effects::graded;
use crate::def::{DampingZone, DAMPING_ZONES};
use crate::particles::ParticleCols;
use crate::simd::lanes::{load, Lane};
use crate::simd::rows::Compare;
use crate::simd::wide::Wide;
use crate::Real;

/// The damping acceleration `d = alpha_g v_gp + alpha_p v_p` (E24; E53 with each rate the
/// substep's global value plus the particle's own).
#[inline(always)]
pub(crate) fn acceleration<I: Compare>(
    v_gp: Wide<I>,
    v_p: Wide<I>,
    alpha_g: Wide<I>,
    alpha_p: Wide<I>,
) -> Wide<I> {
    v_gp * alpha_g + v_p * alpha_p
}

/// The nodal damping of a substep (E49-E51): the grid rate when it acts on the force, and
/// the zones.
#[derive(Clone, Copy)]
pub(crate) struct NodalDamping {
    /// `alpha_g'(t)` and the thermostat's alpha when they act on the force, else 0; 1/s.
    pub alpha: Real,
    pub zones: [DampingZone; DAMPING_ZONES],
    pub zone_count: usize,
}

impl NodalDamping {
    /// The rates along the grid line through `p` (m) parallel to x: the zones it crosses,
    /// each as its x range and its rate there (a grade along y or z is constant on the line).
    pub fn on_line<const D: usize>(&self, p: &[Real; D]) -> LineRates {
        let mut line = LineRates {
            alpha: self.alpha,
            zones: [(0.0, 0.0, 0.0, None); DAMPING_ZONES],
            count: 0,
        };
        for z in &self.zones[..self.zone_count.min(DAMPING_ZONES)] {
            if !(1..D).all(|a| p[a] >= z.min[a] && p[a] <= z.max[a]) {
                continue;
            }
            let (rate, along_x) = match z.ramp {
                Some(f) if f as usize / 2 == 0 => (z.rate, Some(f as usize % 2 == 1)),
                // Evaluated where the line crosses the box (x at its low face).
                _ => {
                    let mut at = *p;
                    at[0] = z.min[0];
                    (z.rate_at(&at), None)
                }
            };
            line.zones[line.count] = (z.min[0], z.max[0], rate, along_x);
            line.count += 1;
        }
        line
    }
}

/// The nodal damping along one grid line ([`NodalDamping::on_line`]): the rate besides the
/// zones, and each zone the line crosses as `(x_min, x_max, rate, grade)`, `grade` whether
/// the rate rises toward x max (true) or x min (false) when it is graded along x.
#[derive(Clone, Copy)]
pub(crate) struct LineRates {
    alpha: Real,
    zones: [(Real, Real, Real, Option<bool>); DAMPING_ZONES],
    count: usize,
}

impl LineRates {
    /// No zone crosses the line: the rate is the same on all of it.
    pub fn uniform(&self) -> bool {
        self.count == 0
    }

    /// The rate at the node of the line at `x` (m), 1/s: [`DampingZone::rate_at`] summed over
    /// the zones, in the same arithmetic.
    #[inline]
    pub fn at(&self, x: Real) -> Real {
        self.zones[..self.count.min(DAMPING_ZONES)].iter().fold(
            self.alpha,
            |r, &(lo, hi, rate, grade)| {
                if x < lo || x > hi {
                    return r;
                }
                match grade {
                    None => r + rate,
                    Some(toward_max) => r + graded(rate, x, lo, hi, toward_max),
                }
            },
        )
    }
}

/// The damping rates of the chunk at `start`, lane by lane: the substep's global values
/// `(alpha_g, alpha_p)` plus
/// each particle's own (E53; empty columns, when per-particle damping is not declared, load
/// as zeros).
#[inline(always)]
pub(crate) fn lane_rates<I: Compare, const D: usize, const W: usize>(
    (global_g, global_p): (Real, Real),
    p: &ParticleCols<'_, D>,
    start: usize,
    alpha_g: &mut Lane<W>,
    alpha_p: &mut Lane<W>,
) {
    let (lg, lp): (Lane<W>, Lane<W>) = (load(p.damping[0], start), load(p.damping[1], start));
    for at in (0..W).step_by(I::N) {
        (Wide::<I>::load(&lg, at) + global_g).store(alpha_g, at);
        (Wide::<I>::load(&lp, at) + global_p).store(alpha_p, at);
    }
}
