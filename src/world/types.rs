//! The world's public value types: the step report, the transported fields, particle
//! definitions and batches, the diagnostics and the borrowed particle view.

#[cfg(doc)]
use super::World;
use crate::def::Dimension;
#[cfg(doc)]
use crate::def::WorldDef;
use crate::material::Deformation;
use crate::math::Mat;
use crate::{Real, Vec3};

/// One particle for [`World::add_particle`]. In 2D the z components are ignored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleDef {
    /// Position, m.
    pub position: Vec3,
    /// Velocity, m/s.
    pub velocity: Vec3,
    /// Mass, kg (per unit thickness in plane strain), > 0.
    pub mass: Real,
    /// Initial volume V0, m^3 (m^2 per unit thickness in plane strain), > 0.
    pub volume: Real,
    /// Material id returned by [`World::add_material`].
    pub material: u32,
}

/// Which particles [`World::remove_particles`] removes.
#[derive(Clone, Debug, PartialEq)]
pub enum Removal<'r> {
    /// The particles of this id range.
    Range(core::ops::Range<u32>),
    /// The particles of these ids, in any order (an id given twice is removed once).
    List(&'r [u32]),
    /// Every particle whose position lies in the box from `min` to `max` (its faces included;
    /// in 2D the z components are not read), whatever its status: a sink.
    Box {
        /// The lowest corner, m.
        min: Vec3,
        /// The highest corner, m.
        max: Vec3,
    },
    /// Every particle that no longer takes part: escaped through an open face or frozen.
    Inactive,
    /// Every particle whose domain reaches into collider `id`'s solid, posed now, or touches
    /// it: the material a solid placed into it displaces. A particle's domain is the square
    /// (cube in 3D) of half-width `l = h / (2 particles_per_cell)` the step's contact reads
    /// (E91); it reaches the solid where the distance at its centre is within `l (|n_x| +
    /// |n_y| + |n_z|)` of the surface, `n` the surface's normal there (exactly the square's
    /// reach towards a flat face, whatever its tilt), or a thousandth of a cell more. Water cut
    /// this way floats a box within 2.2 % of Archimedes' depth at 10 cells across, where a cut
    /// of the centres inside alone leaves half-particles pressed against the solid (3.7 %:
    /// README, known limits).
    Collider(u32),
}

/// Particles as structure-of-arrays slices, all of one length, for [`World::add_particles`].
/// In 2D the z slices may be empty.
#[derive(Clone, Copy, Debug)]
pub struct ParticleBatch<'b> {
    /// Positions x, y, z, m.
    pub position: [&'b [Real]; 3],
    /// Velocities x, y, z, m/s.
    pub velocity: [&'b [Real]; 3],
    /// Masses, kg, > 0.
    pub mass: &'b [Real],
    /// Initial volumes, m^3, > 0.
    pub volume: &'b [Real],
    /// Material ids.
    pub material: &'b [u32],
}

/// Every column of some particles' state, in the shape of [`ParticlesView`], for
/// [`World::add_particles_with_state`] and [`World::set_particle_state`]: what moves a
/// particle out of a world and back, or into another world with the same materials and
/// declared effects, bit for bit (a view's [`ParticlesView::state`], cut to some rows with
/// [`ParticleState::rows`] and copied, is such a state).
///
/// Each column holds `count` values or is empty: not given. A column not given is left as
/// it is by [`World::set_particle_state`] and takes a new particle's value in
/// [`World::add_particles_with_state`] (0; the status [`crate::ParticleStatus::Active`]).
/// A group of columns (the axes of a vector, the entries of a matrix) is given whole or not
/// at all. Columns of axes the dimension lacks (z in 2D, the third row and column of the
/// matrices, stress components 4 and 5 in 2D) and the hoop stretch outside the axisymmetric
/// form are not read; a column of an effect the definition does not declare must be empty.
///
/// Nothing is derived from what is given: the stress is written as given, not computed from
/// the deformation (a viscous stress depends on the velocity gradient of the last step, and
/// a stress computed again differs from the step's in its last bits), so a state read from a
/// world steps on as it would have there. A stress that does not go with the deformation is
/// what a snapshot of such a state would hold: it loads the grid until the particle's next
/// stress update replaces it with its material's. [`World::set_displacement_gradient`] and
/// [`World::set_particle_materials`] derive the stress instead.
#[derive(Clone, Copy, Debug)]
pub struct ParticleState<'s> {
    /// Number of particles: the length of every column given.
    pub count: usize,
    /// Positions per axis, m ([`ParticlesView::position`]).
    pub position: [&'s [Real]; 3],
    /// The low parts of the positions per axis, m ([`ParticlesView::position_low`]).
    pub position_low: [&'s [Real]; 3],
    /// Velocities per axis, m/s.
    pub velocity: [&'s [Real]; 3],
    /// Masses, kg, > 0.
    pub mass: &'s [Real],
    /// Initial volumes, m^3, > 0.
    pub volume0: &'s [Real],
    /// Displacement gradient `H = F - I`, entry `[a][b]` ([`ParticlesView::displacement_gradient`]).
    pub displacement_gradient: [[&'s [Real]; 3]; 3],
    /// Kirchhoff stress over initial density, m^2/s^2, in the order of
    /// [`ParticlesView::stress`].
    pub stress: [&'s [Real]; 6],
    /// Material ids.
    pub material: &'s [u32],
    /// Status codes ([`crate::ParticleStatus`]).
    pub status: &'s [u32],
    /// External forces per axis, N (particle forces).
    pub force: [&'s [Real]; 3],
    /// Local grid and particle damping, 1/s (per-particle damping).
    pub damping: [&'s [Real]; 2],
    /// Temperatures, K (heat conduction).
    pub temperature: &'s [Real],
    /// Concentration potentials (diffusion).
    pub concentration: &'s [Real],
    /// The grid's temperature at each particle ([`ParticlesView::grid_temperature`]), K.
    pub grid_temperature: &'s [Real],
    /// The grid's concentration potential at each particle.
    pub grid_concentration: &'s [Real],
    /// Heat sources, W/m^3 (heat conduction with sources).
    pub temperature_source: &'s [Real],
    /// Sources of the concentration potential, 1/s (diffusion with sources).
    pub concentration_source: &'s [Real],
    /// The hoop stretch `F_thetatheta - 1` (axisymmetric).
    pub hoop: &'s [Real],
    /// The plastic history ([`ParticlesView::plastic`]; declared plasticity).
    pub plastic: &'s [Real],
    /// The affine matrix, entry `[a][b]` ([`ParticlesView::affine`]; APIC and MLS-MPM).
    pub affine: [[&'s [Real]; 3]; 3],
}

/// How many Real columns a state has ([`ParticleState::REAL_COLUMNS`]).
const REAL_COLUMNS: usize = 48;

impl<'s> ParticleState<'s> {
    /// How many Real columns a state has ([`ParticleState::real_columns`]).
    pub const REAL_COLUMNS: usize = REAL_COLUMNS;

    /// Every Real column, those not given empty, in a fixed order: position, its low part and
    /// velocity per axis (0-8), mass (9), initial volume (10), `H` row by row (11-19),
    /// stress (20-25), force (26-28), damping (29-30), temperature, concentration, their
    /// grid values and sources, hoop stretch, plastic history (31-38), affine matrix row by
    /// row (39-47): how a host that keeps or sends a state as columns lays them out.
    pub fn real_columns(&self) -> [&'s [Real]; REAL_COLUMNS] {
        let (h, b) = (self.displacement_gradient, self.affine);
        let scalars = [
            self.temperature,
            self.concentration,
            self.grid_temperature,
            self.grid_concentration,
            self.temperature_source,
            self.concentration_source,
            self.hoop,
            self.plastic,
        ];
        let mut c: [&'s [Real]; REAL_COLUMNS] = [&[]; REAL_COLUMNS];
        let parts: [&[&'s [Real]]; 10] = [
            &self.position,
            &self.position_low,
            &self.velocity,
            &[self.mass, self.volume0],
            h.as_flattened(),
            &self.stress,
            &self.force,
            &self.damping,
            &scalars,
            b.as_flattened(),
        ];
        let mut at = 0;
        for part in parts {
            c[at..at + part.len()].copy_from_slice(part);
            at += part.len();
        }
        c
    }

    /// The state of `count` particles whose Real columns are `c`, in the order of
    /// [`ParticleState::real_columns`].
    pub fn from_real_columns(
        count: usize,
        c: [&'s [Real]; REAL_COLUMNS],
        material: &'s [u32],
        status: &'s [u32],
    ) -> ParticleState<'s> {
        let matrix = |k: usize| -> [[&'s [Real]; 3]; 3] {
            core::array::from_fn(|a| core::array::from_fn(|b| c[k + 3 * a + b]))
        };
        ParticleState {
            count,
            position: [c[0], c[1], c[2]],
            position_low: [c[3], c[4], c[5]],
            velocity: [c[6], c[7], c[8]],
            mass: c[9],
            volume0: c[10],
            displacement_gradient: matrix(11),
            stress: core::array::from_fn(|k| c[20 + k]),
            material,
            status,
            force: [c[26], c[27], c[28]],
            damping: [c[29], c[30]],
            temperature: c[31],
            concentration: c[32],
            grid_temperature: c[33],
            grid_concentration: c[34],
            temperature_source: c[35],
            concentration_source: c[36],
            hoop: c[37],
            plastic: c[38],
            affine: matrix(39),
        }
    }
}

impl ParticleState<'_> {
    /// No particle, no column given: the start of a state built field by field
    /// (`ParticleState { count, mass, .. ParticleState::NONE }`).
    pub const NONE: ParticleState<'static> = ParticleState {
        count: 0,
        position: [&[]; 3],
        position_low: [&[]; 3],
        velocity: [&[]; 3],
        mass: &[],
        volume0: &[],
        displacement_gradient: [[&[]; 3]; 3],
        stress: [&[]; 6],
        material: &[],
        status: &[],
        force: [&[]; 3],
        damping: [&[]; 2],
        temperature: &[],
        concentration: &[],
        grid_temperature: &[],
        grid_concentration: &[],
        temperature_source: &[],
        concentration_source: &[],
        hoop: &[],
        plastic: &[],
        affine: [[&[]; 3]; 3],
    };
}

impl<'s> ParticleState<'s> {
    /// The state of rows `range` of these particles: each column given cut to the range
    /// (columns not given stay empty). `None` unless `range` lies within `0..count` and every
    /// column given is `count` long.
    pub fn rows(&self, range: core::ops::Range<usize>) -> Option<ParticleState<'s>> {
        if range.start > range.end || range.end > self.count {
            return None;
        }
        let mut whole = true;
        let mut cut = |c: &'s [Real]| -> &'s [Real] {
            whole &= c.is_empty() || c.len() == self.count;
            c.get(range.clone()).unwrap_or(&[])
        };
        let out = ParticleState {
            count: range.len(),
            position: self.position.map(&mut cut),
            position_low: self.position_low.map(&mut cut),
            velocity: self.velocity.map(&mut cut),
            mass: cut(self.mass),
            volume0: cut(self.volume0),
            displacement_gradient: self.displacement_gradient.map(|r| r.map(&mut cut)),
            stress: self.stress.map(&mut cut),
            material: &[],
            status: &[],
            force: self.force.map(&mut cut),
            damping: self.damping.map(&mut cut),
            temperature: cut(self.temperature),
            concentration: cut(self.concentration),
            grid_temperature: cut(self.grid_temperature),
            grid_concentration: cut(self.grid_concentration),
            temperature_source: cut(self.temperature_source),
            concentration_source: cut(self.concentration_source),
            hoop: cut(self.hoop),
            plastic: cut(self.plastic),
            affine: self.affine.map(|r| r.map(&mut cut)),
        };
        let ids = |c: &'s [u32]| {
            let ok = c.is_empty() || c.len() == self.count;
            (ok, c.get(range.clone()).unwrap_or(&[]))
        };
        let ((m_ok, material), (s_ok, status)) = (ids(self.material), ids(self.status));
        (whole && m_ok && s_ok).then_some(ParticleState {
            material,
            status,
            ..out
        })
    }
}

/// Sums over the active particles, in f64.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// Total mass of the active particles, kg.
    pub mass: f64,
    /// Linear momentum, kg m/s.
    pub momentum: [f64; 3],
    /// Angular momentum about the coordinate origin, kg m^2/s (2D: the z component only).
    /// With APIC it includes each particle's affine part `m_p eps : B_p^T` (see
    /// [`ParticlesView::affine`]), which the transfer conserves together with `x_p x m_p v_p`
    /// (E85).
    pub angular_momentum: [f64; 3],
    /// Centre of mass, m.
    pub center_of_mass: [f64; 3],
    /// Kinetic energy `sum m v^2 / 2`, J. With APIC and MLS-MPM it includes each particle's
    /// affine velocity field, `m_p tr(B_p D_p^-1 B_p^T) / 2` (E85): what the transfer carries to
    /// the grid beside `m_p v_p^2 / 2`.
    pub kinetic: f64,
    /// Strain energy `sum V0 W(F)`, J.
    pub strain: f64,
    /// Gravitational potential energy `-sum m g . x`, J (zero at the origin).
    pub potential: f64,
}

impl Diagnostics {
    /// Kinetic + strain + gravitational potential energy, J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic + self.strain + self.potential
    }
}

/// Borrowed view of the particle columns, valid while the world is not mutated.
/// Columns of axes the dimension lacks (z in 2D) are empty slices.
#[derive(Clone, Copy, Debug)]
pub struct ParticlesView<'w> {
    /// Number of particles (every column has this length).
    pub count: usize,
    /// The world's dimension.
    pub dimension: Dimension,
    /// Positions per axis, m, rounded to `Real`.
    pub position: [&'w [Real]; 3],
    /// What rounding the positions to `Real` left out, per axis, m (at most one unit in the
    /// last place of the position; half of one once it has moved less than its distance from
    /// the origin in a step): `position + position_low`, summed in f64, is the position to twice
    /// `Real`'s precision. The step moves particles by this pair, so that a displacement
    /// smaller than the last bit of a coordinate is not lost; in f32, a displacement read as
    /// `position` after minus before is exact to that last bit (1 um at 10 m), and to far
    /// less with `position_low` added.
    pub position_low: [&'w [Real]; 3],
    /// Velocities per axis, m/s.
    pub velocity: [&'w [Real]; 3],
    /// Masses, kg.
    pub mass: &'w [Real],
    /// Initial volumes, m^3.
    pub volume0: &'w [Real],
    /// Displacement gradient `H = F - I`, entry `[a][b]` (row a, column b) with F the
    /// deformation gradient; 2D uses a, b < 2 (F_zz = 1). Stored as `F - I` so that small
    /// strains keep full precision in f32. For a fluid and the plastic models, the elastic
    /// part `F_e - I` (`F = F_e F_p`; a fluid keeps `F_e = J^(1/3) I`).
    pub displacement_gradient: [[&'w [Real]; 3]; 3],
    /// Kirchhoff stress over initial density, m^2/s^2: 2D xx, yy, xy, zz; 3D xx, yy, zz, xy,
    /// xz, yz. Cauchy stress is `rho0 / J` times it.
    pub stress: [&'w [Real]; 6],
    /// Material ids.
    pub material: &'w [u32],
    /// Status codes ([`crate::ParticleStatus`]).
    pub status: &'w [u32],
    /// External forces per axis, N (empty unless particle forces are declared).
    pub force: [&'w [Real]; 3],
    /// Local grid and particle damping, 1/s (empty unless per-particle damping is declared).
    pub damping: [&'w [Real]; 2],
    /// Temperature, K (empty unless heat conduction is declared).
    pub temperature: &'w [Real],
    /// Concentration potential (empty unless diffusion is declared).
    pub concentration: &'w [Real],
    /// The grid's temperature at each particle after the last step, `T_g->p = sum S_ip T_i`,
    /// K: what a feature that depends on temperature should read (E63), since
    /// the particles' own values keep any variation within a cell (the FLIP update never
    /// smooths them). Empty unless heat conduction is declared.
    pub grid_temperature: &'w [Real],
    /// The grid's concentration potential at each particle after the last step, as
    /// [`ParticlesView::grid_temperature`]. Empty unless diffusion is declared.
    pub grid_concentration: &'w [Real],
    /// Heat sources, W/m^3 (empty unless heat conduction is declared with
    /// [`crate::Transport::sources`]).
    pub temperature_source: &'w [Real],
    /// Sources of the concentration potential, 1/s (empty unless diffusion is declared with
    /// [`crate::Transport::sources`]).
    pub concentration_source: &'w [Real],
    /// Axisymmetric only (else empty): the hoop stretch `F_thetatheta - 1 = r / r_0 - 1`, the
    /// out-of-plane part of the deformation gradient.
    pub hoop: &'w [Real],
    /// The plastic history of each particle (empty unless [`crate::Effects::plasticity`] is
    /// declared; 0 for particles of other models): the equivalent plastic strain
    /// `sqrt(2/3) |eps_p|` of [`crate::MaterialModel::VonMises`], the accumulated plastic
    /// shear strain of [`crate::MaterialModel::DruckerPrager`], `J_p - 1` of
    /// [`crate::MaterialModel::Snow`] (its volume ratio is `J_e J_p`).
    pub plastic: &'w [Real],
    /// APIC moment matrix `B_p = sum_i S_ip v_i (x_i - x_p)^T`, entry `[a][b]`, m^2/s (empty
    /// unless the transfer is APIC); with linear shape functions, the affine velocity matrix
    /// `C_p` itself, 1/s, in its gradient form (see [`crate::shape::Shape1D::GRADIENT_AFFINE`]). The affine velocity field is `C_p = B_p D_p^-1`, with
    /// `D_p` the particle's second moment of the weights, evaluated where the particle is when
    /// it next scatters (storing `B_p` rather than `C_p` is what makes the transfer conserve
    /// angular momentum when `D_p` depends on position, as with uGIMP).
    pub affine: [[&'w [Real]; 3]; 3],
}

impl<'w> ParticlesView<'w> {
    /// Every column of the view as a [`ParticleState`]: what
    /// [`World::add_particles_with_state`] and [`World::set_particle_state`] take (copied out
    /// of the world first when the world they go to is this one).
    pub fn state(&self) -> ParticleState<'w> {
        ParticleState {
            count: self.count,
            position: self.position,
            position_low: self.position_low,
            velocity: self.velocity,
            mass: self.mass,
            volume0: self.volume0,
            displacement_gradient: self.displacement_gradient,
            stress: self.stress,
            material: self.material,
            status: self.status,
            force: self.force,
            damping: self.damping,
            temperature: self.temperature,
            concentration: self.concentration,
            grid_temperature: self.grid_temperature,
            grid_concentration: self.grid_concentration,
            temperature_source: self.temperature_source,
            concentration_source: self.concentration_source,
            hoop: self.hoop,
            plastic: self.plastic,
            affine: self.affine,
        }
    }

    /// `J - 1 = det F - 1` of particle `i`'s stored `F` (with `F_thetatheta` when
    /// axisymmetric), computed from H without cancellation. The plastic models store the
    /// elastic part `F_e`: snow's whole volume ratio is `J_e J_p`, `J_p - 1` its history.
    pub fn jacobian_minus_one(&self, i: usize) -> Real {
        if self.dimension == Dimension::ThreeD {
            self.deformation::<3>(i).jm1
        } else {
            self.deformation::<2>(i).jm1
        }
    }

    /// The deformation of particle `i` as the materials see it (`D` the world's axes).
    pub(crate) fn deformation<const D: usize>(&self, i: usize) -> Deformation<D> {
        let h = &self.displacement_gradient;
        let m: Mat<D> = core::array::from_fn(|a| core::array::from_fn(|b| h[a][b][i]));
        Deformation::with_plastic(
            m,
            self.hoop.get(i).copied().unwrap_or(0.0),
            self.plastic.get(i).copied().unwrap_or(0.0),
        )
    }

    /// `J = det F` of particle `i`'s stored `F` (current volume over initial volume, but for
    /// snow's `J_p`: see [`ParticlesView::jacobian_minus_one`]).
    pub fn jacobian(&self, i: usize) -> Real {
        1.0 + self.jacobian_minus_one(i)
    }
}

/// A collider as the world holds it ([`World::collider`]): its definition with the pose it
/// has now (the step moves it with its velocities), and what the material put on it over the
/// last step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColliderState {
    /// The definition, its `position` and `rotation` those of now (in 2D, what a 2D world
    /// does not read is 0: [`crate::ColliderDef::position`]).
    pub def: crate::ColliderDef,
    /// The impulse the material put on the collider over the last step, N s (per unit
    /// thickness in plane strain, per radian axisymmetric), summed in a fixed order: the
    /// same bits for any number of workers.
    pub impulse: Vec3,
    /// The angular impulse about the collider's origin over the last step, N m s.
    pub angular_impulse: Vec3,
    /// The last step's length, s (0 before the first step).
    pub duration: Real,
}

impl ColliderState {
    /// The mean force of the last step, `impulse / duration`, N (zero before a step).
    pub fn force(&self) -> Vec3 {
        if self.duration > 0.0 {
            self.impulse / self.duration
        } else {
            Vec3::ZERO
        }
    }

    /// The mean torque about the collider's origin over the last step, N m (zero before a
    /// step).
    pub fn torque(&self) -> Vec3 {
        if self.duration > 0.0 {
            self.angular_impulse / self.duration
        } else {
            Vec3::ZERO
        }
    }
}
