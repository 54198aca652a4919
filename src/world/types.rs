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

impl ParticlesView<'_> {
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
