//! A world's life from C: memory requirements, init (or open a copy), materials, particles,
//! seeding, stable time step and step.

use crate::defs::{material_def_from_c, vec3, world_def_from_c, world_def_to_c, MpmMaterialDef};
use crate::status::MpmStatus;
use crate::{apart, guard, mpm_real, non_null, MpmVec3, MpmWorldDef};
use core::ffi::c_void;
use kernel::{memory_requirements, ParticleBatch, StepReport, World, WorldRef};

/// A world. Opaque: it is the memory the host passed to `mpm_world_init` (the pointer is that
/// memory's address), and it lives as long as the host keeps that memory.
pub struct MpmWorld {
    _opaque: [u8; 0],
}

/// Bytes and alignment a world needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct MpmMemoryRequirements {
    /// Size of the memory, bytes.
    pub bytes: usize,
    /// Alignment of its first byte, bytes (a power of two).
    pub align: usize,
}

/// Ids `first .. first + count` of particles (or tractions) just added.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct MpmIdRange {
    /// Id of the first particle (or traction).
    pub first: u32,
    /// Number of particles (or tractions).
    pub count: u32,
}

/// Particles as structure-of-arrays for `mpm_world_add_particles`: each pointer holds `count`
/// values. In 2D the z pointers are not read and may be NULL.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmParticleArrays {
    /// Positions x, y, z, m.
    pub position: [*const mpm_real; 3],
    /// Velocities x, y, z, m/s.
    pub velocity: [*const mpm_real; 3],
    /// Masses, kg (per unit thickness in plane strain, per radian when axisymmetric), > 0.
    pub mass: *const mpm_real,
    /// Initial volumes, m^3 (m^2 per unit thickness in plane strain, m^3 per radian when
    /// axisymmetric), > 0.
    pub volume: *const mpm_real,
    /// Material ids from `mpm_world_add_material`.
    pub material: *const u32,
}

/// What one `mpm_world_step` did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct MpmStepReport {
    /// Substeps taken (>= 1): a dt above the stable one is split into equal substeps.
    pub substeps: u32,
    /// Length of each substep, s.
    pub substep_dt: mpm_real,
    /// Particle-substeps in which a particle reached a stick or slip wall and was stopped.
    pub stopped: u32,
    /// Particles that crossed an open face and left the simulation.
    pub escaped: u32,
    /// Particles frozen in this call: their state turned non-finite, their F inverted, or
    /// they ran away (see `runaway`). Nonzero means the step went bad somewhere:
    /// `flags` has `MPM_STEP_FLAG_FROZE`.
    pub frozen: u32,
    /// Of the frozen, those that ran away: their volume ratio J left
    /// [1 / max_volume_ratio, max_volume_ratio] (`MpmWorldDef::max_volume_ratio`), their speed
    /// (the sum of its components' magnitudes) passed `cfl h / MPM_MIN_STABLE_DT`, or their
    /// hardening (snow) took their wave speed past what the substep resolves (a Courant
    /// number above 1). The sign of an unstable scheme or a time step too long for the scene.
    pub runaway: u32,
    /// `MPM_STEP_FLAG_FROZE` if any particle froze in this call, `MPM_STEP_FLAG_RUNAWAY` if
    /// any froze as runaway; 0 for a step that went well.
    pub flags: u32,
    /// How many entries of `first_frozen` are set (at most 8).
    pub first_frozen_count: u32,
    /// Ids of the first frozen particles.
    pub first_frozen: [u32; 8],
}

/// `MpmStepReport::flags`: some particle froze in the step.
pub const MPM_STEP_FLAG_FROZE: u32 = 1;
/// `MpmStepReport::flags`: some particle froze because its volume ran away.
pub const MPM_STEP_FLAG_RUNAWAY: u32 = 2;

/// The extent of the world at `w`, read from its header, or why there is none. Reads the
/// magic number (the first 8 bytes) before anything else, so that a pointer to something
/// else, however small, is not read past them.
///
/// # Safety
/// `w` is NULL or points to a world (what `mpm_world_init` or `mpm_world_open` returned, in
/// memory the host still owns).
unsafe fn extent(w: *const MpmWorld) -> Result<usize, MpmStatus> {
    non_null(w)?;
    if !(w as usize).is_multiple_of(kernel::ALIGN) {
        return Err(MpmStatus::BufferMisaligned);
    }
    // SAFETY: the caller promises a world at `w`; anything readable starts with the 8 bytes
    // of the magic (the pointer is aligned to 64, so they lie in one page).
    let magic = unsafe { core::slice::from_raw_parts(w as *const u8, World::MAGIC_BYTES) };
    if !World::has_magic(magic) {
        return Err(MpmStatus::NotAWorld);
    }
    // SAFETY: the magic says a world starts here, and a world is at least a header long.
    let head = unsafe { core::slice::from_raw_parts(w as *const u8, World::HEADER_BYTES) };
    Ok(World::stored_bytes(head)?)
}

/// The world at `w`, opened for a call that changes it.
///
/// # Safety
/// As [`extent`]; no other call on this world runs at the same time.
pub(crate) unsafe fn world_at<'a>(w: *mut MpmWorld) -> Result<World<'a>, MpmStatus> {
    // SAFETY: forwarded contract.
    let total = unsafe { extent(w) }?;
    // SAFETY: the header says the world spans `total` bytes, all of which the caller owns and
    // nothing else accesses during the call.
    let buf = unsafe { core::slice::from_raw_parts_mut(w as *mut u8, total) };
    Ok(World::reopen(buf)?)
}

/// The world at `w`, opened for reading only (calls that take a `const MpmWorld *`; several
/// may run at once on one world).
///
/// # Safety
/// As [`extent`]; no call that changes this world runs at the same time.
pub(crate) unsafe fn world_ref<'a>(w: *const MpmWorld) -> Result<WorldRef<'a>, MpmStatus> {
    // SAFETY: forwarded contract.
    let total = unsafe { extent(w) }?;
    // SAFETY: the header says the world spans `total` bytes, which nothing writes during the
    // call.
    let buf = unsafe { core::slice::from_raw_parts(w as *const u8, total) };
    Ok(WorldRef::reopen(buf)?)
}

/// Writes `v` to `out` (checked non-NULL by the caller).
///
/// # Safety
/// `out` is valid for a write of `T`.
pub(crate) unsafe fn put<T>(out: *mut T, v: T) {
    // SAFETY: as the function's contract says.
    unsafe { out.write(v) }
}

/// Bytes and alignment a world of `def` needs.
///
/// # Safety
/// Each pointer is NULL or valid for its type.
#[no_mangle]
pub unsafe extern "C" fn mpm_memory_requirements(
    def: *const MpmWorldDef,
    requirements_out: *mut MpmMemoryRequirements,
) -> MpmStatus {
    guard(|| {
        non_null(def)?;
        non_null(requirements_out)?;
        // SAFETY: checked non-NULL; the caller promises a valid definition.
        let d = world_def_from_c(unsafe { &*def })?;
        let r = memory_requirements(&d)?;
        let out = MpmMemoryRequirements {
            bytes: r.bytes,
            align: r.align,
        };
        // SAFETY: checked non-NULL.
        unsafe { put(requirements_out, out) };
        Ok(())
    })
}

/// Lays out an empty world of `def` in `memory` (`memory_len` bytes, at least what
/// `mpm_memory_requirements` says, aligned as it says) and returns it in `world_out` (the same
/// address). On failure the memory is untouched.
///
/// # Safety
/// `memory` is NULL or valid for reads and writes of `memory_len` bytes; the other pointers
/// are NULL or valid for their types.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_init(
    def: *const MpmWorldDef,
    memory: *mut c_void,
    memory_len: usize,
    world_out: *mut *mut MpmWorld,
) -> MpmStatus {
    guard(|| {
        non_null(def)?;
        non_null(memory)?;
        non_null(world_out)?;
        // SAFETY: checked non-NULL; the caller promises a valid definition.
        let d = world_def_from_c(unsafe { &*def })?;
        // Validate everything before the memory is formed into a slice and written.
        let r = memory_requirements(&d)?;
        if memory_len < r.bytes {
            return Err(MpmStatus::BufferTooSmall);
        }
        if !(memory as usize).is_multiple_of(r.align) {
            return Err(MpmStatus::BufferMisaligned);
        }
        // SAFETY: the caller promises `memory_len` bytes at `memory`.
        let buf = unsafe { core::slice::from_raw_parts_mut(memory as *mut u8, memory_len) };
        apart(&buf[..r.bytes], world_out, 1)?;
        World::init(&d, buf)?;
        // SAFETY: checked non-NULL.
        unsafe { put(world_out, memory as *mut MpmWorld) };
        Ok(())
    })
}

/// Opens a world that `memory` already holds, such as a byte copy of another world's first
/// `mpm_world_bytes` bytes (a snapshot), and returns it in `world_out`. The memory is
/// untrusted: besides the header (`MPM_STATUS_NOT_A_WORLD`) the whole state is checked, every
/// particle included (`MPM_STATUS_INVALID_STATE`), in one pass over the particles; a world that
/// opens steps with meaningful results.
///
/// # Safety
/// As `mpm_world_init`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_open(
    memory: *mut c_void,
    memory_len: usize,
    world_out: *mut *mut MpmWorld,
) -> MpmStatus {
    guard(|| {
        non_null(memory)?;
        non_null(world_out)?;
        // SAFETY: the caller promises `memory_len` bytes at `memory`.
        let buf = unsafe { core::slice::from_raw_parts_mut(memory as *mut u8, memory_len) };
        let w = World::open(buf)?;
        apart(w.as_bytes(), world_out, 1)?;
        // SAFETY: checked non-NULL.
        unsafe { put(world_out, memory as *mut MpmWorld) };
        Ok(())
    })
}

/// Bytes the world occupies from its start: what a snapshot must copy.
///
/// # Safety
/// `world` is NULL or a world; `bytes_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_bytes(
    world: *const MpmWorld,
    bytes_out: *mut usize,
) -> MpmStatus {
    guard(|| {
        non_null(bytes_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), bytes_out, 1)?;
        let n = w.as_bytes().len();
        // SAFETY: checked non-NULL.
        unsafe { put(bytes_out, n) };
        Ok(())
    })
}

/// The world's definition (with the cookie, so it can init another world).
///
/// # Safety
/// `world` is NULL or a world; `def_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_get_def(
    world: *const MpmWorld,
    def_out: *mut MpmWorldDef,
) -> MpmStatus {
    guard(|| {
        non_null(def_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), def_out, 1)?;
        // SAFETY: checked non-NULL.
        unsafe { put(def_out, world_def_to_c(&w.def())) };
        Ok(())
    })
}

/// Adds a material and returns its id in `id_out`.
///
/// # Safety
/// `world` is NULL or a world; the other pointers are NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_material(
    world: *mut MpmWorld,
    def: *const MpmMaterialDef,
    id_out: *mut u32,
) -> MpmStatus {
    guard(|| {
        non_null(def)?;
        non_null(id_out)?;
        // SAFETY: checked non-NULL; the caller promises a valid definition.
        let m = material_def_from_c(unsafe { &*def })?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), id_out, 1)?;
        let id = w.add_material(&m)?;
        // SAFETY: checked non-NULL.
        unsafe { put(id_out, id) };
        Ok(())
    })
}

/// Adds `count` particles from structure-of-arrays; all or nothing. Their ids go to `ids_out`.
/// A count above the remaining capacity is refused before any array is read.
///
/// # Safety
/// `world` is NULL or a world; `arrays` is NULL or valid, and each pointer in it that the
/// dimension uses is NULL or valid for reads of `count` values; `ids_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_particles(
    world: *mut MpmWorld,
    arrays: *const MpmParticleArrays,
    count: usize,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    guard(|| {
        non_null(arrays)?;
        non_null(ids_out)?;
        // SAFETY: checked non-NULL; copied before the world is opened for writing (the caller
        // may keep the struct anywhere).
        let a = unsafe { *arrays };
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let def = w.def();
        if count > def.particle_capacity as usize - w.particle_count() {
            return Err(MpmStatus::ParticleCapacityExceeded);
        }
        let d = def.axes();
        let required = (0..d)
            .flat_map(|i| [a.position[i], a.velocity[i]])
            .chain([a.mass, a.volume]);
        for p in required.clone() {
            non_null(p)?;
        }
        non_null(a.material)?;
        for p in required {
            apart(w.as_bytes(), p, count)?;
        }
        apart(w.as_bytes(), a.material, count)?;
        apart(w.as_bytes(), ids_out, 1)?;
        let empty: &[mpm_real] = &[];
        // SAFETY (every slice): non-NULL, and the caller promises `count` values; `count` is at
        // most the capacity, so the byte length fits in isize.
        let col = |p: *const mpm_real, used: bool| {
            if used {
                unsafe { core::slice::from_raw_parts(p, count) }
            } else {
                empty
            }
        };
        let batch = ParticleBatch {
            position: core::array::from_fn(|i| col(a.position[i], i < d)),
            velocity: core::array::from_fn(|i| col(a.velocity[i], i < d)),
            mass: col(a.mass, true),
            volume: col(a.volume, true),
            // SAFETY: as above.
            material: unsafe { core::slice::from_raw_parts(a.material, count) },
        };
        let ids = w.add_particles(&batch)?;
        // SAFETY: checked non-NULL.
        unsafe { put(ids_out, id_range(ids)) };
        Ok(())
    })
}

/// Gives particles `first .. first + count` the displacement gradient `H = F - I` and the
/// stress their material gives it (`World::set_displacement_gradient`): a scene that starts
/// deformed or prestressed. `h` points to 9 pointers, row-major: `h[3 * a + b]` holds `count`
/// values of `H_ab`. In 2D only `h[0]`, `h[1]`, `h[3]`, `h[4]` are read, and `h[8]` (the hoop
/// stretch `F_thetatheta - 1`) in the axisymmetric form; the others may be NULL. The volume
/// the particles were added with is their reference volume; positions and velocities are not
/// changed. All or nothing: `MPM_STATUS_UNKNOWN_PARTICLE` if the particles do not exist
/// (checked before any array is read), `MPM_STATUS_INVALID_DEFORMATION` if any `H` is not
/// finite, inverts, has `det F` outside the definition's `max_volume_ratio` band or gives a
/// stress that is not finite.
///
/// # Safety
/// `world` is NULL or a world; `h` is NULL or valid for reads of 9 pointers, each of which
/// the dimension reads is NULL or valid for reads of `count` values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_displacement_gradient(
    world: *mut MpmWorld,
    first: u32,
    h: *const *const mpm_real,
    count: usize,
) -> MpmStatus {
    guard(|| {
        non_null(h)?;
        // SAFETY: checked non-NULL; the caller promises 9 pointers, copied before the world is
        // opened for writing.
        let p: [*const mpm_real; 9] = unsafe { core::array::from_fn(|k| *h.add(k)) };
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let def = w.def();
        let d = def.axes();
        let axisymmetric = def.dimension == kernel::Dimension::Axisymmetric2D;
        let read = |a: usize, b: usize| (a < d && b < d) || (axisymmetric && a == 2 && b == 2);
        match (first as usize).checked_add(count) {
            Some(end) if end <= w.particle_count() => {}
            _ => return Err(MpmStatus::UnknownParticle),
        }
        for a in 0..3 {
            for b in 0..3 {
                if read(a, b) {
                    non_null(p[3 * a + b])?;
                    apart(w.as_bytes(), p[3 * a + b], count)?;
                }
            }
        }
        let empty: &[mpm_real] = &[];
        let cols: [[&[mpm_real]; 3]; 3] = core::array::from_fn(|a| {
            core::array::from_fn(|b| {
                if read(a, b) {
                    // SAFETY: non-NULL, and the caller promises `count` values; `count` is at
                    // most the particle count, so the byte length fits in isize.
                    unsafe { core::slice::from_raw_parts(p[3 * a + b], count) }
                } else {
                    empty
                }
            })
        });
        w.set_displacement_gradient(first, cols)?;
        Ok(())
    })
}

pub(crate) fn id_range(r: core::ops::Range<u32>) -> MpmIdRange {
    MpmIdRange {
        first: r.start,
        count: r.end - r.start,
    }
}

/// One seeding call: the world at `world`, then `fill` on it, its ids to `ids_out`.
///
/// # Safety
/// As the seeding entry points.
unsafe fn seed(
    world: *mut MpmWorld,
    ids_out: *mut MpmIdRange,
    fill: impl FnOnce(&mut World<'_>) -> Result<core::ops::Range<u32>, kernel::Error>,
) -> MpmStatus {
    guard(|| {
        non_null(ids_out)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), ids_out, 1)?;
        let ids = fill(&mut w)?;
        // SAFETY: checked non-NULL.
        unsafe { put(ids_out, id_range(ids)) };
        Ok(())
    })
}

/// Fills the box `[min, max]` with particles of `material` moving at `velocity`, on the lattice
/// of `particles_per_cell` sites per cell per axis, each with its sub-cell's volume and the
/// mass of that volume (axisymmetric: per radian, the sub-cell's area times the site's
/// radius). All or nothing; the box must lie inside the admissible region. The particles come
/// in stencil-bin order, not x fastest (the sites whose stencils start at the same node
/// together, which the step's scatter sums once; the runs at the box's edges last): find a
/// face's particles by position.
///
/// # Safety
/// `world` is NULL or a world; `ids_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_fill_box(
    world: *mut MpmWorld,
    min: MpmVec3,
    max: MpmVec3,
    material: u32,
    velocity: MpmVec3,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        seed(world, ids_out, |w| {
            w.fill_box(vec3(min), vec3(max), material, vec3(velocity))
        })
    }
}

/// Fills a disk (2D worlds only) like `mpm_world_fill_box`.
///
/// # Safety
/// As `mpm_world_fill_box`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_fill_disk(
    world: *mut MpmWorld,
    center: MpmVec3,
    radius: mpm_real,
    material: u32,
    velocity: MpmVec3,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        seed(world, ids_out, |w| {
            w.fill_disk(vec3(center), radius, material, vec3(velocity))
        })
    }
}

/// Fills a sphere (3D worlds only) like `mpm_world_fill_box`.
///
/// # Safety
/// As `mpm_world_fill_box`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_fill_sphere(
    world: *mut MpmWorld,
    center: MpmVec3,
    radius: mpm_real,
    material: u32,
    velocity: MpmVec3,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        seed(world, ids_out, |w| {
            w.fill_sphere(vec3(center), radius, material, vec3(velocity))
        })
    }
}

/// The largest stable time step, s, from the materials' wave speeds (snow's as hardened), the
/// fastest particle, the damping rates and the diffusivities. Never raised to a floor: what a
/// world accepts keeps it at least `MPM_MIN_STABLE_DT / 2`; a particle speed beyond anything
/// a stable step produces can take it lower (to 0, a step `mpm_world_step` refuses).
///
/// # Safety
/// `world` is NULL or a world; `dt_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_stable_dt(
    world: *const MpmWorld,
    dt_out: *mut mpm_real,
) -> MpmStatus {
    guard(|| {
        non_null(dt_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), dt_out, 1)?;
        let dt = w.stable_dt();
        // SAFETY: checked non-NULL.
        unsafe { put(dt_out, dt) };
        Ok(())
    })
}

/// Advances the world by `dt` seconds (> 0, finite), in equal substeps no longer than the
/// stable one (at most the definition's `max_substeps`, else `MPM_STATUS_SUBSTEP_LIMIT` and
/// nothing changes), and reports what happened in `report_out`: check its `flags` (or
/// `frozen`) to learn whether the step went bad for some particles.
///
/// # Safety
/// `world` is NULL or a world; `report_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_step(
    world: *mut MpmWorld,
    dt: mpm_real,
    report_out: *mut MpmStepReport,
) -> MpmStatus {
    guard(|| {
        non_null(report_out)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), report_out, 1)?;
        let r = w.step(dt)?;
        // SAFETY: checked non-NULL.
        unsafe { put(report_out, step_report(&r)) };
        Ok(())
    })
}

/// The C form of a step's report.
pub(crate) fn step_report(r: &StepReport) -> MpmStepReport {
    let mut first_frozen = [0u32; 8];
    first_frozen[..r.first_frozen.len()].copy_from_slice(&r.first_frozen);
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    MpmStepReport {
        substeps: r.substeps,
        substep_dt: r.substep_dt,
        stopped: r.stopped,
        escaped: r.escaped,
        frozen: r.frozen,
        runaway: r.runaway,
        flags: flag(r.went_bad(), MPM_STEP_FLAG_FROZE) | flag(r.runaway > 0, MPM_STEP_FLAG_RUNAWAY),
        first_frozen_count: r.first_frozen.len() as u32,
        first_frozen,
    }
}

/// Makes every later step of this process use the baseline (SSE2) instance of the particle
/// passes instead of the AVX2 or AVX-512 one. All give bit-identical results; this exists for
/// tools that cannot decode AVX instructions (valgrind 3.19). Irreversible for the process.
#[no_mangle]
pub extern "C" fn mpm_simd_use_baseline_only() {
    kernel::simd::use_baseline_only();
}

/// Makes every later step of this process use at most the AVX2 instance of the particle passes,
/// never the AVX-512 one, for hosts on CPUs that lower their clock while 512-bit instructions
/// run (some Intel server parts), which would slow the host's own code too. Results do not
/// change, only speed. Irreversible for the process.
#[no_mangle]
pub extern "C" fn mpm_simd_use_avx2_at_most() {
    kernel::simd::use_avx2_at_most();
}
