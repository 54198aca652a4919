//! `MpmStatus`: the result of every fallible C call, and its static description.

use kernel::Error;

/// Result of a C call. The numbers are stable: the kernel's errors keep the numbers of
/// `mpm_gimp::Error`, and the conditions only the C interface can meet start at 64.
/// A call that returns anything but `MPM_STATUS_OK` has written nothing and changed nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum MpmStatus {
    /// Success.
    Ok = 0,
    /// The memory is smaller than `mpm_memory_requirements` says.
    BufferTooSmall = 1,
    /// The memory does not start at the alignment `mpm_memory_requirements` says.
    BufferMisaligned = 2,
    /// The memory does not hold a world of this build: wrong magic (checked first, on the
    /// first 8 bytes alone), version, precision, definition or size. (A world of this build
    /// whose state is not valid is `MPM_STATUS_INVALID_STATE`.)
    NotAWorld = 3,
    /// The definition declares an effect (the axisymmetric form included) and the build lacks
    /// the kernel's `effects` feature (this library is built with it).
    Unsupported = 4,
    /// Cell size not finite or <= 0.
    InvalidCellSize = 5,
    /// Too few cells on an axis for the shape function's margin, or too many nodes to index.
    InvalidCellCount = 6,
    /// Particle or material capacity is zero or too large to index.
    InvalidCapacity = 7,
    /// FLIP fraction outside [0, 1].
    InvalidFlipBeta = 8,
    /// Courant number outside (0, 1].
    InvalidCfl = 9,
    /// Series terms for exp(grad v dt) outside 1..=8.
    InvalidExpTerms = 10,
    /// Particles per cell outside 1..=8.
    InvalidParticlesPerCell = 11,
    /// Origin or gravity not finite (on the axes the dimension uses).
    NonFiniteDefinition = 12,
    /// A material parameter out of the range `MpmMaterialDef` documents for it (Young's modulus
    /// <= 0, Poisson's ratio outside (-1, 0.5), density <= 0, heat capacity <= 0, conductivity
    /// or diffusivity < 0, a value not finite, ...), or parameters each in range whose derived
    /// moduli overflow the real type: the Lame parameters or the wave speed of a Young's
    /// modulus near the largest real, or of a density near the smallest.
    InvalidMaterial = 13,
    /// The material table is full.
    MaterialCapacityExceeded = 14,
    /// The particles do not fit in the remaining capacity (none was added).
    ParticleCapacityExceeded = 15,
    /// A material id that names no material.
    UnknownMaterial = 16,
    /// A position, velocity, mass or volume that is NaN or infinite (or a particle force,
    /// temperature, concentration or source).
    NonFiniteInput = 17,
    /// A mass or volume <= 0.
    NonPositiveMassOrVolume = 18,
    /// A position outside the grid or inside the boundary margin the shape function needs.
    PositionOutsideDomain = 19,
    /// Input arrays of different lengths (Rust API only: C passes one count for all arrays).
    LengthMismatch = 20,
    /// A time step that is <= 0 or not finite. (A finite positive dt that needs too many
    /// substeps is `MPM_STATUS_SUBSTEP_LIMIT`.)
    InvalidTimeStep = 21,
    /// A box inverted on an axis (min > max), a radius not finite or <= 0, or a disk in 3D or
    /// a sphere in 2D. (Non-finite corners, centres or velocities are `NON_FINITE_INPUT`; a
    /// region that holds no lattice site is accepted and adds no particle.)
    InvalidRegion = 22,
    /// An effect parameter out of range: a schedule with more than 8 points, times that do not
    /// increase or values not finite; a damping value < 0 or not finite; a thermostat gain or
    /// bound <= 0; a body force not finite; a fixed or flux face value of heat or diffusion not
    /// finite; a traction not finite or on a face the dimension lacks.
    InvalidEffect = 23,
    /// The call needs an effect that the world's definition does not declare.
    EffectNotDeclared = 24,
    /// A particle id at or past the particle count (or a range of ids that reaches past it).
    UnknownParticle = 25,
    /// The tractions do not fit in the remaining traction capacity (none was added).
    TractionCapacityExceeded = 26,
    /// An axisymmetric world whose lower x (r) face is `MPM_BOUNDARY_OPEN`, or whose wall plane
    /// there is not the axis r = 0 (set `origin.x = -margin * cell_size`, see
    /// `MPM_DIMENSION_AXISYMMETRIC2D`).
    InvalidAxis = 27,
    /// `mpm_world_step`: the dt needs more substeps than the definition's `max_substeps`
    /// allows (nothing was stepped). Step with a smaller dt or raise the limit.
    SubstepLimit = 28,
    /// `mpm_world_open`: the memory holds a world of this build whose state is not valid: a
    /// time, minimum particle mass or thermostat alpha not finite or out of range; a particle
    /// with a mass or volume not finite or <= 0, an unknown status or material id; an active
    /// particle outside the grid's admissible region, with a value not finite or an inverted F;
    /// a low part of a position past one unit in its last place; a speed or per-particle
    /// damping rate past what the world resolves (MPM_STATUS_STABLE_STEP_TOO_SHORT's bounds);
    /// a plastic history out of its model's range (snow: `J_p <= 0`, or an active particle
    /// hardened past the wave speed the world resolves; von Mises, Drucker-Prager: < 0; a
    /// model without one: not 0); a material or traction record out of range. Calls on a world pointer (every other
    /// call) check only the header, in constant time. `mpm_world_set_particle_state`,
    /// `mpm_world_add_particles_with_state`: an unknown status, or a low part of a position
    /// past one unit in its last place.
    InvalidState = 29,
    /// A limit of the definition out of range: `max_substeps` outside 1..=1048576,
    /// `max_volume_ratio` not > 1, or `workers` outside 1..=256; or a task system's
    /// `worker_count` of 0 or above the definition's `workers` (`mpm_world_step_tasks`).
    InvalidLimit = 30,
    /// `mpm_world_set_displacement_gradient`: a displacement gradient not finite, inverted
    /// (`det F <= 0`), with `det F` outside the definition's `max_volume_ratio` band, or whose
    /// stress is not finite (nothing was set). `mpm_world_set_particle_state`,
    /// `mpm_world_add_particles_with_state`: an H, hoop stretch or stress not finite, an
    /// inverted F, a hoop stretch <= -1, or a plastic history out of its model's range.
    InvalidDeformation = 31,
    /// A transfer that does not go with the shape function or dimension: `MPM_TRANSFER_MLS`
    /// needs the quadratic or cubic B-spline, in 2D or 3D; `MPM_TRANSFER_FLIP_MOMENTUM` is not
    /// axisymmetric.
    InvalidTransfer = 32,
    /// A traction id past the table or removed (`mpm_world_remove_tractions`).
    UnknownTraction = 33,
    /// A value whose own stable time step would be shorter than 1e-15 s (`MPM_MIN_STABLE_DT`):
    /// a material's wave speed `c > cfl h / 1e-15` (`mpm_world_add_material`), its thermal
    /// diffusivity, diffusivity or kinematic viscosity above `cfl h^2 / (2 d 1e-15)` where it
    /// acts, the definition's damping rates summed above `cfl / 1e-15` (`mpm_world_init`,
    /// `mpm_memory_requirements`), or a per-particle damping rate above half of what that sum
    /// leaves (`mpm_world_set_particle_damping`). Nothing was added or set.
    StableStepTooShort = 34,
    /// A collider added past `MpmEffects::collider_capacity`.
    ColliderCapacityExceeded = 35,
    /// A collider id at or past the number of colliders.
    UnknownCollider = 36,
    /// A periodic face (`MPM_BOUNDARY_PERIODIC`) whose opposite face is not periodic, on the
    /// radial axis of an axisymmetric world, with a wall friction or velocity, or with a heat
    /// or diffusion condition other than insulated.
    InvalidBoundary = 37,
    /// A pointer argument that must not be NULL was NULL.
    NullPointer = 64,
    /// A definition that did not come from `mpm_world_def_default` or
    /// `mpm_material_def_default` (its cookie is missing or belongs to another precision).
    DefNotFromDefault = 65,
    /// An enum field or argument holds a value the enum does not have, or a flag field (such as
    /// `MpmDamping::declared`) holds a value other than 0 or 1.
    InvalidEnum = 66,
    /// An output buffer shorter than the data to copy.
    OutputTooSmall = 67,
    /// The library hit an internal error: a Rust panic caught at the boundary (in a build
    /// with `panic = "abort"` the process aborts instead). No panic is known to be reachable;
    /// report one as a bug. The world may be in an intermediate state.
    Internal = 68,
    /// An input array or an output pointer of the call overlaps the world's memory (its first
    /// `mpm_world_bytes` bytes; for `mpm_world_init` and `mpm_world_open`, the world they lay
    /// out or open in the memory handed in):
    /// passing a column of the particle view back as input, or copying out into the world.
    /// Nothing is read from the arrays and nothing is written.
    OverlappingMemory = 69,
    /// `mpm_world_step_tasks`: the host's task system broke the contract of
    /// `MpmEnqueueTaskCallback`: it called the task with a range outside the items, a worker
    /// index at or past `worker_count`, two ranges at once on one worker or a range with an
    /// item that another range ran or runs (such ranges were not run: no item runs twice),
    /// left items out, or its finish returned while a range still ran. The report is not
    /// written; the world may be in an intermediate state (restore a snapshot).
    TaskContract = 70,
}

impl From<Error> for MpmStatus {
    fn from(e: Error) -> MpmStatus {
        match e {
            Error::BufferTooSmall => MpmStatus::BufferTooSmall,
            Error::BufferMisaligned => MpmStatus::BufferMisaligned,
            Error::NotAWorld => MpmStatus::NotAWorld,
            Error::Unsupported => MpmStatus::Unsupported,
            Error::InvalidCellSize => MpmStatus::InvalidCellSize,
            Error::InvalidCellCount => MpmStatus::InvalidCellCount,
            Error::InvalidCapacity => MpmStatus::InvalidCapacity,
            Error::InvalidFlipBeta => MpmStatus::InvalidFlipBeta,
            Error::InvalidCfl => MpmStatus::InvalidCfl,
            Error::InvalidExpTerms => MpmStatus::InvalidExpTerms,
            Error::InvalidParticlesPerCell => MpmStatus::InvalidParticlesPerCell,
            Error::NonFiniteDefinition => MpmStatus::NonFiniteDefinition,
            Error::InvalidMaterial => MpmStatus::InvalidMaterial,
            Error::MaterialCapacityExceeded => MpmStatus::MaterialCapacityExceeded,
            Error::ParticleCapacityExceeded => MpmStatus::ParticleCapacityExceeded,
            Error::UnknownMaterial => MpmStatus::UnknownMaterial,
            Error::NonFiniteInput => MpmStatus::NonFiniteInput,
            Error::NonPositiveMassOrVolume => MpmStatus::NonPositiveMassOrVolume,
            Error::PositionOutsideDomain => MpmStatus::PositionOutsideDomain,
            Error::LengthMismatch => MpmStatus::LengthMismatch,
            Error::InvalidTimeStep => MpmStatus::InvalidTimeStep,
            Error::InvalidRegion => MpmStatus::InvalidRegion,
            Error::InvalidEffect => MpmStatus::InvalidEffect,
            Error::EffectNotDeclared => MpmStatus::EffectNotDeclared,
            Error::UnknownParticle => MpmStatus::UnknownParticle,
            Error::TractionCapacityExceeded => MpmStatus::TractionCapacityExceeded,
            Error::InvalidAxis => MpmStatus::InvalidAxis,
            Error::SubstepLimit => MpmStatus::SubstepLimit,
            Error::InvalidState => MpmStatus::InvalidState,
            Error::InvalidLimit => MpmStatus::InvalidLimit,
            Error::InvalidDeformation => MpmStatus::InvalidDeformation,
            Error::InvalidTransfer => MpmStatus::InvalidTransfer,
            Error::UnknownTraction => MpmStatus::UnknownTraction,
            Error::StableStepTooShort => MpmStatus::StableStepTooShort,
            Error::ColliderCapacityExceeded => MpmStatus::ColliderCapacityExceeded,
            Error::UnknownCollider => MpmStatus::UnknownCollider,
            Error::InvalidBoundary => MpmStatus::InvalidBoundary,
        }
    }
}

impl MpmStatus {
    /// Every status, in numeric order.
    pub const ALL: [MpmStatus; 45] = [
        MpmStatus::Ok,
        MpmStatus::BufferTooSmall,
        MpmStatus::BufferMisaligned,
        MpmStatus::NotAWorld,
        MpmStatus::Unsupported,
        MpmStatus::InvalidCellSize,
        MpmStatus::InvalidCellCount,
        MpmStatus::InvalidCapacity,
        MpmStatus::InvalidFlipBeta,
        MpmStatus::InvalidCfl,
        MpmStatus::InvalidExpTerms,
        MpmStatus::InvalidParticlesPerCell,
        MpmStatus::NonFiniteDefinition,
        MpmStatus::InvalidMaterial,
        MpmStatus::MaterialCapacityExceeded,
        MpmStatus::ParticleCapacityExceeded,
        MpmStatus::UnknownMaterial,
        MpmStatus::NonFiniteInput,
        MpmStatus::NonPositiveMassOrVolume,
        MpmStatus::PositionOutsideDomain,
        MpmStatus::LengthMismatch,
        MpmStatus::InvalidTimeStep,
        MpmStatus::InvalidRegion,
        MpmStatus::InvalidEffect,
        MpmStatus::EffectNotDeclared,
        MpmStatus::UnknownParticle,
        MpmStatus::TractionCapacityExceeded,
        MpmStatus::InvalidAxis,
        MpmStatus::SubstepLimit,
        MpmStatus::InvalidState,
        MpmStatus::InvalidLimit,
        MpmStatus::InvalidDeformation,
        MpmStatus::InvalidTransfer,
        MpmStatus::UnknownTraction,
        MpmStatus::StableStepTooShort,
        MpmStatus::ColliderCapacityExceeded,
        MpmStatus::UnknownCollider,
        MpmStatus::InvalidBoundary,
        MpmStatus::NullPointer,
        MpmStatus::DefNotFromDefault,
        MpmStatus::InvalidEnum,
        MpmStatus::OutputTooSmall,
        MpmStatus::Internal,
        MpmStatus::OverlappingMemory,
        MpmStatus::TaskContract,
    ];

    /// The description `mpm_status_string` returns, NUL-terminated: the kernel's own for its
    /// errors.
    pub fn as_cstr(self) -> &'static core::ffi::CStr {
        match self {
            MpmStatus::Ok => c"ok",
            MpmStatus::NullPointer => c"a required pointer argument is NULL",
            MpmStatus::DefNotFromDefault => {
                c"definition not from mpm_world_def_default or mpm_material_def_default (or of another precision)"
            }
            MpmStatus::InvalidEnum => c"enum value out of range",
            MpmStatus::OutputTooSmall => c"output buffer shorter than the data",
            MpmStatus::Internal => c"internal error (caught panic): please report",
            MpmStatus::OverlappingMemory => {
                c"an input array or output pointer overlaps the world's memory"
            }
            MpmStatus::TaskContract => {
                c"the host's task system broke its contract (a range out of bounds, overlapping or on a busy worker, items left out, or an early finish)"
            }
            kernel => Error::ALL
                .iter()
                .find(|e| **e as u32 == kernel as u32)
                .map_or(c"unknown status", |e| e.as_cstr()),
        }
    }
}

/// A status as the C side passes it: any 32-bit value (the C enum's storage type). Named
/// `MpmStatus` in the header; taking it as a plain integer keeps an out-of-range value from C
/// defined behaviour.
pub type MpmStatusValue = u32;

/// A static, NUL-terminated description of `status`; "unknown status" for a value that is not
/// an `MpmStatus`. Never NULL; the string lives as long as the program.
#[no_mangle]
pub extern "C" fn mpm_status_string(status: MpmStatusValue) -> *const core::ffi::c_char {
    MpmStatus::ALL
        .iter()
        .find(|s| **s as u32 == status)
        .map_or(c"unknown status", |s| s.as_cstr())
        .as_ptr()
}
