//! Damping (E48-E53): the declaration, the damping acceleration the particle update
//! subtracts (E24, with the per-particle rates of E53), the nodal damping the grid update
//! subtracts (E49-E51: the grid rate on the force, and the zones of space that damp) and the
//! thermostat that adds to the grid rate before each substep (E52). The per-particle rates
//! are set with [`crate::World::set_particle_damping`].

use super::Schedule;
use crate::def::Face;
use crate::layout::Layout;
use crate::particles::ParticleCols;
use crate::phases::lanes::{load, Lane};
use crate::phases::rows::Compare;
use crate::phases::wide::Wide;
use crate::phases::Ctx;
use crate::world::World;
use crate::{Error, Real, Vec3};

/// A kinetic-energy thermostat on the grid damping (NairnMPM's feedback damping, a
/// Nosé-Hoover-style controller; E52): once per substep,
/// `alpha += 2 gain (KE - target(t)) dt / M`, clamped to `[0, max_alpha]`, where KE and M are
/// the kinetic energy (with APIC's affine part, as [`crate::Diagnostics::kinetic`]) and mass
/// of the active particles. The evolving alpha adds to the grid
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

/// Damping (E48-E53), on top of the PIC damping that [`crate::WorldDef::flip_beta`] sets
/// (E22-E26).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Damping {
    /// Grid damping `alpha_g'(t)`, 1/s, >= 0: damps the velocity extrapolated from the grid.
    pub grid: Schedule,
    /// Particle damping `alpha_p'(t)`, 1/s, >= 0: damps the particle velocity.
    pub particle: Schedule,
    /// A thermostat that adds to the grid damping, if any.
    pub feedback: Option<Feedback>,
    /// Reserve two per-particle columns, `alpha_g(x_p)` and `alpha_p(x_p)` in 1/s, added to the
    /// global values for that particle: position-dependent damping as E53 writes it (the
    /// host sets them with [`crate::World::set_particle_damping`], for example from each
    /// particle's position). They act in the particle update whatever `grid_on_force` says.
    pub per_particle: bool,
    /// Where the grid damping `alpha_g'(t)` (and the thermostat's alpha) acts. `false` (the
    /// default): in the particle update, on the velocity extrapolated from the grid (E24,
    /// E48). `true`: on the nodal force, `f_i - alpha_g' p_i` (E49), so that the nodal
    /// momenta the walls act on are already damped; the particle update keeps the PIC
    /// damping and `alpha_p'`. The two agree for a resolved motion away from walls; at a wall
    /// the force form damps only what the wall leaves free (the wall's fixed components take
    /// the wall's value, damped or not), where the particle form also damps the velocity the
    /// wall has taken out of the nodes.
    pub grid_on_force: bool,
    /// Zones of space where the grid damps, on the nodal force (E50-E51): a node at `x_i`
    /// takes the rate `alpha_g(x_i)`, the sum of [`DampingZone::rate_at`] over the first
    /// `zone_count` zones, besides the grid rate. An absorbing layer at a boundary, a region
    /// to calm. Boxes rather than a nodal field the host fills: they are part of the
    /// definition (a snapshot and a C host carry them as they are), cost no memory and do not
    /// depend on the grid's resolution.
    // A literal length: with the constant there, rustc 1.95 fails on struct-update syntax
    // inside a closure (an internal compiler error).
    pub zones: [DampingZone; 4],
    /// How many of `zones` are used (at most [`DAMPING_ZONES`]).
    pub zone_count: u32,
}

/// Most zones of [`Damping::zones`].
pub const DAMPING_ZONES: usize = 4;

/// A box of space where the grid damps (E50-E51), for
/// [`Damping::zones`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampingZone {
    /// The box's lowest corner, m (z is not read in 2D).
    pub min: Vec3,
    /// The box's highest corner, m, above `min` on every axis the world has.
    pub max: Vec3,
    /// Rate, 1/s (finite, >= 0): uniform in the box, or its value on face `ramp`.
    pub rate: Real,
    /// `None`: the rate is uniform in the box. `Some(face)`: it rises as the square of the
    /// distance from the box's opposite face, from 0 there to `rate` on `face`: an absorbing
    /// layer against that face of the grid, graded so that a wave entering it is not
    /// reflected by a jump in damping (a face of an axis the world has).
    pub ramp: Option<Face>,
}

impl DampingZone {
    /// An empty zone (rate 0): a starting point for struct-update syntax.
    pub const NONE: DampingZone = DampingZone {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
        rate: 0.0,
        ramp: None,
    };

    /// The zone's rate at `x` (m, the world's axes), 1/s: 0 outside the box (E51: the
    /// `alpha_g(t, x_i)` of E50 for one zone).
    pub fn rate_at(&self, x: &[Real]) -> Real {
        let inside = x
            .iter()
            .enumerate()
            .all(|(a, &c)| c >= self.min[a] && c <= self.max[a]);
        if !inside {
            return 0.0;
        }
        match self.ramp {
            None => self.rate,
            Some(face) => {
                let axis = face as usize / 2;
                let (lo, hi) = (self.min[axis], self.max[axis]);
                let c = x.get(axis).copied().unwrap_or(lo);
                graded(self.rate, c, lo, hi, face as usize % 2 == 1)
            }
        }
    }

    /// Whether the zone is valid in a world of `axes` axes.
    fn is_valid(&self, axes: usize) -> bool {
        self.rate.is_finite()
            && self.rate >= 0.0
            && (0..axes).all(|a| {
                self.min[a].is_finite() && self.max[a].is_finite() && self.min[a] < self.max[a]
            })
            && self.ramp.is_none_or(|f| (f as usize / 2) < axes)
    }
}

/// A graded zone's rate at coordinate `c` of its grading axis, the box spanning `lo..hi` on
/// it (E51): `rate s^2`, `s` the distance from the face opposite the one the rate rises toward
/// (`toward_max`: the high face) over the box's width.
#[inline]
fn graded(rate: Real, c: Real, lo: Real, hi: Real, toward_max: bool) -> Real {
    let s = if toward_max {
        (c - lo) / (hi - lo)
    } else {
        (hi - c) / (hi - lo)
    };
    rate * s * s
}

impl Damping {
    /// No damping: a starting point for struct-update syntax.
    pub const NONE: Damping = Damping {
        grid: Schedule::ZERO,
        particle: Schedule::ZERO,
        feedback: None,
        per_particle: false,
        grid_on_force: false,
        zones: [DampingZone::NONE; DAMPING_ZONES],
        zone_count: 0,
    };

    /// The zones in use.
    pub fn used_zones(&self) -> &[DampingZone] {
        &self.zones[..(self.zone_count as usize).min(DAMPING_ZONES)]
    }

    /// Whether the particle update damps: a particle rate, per-particle rates, or the grid
    /// rate (or thermostat) where it acts in the particle update.
    pub(crate) fn on_particles(&self) -> bool {
        let grid = self.grid.max_value() > 0.0 || self.feedback.is_some();
        self.particle.max_value() > 0.0 || self.per_particle || (grid && !self.grid_on_force)
    }

    /// Whether the grid update damps the nodes: the grid rate on the force, or a zone.
    pub(crate) fn on_nodes(&self) -> bool {
        self.grid_on_force || self.zone_count > 0
    }

    /// The largest damping rate the definition gives any particle, 1/s, in f64: the grid and
    /// particle schedules' maxima and the zones' summed rates (zones may overlap; the
    /// thermostat's alpha adapts
    /// to the step and the per-particle rates come on top).
    pub(crate) fn definition_rate(&self) -> f64 {
        let zones: f64 = self.used_zones().iter().map(|z| z.rate as f64).sum();
        self.grid.max_value() as f64 + self.particle.max_value() as f64 + zones
    }

    /// The largest per-particle rate ([`crate::World::set_particle_damping`]) a world of the
    /// definition `def` resolves, 1/s: half of what the definition's rates leave of
    /// [`crate::Resolvable::rate`], so that a particle's two rates and the definition's stay
    /// within it.
    pub(crate) fn particle_rate_limit(&self, def: &crate::WorldDef) -> f64 {
        0.5 * (def.resolvable().rate - self.definition_rate())
    }
}

impl Damping {
    /// Whether every parameter is valid in a world of `axes` axes.
    pub(crate) fn is_valid(&self, axes: usize) -> bool {
        self.zone_count as usize <= DAMPING_ZONES
            && self.used_zones().iter().all(|z| z.is_valid(axes))
            && self.grid.is_valid(true)
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

/// The damping rates of the chunk at `start`, lane by lane: the substep's global values plus
/// each particle's own (E53; empty columns, when per-particle damping is not declared, load
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
    /// The thermostat (NairnMPM's feedback damping, E52): `alpha += 2 gain (KE - target) dt / M`,
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
    /// particles `first..first + n`, added to the global damping for those particles (E53).
    /// Needs [`crate::Damping::per_particle`]. A rate the step cannot resolve (above half of
    /// what the definition's rates leave of [`crate::Resolvable::rate`]) is
    /// [`Error::StableStepTooShort`].
    pub fn set_particle_damping(
        &mut self,
        first: u32,
        alpha_g: &[Real],
        alpha_p: &[Real],
    ) -> Result<(), Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        let group = (layout.damping.count > 0).then_some(layout.damping.first);
        let limit = def
            .effects
            .damping
            .map_or(0.0, |d| d.particle_rate_limit(&def));
        let columns = &[alpha_g, alpha_p];
        self.write_particle_columns(&layout, group, first, columns, Error::InvalidEffect, |v| {
            if v < 0.0 {
                Err(Error::InvalidEffect)
            } else if v as f64 > limit {
                Err(Error::StableStepTooShort)
            } else {
                Ok(())
            }
        })
    }
}
