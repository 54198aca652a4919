//! Damping (seeds/000 sections 5.1.2 and 5.3): the declaration, the damping acceleration the
//! particle update subtracts (eq 47, with eq 107's per-particle rates) and the thermostat that
//! adds to the grid rate before each substep. The per-particle rates are set with
//! [`crate::World::set_particle_damping`].

use super::Schedule;
use crate::layout::Layout;
use crate::particles::ParticleCols;
use crate::phases::lanes::{load, Lane};
use crate::phases::rows::Compare;
use crate::phases::wide::Wide;
use crate::phases::Ctx;
use crate::world::World;
use crate::{Error, Real};

/// A kinetic-energy thermostat on the grid damping (NairnMPM's feedback damping, a
/// Nosé-Hoover-style controller): once per substep,
/// `alpha += 2 gain (KE - target(t)) dt / M`, clamped to `[0, max_alpha]`, where KE and M are
/// the kinetic energy and mass of the active particles. The evolving alpha adds to the grid
/// damping `alpha_g` and is kept in the world (a snapshot carries it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feedback {
    /// Gain `1/Q`, 1/m^2, > 0. Sets how fast alpha reacts: an excess kinetic energy per unit
    /// mass `e` (m^2/s^2) raises alpha by `2 gain e` per second.
    pub gain: Real,
    /// Target kinetic energy, J, a function of time (>= 0). 0 drives the scene to rest.
    pub target: Schedule,
    /// Largest alpha, 1/s, > 0 (infinity: unbounded).
    pub max_alpha: Real,
}

/// Damping of seeds/000 sections 5.1.2 and 5.3, on top of the PIC damping that
/// [`crate::WorldDef::flip_beta`] sets (eqs 41-52).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Damping {
    /// Grid damping `alpha_g'(t)`, 1/s, >= 0: damps the velocity extrapolated from the grid.
    pub grid: Schedule,
    /// Particle damping `alpha_p'(t)`, 1/s, >= 0: damps the particle velocity.
    pub particle: Schedule,
    /// A thermostat that adds to the grid damping, if any.
    pub feedback: Option<Feedback>,
    /// Reserve two per-particle columns, `alpha_g(x_p)` and `alpha_p(x_p)` in 1/s, added to the
    /// global values for that particle: position-dependent damping as eq 107 writes it (the
    /// host sets them with [`crate::World::set_particle_damping`], for example from each
    /// particle's position).
    pub per_particle: bool,
}

impl Damping {
    /// No damping: a starting point for struct-update syntax.
    pub const NONE: Damping = Damping {
        grid: Schedule::ZERO,
        particle: Schedule::ZERO,
        feedback: None,
        per_particle: false,
    };
}

impl Damping {
    /// Whether every parameter is valid.
    pub(crate) fn is_valid(&self) -> bool {
        self.grid.is_valid(true)
            && self.particle.is_valid(true)
            && self.feedback.is_none_or(|f| {
                f.gain.is_finite()
                    && f.gain > 0.0
                    && f.target.is_valid(true)
                    && f.max_alpha > 0.0
                    && !f.max_alpha.is_nan()
            })
    }
}

/// The damping acceleration `d = alpha_g v_gp + alpha_p v_p` (seeds/000 eq 47; eq 107 with
/// each rate the substep's global value plus the particle's own).
#[inline(always)]
pub(crate) fn acceleration<I: Compare>(
    v_gp: Wide<I>,
    v_p: Wide<I>,
    alpha_g: Wide<I>,
    alpha_p: Wide<I>,
) -> Wide<I> {
    v_gp * alpha_g + v_p * alpha_p
}

/// The damping rates of the chunk at `start`, lane by lane: the substep's global values plus
/// each particle's own (eq 107; empty columns, when per-particle damping is not declared, load
/// as zeros).
#[inline(always)]
pub(crate) fn lane_rates<const D: usize, const W: usize>(
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    start: usize,
    alpha_g: &mut Lane<W>,
    alpha_p: &mut Lane<W>,
) {
    let (lg, lp): (Lane<W>, Lane<W>) = (load(p.damping[0], start), load(p.damping[1], start));
    for ln in 0..W {
        alpha_g[ln] = ctx.alpha_g + lg[ln];
        alpha_p[ln] = ctx.alpha_p + lp[ln];
    }
}

impl World<'_> {
    /// The thermostat (NairnMPM's feedback damping): `alpha += 2 gain (KE - target) dt / M`,
    /// clamped to `[0, min(max_alpha, room)]`, from the active particles' kinetic energy and
    /// mass; `room` is the largest alpha the substep integrates stably. The stored alpha stays
    /// finite: a rate that is not a number (no finite energy to compare) leaves it as it was.
    pub(crate) fn update_feedback(&mut self, f: &Feedback, time: f64, dt: Real, room: f64) {
        let (kinetic, mass) = self.read().kinetic_energy_and_mass();
        let h = self.header_mut();
        if mass > 0.0 {
            let target = f.target.at(time) as f64;
            let rate = 2.0 * f.gain as f64 * (kinetic - target) / mass;
            let alpha = h.feedback_alpha + rate * dt as f64;
            if !alpha.is_nan() {
                h.feedback_alpha = alpha.clamp(0.0, (f.max_alpha as f64).min(room));
            }
        }
    }

    /// Sets the local grid and particle damping `alpha_g(x_p)`, `alpha_p(x_p)` (1/s, >= 0) of
    /// particles `first..first + n`, added to the global damping for those particles (eq 107).
    /// Needs [`crate::Damping::per_particle`].
    pub fn set_particle_damping(
        &mut self,
        first: u32,
        alpha_g: &[Real],
        alpha_p: &[Real],
    ) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        let group = (layout.damping.count > 0).then_some(layout.damping.first);
        let columns = &[alpha_g, alpha_p];
        self.write_particle_columns(&layout, group, first, columns, Error::InvalidEffect, |v| {
            v >= 0.0
        })
    }
}
