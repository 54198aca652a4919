//! The error type of every fallible call. Each variant has a stable number (the C interface's
//! `MpmStatus` uses the same values) and a static message.

use core::fmt;

/// Why a call failed. A call that returns an error has changed nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Error {
    /// The buffer is smaller than [`crate::memory_requirements`] says.
    BufferTooSmall = 1,
    /// The buffer does not start at the alignment [`crate::memory_requirements`] says.
    BufferMisaligned = 2,
    /// The buffer does not hold a world of this build (wrong magic, version, precision or size).
    NotAWorld = 3,
    /// The definition declares an effect (the axisymmetric form included) and the build lacks
    /// the `effects` feature.
    Unsupported = 4,
    /// Cell size not finite or <= 0.
    InvalidCellSize = 5,
    /// Too few cells on an axis for the shape function's margin, or too many nodes to index.
    InvalidCellCount = 6,
    /// Particle or material capacity is zero or too large to index.
    InvalidCapacity = 7,
    /// FLIP fraction outside [0, 1], or a PIC rate negative or not finite.
    InvalidFlipBeta = 8,
    /// Courant number outside (0, 1].
    InvalidCfl = 9,
    /// Series terms for `exp(grad v dt)` outside 1..=8.
    InvalidExpTerms = 10,
    /// Particles per cell outside 1..=8.
    InvalidParticlesPerCell = 11,
    /// Origin or gravity not finite (on the axes the dimension uses).
    NonFiniteDefinition = 12,
    /// A material parameter out of its documented range ([`crate::MaterialDef`]: Young's
    /// modulus <= 0, Poisson's ratio outside (-1, 0.5), density <= 0, heat capacity <= 0,
    /// conductivity or diffusivity < 0, not finite, ...), or values each in range whose derived
    /// moduli (the Lame parameters, the wave speed) overflow: Young's modulus near the largest
    /// Real, a density near the smallest.
    InvalidMaterial = 13,
    /// The material table is full.
    MaterialCapacityExceeded = 14,
    /// The particles do not fit in the remaining capacity (none was added).
    ParticleCapacityExceeded = 15,
    /// A material id that names no material.
    UnknownMaterial = 16,
    /// A position, velocity, mass, volume, or a value set on particles (force, temperature,
    /// concentration, source) that is NaN or infinite.
    NonFiniteInput = 17,
    /// A mass or volume <= 0.
    NonPositiveMassOrVolume = 18,
    /// A position outside the grid or inside the boundary margin the shape function needs.
    PositionOutsideDomain = 19,
    /// Input arrays of different lengths.
    LengthMismatch = 20,
    /// A time step that is <= 0 or not finite.
    InvalidTimeStep = 21,
    /// A box inverted on an axis (min > max), a radius not finite or <= 0, or a disk in 3D or
    /// a sphere in 2D. (Non-finite corners, centres or velocities are
    /// [`Error::NonFiniteInput`]; a region that holds no lattice site adds no particle.)
    InvalidRegion = 22,
    /// An effect parameter out of range: a schedule with more than 8 points, times that do not
    /// increase or values not finite; a damping value < 0; a thermostat gain or bound <= 0; a
    /// body force not finite; a traction not finite or on a face the dimension lacks; a
    /// transport's fixed or flux face value not finite.
    InvalidEffect = 23,
    /// The call needs an effect the world's definition does not declare.
    EffectNotDeclared = 24,
    /// A particle id at or past the particle count.
    UnknownParticle = 25,
    /// The tractions do not fit in the remaining traction capacity (none was added).
    TractionCapacityExceeded = 26,
    /// An axisymmetric world whose lower r face is open, or whose wall plane there is not the
    /// axis `r = 0` (set `origin.x = -margin_cells * cell_size`).
    InvalidAxis = 27,
    /// The time step needs more substeps than the definition's
    /// [`max_substeps`](crate::WorldDef::max_substeps) allows (nothing was stepped): take a
    /// smaller `dt` per call or raise the limit.
    SubstepLimit = 28,
    /// The buffer holds a world of this build whose state is not valid ([`crate::World::open`]
    /// checks it): a time, minimum particle mass or thermostat alpha not finite or out of
    /// range; a particle with a mass or volume not finite or <= 0, an unknown status or
    /// material; a particle with a position outside the admissible region, a low part of the
    /// position past one unit in its last place, a value not finite, a speed or damping rate
    /// past what the world resolves ([`crate::Resolvable`]), a plastic history out of its
    /// model's range (`J_p <= 0` or, active, hardened past the resolved wave speed, for snow;
    /// < 0 for von Mises and Drucker-Prager; not 0 for a model without one) or an inverted F;
    /// a material or traction record out of range. From [`crate::World::set_particle_state`]
    /// and [`crate::World::add_particles_with_state`]: an unknown status, or a low part of a
    /// position past one unit in the last place of the position.
    InvalidState = 29,
    /// A limit of the definition out of range: [`max_substeps`](crate::WorldDef::max_substeps)
    /// outside `1..=MAX_SUBSTEPS`, [`max_volume_ratio`](crate::WorldDef::max_volume_ratio)
    /// not > 1, or [`workers`](crate::WorldDef::workers) outside `1..=MAX_WORKERS` or fewer
    /// than the task system a step is given has ([`crate::World::step_with_tasks`]).
    InvalidLimit = 30,
    /// A displacement gradient ([`crate::World::set_displacement_gradient`]) not finite,
    /// inverted (`det F <= 0`), with `det F` outside the definition's
    /// [`max_volume_ratio`](crate::WorldDef::max_volume_ratio) band, or whose stress is not
    /// finite; a state ([`crate::World::set_particle_state`]) whose `H`, hoop stretch or
    /// stress is not finite, whose F inverts or hoop stretch is <= -1, or whose plastic
    /// history is out of its model's range.
    InvalidDeformation = 31,
    /// A transfer that does not go with the shape function or the dimension:
    /// [`Transfer::Mls`](crate::Transfer::Mls) needs the quadratic or cubic B-spline, in 2D or
    /// 3D; [`Transfer::FlipMomentum`](crate::Transfer::FlipMomentum) is not axisymmetric;
    /// XPIC's order is in `1..=`[`crate::MAX_TRANSFER_ORDER`], FMPM's in
    /// `1..=`[`crate::MAX_FMPM_ORDER`], and FMPM(2) does not go with USL.
    InvalidTransfer = 32,
    /// A traction id past the table or removed ([`crate::World::remove_tractions`]).
    UnknownTraction = 33,
    /// A value whose own stable time step would be shorter than
    /// [`MIN_STABLE_DT`](crate::MIN_STABLE_DT) (see [`crate::Resolvable`]): a material's wave
    /// speed, thermal diffusivity, diffusivity or kinematic viscosity, the definition's damping
    /// rates (summed), or a per-particle damping rate. Nothing was added or set.
    StableStepTooShort = 34,
    /// [`crate::World::add_collider`] past [`crate::Effects::collider_capacity`].
    ColliderCapacityExceeded = 35,
    /// A collider id at or past the number of colliders.
    UnknownCollider = 36,
    /// A periodic face ([`crate::Boundary::Periodic`]) whose opposite face is not periodic,
    /// on the radial axis of an axisymmetric world, with a wall friction or velocity, or with
    /// a heat or diffusion condition other than insulated.
    InvalidBoundary = 37,
}

impl Error {
    /// A static, human-readable description.
    pub const fn as_str(self) -> &'static str {
        match core::str::from_utf8(self.as_cstr().to_bytes()) {
            Ok(s) => s,
            Err(_) => "",
        }
    }

    /// The description as a NUL-terminated C string (what the C interface hands out).
    pub const fn as_cstr(self) -> &'static core::ffi::CStr {
        match self {
            Error::BufferTooSmall => c"buffer smaller than the memory requirement",
            Error::BufferMisaligned => c"buffer not aligned as the memory requirement says",
            Error::NotAWorld => c"buffer does not hold a world of this build",
            Error::Unsupported => c"dimension or effect not supported by this build",
            Error::InvalidCellSize => c"cell size must be finite and > 0",
            Error::InvalidCellCount => c"too few cells for the shape margin, or too many nodes",
            Error::InvalidCapacity => c"capacity must be > 0 and small enough to index",
            Error::InvalidFlipBeta => c"FLIP fraction beta must be in [0, 1] and the PIC rate finite and >= 0",
            Error::InvalidCfl => c"Courant number must be in (0, 1]",
            Error::InvalidExpTerms => c"exp(grad v dt) series terms must be in 1..=8",
            Error::InvalidParticlesPerCell => c"particles per cell must be in 1..=8",
            Error::NonFiniteDefinition => c"origin and gravity must be finite",
            Error::InvalidMaterial => {
                c"material parameter out of its documented range, or derived moduli that overflow"
            }
            Error::MaterialCapacityExceeded => c"material table is full",
            Error::ParticleCapacityExceeded => c"particles do not fit in the remaining capacity",
            Error::UnknownMaterial => c"material id names no material",
            Error::NonFiniteInput => c"input value not finite (position, velocity, mass, volume, force, scalar)",
            Error::NonPositiveMassOrVolume => c"mass and volume must be > 0",
            Error::PositionOutsideDomain => {
                c"position outside the grid or inside its boundary margin"
            }
            Error::LengthMismatch => c"input arrays differ in length",
            Error::InvalidTimeStep => c"time step must be finite and > 0",
            Error::InvalidRegion => {
                c"region inverted, radius not finite or <= 0, or of the other dimension"
            }
            Error::InvalidEffect => c"effect parameter out of range or not finite",
            Error::EffectNotDeclared => c"the world's definition does not declare this effect",
            Error::UnknownParticle => c"particle id names no particle",
            Error::TractionCapacityExceeded => {
                c"tractions do not fit in the remaining traction capacity"
            }
            Error::InvalidAxis => {
                c"axisymmetric: the lower r face must be a wall whose plane is the axis r = 0"
            }
            Error::SubstepLimit => {
                c"time step needs more substeps than the definition's max_substeps"
            }
            Error::InvalidState => {
                c"world state invalid: a value not finite or out of range, or an unknown status or material"
            }
            Error::InvalidLimit => {
                c"max_substeps must be in 1..=2^20, max_volume_ratio > 1 and workers in 1..=256 (no fewer than the task system's)"
            }
            Error::InvalidDeformation => {
                c"deformation gradient, stress or plastic history not finite or out of range (F inverted, volume ratio past max_volume_ratio)"
            }
            Error::UnknownTraction => c"traction id past the table or removed",
            Error::StableStepTooShort => {
                c"a wave speed, diffusivity or damping rate needs a stable step below 1e-15 s"
            }
            Error::InvalidTransfer => {
                c"transfer does not go with the shape function or dimension (MLS needs a B-spline, 2D or 3D; FLIP momentum is not axisymmetric), or an XPIC order outside 1..=8, FMPM outside 1..=2 or FMPM(2) with USL"
            }
            Error::ColliderCapacityExceeded => c"collider capacity exceeded",
            Error::UnknownCollider => c"collider id at or past the number of colliders",
            Error::InvalidBoundary => {
                c"periodic face without a periodic opposite face, on the radial axis, or with a wall or scalar condition"
            }
        }
    }

    /// Every variant, in numeric order (for tests and the C status table).
    pub const ALL: [Error; 37] = [
        Error::BufferTooSmall,
        Error::BufferMisaligned,
        Error::NotAWorld,
        Error::Unsupported,
        Error::InvalidCellSize,
        Error::InvalidCellCount,
        Error::InvalidCapacity,
        Error::InvalidFlipBeta,
        Error::InvalidCfl,
        Error::InvalidExpTerms,
        Error::InvalidParticlesPerCell,
        Error::NonFiniteDefinition,
        Error::InvalidMaterial,
        Error::MaterialCapacityExceeded,
        Error::ParticleCapacityExceeded,
        Error::UnknownMaterial,
        Error::NonFiniteInput,
        Error::NonPositiveMassOrVolume,
        Error::PositionOutsideDomain,
        Error::LengthMismatch,
        Error::InvalidTimeStep,
        Error::InvalidRegion,
        Error::InvalidEffect,
        Error::EffectNotDeclared,
        Error::UnknownParticle,
        Error::TractionCapacityExceeded,
        Error::InvalidAxis,
        Error::SubstepLimit,
        Error::InvalidState,
        Error::InvalidLimit,
        Error::InvalidDeformation,
        Error::InvalidTransfer,
        Error::UnknownTraction,
        Error::StableStepTooShort,
        Error::ColliderCapacityExceeded,
        Error::UnknownCollider,
        Error::InvalidBoundary,
    ];
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(feature = "std")]
extern crate std;

#[cfg(feature = "std")]
impl std::error::Error for Error {}
