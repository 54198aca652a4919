//! What a scene declares beyond the momentum equation ([`Effects`], in
//! [`crate::WorldDef::effects`]): damping and its thermostat, particle forces and tractions,
//! a body force, heat conduction and diffusion, plasticity. Declarations only, checked when a
//! world is made; the terms they add to a step are [`crate::effects`], the setters of their
//! per-particle data [`crate::World`]'s.

use super::Face;
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
    /// domain, integrated over the deformed face into `f_iT` (E15, E16; see
    /// [`crate::World::add_tractions`]).
    pub traction_capacity: u32,
    /// A uniform body force per unit mass besides gravity, m/s^2, scaled by
    /// `body_force_scale(t)`: added to every node as `m_i b(t)` (E14). Unlike gravity it is
    /// not counted in the potential energy of [`crate::Diagnostics`].
    pub body_force: Vec3,
    /// Time factor of `body_force` and `body_force_gradient` (a ramp, a pulse); no point
    /// means a factor of 0.
    pub body_force_scale: Schedule,
    /// The body force's change with position, 1/s^2: the rows of `G` in
    /// `b(x, t) = (body_force + G x) body_force_scale(t)`, `x` the node's position in the
    /// world's axes (m), added to every node as `m_i G x_i` (E14). An affine field: a
    /// rotating frame's centrifugal force about an axis through `c` is
    /// `G = w^2 (I - e e^T)`, `body_force = -G c`; a tidal or varying gravity its
    /// gradient. Default zero (and then nothing is computed); entries past the world's axes
    /// are ignored. A field is resolved while `|G| dt^2` stays well below 1 (its own
    /// oscillation, `sqrt(-G)`, takes no part in the stable step).
    pub body_force_gradient: [Vec3; 3],
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
    /// Most colliders the world holds (0: none, and no collider pass runs): kinematic solids
    /// in the scene that the material contacts at the grid and pushes back
    /// ([`crate::World::add_collider`], E90-E93).
    pub collider_capacity: u32,
    /// Most samples of signed distance fields the world holds
    /// ([`crate::World::add_distance_field`], for [`ColliderShape::Sdf`] colliders); 0: none.
    pub sdf_capacity: u32,
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
        body_force_gradient: [Vec3::ZERO; 3],
        traction_schedules: [Schedule::constant(1.0); TRACTION_SCHEDULES],
        heat: None,
        diffusion: None,
        plasticity: false,
        collider_capacity: 0,
        sdf_capacity: 0,
    };

    /// Checks every parameter ([`Error::InvalidEffect`] names them all).
    pub(crate) fn validate(&self, axes: usize) -> Result<(), Error> {
        let ok_damping = self.damping.is_none_or(|d| d.is_valid(axes));
        let ok_body = (0..axes).all(|a| self.body_force[a].is_finite())
            && (0..axes).all(|a| (0..axes).all(|b| self.body_force_gradient[a][b].is_finite()))
            && self.body_force_scale.is_valid(false)
            && self.traction_schedules.iter().all(|s| s.is_valid(false));
        let ok_transport = [self.heat, self.diffusion]
            .iter()
            .all(|t| t.is_none_or(|t| t.is_valid(axes)));
        let ok_capacity = self.traction_capacity <= 1 << 24
            && self.collider_capacity <= 1 << 12
            && self.sdf_capacity <= 1 << 26;
        if ok_damping && ok_body && ok_transport && ok_capacity {
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
pub(crate) fn graded(rate: Real, c: Real, lo: Real, hi: Real, toward_max: bool) -> Real {
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

/// Boundary condition of a transported scalar (temperature or concentration potential) on one
/// face of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScalarBoundary {
    /// No flow across the face (the natural condition of E55).
    Insulated,
    /// The value held fixed on the face: the nodes from the grid face to the wall plane (as the
    /// walls of [`crate::Boundary`]) take it.
    Fixed(Real),
    /// A flow into the domain per unit area of the face (W/m^2 for heat, m/s for the
    /// concentration potential), applied on the wall plane's nodes (E60).
    Flux(Real),
}

/// A transported scalar field (heat conduction or diffusion, E54-E64):
/// its boundary conditions and whether particles carry a source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transport {
    /// Condition of each face, indexed by [`crate::Face`].
    pub faces: [ScalarBoundary; 6],
    /// Reserve a per-particle source column (W/m^3 for heat, 1/s for the concentration
    /// potential), set with [`crate::World::set_particle_sources`].
    pub sources: bool,
}

impl Transport {
    /// Every face insulated, no sources.
    pub const INSULATED: Transport = Transport {
        faces: [ScalarBoundary::Insulated; 6],
        sources: false,
    };

    /// Whether the faces of the `axes` used have finite values (the z faces of a 2D world are
    /// not read, like every other z component there).
    pub(crate) fn is_valid(&self, axes: usize) -> bool {
        self.faces[..2 * axes].iter().all(|f| match f {
            ScalarBoundary::Insulated => true,
            ScalarBoundary::Fixed(v) | ScalarBoundary::Flux(v) => v.is_finite(),
        })
    }
}

/// A transported scalar field.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum ScalarField {
    /// Temperature, K (heat conduction).
    Temperature = 0,
    /// Concentration potential `c / c_sat` (diffusion).
    Concentration = 1,
}

/// The solid of a collider in its own frame: centred on its position, its axes turned by its
/// rotation ([`ColliderDef`]). In 2D the frame's z axis is the plane's normal, and a solid is
/// its section by the plane z = 0; axisymmetric, by the (r, z) half-plane, so a solid on the
/// axis is a solid of revolution (a [`ColliderShape::Cylinder`] along the axis is a disk).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColliderShape {
    /// The half-space below the plane through the position whose normal is the frame's y
    /// axis: a floor with no rotation, a slope when turned.
    HalfSpace,
    /// A sphere (a circle in 2D) of `radius`, m, > 0.
    Sphere {
        /// m.
        radius: Real,
    },
    /// A box (a rectangle in 2D) of half-extents along the frame's axes, m, each > 0.
    Box {
        /// m.
        half_extents: Vec3,
    },
    /// The points within `radius` of the segment from `-half_length` to `half_length` along
    /// the frame's y axis (a stadium in 2D). m; `radius > 0`, `half_length >= 0`.
    Capsule {
        /// m.
        half_length: Real,
        /// m.
        radius: Real,
    },
    /// Any solid: the signed distance field (negative inside, m) sampled on a grid of
    /// `dims` points `spacing` apart, centred on the frame's origin, its samples x fastest
    /// from `first` in the world's distance samples ([`crate::World::add_distance_field`]).
    /// Between samples it is interpolated linearly (bilinearly in 2D, where `dims[2]` is 1);
    /// outside the grid's box, the distance to the box is added to the nearest point's.
    Sdf {
        /// The field's first sample (what `add_distance_field` returned).
        first: u32,
        /// Samples along x, y, z: at least 2 along x and y, 1 or more along z (1 in 2D).
        dims: [u32; 3],
        /// Distance between samples, m, > 0.
        spacing: Real,
    },
    /// A cylinder along the frame's y axis (a rectangle in 2D), hollow inside `inner_radius`
    /// (0: solid): a tube, a drum's shell; axisymmetric, on the axis, a disk or a ring. m;
    /// `half_length > 0`, `0 <= inner_radius < radius`.
    Cylinder {
        /// m.
        half_length: Real,
        /// m.
        radius: Real,
        /// m.
        inner_radius: Real,
    },
}

impl ColliderShape {
    /// The shape's number: what a collider record stores and the C interface's
    /// `MpmColliderShape` calls it. The one table of the shapes' numbers.
    pub const fn number(&self) -> u32 {
        match self {
            ColliderShape::HalfSpace => 0,
            ColliderShape::Sphere { .. } => 1,
            ColliderShape::Box { .. } => 2,
            ColliderShape::Capsule { .. } => 3,
            ColliderShape::Cylinder { .. } => 4,
            ColliderShape::Sdf { .. } => 5,
        }
    }

    /// The shape's lengths, m, as [`ColliderShape::from_parts`] reads them (a sphere's radius;
    /// a box's half-extents; a capsule's half-length and radius; a cylinder's half-length,
    /// radius and inner radius; a distance field's spacing; 0 where unused), and a distance
    /// field's first sample and points per axis (0 for the other shapes).
    pub(crate) fn parts(&self) -> ([Real; 3], [u32; 4]) {
        match *self {
            ColliderShape::HalfSpace => ([0.0; 3], [0; 4]),
            ColliderShape::Sphere { radius } => ([radius, 0.0, 0.0], [0; 4]),
            ColliderShape::Box { half_extents: e } => ([e.x, e.y, e.z], [0; 4]),
            ColliderShape::Capsule {
                half_length,
                radius,
            } => ([half_length, radius, 0.0], [0; 4]),
            ColliderShape::Cylinder {
                half_length,
                radius,
                inner_radius,
            } => ([half_length, radius, inner_radius], [0; 4]),
            ColliderShape::Sdf {
                first,
                dims,
                spacing,
            } => ([spacing, 0.0, 0.0], [first, dims[0], dims[1], dims[2]]),
        }
    }

    /// The shape of `number` ([`ColliderShape::number`]) with the `lengths` and `grid` that
    /// [`ColliderShape::parts`] gives; `None` for a number no shape has.
    pub(crate) fn from_parts(number: u32, lengths: [Real; 3], grid: [u32; 4]) -> Option<Self> {
        let [a, b, c] = lengths;
        [
            ColliderShape::HalfSpace,
            ColliderShape::Sphere { radius: a },
            ColliderShape::Box {
                half_extents: Vec3::new(a, b, c),
            },
            ColliderShape::Capsule {
                half_length: a,
                radius: b,
            },
            ColliderShape::Cylinder {
                half_length: a,
                radius: b,
                inner_radius: c,
            },
            ColliderShape::Sdf {
                first: grid[0],
                dims: [grid[1], grid[2], grid[3]],
                spacing: a,
            },
        ]
        .into_iter()
        .find(|s| s.number() == number)
    }
}

/// How the material meets a collider at a node inside it (E91).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// The node moves with the collider.
    Stick,
    /// The node keeps no velocity along the collider's normal relative to it, in either
    /// direction (bilateral), and slides along it with Coulomb friction where it presses.
    Slip,
    /// As [`Contact::Slip`] while the node approaches the collider; a node moving away from
    /// it is left free (unilateral contact, the usual one).
    Separate,
}

/// A collider: its solid, its pose and velocity, how the material meets it, and whether the
/// host moves it (kinematic, `mass` 0) or the step does (dynamic, `mass` > 0)
/// ([`crate::World::add_collider`]). [`ColliderDef::DEFAULT`] is a kinematic floor through
/// the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColliderDef {
    /// The solid in the collider's frame.
    pub shape: ColliderShape,
    /// The frame's origin, m: the solid's centre, the point about which its angular velocity
    /// turns it and about which [`crate::ColliderState::torque`] is reported. In 2D its z is
    /// not read, as no z of a 2D call is: the origin lies in the plane z = 0, and reads back
    /// with z = 0.
    pub position: Vec3,
    /// The frame's rotation as a unit quaternion `[x, y, z, w]` (normalised when set); in 2D
    /// only turns about z keep the solid in the plane.
    pub rotation: [Real; 4],
    /// Velocity of the frame's origin, m/s (in 2D its z is not read, and reads back 0).
    pub velocity: Vec3,
    /// Angular velocity about the origin, rad/s (in 2D only its z is read; x and y read back
    /// 0).
    pub angular_velocity: Vec3,
    /// Stick, slip or separating contact.
    pub contact: Contact,
    /// Coulomb friction coefficient of slip and separating contact, >= 0 (0: frictionless).
    pub friction: Real,
    /// The solid's mass, kg (per metre of thickness in plane strain, per radian
    /// axisymmetric, as the impulse), >= 0. 0 (the default): kinematic, the host moves it
    /// and the velocity it sets holds through the step. Above 0: dynamic, the step moves it
    /// each substep by the impulse the material puts on it and the world's gravity (E96),
    /// from the pose and velocity last set, so that a host coupling a rigid body steps it
    /// at any frame rate; read the pose back after the step.
    pub mass: Real,
    /// A dynamic solid's principal moments of inertia about its origin, along its frame's
    /// axes, kg m^2 (per metre of thickness in plane strain: only z is read), each >= 0; a
    /// moment of 0 keeps the angular velocity about that axis as set (a solid that does
    /// not turn). Not read while `mass` is 0.
    pub inertia: Vec3,
}

impl ColliderDef {
    /// A frictionless separating floor: the half-space y < 0, at rest.
    pub const DEFAULT: ColliderDef = ColliderDef {
        shape: ColliderShape::HalfSpace,
        position: Vec3::ZERO,
        rotation: [0.0, 0.0, 0.0, 1.0],
        velocity: Vec3::ZERO,
        angular_velocity: Vec3::ZERO,
        contact: Contact::Separate,
        friction: 0.0,
        mass: 0.0,
        inertia: Vec3::ZERO,
    };

    /// The components of [`ColliderDef::position`], [`ColliderDef::velocity`] and
    /// [`ColliderDef::angular_velocity`] a world reads: every one in 3D; in 2D (`planar`) the
    /// position and velocity in the plane and the turn about z (E90). The others are not read,
    /// as no z of a 2D call is, and are stored as 0.
    pub(crate) const fn read_components(planar: bool) -> [[bool; 3]; 3] {
        let off_plane = !planar;
        [
            [true, true, off_plane],
            [true, true, off_plane],
            [off_plane, off_plane, true],
        ]
    }

    /// Whether every value a world of `planar` (2D) motion or not reads is finite and in
    /// range (the rotation's length above zero; [`ColliderDef::read_components`]): what
    /// [`crate::World::add_collider`] accepts, and what [`crate::World::open`] asks of a
    /// stored collider's definition.
    pub(crate) fn is_valid(&self, planar: bool) -> bool {
        let finite = |v: Vec3| v.is_finite();
        let [position, velocity, omega] = Self::read_components(planar);
        let read_finite = |v: Vec3, read: [bool; 3]| (0..3).all(|a| !read[a] || v[a].is_finite());
        let q = self.rotation;
        let q2: Real = q.iter().map(|c| c * c).sum();
        let shape = match self.shape {
            ColliderShape::HalfSpace => true,
            ColliderShape::Sphere { radius } => radius > 0.0 && radius.is_finite(),
            ColliderShape::Box { half_extents } => {
                finite(half_extents) && half_extents.min_element() > 0.0
            }
            ColliderShape::Capsule {
                half_length,
                radius,
            } => {
                half_length >= 0.0 && half_length.is_finite() && radius > 0.0 && radius.is_finite()
            }
            ColliderShape::Sdf { dims, spacing, .. } => {
                spacing > 0.0 && spacing.is_finite() && dims[0] >= 2 && dims[1] >= 2 && dims[2] >= 1
            }
            ColliderShape::Cylinder {
                half_length,
                radius,
                inner_radius,
            } => {
                half_length > 0.0
                    && half_length.is_finite()
                    && radius.is_finite()
                    && inner_radius >= 0.0
                    && inner_radius < radius
            }
        };
        shape
            && read_finite(self.position, position)
            && read_finite(self.velocity, velocity)
            && read_finite(self.angular_velocity, omega)
            && q2.is_finite()
            && q2 > 1e-12
            && self.friction >= 0.0
            && self.friction.is_finite()
            && self.mass >= 0.0
            && self.mass.is_finite()
            && (0..3).all(|a| !omega[a] || (self.inertia[a] >= 0.0 && self.inertia[a].is_finite()))
    }
}

impl Default for ColliderDef {
    fn default() -> Self {
        ColliderDef::DEFAULT
    }
}
