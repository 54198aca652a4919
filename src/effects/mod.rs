//! The optional effects a scene declares in [`crate::WorldDef::effects`]
//! ([`Effects`]). An effect that is not declared reserves no column and runs no loop. Each
//! effect is one module: its declaration, its per-particle data, and its terms in the step.
//! - [`damping`]: grid and particle damping, per-particle rates and the thermostat
//!   (E48-E53).
//! - [`forces`]: particle forces, tractions and a body force (E14-E16).
//! - [`transport`]: heat conduction and diffusion (E54-E64); their pass, a phase of the
//!   substep of its own, is [`crate::phases::transport`].
//!
//! (The APIC transfer, E78-E80, is a method choice, [`crate::Transfer`], with the other
//! method switches in [`crate::def`].)

pub mod damping;
pub mod forces;
pub mod transport;

pub use damping::{Damping, DampingZone, Feedback, DAMPING_ZONES};
pub use transport::{ScalarBoundary, Transport};

use crate::{Error, Real, Vec3};

/// Most points a [`Schedule`] holds.
pub const SCHEDULE_POINTS: usize = 8;

/// A value that is a function of time: piecewise linear through up to [`SCHEDULE_POINTS`]
/// `(time, value)` points, constant before the first point and after the last. No point is the
/// constant 0; one point is a constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// Number of points used, 0..=[`SCHEDULE_POINTS`].
    pub points: u32,
    /// Times of the points, s, strictly increasing; entries past `points` are ignored.
    pub times: [Real; SCHEDULE_POINTS],
    /// Values at those times; entries past `points` are ignored.
    pub values: [Real; SCHEDULE_POINTS],
}

impl Schedule {
    /// The constant 0.
    pub const ZERO: Schedule = Schedule {
        points: 0,
        times: [0.0; SCHEDULE_POINTS],
        values: [0.0; SCHEDULE_POINTS],
    };

    /// The constant `value`.
    pub const fn constant(value: Real) -> Schedule {
        let mut s = Schedule::ZERO;
        s.points = 1;
        s.values[0] = value;
        s
    }

    /// Piecewise linear through `points` (time, value); [`Error::InvalidEffect`] if there are
    /// more than [`SCHEDULE_POINTS`], or they are not finite, or the times do not increase.
    pub fn from_points(points: &[(Real, Real)]) -> Result<Schedule, Error> {
        if points.len() > SCHEDULE_POINTS {
            return Err(Error::InvalidEffect);
        }
        let mut s = Schedule::ZERO;
        s.points = points.len() as u32;
        for (k, &(t, v)) in points.iter().enumerate() {
            s.times[k] = t;
            s.values[k] = v;
        }
        if !s.is_valid(false) {
            return Err(Error::InvalidEffect);
        }
        Ok(s)
    }

    /// Whether the used points are finite with increasing times (and, with `non_negative`,
    /// values >= 0).
    pub fn is_valid(&self, non_negative: bool) -> bool {
        let n = self.points as usize;
        n <= SCHEDULE_POINTS
            && (0..n).all(|k| {
                let (t, v) = (self.times[k], self.values[k]);
                t.is_finite()
                    && v.is_finite()
                    && (!non_negative || v >= 0.0)
                    && (k == 0 || t > self.times[k - 1])
            })
    }

    /// The value at time `t`, s.
    pub fn at(&self, t: f64) -> Real {
        let n = (self.points as usize).min(SCHEDULE_POINTS);
        if n == 0 {
            return 0.0;
        }
        let (ts, vs) = (&self.times[..n], &self.values[..n]);
        if t <= ts[0] as f64 {
            return vs[0];
        }
        for k in 1..n {
            if t <= ts[k] as f64 {
                let f = (t - ts[k - 1] as f64) / (ts[k] as f64 - ts[k - 1] as f64);
                return (vs[k - 1] as f64 + f * (vs[k] as f64 - vs[k - 1] as f64)) as Real;
            }
        }
        vs[n - 1]
    }

    /// Largest value over all time (0 for no point).
    pub fn max_value(&self) -> Real {
        let n = (self.points as usize).min(SCHEDULE_POINTS);
        self.values[..n].iter().fold(0.0, |m: Real, &v| m.max(v))
    }
}

impl Default for Schedule {
    fn default() -> Self {
        Schedule::ZERO
    }
}

/// What a scene declares beyond the momentum equation. [`Effects::NONE`] is the default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effects {
    /// Damping, if declared.
    pub damping: Option<Damping>,
    /// Reserve a per-particle external force column `F_p`, N (per unit thickness in plane
    /// strain), added to the nodal force as `S_ip F_p` (E14). Set with
    /// [`crate::World::set_particle_forces`].
    pub particle_forces: bool,
    /// Most tractions the world holds (0: none). A traction loads one face of one particle's
    /// domain; its resultant enters `f_iT` (E16) spread with the particle's weights (see
    /// [`crate::World::add_tractions`] and the traction pass for why not with `N_i` on the
    /// face).
    pub traction_capacity: u32,
    /// A uniform body force per unit mass besides gravity, m/s^2, scaled by
    /// `body_force_scale(t)`: added to every node as `m_i b(t)` (E14). Unlike gravity it is
    /// not counted in the potential energy of [`crate::Diagnostics`].
    pub body_force: Vec3,
    /// Time factor of `body_force` (a ramp, a pulse); no point means a factor of 0.
    pub body_force_scale: Schedule,
    /// Time factors of the tractions (a ramp, a load cycle): each traction follows one of
    /// them, the first unless [`crate::World::set_traction_schedule`] chose another. Default
    /// the constant 1 for all. No point means a factor of 0.
    pub traction_schedules: [Schedule; TRACTION_SCHEDULES],
    /// Heat conduction (E54-E64), if declared: a temperature column (K) on the
    /// particles, conducted with each material's [`crate::MaterialDef::conductivity`] and
    /// [`crate::MaterialDef::heat_capacity`].
    pub heat: Option<Transport>,
    /// Diffusion (E54-E64), if declared: a concentration-potential column
    /// (dimensionless, c / c_sat) on the particles, diffused with each material's
    /// [`crate::MaterialDef::diffusivity`].
    pub diffusion: Option<Transport>,
    /// Reserve the plastic history column: one value per particle that the plastic models
    /// keep ([`crate::MaterialModel::plastic`]: the equivalent plastic strain of
    /// [`crate::MaterialModel::VonMises`], the accumulated plastic shear of
    /// [`crate::MaterialModel::DruckerPrager`], `J_p - 1` of [`crate::MaterialModel::Snow`]).
    /// Those models can be added only when it is declared; a world without it has the memory
    /// and the step of one without plastic materials.
    pub plasticity: bool,
}

/// How many schedules the tractions may follow ([`Effects::traction_schedules`]).
pub const TRACTION_SCHEDULES: usize = 4;

impl Effects {
    /// Nothing declared.
    pub const NONE: Effects = Effects {
        damping: None,
        particle_forces: false,
        traction_capacity: 0,
        body_force: Vec3::ZERO,
        body_force_scale: Schedule::ZERO,
        traction_schedules: [Schedule::constant(1.0); TRACTION_SCHEDULES],
        heat: None,
        diffusion: None,
        plasticity: false,
    };

    /// Checks every parameter ([`Error::InvalidEffect`] names them all).
    pub(crate) fn validate(&self, axes: usize) -> Result<(), Error> {
        let ok_damping = self.damping.is_none_or(|d| d.is_valid(axes));
        let ok_body = (0..axes).all(|a| self.body_force[a].is_finite())
            && self.body_force_scale.is_valid(false)
            && self.traction_schedules.iter().all(|s| s.is_valid(false));
        let ok_transport = [self.heat, self.diffusion]
            .iter()
            .all(|t| t.is_none_or(|t| t.is_valid(axes)));
        if ok_damping && ok_body && ok_transport && self.traction_capacity <= 1 << 24 {
            Ok(())
        } else {
            Err(Error::InvalidEffect)
        }
    }
}

impl Default for Effects {
    fn default() -> Self {
        Effects::NONE
    }
}
