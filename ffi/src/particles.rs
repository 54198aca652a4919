//! Particles after they are in: setting their position, velocity, affine matrix and material,
//! or every column of their state at once (and adding particles with it), and removing them
//! (by range, list, box or status), which frees their room.

use crate::defs::vec3;
use crate::status::MpmStatus;
use crate::world::{id_range, put, world_at, MpmIdRange, MpmWorld};
use crate::{apart, guard, mpm_real, non_null, MpmVec3};
use kernel::{ParticleState, Removal, World, WorldDef};

/// `first..first + count` exists (else `UnknownParticle`), checked before any array is
/// formed: a count past the particles reads nothing.
fn existing(w: &World<'_>, first: u32, count: usize) -> Result<(), MpmStatus> {
    match (first as usize).checked_add(count) {
        Some(end) if end <= w.particle_count() => Ok(()),
        _ => Err(MpmStatus::UnknownParticle),
    }
}

/// The `d` arrays of `pointers` the dimension reads, `count` values each, after checking them
/// (NULL, overlap with the world); the others empty.
///
/// # Safety
/// Each of the first `d` pointers is NULL or valid for reads of `count` values that nothing
/// writes during the call; `count` is at most the particle count.
unsafe fn arrays<'a, const N: usize>(
    w: &World<'_>,
    pointers: [*const mpm_real; N],
    read: impl Fn(usize) -> bool,
    count: usize,
) -> Result<[&'a [mpm_real]; N], MpmStatus> {
    for (k, &p) in pointers.iter().enumerate() {
        if read(k) {
            non_null(p)?;
            apart(w.as_bytes(), p, count)?;
        }
    }
    Ok(core::array::from_fn(|k| {
        if read(k) {
            // SAFETY: non-NULL and apart from the world; the caller promises `count` values.
            unsafe { core::slice::from_raw_parts(pointers[k], count) }
        } else {
            &[]
        }
    }))
}

/// Moves particles `first .. first + count` to the positions `x`, `y`, `z` (`count` values
/// each; `z` not read in 2D, and may be NULL there): a teleport (`World::set_particle_positions`).
/// All or nothing: `MPM_STATUS_UNKNOWN_PARTICLE`, `MPM_STATUS_NON_FINITE_INPUT`,
/// `MPM_STATUS_POSITION_OUTSIDE_DOMAIN` as `mpm_world_add_particles` checks them.
///
/// # Safety
/// `world` is NULL or a world; each array the dimension reads is NULL or valid for reads of
/// `count` values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_positions(
    world: *mut MpmWorld,
    first: u32,
    x: *const mpm_real,
    y: *const mpm_real,
    z: *const mpm_real,
    count: usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        set_vectors(world, first, [x, y, z], count, |w, first, x| {
            w.set_particle_positions(first, x)
        })
    }
}

/// Gives particles `first .. first + count` the velocities `vx`, `vy`, `vz` (m/s, `count`
/// values each; `vz` not read in 2D): an impulse, or a kinematic particle set before each
/// step (`World::set_particle_velocities`). All or nothing:
/// `MPM_STATUS_UNKNOWN_PARTICLE`, `MPM_STATUS_NON_FINITE_INPUT`, and
/// `MPM_STATUS_STABLE_STEP_TOO_SHORT` for a speed no stable step resolves.
///
/// # Safety
/// As `mpm_world_set_particle_positions`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_velocities(
    world: *mut MpmWorld,
    first: u32,
    vx: *const mpm_real,
    vy: *const mpm_real,
    vz: *const mpm_real,
    count: usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        set_vectors(world, first, [vx, vy, vz], count, |w, first, v| {
            w.set_particle_velocities(first, v)
        })
    }
}

/// A vector setter's one path: the world, the particles, the arrays the dimension reads,
/// then `set`.
///
/// # Safety
/// As `mpm_world_set_particle_positions`.
unsafe fn set_vectors(
    world: *mut MpmWorld,
    first: u32,
    pointers: [*const mpm_real; 3],
    count: usize,
    set: impl FnOnce(&mut World<'_>, u32, [&[mpm_real]; 3]) -> Result<(), kernel::Error>,
) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let d = w.def().axes();
        existing(&w, first, count)?;
        // SAFETY: as the function's contract says; `count` is at most the particle count.
        let values = unsafe { arrays(&w, pointers, |a| a < d, count) }?;
        set(&mut w, first, values)?;
        Ok(())
    })
}

/// Sets the affine matrix of particles `first .. first + count` as the particle view's
/// `affine` holds it (`World::set_particle_affine`: APIC's `B_p`, or `C_p` with linear shapes
/// and MLS-MPM). `affine` points to 9 pointers, row-major: `affine[3 * a + b]` holds `count`
/// values of entry `(a, b)`; in 2D only `affine[0]`, `[1]`, `[3]`, `[4]` are read.
/// `MPM_STATUS_EFFECT_NOT_DECLARED` unless the transfer is APIC or MLS-MPM; all or nothing:
/// `MPM_STATUS_UNKNOWN_PARTICLE`, `MPM_STATUS_NON_FINITE_INPUT`.
///
/// # Safety
/// `world` is NULL or a world; `affine` is NULL or valid for reads of 9 pointers, each of
/// which the dimension reads NULL or valid for reads of `count` values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_affine(
    world: *mut MpmWorld,
    first: u32,
    affine: *const *const mpm_real,
    count: usize,
) -> MpmStatus {
    guard(|| {
        non_null(affine)?;
        // SAFETY: checked non-NULL; the caller promises 9 pointers, copied before the world is
        // opened for writing.
        let p: [*const mpm_real; 9] = unsafe { core::array::from_fn(|k| *affine.add(k)) };
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let d = w.def().axes();
        if !w.def().transfer.is_affine() {
            return Err(MpmStatus::EffectNotDeclared);
        }
        existing(&w, first, count)?;
        // SAFETY: as the function's contract says; `count` is at most the particle count.
        let m = unsafe { arrays(&w, p, |k| k / 3 < d && k % 3 < d, count) }?;
        w.set_particle_affine(
            first,
            [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]],
        )?;
        Ok(())
    })
}

/// Gives particles `first .. first + count` the materials `material` (`count` ids) as adding
/// them would (`World::set_particle_materials`): the plastic history restarts and the stress is
/// the new material's at the current deformation. All or nothing:
/// `MPM_STATUS_UNKNOWN_PARTICLE`, `MPM_STATUS_UNKNOWN_MATERIAL`,
/// `MPM_STATUS_INVALID_DEFORMATION` where the new material's stress is not finite.
///
/// # Safety
/// `world` is NULL or a world; `material` is NULL or valid for reads of `count` ids.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_materials(
    world: *mut MpmWorld,
    first: u32,
    material: *const u32,
    count: usize,
) -> MpmStatus {
    guard(|| {
        non_null(material)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        existing(&w, first, count)?;
        apart(w.as_bytes(), material, count)?;
        // SAFETY: non-NULL and apart from the world; the caller promises `count` ids, at most
        // the particle count.
        let ids = unsafe { core::slice::from_raw_parts(material, count) };
        w.set_particle_materials(first, ids)?;
        Ok(())
    })
}

/// Every column of some particles' state, for `mpm_world_add_particles_with_state` and
/// `mpm_world_set_particle_state`: the fields of `MpmParticlesView`, each pointing to `count`
/// values of the host's (never the world's own memory: copy a view's columns first), or NULL:
/// not given. A column not given stays as it is when set, and takes a new particle's value
/// when added (0; status `MPM_PARTICLE_STATUS_ACTIVE`); a group of columns (the axes of a
/// vector, the entries of a matrix) is given whole or not at all. Pointers of axes the
/// dimension lacks (z in 2D; matrix entries `3 a + b` with a or b = 2 in 2D; stress 4 and 5 in
/// 2D) and `hoop` outside the axisymmetric form are not read; one of an effect the
/// definition does not declare must be NULL. Nothing is derived from what is given: the stress
/// is written as given (a viscous stress depends on the last step's velocity gradient), so a
/// particle's columns read from a world and given back are that particle, bit for bit.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmParticleState {
    /// Positions per axis, m.
    pub position: [*const mpm_real; 3],
    /// The low parts of the positions per axis, m (`MpmParticlesView::position_low`).
    pub position_low: [*const mpm_real; 3],
    /// Velocities per axis, m/s.
    pub velocity: [*const mpm_real; 3],
    /// Masses, kg, > 0.
    pub mass: *const mpm_real,
    /// Initial volumes, m^3 (m^2 per unit thickness in plane strain), > 0.
    pub volume0: *const mpm_real,
    /// Displacement gradient H = F - I, entry (a, b) at index `3 a + b`.
    pub displacement_gradient: [*const mpm_real; 9],
    /// Kirchhoff stress over initial density, in the order of `MpmParticlesView::stress`.
    pub stress: [*const mpm_real; 6],
    /// Material ids.
    pub material: *const u32,
    /// Statuses (`MpmParticleStatus`).
    pub status: *const u32,
    /// External forces per axis, N (`MpmEffects::particle_forces`).
    pub force: [*const mpm_real; 3],
    /// Local grid and particle damping, 1/s (`MpmDamping::per_particle`).
    pub damping: [*const mpm_real; 2],
    /// The affine matrix, entry (a, b) at index `3 a + b` (`MPM_TRANSFER_APIC`,
    /// `MPM_TRANSFER_MLS`).
    pub affine: [*const mpm_real; 9],
    /// Temperatures, K (`MpmEffects::heat`).
    pub temperature: *const mpm_real,
    /// Concentration potentials (`MpmEffects::diffusion`).
    pub concentration: *const mpm_real,
    /// The grid's temperature at each particle, K (`MpmEffects::heat`).
    pub grid_temperature: *const mpm_real,
    /// The grid's concentration potential at each particle (`MpmEffects::diffusion`).
    pub grid_concentration: *const mpm_real,
    /// The hoop stretch F_thetatheta - 1 (axisymmetric).
    pub hoop: *const mpm_real,
    /// The plastic history (`MpmEffects::plasticity`).
    pub plastic: *const mpm_real,
    /// Heat sources, W/m^3 (`MpmEffects::heat` with `sources`).
    pub temperature_source: *const mpm_real,
    /// Sources of the concentration potential, 1/s (`MpmEffects::diffusion` with `sources`).
    pub concentration_source: *const mpm_real,
}

/// Where a world of a definition keeps an array of [`MpmParticleState`]: whether the
/// dimension reads it, and whether the definition reserves its column.
#[derive(Clone, Copy)]
struct Kept {
    read: bool,
    kept: bool,
}

/// The kernel's state of the arrays `s`, each array the dimension reads turned into a slice by
/// `col` (an array of real values) or `ids` (of u32 ids), with where the world keeps it; the
/// others empty.
fn state_of<'a, E>(
    def: &WorldDef,
    s: &MpmParticleState,
    count: usize,
    mut col: impl FnMut(*const mpm_real, Kept) -> Result<&'a [mpm_real], E>,
    mut ids: impl FnMut(*const u32) -> Result<&'a [u32], E>,
) -> Result<ParticleState<'a>, E> {
    let d = def.axes();
    let fx = &def.effects;
    let heat = fx.heat.is_some();
    let diffusion = fx.diffusion.is_some();
    let sources = |t: Option<kernel::Transport>| t.is_some_and(|t| t.sources);
    let all = |read: bool| Kept { read, kept: true };
    let effect = |kept: bool| Kept { read: true, kept };
    let mut vector = |p: [*const mpm_real; 3], kept: bool| -> Result<[&'a [mpm_real]; 3], E> {
        let mut out: [&'a [mpm_real]; 3] = [&[]; 3];
        for a in 0..3 {
            out[a] = col(p[a], Kept { read: a < d, kept })?;
        }
        Ok(out)
    };
    let position = vector(s.position, true)?;
    let position_low = vector(s.position_low, true)?;
    let velocity = vector(s.velocity, true)?;
    let force = vector(s.force, fx.particle_forces)?;
    let mut matrix = |p: [*const mpm_real; 9], kept: bool| -> Result<[[&'a [mpm_real]; 3]; 3], E> {
        let mut out: [[&'a [mpm_real]; 3]; 3] = [[&[]; 3]; 3];
        for k in 0..9 {
            let read = k / 3 < d && k % 3 < d;
            out[k / 3][k % 3] = col(p[k], Kept { read, kept })?;
        }
        Ok(out)
    };
    let displacement_gradient = matrix(s.displacement_gradient, true)?;
    let affine = matrix(s.affine, def.transfer.is_affine())?;
    let ns = if d == 3 { 6 } else { 4 };
    let mut stress: [&'a [mpm_real]; 6] = [&[]; 6];
    for (k, out) in stress.iter_mut().enumerate() {
        *out = col(s.stress[k], all(k < ns))?;
    }
    let per_particle = fx.damping.is_some_and(|dm| dm.per_particle);
    let damping = [
        col(s.damping[0], effect(per_particle))?,
        col(s.damping[1], effect(per_particle))?,
    ];
    Ok(ParticleState {
        count,
        position,
        position_low,
        velocity,
        mass: col(s.mass, all(true))?,
        volume0: col(s.volume0, all(true))?,
        displacement_gradient,
        stress,
        material: ids(s.material)?,
        status: ids(s.status)?,
        force,
        damping,
        temperature: col(s.temperature, effect(heat))?,
        concentration: col(s.concentration, effect(diffusion))?,
        grid_temperature: col(s.grid_temperature, effect(heat))?,
        grid_concentration: col(s.grid_concentration, effect(diffusion))?,
        temperature_source: col(s.temperature_source, effect(sources(fx.heat)))?,
        concentration_source: col(s.concentration_source, effect(sources(fx.diffusion)))?,
        hoop: col(
            s.hoop,
            all(def.dimension == kernel::Dimension::Axisymmetric2D),
        )?,
        plastic: col(s.plastic, effect(fx.plasticity))?,
        affine,
    })
}

/// The state setters' one path: the world, the struct (copied first), the arrays an undeclared
/// effect's column must not have (`MPM_STATUS_EFFECT_NOT_DECLARED`), then `room` (the particle
/// range or the capacity, before any array is read), each array's overlap with the world,
/// then `write` with the kernel's state.
///
/// # Safety
/// As `mpm_world_set_particle_state`.
unsafe fn with_state(
    world: *mut MpmWorld,
    state: *const MpmParticleState,
    count: usize,
    room: impl FnOnce(&World<'_>, &MpmParticleState) -> Result<(), MpmStatus>,
    write: impl FnOnce(&mut World<'_>, &ParticleState<'_>) -> Result<(), MpmStatus>,
) -> Result<(), MpmStatus> {
    non_null(state)?;
    // SAFETY: checked non-NULL; copied before the world is opened for writing (the caller may
    // keep the struct anywhere).
    let s = unsafe { *state };
    // SAFETY: the caller promises a world.
    let mut w = unsafe { world_at(world) }?;
    let def = w.def();
    state_of(
        &def,
        &s,
        count,
        |p, k| {
            if k.read && !k.kept && !p.is_null() {
                Err(MpmStatus::EffectNotDeclared)
            } else {
                Ok(&[])
            }
        },
        |_| Ok(&[]),
    )?;
    room(&w, &s)?;
    let bytes = w.as_bytes();
    let kernel_state = state_of(
        &def,
        &s,
        count,
        |p, k| -> Result<&[mpm_real], MpmStatus> {
            if !k.read || p.is_null() {
                return Ok(&[]);
            }
            apart(bytes, p, count)?;
            // SAFETY: non-NULL and apart from the world; the caller promises `count` values,
            // which `room` bounded by the capacity (so the byte length fits in isize).
            Ok(unsafe { core::slice::from_raw_parts(p, count) })
        },
        |p| -> Result<&[u32], MpmStatus> {
            if p.is_null() {
                return Ok(&[]);
            }
            apart(bytes, p, count)?;
            // SAFETY: as for the real arrays.
            Ok(unsafe { core::slice::from_raw_parts(p, count) })
        },
    )?;
    write(&mut w, &kernel_state)
}

/// Adds `count` particles with the state `state` (`MpmParticleState`; the kernel's
/// `World::add_particles_with_state`); all or nothing. Their ids go to `ids_out`. Their
/// position, mass, volume0 and material must be given (`MPM_STATUS_NULL_POINTER`); every
/// other column not given takes a new particle's value. A particle's columns read from a
/// world (`MpmParticlesView`, copied) and added here, to that world or another with the same
/// materials and declared effects, are that particle, bit for bit. In order:
/// `MPM_STATUS_NULL_POINTER` for `state` or `ids_out`, the world's checks,
/// `MPM_STATUS_EFFECT_NOT_DECLARED` for an array of an undeclared effect,
/// `MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED` (before any array is read), NULL required arrays,
/// `MPM_STATUS_OVERLAPPING_MEMORY`, then each particle as `mpm_world_set_particle_state`
/// checks it.
///
/// # Safety
/// `world` is NULL or a world; `state` is NULL or valid, and each pointer in it that the
/// dimension reads is NULL or valid for reads of `count` values; `ids_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_particles_with_state(
    world: *mut MpmWorld,
    state: *const MpmParticleState,
    count: usize,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    guard(|| {
        non_null(ids_out)?;
        let room = |w: &World<'_>, s: &MpmParticleState| {
            if count > w.def().particle_capacity as usize - w.particle_count() {
                return Err(MpmStatus::ParticleCapacityExceeded);
            }
            let d = w.def().axes();
            for &p in s.position[..d].iter().chain([&s.mass, &s.volume0]) {
                non_null(p)?;
            }
            non_null(s.material)?;
            apart(w.as_bytes(), ids_out, 1)
        };
        let write = |w: &mut World<'_>, s: &ParticleState<'_>| {
            let ids = w.add_particles_with_state(s)?;
            // SAFETY: checked non-NULL and apart from the world.
            unsafe { put(ids_out, id_range(ids)) };
            Ok(())
        };
        // SAFETY: forwarded contract.
        unsafe { with_state(world, state, count, room, write) }
    })
}

/// Sets the columns `state` gives (`MpmParticleState`, non-NULL pointers) of particles
/// `first .. first + count`, as given, bit for bit; the others stay (the kernel's
/// `World::set_particle_state`). Nothing is derived: the stress is what is given
/// (`mpm_world_set_displacement_gradient` derives it). In order: `MPM_STATUS_NULL_POINTER`
/// for `state`, the world's checks, `MPM_STATUS_EFFECT_NOT_DECLARED` for an array of an
/// undeclared effect, `MPM_STATUS_UNKNOWN_PARTICLE` (before any array is read),
/// `MPM_STATUS_OVERLAPPING_MEMORY`, `MPM_STATUS_LENGTH_MISMATCH` for a group given in part; then
/// each particle with its values after the call, as `mpm_world_open` checks a snapshot's:
/// `MPM_STATUS_NON_FINITE_INPUT`, `MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME`,
/// `MPM_STATUS_STABLE_STEP_TOO_SHORT` (a speed, a snow's hardening or a damping rate no step
/// resolves), `MPM_STATUS_UNKNOWN_MATERIAL`, `MPM_STATUS_POSITION_OUTSIDE_DOMAIN`,
/// `MPM_STATUS_INVALID_STATE` (an unknown status, a low part of the position past one unit
/// in the last place of the position), `MPM_STATUS_INVALID_DEFORMATION` (H, hoop stretch or
/// stress not finite, J <= 0, a hoop stretch <= -1, a plastic history out of its model's
/// range), `MPM_STATUS_INVALID_EFFECT` (a damping rate < 0).
///
/// # Safety
/// `world` is NULL or a world; `state` is NULL or valid, and each pointer in it that the
/// dimension reads is NULL or valid for reads of `count` values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_state(
    world: *mut MpmWorld,
    first: u32,
    state: *const MpmParticleState,
    count: usize,
) -> MpmStatus {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            with_state(
                world,
                state,
                count,
                |w, _| existing(w, first, count),
                |w, s| Ok(w.set_particle_state(first, s)?),
            )
        }
    })
}

/// Runs a removal and writes how many particles it removed to `removed_out`.
///
/// # Safety
/// `world` is NULL or a world; `removed_out` is NULL or valid.
unsafe fn remove<'r>(
    world: *mut MpmWorld,
    removed_out: *mut u32,
    which: impl FnOnce(&World<'_>) -> Result<Removal<'r>, MpmStatus>,
) -> MpmStatus {
    guard(|| {
        non_null(removed_out)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), removed_out, 1)?;
        let which = which(&w)?;
        let removed = w.remove_particles(which)?;
        // SAFETY: checked non-NULL; a count of particles fits in u32.
        unsafe { put(removed_out, removed as u32) };
        Ok(())
    })
}

/// Removes particles `first .. first + count`. The others keep their order and state (the
/// world steps as one built with them alone would); a particle after the removed ones moves
/// down by the number removed before it, which is how a host follows its ids; the room is
/// free for later additions. Tractions on removed particles go too (those after them move
/// down); the others follow their particle. O(n) in the particle count.
/// `MPM_STATUS_UNKNOWN_PARTICLE` for a range past the particles (nothing removed).
///
/// # Safety
/// `world` is NULL or a world; `removed_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_remove_particles(
    world: *mut MpmWorld,
    first: u32,
    count: u32,
    removed_out: *mut u32,
) -> MpmStatus {
    let range = first.checked_add(count).map(|end| first..end);
    // SAFETY: forwarded contract.
    unsafe {
        remove(world, removed_out, |_| {
            range.map(Removal::Range).ok_or(MpmStatus::UnknownParticle)
        })
    }
}

/// Removes the particles of the `count` ids at `ids` (any order; an id given twice is
/// removed once), as `mpm_world_remove_particles` does. `MPM_STATUS_UNKNOWN_PARTICLE` if any
/// id is not a particle's (nothing removed).
///
/// # Safety
/// `world` is NULL or a world; `ids` is NULL or valid for reads of `count` ids (none is read
/// when `count` is 0); `removed_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_remove_particle_list(
    world: *mut MpmWorld,
    ids: *const u32,
    count: usize,
    removed_out: *mut u32,
) -> MpmStatus {
    let list = |w: &World<'_>| {
        non_null(ids)?;
        apart(w.as_bytes(), ids, count)?;
        if count > isize::MAX as usize / 4 {
            return Err(MpmStatus::UnknownParticle);
        }
        // SAFETY: non-NULL and apart from the world; the caller promises `count` ids (the
        // byte length fits in isize), which the removal reads within the call.
        Ok(Removal::List(unsafe {
            core::slice::from_raw_parts(ids, count)
        }))
    };
    // SAFETY: forwarded contract.
    unsafe { remove(world, removed_out, list) }
}

/// Removes every particle whose position lies in the box from `min` to `max` (faces
/// included; z not read in 2D), whatever its status: a sink. As `mpm_world_remove_particles`
/// does; `MPM_STATUS_NON_FINITE_INPUT` for a corner that is not finite,
/// `MPM_STATUS_INVALID_REGION` for `min > max` on an axis (nothing removed).
///
/// # Safety
/// `world` is NULL or a world; `removed_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_remove_particles_in_box(
    world: *mut MpmWorld,
    min: MpmVec3,
    max: MpmVec3,
    removed_out: *mut u32,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        remove(world, removed_out, |_| {
            Ok(Removal::Box {
                min: vec3(min),
                max: vec3(max),
            })
        })
    }
}

/// Removes every particle whose domain reaches into collider `collider`'s solid, posed now,
/// or touches it: the material a solid placed into it displaces (`Removal::Collider`: a
/// domain is the square, cube in 3D, of half-width `cell_size / (2 particles_per_cell)`; it
/// reaches a flat face exactly where it would overlap it, and a curved one a little sooner).
/// The call a host makes after adding a body into water or sand, in place of testing the
/// particles' centres, which leaves half-particles pressed into the solid. As
/// `mpm_world_remove_particles` does; `MPM_STATUS_UNKNOWN_COLLIDER` for an id past the
/// colliders (nothing removed).
///
/// # Safety
/// `world` is NULL or a world; `removed_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_remove_particles_in_collider(
    world: *mut MpmWorld,
    collider: u32,
    removed_out: *mut u32,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe { remove(world, removed_out, |_| Ok(Removal::Collider(collider))) }
}

/// Removes every particle that no longer takes part (escaped through an open face, or
/// frozen), as `mpm_world_remove_particles` does.
///
/// # Safety
/// `world` is NULL or a world; `removed_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_remove_inactive_particles(
    world: *mut MpmWorld,
    removed_out: *mut u32,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe { remove(world, removed_out, |_| Ok(Removal::Inactive)) }
}

/// Reorders the particles by cell, in place (`World::sort_particles`): by the node their
/// stencil starts at, each cell's groups of four first, those of one cell keeping their order.
/// A host calls it between frames, every so many steps, on a scene whose particles lost their
/// order (a stirred fluid, particles added in the host's order): the step then reads and adds
/// the grid's rows four particles at a time again. `order_out` receives, for each new index,
/// the particle's index before the call (`order_out[new] = old`), which is how a host follows
/// its ids. Every particle's whole state moves with it and tractions follow their particle:
/// right after the call the world is the world before, permuted, to the bit; later steps sum
/// the nodes in another order, so they agree with the unsorted world's to round-off only.
/// O(n + nodes). `MPM_STATUS_OUTPUT_TOO_SMALL` if `order_len` is below the particle count
/// (nothing changed, nothing written); only the first count entries are written.
///
/// # Safety
/// `world` is NULL or a world; `order_out` is NULL or valid for `order_len` writes.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_sort_particles(
    world: *mut MpmWorld,
    order_out: *mut u32,
    order_len: usize,
) -> MpmStatus {
    guard(|| {
        non_null(order_out)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let n = w.particle_count();
        if order_len < n {
            return Err(MpmStatus::OutputTooSmall);
        }
        apart(w.as_bytes(), order_out, n)?;
        // SAFETY: non-NULL, the caller promises `order_len >= n` writable values, and they lie
        // outside the world's memory (checked).
        let order = unsafe { core::slice::from_raw_parts_mut(order_out, n) };
        w.sort_particles(order)?;
        Ok(())
    })
}
