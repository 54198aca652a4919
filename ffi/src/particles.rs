//! Particles after they are in: setting their position, velocity, affine matrix and material,
//! and removing them (by range, list, box or status), which frees their room.

use crate::defs::vec3;
use crate::status::MpmStatus;
use crate::world::{put, world_at, MpmWorld};
use crate::{apart, guard, mpm_real, non_null, MpmVec3};
use kernel::{Removal, World};

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
