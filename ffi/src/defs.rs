//! The definitions a C host fills: world, material, and the enums that choose the method.
//! Every definition starts from its `*_default()` function, which sets a cookie that init and
//! add check, so a struct the host zeroed or filled by hand is refused instead of misread.
//!
//! Enum-valued fields are plain `uint32_t` on the Rust side (named by their enum type in the
//! header): a value out of range from C is then an `MPM_STATUS_INVALID_ENUM`, never undefined
//! behaviour. Flags (`declared`, `per_particle`, `particle_forces`, `sources`) are `uint32_t`
//! too and must be 0 or 1; any other value is also `MPM_STATUS_INVALID_ENUM`.
//!
//! The optional effects (`MpmEffects`, the C form of `mpm_gimp::Effects`) sit inside
//! `MpmWorldDef`; `mpm_world_def_default` declares none of them.

use crate::status::MpmStatus;
use crate::{mpm_real, MpmVec3};
use kernel::{
    Boundary, Damping, DampingZone, Dimension, Effects, Face, Feedback, FrictionFit, MaterialDef,
    MaterialModel, ScalarBoundary, ScalarField, Schedule, ShapeFunction, Transfer, Transport,
    UpdateOrder, WorldDef,
};

/// Spatial dimension and kinematic assumption (`mpm_gimp::Dimension`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmDimension {
    /// Two dimensions, plane strain (per unit thickness; F_zz = 1).
    Plane2d = 2,
    /// Three dimensions.
    Space3d = 3,
    /// Two dimensions, axisymmetric: x is the radius r and y the axis z. Masses, volumes,
    /// forces and energies are per radian, and the out-of-plane stress is tau_thetatheta
    /// (`MpmParticlesView::hoop` holds F_thetatheta - 1). The axis r = 0 must be the lower x
    /// face's wall plane: `origin.x = -margin * cell_size` (margin 0 cells for
    /// `MPM_SHAPE_LINEAR`, 1 for the others) and `faces[MPM_FACE_X_MIN]` not
    /// `MPM_BOUNDARY_OPEN`, or `MPM_STATUS_INVALID_AXIS`.
    Axisymmetric2d = 4,
}

/// Grid shape function (`mpm_gimp::ShapeFunction`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmShape {
    /// Classic MPM: linear hats, 2 nodes per axis.
    Linear = 0,
    /// uGIMP (Bardenhagen and Kober 2004), 3 nodes per axis.
    Gimp = 1,
    /// Quadratic B-spline, 3 nodes per axis.
    QuadraticBspline = 2,
    /// Cubic B-spline, 4 nodes per axis.
    CubicBspline = 3,
    /// cpGIMP (Wallstedt and Guilkey 2008): uGIMP whose particle domain deforms with the
    /// material. On each axis the domain's half-width is uGIMP's,
    /// `cell_size / (2 * particles_per_cell)`, times the deformed domain's extent along that
    /// axis (the row sum of |F|), clamped between a tenth of uGIMP's and half a cell so that it
    /// keeps to 3 nodes per axis. Margin 1 cell, as uGIMP; each pass also reads the
    /// deformation gradient.
    CpGimp = 4,
}

/// Where the stress update sits in a step (`mpm_gimp::UpdateOrder`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmUpdateOrder {
    /// Update stress first.
    Usf = 0,
    /// Update stress last (cheapest).
    Usl = 1,
    /// Modified USL (most robust where nodal masses are tiny).
    Musl = 2,
}

/// How velocity moves from the grid back to the particles (`mpm_gimp::Transfer`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmTransfer {
    /// FLIP blended with PIC by `MpmWorldDef::flip_beta`; the particle moves by the grid's
    /// velocity and acceleration at its place.
    Flip = 0,
    /// APIC: the grid velocity plus an affine field per particle, which conserves angular
    /// momentum; `flip_beta` is not used. Reserves D x D columns (`MpmParticlesView::affine`).
    Apic = 1,
    /// FLIP blended as `MPM_TRANSFER_FLIP`, each particle moving with its own new velocity,
    /// `x += v(n+1) dt`: a time error about a hundredth of `MPM_TRANSFER_FLIP`'s, as APIC's,
    /// but with `flip_beta` near 1 the particles follow the FLIP velocity's noise and large
    /// deformations do not converge (`mpm_gimp::Transfer::FlipParticleVelocity`). Same
    /// columns and cost as `MPM_TRANSFER_FLIP`.
    FlipParticleVelocity = 2,
    /// MLS-MPM: APIC's transfer, with the MLS gradient `D_p^-1 S_ip (x_i - x_p)` in place of
    /// the shape function's for the nodal force and the velocity gradient
    /// (`mpm_gimp::Transfer::Mls`). The quadratic and cubic B-splines, 2D and 3D only
    /// (otherwise `MPM_STATUS_INVALID_TRANSFER`). Reserves the columns APIC does.
    Mls = 3,
    /// FLIP in the momentum approach (E73-E77 of docs/equations.md,
    /// `mpm_gimp::Transfer::FlipMomentum`): the velocity gradient of the mass-weighted grid
    /// velocity field, exact for affine fields, with its work-conjugate internal force, and the
    /// particles moving with the mass-weighted grid velocity. Plane strain and 3D only
    /// (otherwise `MPM_STATUS_INVALID_TRANSFER`). Same columns as `MPM_TRANSFER_FLIP`, 1.4 to 2
    /// times its cost per step. For dynamics: at rest, stresses next to a free or loaded face
    /// are off (up to 28 % in a block pulled by a traction, against 0.2 % with FLIP).
    FlipMomentum = 4,
    /// XPIC(k) (`mpm_gimp::Transfer::Xpic`): the field `transfer` holds
    /// `MPM_TRANSFER_XPIC + 256 * k`, k in 1..=8 (otherwise `MPM_STATUS_INVALID_TRANSFER`). The
    /// particle velocity from the series `sum_{r=1..k} (-1)^(r+1) C(k, r) A^(r-1) v^L` of the
    /// step's lumped velocity, `A` the projection particles-to-grid of the velocity gathered
    /// from the grid: PIC for k = 1, FLIP's energy without its noise as k grows. `flip_beta`
    /// is not used; k - 1 extra gather and scatter passes.
    Xpic = 5,
    /// FMPM(k) (`mpm_gimp::Transfer::Fmpm`): `MPM_TRANSFER_FMPM + 256 * k`, k in 1..=2 (not
    /// k = 2 with `MPM_UPDATE_ORDER_USL`); the same series on the updated lumped velocity,
    /// which the particle takes.
    Fmpm = 6,
}

/// Boundary condition of one face of the grid box (`mpm_gimp::Boundary`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmBoundary {
    /// Wall nodes have zero velocity.
    Stick = 0,
    /// Wall nodes have zero normal velocity.
    Slip = 1,
    /// No condition; particles that cross the face leave the simulation.
    Open = 2,
    /// Material that leaves comes back through the opposite face, which must be periodic
    /// too; not the radial axis, no wall friction or velocity, scalar faces insulated, or
    /// `MPM_STATUS_INVALID_BOUNDARY`.
    Periodic = 3,
}

/// Index of each face in `MpmWorldDef::faces`, and the face of a particle's domain that a
/// traction loads (`mpm_world_add_tractions`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmFace {
    /// Lowest x.
    XMin = 0,
    /// Highest x.
    XMax = 1,
    /// Lowest y.
    YMin = 2,
    /// Highest y.
    YMax = 3,
    /// Lowest z (3D only).
    ZMin = 4,
    /// Highest z (3D only).
    ZMax = 5,
}

/// Kind of condition a transported scalar (temperature or concentration potential) meets on
/// one face of the grid box (`mpm_gimp::ScalarBoundary`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmScalarBoundaryKind {
    /// No flow across the face; `MpmScalarBoundary::value` is not read.
    Insulated = 0,
    /// The value held fixed on the face (K, or the concentration potential).
    Fixed = 1,
    /// A flow into the domain per unit area of the face (W/m^2 for heat, m/s for the
    /// concentration potential).
    Flux = 2,
}

/// A transported scalar field (`mpm_gimp::ScalarField`), the field that
/// `mpm_world_set_particle_scalar` and `mpm_world_set_particle_sources` set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmScalarField {
    /// Temperature, K (`MpmEffects::heat`).
    Temperature = 0,
    /// Concentration potential c / c_sat (`MpmEffects::diffusion`).
    Concentration = 1,
}

/// Constitutive model (`mpm_gimp::MaterialModel`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmMaterialModel {
    /// Corotated isotropic linear elasticity (small strain).
    LinearElastic = 0,
    /// Compressible neo-Hookean.
    NeoHookean = 1,
    /// Fixed-corotated elasticity (Stomakhin et al. 2012).
    FixedCorotated = 2,
    /// Weakly compressible fluid (Tait's equation: `bulk_modulus`, `pressure_exponent`; with
    /// `viscosity`).
    Fluid = 3,
    /// Metal: J2 plasticity with linear isotropic hardening (`yield_stress`,
    /// `hardening_modulus`). Needs `MpmEffects::plasticity`.
    VonMises = 4,
    /// Sand: Drucker-Prager plasticity (`friction_angle`, `cohesion`). Needs
    /// `MpmEffects::plasticity`.
    DruckerPrager = 5,
    /// Snow: clamped fixed-corotated with hardening (`critical_compression`,
    /// `critical_stretch`, `hardening_coefficient`). Needs `MpmEffects::plasticity`.
    Snow = 6,
}

/// How the Drucker-Prager cone is fitted to the friction angle (`mpm_gimp::FrictionFit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmFrictionFit {
    /// Through Mohr-Coulomb's compression corners (Klar et al. 2016); the default. In plane
    /// strain: Rankine's Ka 0.368 and Kp 2.717 at 30 degrees (Mohr-Coulomb: 1/3 and 3).
    Compression = 0,
    /// Through the extension corners.
    Extension = 1,
    /// Inscribed in Mohr-Coulomb's pyramid.
    Inscribed = 2,
    /// Mohr-Coulomb exactly in plane strain (Rankine's earth pressures).
    PlaneStrain = 3,
}

/// Status of a particle in the status column (`mpm_gimp::ParticleStatus`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmParticleStatus {
    /// Takes part in every step.
    Active = 0,
    /// Its state turned non-finite (or F inverted): it keeps its last finite position, its
    /// velocity is zero, and it no longer takes part.
    Frozen = 1,
    /// It crossed an open face and no longer takes part.
    Escaped = 2,
}

/// An `MpmDimension` value as stored in a definition (any 32-bit value from C).
pub type MpmDimensionValue = u32;
/// An `MpmShape` value as stored in a definition.
pub type MpmShapeValue = u32;
/// An `MpmUpdateOrder` value as stored in a definition.
pub type MpmUpdateOrderValue = u32;
/// An `MpmTransfer` value as stored in a definition.
pub type MpmTransferValue = u32;
/// An `MpmFace` value as passed to a function.
pub type MpmFaceValue = u32;
/// An `MpmBoundary` value as stored in a definition.
pub type MpmBoundaryValue = u32;
/// An `MpmMaterialModel` value as stored in a definition.
pub type MpmMaterialModelValue = u32;
/// An `MpmFrictionFit` value as stored in a definition.
pub type MpmFrictionFitValue = u32;
/// An `MpmScalarBoundaryKind` value as stored in a definition.
pub type MpmScalarBoundaryKindValue = u32;
/// An `MpmScalarField` value as passed to a function.
pub type MpmScalarFieldValue = u32;

/// Most points an `MpmSchedule` holds.
pub const MPM_SCHEDULE_POINTS: usize = 8;

/// The shortest stable time step a world accepts, s (`mpm_gimp::MIN_STABLE_DT`): a value
/// whose own stable step would be shorter is `MPM_STATUS_STABLE_STEP_TOO_SHORT`.
pub const MPM_MIN_STABLE_DT: f64 = 1.0e-15;
const _: () = assert!(MPM_MIN_STABLE_DT == kernel::MIN_STABLE_DT);

/// The largest snow hardening coefficient xi (`mpm_gimp::MAX_HARDENING_COEFFICIENT`).
pub const MPM_MAX_HARDENING_COEFFICIENT: mpm_real = 100.0;
const _: () = assert!(MPM_MAX_HARDENING_COEFFICIENT == kernel::MAX_HARDENING_COEFFICIENT);

const _: () = assert!(MPM_SCHEDULE_POINTS == kernel::SCHEDULE_POINTS);

/// A value that is a function of time (`mpm_gimp::Schedule`): piecewise linear through the
/// first `points` (time, value) pairs, constant before the first and after the last. No point
/// is the constant 0; one point is a constant.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmSchedule {
    /// Number of points used, 0..=`MPM_SCHEDULE_POINTS` (more is `MPM_STATUS_INVALID_EFFECT`).
    pub points: u32,
    /// Times of the points, s, finite and strictly increasing; entries past `points` are
    /// ignored.
    pub times: [mpm_real; MPM_SCHEDULE_POINTS],
    /// Values at those times, finite; entries past `points` are ignored.
    pub values: [mpm_real; MPM_SCHEDULE_POINTS],
}

/// A kinetic-energy thermostat on the grid damping (`mpm_gimp::Feedback`): once per substep
/// `alpha += 2 gain (KE - target(t)) dt / M`, clamped to `[0, max_alpha]`; the evolving alpha
/// (`mpm_world_feedback_alpha`) adds to the grid damping.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmFeedback {
    /// 1: the thermostat is declared; 0: none (the other fields are then ignored).
    pub declared: u32,
    /// Gain 1/Q, 1/m^2, > 0.
    pub gain: mpm_real,
    /// Target kinetic energy, J, a function of time (values >= 0).
    pub target: MpmSchedule,
    /// Largest alpha, 1/s, > 0 (infinity: unbounded).
    pub max_alpha: mpm_real,
}

/// Damping on top of the PIC damping that `flip_beta` sets (`mpm_gimp::Damping`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmDamping {
    /// 1: damping is declared; 0: none (the other fields are then ignored).
    pub declared: u32,
    /// Grid damping alpha_g(t), 1/s (values >= 0): damps the velocity from the grid.
    pub grid: MpmSchedule,
    /// Particle damping alpha_p(t), 1/s (values >= 0): damps the particle velocity.
    pub particle: MpmSchedule,
    /// A thermostat that adds to the grid damping, if declared.
    pub feedback: MpmFeedback,
    /// 1: reserve per-particle alpha_g and alpha_p columns, added to the global values and set
    /// with `mpm_world_set_particle_damping`; 0: none.
    pub per_particle: u32,
    /// 1: the grid damping (and the thermostat's alpha) acts on the nodal force (E49 of
    /// docs/equations.md), so that the walls act on momenta already damped; 0 (default): in
    /// the particle update (E24, E48).
    pub grid_on_force: u32,
    /// How many of `zones` are used, 0..=`MPM_DAMPING_ZONES`.
    pub zone_count: u32,
    /// Zones of space where the nodes are damped (E50-E51 of docs/equations.md), each adding
    /// its rate.
    pub zones: [MpmDampingZone; MPM_DAMPING_ZONES],
}

/// Most zones an `MpmDamping` holds.
pub const MPM_DAMPING_ZONES: usize = 4;

const _: () = assert!(MPM_DAMPING_ZONES == kernel::DAMPING_ZONES);

/// How many schedules the tractions may follow (`MpmEffects::traction_schedules`).
pub const MPM_TRACTION_SCHEDULES: usize = 4;

const _: () = assert!(MPM_TRACTION_SCHEDULES == kernel::TRACTION_SCHEDULES);

/// A box of space where the grid damps (`mpm_gimp::DampingZone`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmDampingZone {
    /// The box's lowest corner, m (z not read in 2D).
    pub min: MpmVec3,
    /// The box's highest corner, m, above `min` on every axis the world has.
    pub max: MpmVec3,
    /// Rate, 1/s (finite, >= 0): uniform in the box, or its value on face `ramp_face`.
    pub rate: mpm_real,
    /// 1: the rate rises as the square of the distance from the box's face opposite
    /// `ramp_face`, from 0 there to `rate` on `ramp_face` (an absorbing layer); 0: uniform.
    pub ramped: u32,
    /// `MpmFace` the rate rises toward (read when `ramped` is 1; an axis the world has).
    pub ramp_face: MpmFaceValue,
}

/// The condition of a transported scalar on one face (`mpm_gimp::ScalarBoundary`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmScalarBoundary {
    /// `MpmScalarBoundaryKind`; default `MPM_SCALAR_BOUNDARY_KIND_INSULATED`.
    pub kind: MpmScalarBoundaryKindValue,
    /// The fixed value or the inflow per area, finite on the faces the dimension has (the z
    /// faces of a 2D world are not read); not read for an insulated face.
    pub value: mpm_real,
}

/// A transported scalar field, heat conduction or diffusion (`mpm_gimp::Transport`): its
/// face conditions and whether particles carry a source.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmTransport {
    /// 1: the field is declared; 0: none (the other fields are then ignored).
    pub declared: u32,
    /// Condition of each face, indexed by `MpmFace`.
    pub faces: [MpmScalarBoundary; 6],
    /// 1: reserve a per-particle source column (W/m^3 for heat, 1/s for the concentration
    /// potential), set with `mpm_world_set_particle_sources`; 0: none.
    pub sources: u32,
}

/// What a scene declares beyond the momentum equation (`mpm_gimp::Effects`). An effect that is
/// not declared reserves no memory and costs nothing in a step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MpmEffects {
    /// Damping; default not declared.
    pub damping: MpmDamping,
    /// 1: reserve a per-particle external force column, N (per unit thickness in plane strain,
    /// per radian when axisymmetric), set with `mpm_world_set_particle_forces`; 0 (default):
    /// none.
    pub particle_forces: u32,
    /// Most tractions the world holds (`mpm_world_add_tractions`), at most 2^24; default 0.
    pub traction_capacity: u32,
    /// A uniform body force per unit mass besides gravity, m/s^2, times
    /// `body_force_scale(t)`; not counted in the potential energy. Default (0, 0, 0).
    pub body_force: MpmVec3,
    /// Time factor of `body_force` and `body_force_gradient`; no point (default) is a factor
    /// of 0.
    pub body_force_scale: MpmSchedule,
    /// The body force's change with position, 1/s^2, by rows: `b(x, t) = (body_force + G x)
    /// body_force_scale(t)` at each node's position `x` (m; `mpm_gimp::Effects::body_force_gradient`:
    /// a rotating frame's centrifugal force, a varying gravity). Default zero (nothing is
    /// computed); entries past the world's axes are ignored.
    pub body_force_gradient: [MpmVec3; 3],
    /// Time factors of the tractions (`mpm_gimp::Effects::traction_schedules`): each traction
    /// follows one, the first unless `mpm_world_set_traction_schedule` chose another. The
    /// default is the constant 1 for all; no point means a factor of 0.
    pub traction_schedules: [MpmSchedule; MPM_TRACTION_SCHEDULES],
    /// Heat conduction: a temperature column (K, set with `mpm_world_set_particle_scalar`,
    /// starting at 0) conducted with each material's `conductivity` and `heat_capacity`.
    /// Default not declared.
    pub heat: MpmTransport,
    /// Diffusion: a concentration-potential column (c / c_sat, starting at 0) diffused with
    /// each material's `diffusivity`. Default not declared.
    pub diffusion: MpmTransport,
    /// 1: reserve the plastic history column the plastic models need
    /// (`mpm_gimp::Effects::plasticity`); 0 (default): none.
    pub plasticity: u32,
    /// Most colliders the world holds (`mpm_world_add_collider`), at most 4096; default 0.
    pub collider_capacity: u32,
    /// Most distance-field samples the world holds (`mpm_world_add_distance_field`), at most
    /// 2^26; default 0.
    pub sdf_capacity: u32,
}

/// Everything that fixes a world's size and method: the C form of `mpm_gimp::WorldDef`, whose
/// documentation gives each field's unit, range and the reason for its default. Get one from
/// `mpm_world_def_default()` and change the fields you need.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmWorldDef {
    /// Default `MPM_DIMENSION_PLANE2D`.
    pub dimension: MpmDimensionValue,
    /// Lowest corner of the grid, m (axisymmetric: x = -margin * cell_size, see
    /// `MPM_DIMENSION_AXISYMMETRIC2D`). Default (0, 0, 0).
    pub origin: MpmVec3,
    /// Cell edge length h, m, > 0. Default 0.01.
    pub cell_size: mpm_real,
    /// Cells along x, y, z (z ignored in 2D). Default 100 x 100 x 1.
    pub cells: [u32; 3],
    /// Most particles the world holds. Default 65536.
    pub particle_capacity: u32,
    /// Most materials the world holds. Default 8.
    pub material_capacity: u32,
    /// Default `MPM_SHAPE_GIMP`.
    pub shape: MpmShapeValue,
    /// Particles per cell per axis (uGIMP particle size, fill spacing), 1..=8. Default 2.
    pub particles_per_cell: u32,
    /// FLIP fraction beta in [0, 1]. Default 0.99.
    pub flip_beta: mpm_real,
    /// PIC share as a rate, 1/s, finite and >= 0: a substep of length dt blends with FLIP
    /// fraction `flip_beta * exp(-pic_rate * dt)`. Default 0.
    pub pic_rate: mpm_real,
    /// Default `MPM_TRANSFER_FLIP`.
    pub transfer: MpmTransferValue,
    /// Default `MPM_UPDATE_ORDER_MUSL`.
    pub update_order: MpmUpdateOrderValue,
    /// Gravity, m/s^2. Default (0, -9.81, 0).
    pub gravity: MpmVec3,
    /// Boundary of each face, indexed by `MpmFace`. Default all `MPM_BOUNDARY_SLIP`.
    pub faces: [MpmBoundaryValue; 6],
    /// Coulomb friction coefficient of each slip face, >= 0. Default 0.
    pub wall_friction: [mpm_real; 6],
    /// Velocity of each face's wall along its plane, m/s (a stick face moves the material on
    /// it so; a slip face's friction acts relative to it). Default zero.
    pub wall_velocity: [MpmVec3; 6],
    /// Terms of exp(grad v dt), 1..=8. Default 2.
    pub exp_terms: u32,
    /// Courant number in (0, 1] of the fastest wave and particle, and of a collider near the
    /// material (at most this many cells a substep). Default 0.5.
    pub cfl: mpm_real,
    /// Most substeps one `mpm_world_step` call may take, 1..=1048576; a dt that needs more is
    /// refused with `MPM_STATUS_SUBSTEP_LIMIT` (nothing changes), so a call costs at most this
    /// many substeps. Default 1000.
    pub max_substeps: u32,
    /// Runaway bound on the volume ratio J = det F, > 1 (`INFINITY`: none): a particle whose J
    /// leaves [1 / max_volume_ratio, max_volume_ratio] in a step is frozen and counted in
    /// `MpmStepReport::runaway`. Default 100.
    pub max_volume_ratio: mpm_real,
    /// The most workers a task system may step the world on (`mpm_world_step_tasks`),
    /// 1..=256: the world's memory holds the parallel step's scratch for that many. Default 1.
    pub workers: u32,
    /// The optional effects. Default: none declared.
    pub effects: MpmEffects,
    /// Set by `mpm_world_def_default`; do not change.
    pub internal_cookie: u32,
}

/// A material: the C form of `mpm_gimp::MaterialDef`. Get one from
/// `mpm_material_def_default()`.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmMaterialDef {
    /// Default `MPM_MATERIAL_MODEL_NEO_HOOKEAN`.
    pub model: MpmMaterialModelValue,
    /// Young's modulus E, Pa, > 0. Default 1e6.
    pub youngs_modulus: mpm_real,
    /// Poisson's ratio in (-1, 0.5). Default 0.3.
    pub poisson_ratio: mpm_real,
    /// Initial density, kg/m^3, > 0. Default 1000.
    pub density: mpm_real,
    /// Specific heat capacity C_p, J/(kg K), > 0 (read by heat conduction only). Default 1000.
    pub heat_capacity: mpm_real,
    /// Thermal conductivity k, W/(m K), >= 0 (heat conduction only). Default 0.
    pub conductivity: mpm_real,
    /// Diffusivity D of the concentration potential, m^2/s, >= 0 (diffusion only). Default 0.
    pub diffusivity: mpm_real,
    /// Linear thermal expansion coefficient alpha, 1/K, finite (heat conduction only): the
    /// material is free of stress under the stretch 1 + alpha (T - T_0) per axis, T the grid
    /// temperature at the particle (`MpmParticlesView::grid_temperature`). Default 0.
    pub thermal_expansion: mpm_real,
    /// Stress-free temperature T_0 of the thermal expansion, K, finite. Default 0.
    pub reference_temperature: mpm_real,
    /// Linear swelling coefficient beta, strain per unit concentration potential, finite
    /// (diffusion only): the stress-free stretch gains beta (c - c_0) per axis, c the grid
    /// concentration potential at the particle. Default 0.
    pub swelling: mpm_real,
    /// Stress-free concentration potential c_0 of the swelling, finite. Default 0.
    pub reference_concentration: mpm_real,
    /// Dynamic viscosity eta, Pa s, >= 0: Newtonian stress added to any model's. Default 0.
    pub viscosity: mpm_real,
    /// Bulk viscosity zeta, Pa s, >= 0: the stress `zeta tr(sym grad v) I` added to any
    /// model's, which damps sound (a fluid's acoustic modes). Default 0.
    pub bulk_viscosity: mpm_real,
    /// Rate at which the fluid model relaxes a crowd, 1/s, >= 0: where its particles fill more
    /// than the space around them, their volume ratio shrinks toward it (E97). Default 20;
    /// 0 turns it off. Other models ignore it.
    pub volume_relaxation: mpm_real,
    /// Bulk modulus K of the fluid model, Pa, > 0. Default 1e5.
    pub bulk_modulus: mpm_real,
    /// Tait exponent gamma of the fluid model, >= 1. Default 7.
    pub pressure_exponent: mpm_real,
    /// Initial uniaxial yield stress of the von Mises model, Pa, > 0. Default 1e4.
    pub yield_stress: mpm_real,
    /// Linear isotropic hardening modulus of the von Mises model, Pa, >= 0. Default 0.
    pub hardening_modulus: mpm_real,
    /// Friction angle of the Drucker-Prager model, degrees, in [0, 90). Default 30.
    pub friction_angle: mpm_real,
    /// How the Drucker-Prager cone is fitted to the friction angle (an `MpmFrictionFit`).
    /// Default `MPM_FRICTION_FIT_COMPRESSION`.
    pub friction_fit: MpmFrictionFitValue,
    /// Cohesion of the Drucker-Prager model, Pa, >= 0 (> 0 needs a friction angle > 0).
    /// Default 0.
    pub cohesion: mpm_real,
    /// Critical compression theta_c of the snow model, in (0, 1). Default 0.025.
    pub critical_compression: mpm_real,
    /// Critical stretch theta_s of the snow model, > 0. Default 0.0075.
    pub critical_stretch: mpm_real,
    /// Hardening coefficient xi of the snow model, in [0, `MPM_MAX_HARDENING_COEFFICIENT`]
    /// (100; past it the model's hardening gains energy without bound). Default 10.
    pub hardening_coefficient: mpm_real,
    /// Set by `mpm_material_def_default`; do not change.
    pub internal_cookie: u32,
}

/// The cookie of a world definition of this precision ("MPMW" and the size of `mpm_real`).
const WORLD_COOKIE: u32 = u32::from_le_bytes(*b"MPMW") ^ (core::mem::size_of::<mpm_real>() as u32);
/// The cookie of a material definition of this precision.
const MATERIAL_COOKIE: u32 =
    u32::from_le_bytes(*b"MPMM") ^ (core::mem::size_of::<mpm_real>() as u32);

pub(crate) fn vec3(v: MpmVec3) -> kernel::Vec3 {
    kernel::Vec3::new(v.x, v.y, v.z)
}

pub(crate) fn c_vec3(v: kernel::Vec3) -> MpmVec3 {
    MpmVec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// The C definition of a Rust one (with the cookie).
pub(crate) fn world_def_to_c(d: &WorldDef) -> MpmWorldDef {
    MpmWorldDef {
        dimension: d.dimension as u32,
        origin: c_vec3(d.origin),
        cell_size: d.cell_size,
        cells: d.cells,
        particle_capacity: d.particle_capacity,
        material_capacity: d.material_capacity,
        shape: d.shape as u32,
        particles_per_cell: d.particles_per_cell,
        flip_beta: d.flip_beta,
        pic_rate: d.pic_rate,
        transfer: d.transfer.code(),
        update_order: d.update_order as u32,
        gravity: c_vec3(d.gravity),
        faces: d.faces.map(|f| f as u32),
        wall_friction: d.wall_friction,
        wall_velocity: d.wall_velocity.map(c_vec3),
        exp_terms: d.exp_terms,
        cfl: d.cfl,
        max_substeps: d.max_substeps,
        max_volume_ratio: d.max_volume_ratio,
        workers: d.workers,
        effects: effects_to_c(&d.effects),
        internal_cookie: WORLD_COOKIE,
    }
}

fn schedule_to_c(s: &Schedule) -> MpmSchedule {
    MpmSchedule {
        points: s.points,
        times: s.times,
        values: s.values,
    }
}

fn schedule_from_c(s: &MpmSchedule) -> Schedule {
    Schedule {
        points: s.points,
        times: s.times,
        values: s.values,
    }
}

/// The C form of an optional transport; what is not declared is zero, and so is the value of
/// an insulated face.
fn transport_to_c(t: &Option<Transport>) -> MpmTransport {
    let face = |f: &ScalarBoundary| match *f {
        ScalarBoundary::Insulated => MpmScalarBoundary {
            kind: MpmScalarBoundaryKind::Insulated as u32,
            value: 0.0,
        },
        ScalarBoundary::Fixed(value) => MpmScalarBoundary {
            kind: MpmScalarBoundaryKind::Fixed as u32,
            value,
        },
        ScalarBoundary::Flux(value) => MpmScalarBoundary {
            kind: MpmScalarBoundaryKind::Flux as u32,
            value,
        },
    };
    match t {
        Some(t) => MpmTransport {
            declared: 1,
            faces: core::array::from_fn(|k| face(&t.faces[k])),
            sources: t.sources as u32,
        },
        None => MpmTransport {
            declared: 0,
            faces: [face(&ScalarBoundary::Insulated); 6],
            sources: 0,
        },
    }
}

/// The C effects of Rust ones; what is not declared is zero.
fn effects_to_c(e: &Effects) -> MpmEffects {
    let zero = schedule_to_c(&Schedule::ZERO);
    let feedback = |f: Option<Feedback>| match f {
        Some(f) => MpmFeedback {
            declared: 1,
            gain: f.gain,
            target: schedule_to_c(&f.target),
            max_alpha: f.max_alpha,
        },
        None => MpmFeedback {
            declared: 0,
            gain: 0.0,
            target: zero,
            max_alpha: 0.0,
        },
    };
    let damping = match e.damping {
        Some(d) => MpmDamping {
            declared: 1,
            grid: schedule_to_c(&d.grid),
            particle: schedule_to_c(&d.particle),
            feedback: feedback(d.feedback),
            per_particle: d.per_particle as u32,
            grid_on_force: d.grid_on_force as u32,
            zone_count: d.zone_count,
            zones: d.zones.map(|z| zone_to_c(&z)),
        },
        None => MpmDamping {
            declared: 0,
            grid: zero,
            particle: zero,
            feedback: feedback(None),
            per_particle: 0,
            grid_on_force: 0,
            zone_count: 0,
            zones: [zone_to_c(&DampingZone::NONE); MPM_DAMPING_ZONES],
        },
    };
    MpmEffects {
        damping,
        particle_forces: e.particle_forces as u32,
        traction_capacity: e.traction_capacity,
        body_force: c_vec3(e.body_force),
        body_force_scale: schedule_to_c(&e.body_force_scale),
        body_force_gradient: e.body_force_gradient.map(c_vec3),
        traction_schedules: e.traction_schedules.each_ref().map(schedule_to_c),
        heat: transport_to_c(&e.heat),
        diffusion: transport_to_c(&e.diffusion),
        plasticity: e.plasticity as u32,
        collider_capacity: e.collider_capacity,
        sdf_capacity: e.sdf_capacity,
    }
}

/// The C zone of a Rust one.
fn zone_to_c(z: &DampingZone) -> MpmDampingZone {
    MpmDampingZone {
        min: c_vec3(z.min),
        max: c_vec3(z.max),
        rate: z.rate,
        ramped: z.ramp.is_some() as u32,
        ramp_face: z.ramp.map_or(0, |f| f as u32),
    }
}

/// The Rust zone of a C one: the flag and, when ramped, the face checked.
fn zone_from_c(z: &MpmDampingZone) -> Result<DampingZone, MpmStatus> {
    let ramp = if flag(z.ramped)? {
        Some(face_from_c(z.ramp_face)?)
    } else {
        None
    };
    Ok(DampingZone {
        min: vec3(z.min),
        max: vec3(z.max),
        rate: z.rate,
        ramp,
    })
}

/// A flag field: 0 or 1, anything else `InvalidEnum`.
fn flag(v: u32) -> Result<bool, MpmStatus> {
    match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(MpmStatus::InvalidEnum),
    }
}

/// The Rust transport of a C one: the flags and each face's kind checked when declared, nothing
/// read when not (the values are the kernel's to check).
fn transport_from_c(t: &MpmTransport) -> Result<Option<Transport>, MpmStatus> {
    if !flag(t.declared)? {
        return Ok(None);
    }
    let mut faces = [ScalarBoundary::Insulated; 6];
    for (f, c) in faces.iter_mut().zip(t.faces.iter()) {
        *f = match c.kind {
            0 => ScalarBoundary::Insulated,
            1 => ScalarBoundary::Fixed(c.value),
            2 => ScalarBoundary::Flux(c.value),
            _ => return Err(MpmStatus::InvalidEnum),
        };
    }
    Ok(Some(Transport {
        faces,
        sources: flag(t.sources)?,
    }))
}

/// The Rust effects of C ones: every flag checked, the fields of what is not declared ignored.
/// (The values are the kernel's to check.)
fn effects_from_c(e: &MpmEffects) -> Result<Effects, MpmStatus> {
    let d = &e.damping;
    let damping = if flag(d.declared)? {
        let f = &d.feedback;
        let feedback = if flag(f.declared)? {
            Some(Feedback {
                gain: f.gain,
                target: schedule_from_c(&f.target),
                max_alpha: f.max_alpha,
            })
        } else {
            None
        };
        Some(Damping {
            grid: schedule_from_c(&d.grid),
            particle: schedule_from_c(&d.particle),
            feedback,
            per_particle: flag(d.per_particle)?,
            grid_on_force: flag(d.grid_on_force)?,
            // Only the zones in use are read (and checked); a count past the room is the
            // kernel's to refuse.
            zones: {
                let mut zones = [DampingZone::NONE; MPM_DAMPING_ZONES];
                let used = (d.zone_count as usize).min(MPM_DAMPING_ZONES);
                for (z, c) in zones.iter_mut().zip(&d.zones[..used]) {
                    *z = zone_from_c(c)?;
                }
                zones
            },
            zone_count: d.zone_count,
        })
    } else {
        None
    };
    Ok(Effects {
        damping,
        particle_forces: flag(e.particle_forces)?,
        traction_capacity: e.traction_capacity,
        collider_capacity: e.collider_capacity,
        sdf_capacity: e.sdf_capacity,
        body_force: vec3(e.body_force),
        body_force_scale: schedule_from_c(&e.body_force_scale),
        body_force_gradient: e.body_force_gradient.map(vec3),
        traction_schedules: e.traction_schedules.each_ref().map(schedule_from_c),
        heat: transport_from_c(&e.heat)?,
        diffusion: transport_from_c(&e.diffusion)?,
        plasticity: flag(e.plasticity)?,
    })
}

/// The field numbered `v` (`MpmScalarField`), or `InvalidEnum`.
pub(crate) fn scalar_field_from_c(v: MpmScalarFieldValue) -> Result<ScalarField, MpmStatus> {
    Ok(match v {
        0 => ScalarField::Temperature,
        1 => ScalarField::Concentration,
        _ => return Err(MpmStatus::InvalidEnum),
    })
}

/// The face numbered `v` (`MpmFace`), or `InvalidEnum`.
pub(crate) fn face_from_c(v: MpmFaceValue) -> Result<Face, MpmStatus> {
    Face::from_code(v).ok_or(MpmStatus::InvalidEnum)
}

/// The Rust definition of a C one: the cookie and every enum value checked.
pub(crate) fn world_def_from_c(d: &MpmWorldDef) -> Result<WorldDef, MpmStatus> {
    if d.internal_cookie != WORLD_COOKIE {
        return Err(MpmStatus::DefNotFromDefault);
    }
    let enum_value = MpmStatus::InvalidEnum;
    let dimension = Dimension::from_code(d.dimension).ok_or(enum_value)?;
    let shape = ShapeFunction::from_code(d.shape).ok_or(enum_value)?;
    let transfer = Transfer::from_code(d.transfer).ok_or(enum_value)?;
    let update_order = UpdateOrder::from_code(d.update_order).ok_or(enum_value)?;
    let mut faces = [Boundary::Slip; 6];
    for (f, &v) in faces.iter_mut().zip(d.faces.iter()) {
        *f = Boundary::from_code(v).ok_or(enum_value)?;
    }
    let effects = effects_from_c(&d.effects)?;
    Ok(WorldDef {
        dimension,
        origin: vec3(d.origin),
        cell_size: d.cell_size,
        cells: d.cells,
        particle_capacity: d.particle_capacity,
        material_capacity: d.material_capacity,
        shape,
        particles_per_cell: d.particles_per_cell,
        flip_beta: d.flip_beta,
        pic_rate: d.pic_rate,
        transfer,
        update_order,
        gravity: vec3(d.gravity),
        faces,
        wall_friction: d.wall_friction,
        wall_velocity: d.wall_velocity.map(vec3),
        exp_terms: d.exp_terms,
        cfl: d.cfl,
        max_substeps: d.max_substeps,
        max_volume_ratio: d.max_volume_ratio,
        workers: d.workers,
        effects,
    })
}

/// The Rust material of a C one: the cookie and the model checked.
pub(crate) fn material_def_from_c(d: &MpmMaterialDef) -> Result<MaterialDef, MpmStatus> {
    if d.internal_cookie != MATERIAL_COOKIE {
        return Err(MpmStatus::DefNotFromDefault);
    }
    let model = MaterialModel::from_code(d.model).ok_or(MpmStatus::InvalidEnum)?;
    let friction_fit = FrictionFit::from_code(d.friction_fit).ok_or(MpmStatus::InvalidEnum)?;
    Ok(MaterialDef {
        friction_fit,
        model,
        youngs_modulus: d.youngs_modulus,
        poisson_ratio: d.poisson_ratio,
        density: d.density,
        heat_capacity: d.heat_capacity,
        conductivity: d.conductivity,
        diffusivity: d.diffusivity,
        thermal_expansion: d.thermal_expansion,
        reference_temperature: d.reference_temperature,
        swelling: d.swelling,
        reference_concentration: d.reference_concentration,
        viscosity: d.viscosity,
        bulk_viscosity: d.bulk_viscosity,
        volume_relaxation: d.volume_relaxation,
        bulk_modulus: d.bulk_modulus,
        pressure_exponent: d.pressure_exponent,
        yield_stress: d.yield_stress,
        hardening_modulus: d.hardening_modulus,
        friction_angle: d.friction_angle,
        cohesion: d.cohesion,
        critical_compression: d.critical_compression,
        critical_stretch: d.critical_stretch,
        hardening_coefficient: d.hardening_coefficient,
    })
}

/// The documented world defaults (`mpm_gimp::WorldDef::DEFAULT`), with the cookie init checks.
/// The header maps this name to a symbol of the header's precision, so code compiled for one
/// precision does not link against the library of the other.
#[cfg(not(feature = "f64"))]
#[no_mangle]
pub extern "C" fn mpm_world_def_default_f32() -> MpmWorldDef {
    world_def_to_c(&WorldDef::DEFAULT)
}

/// The documented world defaults (`mpm_gimp::WorldDef::DEFAULT`), with the cookie init checks.
/// The header maps this name to a symbol of the header's precision, so code compiled for one
/// precision does not link against the library of the other.
#[cfg(feature = "f64")]
#[no_mangle]
pub extern "C" fn mpm_world_def_default_f64() -> MpmWorldDef {
    world_def_to_c(&WorldDef::DEFAULT)
}

/// The documented material defaults (`mpm_gimp::MaterialDef::DEFAULT`), with the cookie
/// `mpm_world_add_material` checks. Precision-specific symbol, as `mpm_world_def_default`.
#[cfg(not(feature = "f64"))]
#[no_mangle]
pub extern "C" fn mpm_material_def_default_f32() -> MpmMaterialDef {
    material_def_default()
}

/// The documented material defaults (`mpm_gimp::MaterialDef::DEFAULT`), with the cookie
/// `mpm_world_add_material` checks. Precision-specific symbol, as `mpm_world_def_default`.
#[cfg(feature = "f64")]
#[no_mangle]
pub extern "C" fn mpm_material_def_default_f64() -> MpmMaterialDef {
    material_def_default()
}

fn material_def_default() -> MpmMaterialDef {
    material_def_to_c(&MaterialDef::DEFAULT)
}

/// The C material of a Rust one (with the cookie).
fn material_def_to_c(d: &MaterialDef) -> MpmMaterialDef {
    MpmMaterialDef {
        model: d.model as u32,
        youngs_modulus: d.youngs_modulus,
        poisson_ratio: d.poisson_ratio,
        density: d.density,
        heat_capacity: d.heat_capacity,
        conductivity: d.conductivity,
        diffusivity: d.diffusivity,
        thermal_expansion: d.thermal_expansion,
        reference_temperature: d.reference_temperature,
        swelling: d.swelling,
        reference_concentration: d.reference_concentration,
        viscosity: d.viscosity,
        bulk_viscosity: d.bulk_viscosity,
        volume_relaxation: d.volume_relaxation,
        bulk_modulus: d.bulk_modulus,
        pressure_exponent: d.pressure_exponent,
        yield_stress: d.yield_stress,
        hardening_modulus: d.hardening_modulus,
        friction_angle: d.friction_angle,
        friction_fit: d.friction_fit as u32,
        cohesion: d.cohesion,
        critical_compression: d.critical_compression,
        critical_stretch: d.critical_stretch,
        hardening_coefficient: d.hardening_coefficient,
        internal_cookie: MATERIAL_COOKIE,
    }
}
