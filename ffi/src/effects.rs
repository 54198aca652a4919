//! The effects a world's definition declares (`MpmWorldDef::effects`), driven from C:
//! per-particle forces and damping, tractions, the thermostat's state, and the values and
//! sources of the transported scalars (temperature, concentration potential).
//!
//! No input array may lie in the world's memory (`MPM_STATUS_OVERLAPPING_MEMORY`: copy a
//! column of the particle view to memory of your own first).
//!
//! Every call that sets an effect's data needs that effect declared
//! (`MPM_STATUS_EFFECT_NOT_DECLARED` otherwise), and names existing particles
//! (`MPM_STATUS_UNKNOWN_PARTICLE` otherwise, checked before any array is read). The setters of
//! per-particle values check the world and the pointers (and the field's number), then the
//! declaration, the particle range and the values; `mpm_world_add_tractions` checks the world,
//! the output pointer and the face's number, then (as the kernel) the declaration, the face and
//! traction, the particle range and the capacity.

use crate::defs::{face_from_c, scalar_field_from_c, vec3, MpmFaceValue, MpmScalarFieldValue};
use crate::status::MpmStatus;
use crate::world::{id_range, put, world_at, world_ref, MpmIdRange, MpmWorld};
use crate::{apart, guard, mpm_real, non_null, MpmVec3};
use core::ops::Range;
use kernel::{ScalarField, World};

/// `Err(UnknownParticle)` unless particles `first .. first + count` exist: checked before any
/// array of `count` values is formed, so a count past the particles reads nothing, and before
/// the arrays' overlap with the world, which for a count no world holds (`SIZE_MAX`) depends
/// on where the host's memory lies (the same call was refused as one or the other by address).
fn existing(w: &World<'_>, first: u32, count: usize) -> Result<(), MpmStatus> {
    match (first as usize).checked_add(count) {
        Some(end) if end <= w.particle_count() => Ok(()),
        _ => Err(MpmStatus::UnknownParticle),
    }
}

/// `count` values at `p` (non-NULL, checked by the caller).
///
/// # Safety
/// `p` is valid for reads of `count` values that nothing writes during the call; `count` is at
/// most the particle capacity (so the byte length fits in isize).
unsafe fn column<'a>(p: *const mpm_real, count: usize) -> &'a [mpm_real] {
    // SAFETY: as the function's contract says.
    unsafe { core::slice::from_raw_parts(p, count) }
}

/// Sets the external force (N; per unit thickness in plane strain, per radian when
/// axisymmetric) of particles `first .. first + count` from one array per axis, each of
/// `count` values; the force stays until set again. `fz` is not read in 2D and may be NULL
/// there. Needs `MpmEffects::particle_forces`. Refused with `MPM_STATUS_NON_FINITE_INPUT` if
/// any value is not finite (none is set).
///
/// # Safety
/// `world` is NULL or a world; each array the dimension uses is NULL or valid for reads of
/// `count` values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_forces(
    world: *mut MpmWorld,
    first: u32,
    fx: *const mpm_real,
    fy: *const mpm_real,
    fz: *const mpm_real,
    count: usize,
) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let def = w.def();
        let d = def.axes();
        let arrays = [fx, fy, fz];
        for &p in &arrays[..d] {
            non_null(p)?;
        }
        if !def.effects.particle_forces {
            return Err(MpmStatus::EffectNotDeclared);
        }
        existing(&w, first, count)?;
        for &p in &arrays[..d] {
            apart(w.as_bytes(), p, count)?;
        }
        let force: [&[mpm_real]; 3] = core::array::from_fn(|a| {
            if a < d {
                // SAFETY: non-NULL, and the caller promises `count` values; `count` is at most
                // the particle count.
                unsafe { column(arrays[a], count) }
            } else {
                &[]
            }
        });
        w.set_particle_forces(first, force)?;
        Ok(())
    })
}

/// Sets the local grid and particle damping `alpha_g`, `alpha_p` (1/s, finite, >= 0) of
/// particles `first .. first + count`, added to the global damping for those particles; each
/// array holds `count` values. Needs `MpmDamping::per_particle`. Refused with
/// `MPM_STATUS_INVALID_EFFECT` if any value is negative or not finite (none is set).
///
/// # Safety
/// `world` is NULL or a world; `alpha_g` and `alpha_p` are NULL or valid for reads of `count`
/// values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_damping(
    world: *mut MpmWorld,
    first: u32,
    alpha_g: *const mpm_real,
    alpha_p: *const mpm_real,
    count: usize,
) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        non_null(alpha_g)?;
        non_null(alpha_p)?;
        if !w.def().effects.damping.is_some_and(|d| d.per_particle) {
            return Err(MpmStatus::EffectNotDeclared);
        }
        existing(&w, first, count)?;
        apart(w.as_bytes(), alpha_g, count)?;
        apart(w.as_bytes(), alpha_p, count)?;
        // SAFETY: non-NULL, and the caller promises `count` values; `count` is at most the
        // particle count.
        let (g, p) = unsafe { (column(alpha_g, count), column(alpha_p, count)) };
        w.set_particle_damping(first, g, p)?;
        Ok(())
    })
}

/// Which column of a transported scalar a setter writes.
#[derive(Clone, Copy)]
enum ScalarColumn {
    /// The value (temperature or concentration potential).
    Value,
    /// The source.
    Source,
}

/// Sets `count` values of column `which` of `field` from `values`, starting at particle
/// `first`: the checks and the call both scalar setters share.
///
/// # Safety
/// As `mpm_world_set_particle_scalar`.
unsafe fn set_scalar(
    world: *mut MpmWorld,
    field: MpmScalarFieldValue,
    which: ScalarColumn,
    first: u32,
    values: *const mpm_real,
    count: usize,
) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        non_null(values)?;
        let field = scalar_field_from_c(field)?;
        let effects = w.def().effects;
        let transport = match field {
            ScalarField::Temperature => effects.heat,
            ScalarField::Concentration => effects.diffusion,
        };
        let declared = match which {
            ScalarColumn::Value => transport.is_some(),
            ScalarColumn::Source => transport.is_some_and(|t| t.sources),
        };
        if !declared {
            return Err(MpmStatus::EffectNotDeclared);
        }
        existing(&w, first, count)?;
        apart(w.as_bytes(), values, count)?;
        // SAFETY: non-NULL, and the caller promises `count` values; `count` is at most the
        // particle count.
        let v = unsafe { column(values, count) };
        match which {
            ScalarColumn::Value => w.set_particle_scalar(field, first, v)?,
            ScalarColumn::Source => w.set_particle_sources(field, first, v)?,
        }
        Ok(())
    })
}

/// Sets the value of a transported scalar of particles `first .. first + count` from `values`
/// (`count` values): the temperature, K (`MPM_SCALAR_FIELD_TEMPERATURE`, needs
/// `MpmEffects::heat`) or the concentration potential c / c_sat
/// (`MPM_SCALAR_FIELD_CONCENTRATION`, needs `MpmEffects::diffusion`). Values start at 0. A
/// field out of range is `MPM_STATUS_INVALID_ENUM`; refused with `MPM_STATUS_NON_FINITE_INPUT`
/// if any value is not finite (none is set). The view's `temperature` and `concentration`
/// show the values, `grid_temperature` and `grid_concentration` the grid's after a step.
///
/// # Safety
/// `world` is NULL or a world; `values` is NULL or valid for reads of `count` values.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_scalar(
    world: *mut MpmWorld,
    field: MpmScalarFieldValue,
    first: u32,
    values: *const mpm_real,
    count: usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe { set_scalar(world, field, ScalarColumn::Value, first, values, count) }
}

/// Sets the source of a transported scalar of particles `first .. first + count` from
/// `values` (`count` values): W/m^3 for the temperature, 1/s for the concentration potential;
/// the source stays until set again. Needs the field declared with `MpmTransport::sources`
/// (`MPM_STATUS_EFFECT_NOT_DECLARED` otherwise). Refused as `mpm_world_set_particle_scalar`.
///
/// # Safety
/// As `mpm_world_set_particle_scalar`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_particle_sources(
    world: *mut MpmWorld,
    field: MpmScalarFieldValue,
    first: u32,
    values: *const mpm_real,
    count: usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe { set_scalar(world, field, ScalarColumn::Source, first, values, count) }
}

/// Adds one traction per particle of `first_particle .. first_particle + particle_count`, each
/// loading the `face` of that particle's domain (the side of its undeformed square or cube of
/// side `h / particles_per_cell`, deformed with it) with `traction` (Pa, force per area of the
/// deformed face, per radian axisymmetric; z ignored in 2D), and returns the traction ids in
/// `ids_out`: `mpm_world_add_surface_tractions` with the face's normal and area. All or nothing. Needs
/// `MpmEffects::traction_capacity`; a face out of range is `MPM_STATUS_INVALID_ENUM`, a z face
/// in 2D or a traction not finite `MPM_STATUS_INVALID_EFFECT`, more tractions than the
/// remaining capacity `MPM_STATUS_TRACTION_CAPACITY_EXCEEDED`. A traction acts while its
/// particle is active.
///
/// # Safety
/// `world` is NULL or a world; `ids_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_tractions(
    world: *mut MpmWorld,
    first_particle: u32,
    particle_count: u32,
    face: MpmFaceValue,
    traction: MpmVec3,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    let range = (first_particle, particle_count);
    // SAFETY: forwarded contract.
    unsafe {
        add_tractions_by(world, range, ids_out, |w, particles| {
            let face = face_from_c(face)?;
            Ok(w.add_tractions(particles, face, vec3(traction))?)
        })
    }
}

/// Adds one traction per particle of `first_particle .. first_particle + particle_count`, each
/// loading a plane face of outward `normal` and `area` (m^2; in 2D the face's length, per unit
/// thickness, axisymmetric its trace in the (r, z) plane), both in the undeformed state, with
/// `traction` (Pa, per area of the deformed face; per radian axisymmetric; z ignored in 2D),
/// and returns the traction ids in `ids_out`. The face lies across the normal where the normal
/// leaves the particle's undeformed square (cube) of half-width `l_p`, and deforms with the
/// particle: give the particles along a curved surface its local normal and each one's share of
/// its area. All or nothing. Needs `MpmEffects::traction_capacity`; a normal of zero length or
/// not finite, an area not positive or not finite, or a traction not finite is
/// `MPM_STATUS_INVALID_EFFECT`; more tractions than the remaining capacity
/// `MPM_STATUS_TRACTION_CAPACITY_EXCEEDED`.
///
/// # Safety
/// `world` is NULL or a world; `ids_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_surface_tractions(
    world: *mut MpmWorld,
    first_particle: u32,
    particle_count: u32,
    normal: MpmVec3,
    area: mpm_real,
    traction: MpmVec3,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    let range = (first_particle, particle_count);
    // SAFETY: forwarded contract.
    unsafe {
        add_tractions_by(world, range, ids_out, |w, particles| {
            Ok(w.add_surface_tractions(particles, vec3(normal), area, vec3(traction))?)
        })
    }
}

/// Adds one load per particle of `first_particle .. first_particle + particle_count` on a face
/// given as for `mpm_world_add_surface_tractions` (reference `normal` and `area`) that turns and
/// stretches with the face: `load` is the traction (Pa, per area of the deformed face) along
/// the face's current outward normal, then its current tangents (z ignored in 2D), so a
/// pressure `p` is `{-p, 0, 0}`. The tangents are the reference ones carried by the particle's
/// deformation: in 2D `(-N_y, N_x)`; in 3D `T1 = N x e / |N x e|` (`e` the axis of `N`'s
/// smallest component) and `n x t1`. Ids, schedules, removal and errors are those of
/// `mpm_world_add_surface_tractions`.
///
/// # Safety
/// `world` is NULL or a world; `ids_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_follower_tractions(
    world: *mut MpmWorld,
    first_particle: u32,
    particle_count: u32,
    normal: MpmVec3,
    area: mpm_real,
    load: MpmVec3,
    ids_out: *mut MpmIdRange,
) -> MpmStatus {
    let range = (first_particle, particle_count);
    // SAFETY: forwarded contract.
    unsafe {
        add_tractions_by(world, range, ids_out, |w, particles| {
            Ok(w.add_follower_tractions(particles, vec3(normal), area, vec3(load))?)
        })
    }
}

/// Makes the `count` tractions from id `first` (a range an adder gave, or any part of the
/// table) follow the schedule `schedule` of `MpmEffects::traction_schedules` (new tractions
/// follow the first). Needs `MpmEffects::traction_capacity`; `MPM_STATUS_UNKNOWN_TRACTION` if
/// the range is not within the table or holds a removed id, `MPM_STATUS_INVALID_EFFECT` for a schedule past
/// `MPM_TRACTION_SCHEDULES` (nothing changes).
///
/// # Safety
/// `world` is NULL or a world.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_traction_schedule(
    world: *mut MpmWorld,
    first: u32,
    count: u32,
    schedule: u32,
) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        // A range past u32 saturates: its end lies past any table (at most 2^24 entries).
        w.set_traction_schedule(first..first.saturating_add(count), schedule)?;
        Ok(())
    })
}

/// What the traction adders share: `ids_out` not NULL and apart from the world, the particle
/// range `first .. first + count` (a range past u32 saturates: its end lies past any world's
/// particles, at most 2^30, so the kernel refuses it as an unknown particle, after its other
/// checks), and the ids `add` returns written to `ids_out` on success.
///
/// # Safety
/// `world` is NULL or a world; `ids_out` is NULL or valid.
unsafe fn add_tractions_by(
    world: *mut MpmWorld,
    (first, count): (u32, u32),
    ids_out: *mut MpmIdRange,
    add: impl FnOnce(&mut World<'_>, Range<u32>) -> Result<Range<u32>, MpmStatus>,
) -> MpmStatus {
    guard(|| {
        non_null(ids_out)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), ids_out, 1)?;
        let ids = add(&mut w, first..first.saturating_add(count))?;
        // SAFETY: checked non-NULL.
        unsafe { put(ids_out, id_range(ids)) };
        Ok(())
    })
}

/// Removes every traction (the capacity stays). Needs `MpmEffects::traction_capacity`.
///
/// # Safety
/// `world` is NULL or a world.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_clear_tractions(world: *mut MpmWorld) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        if w.def().effects.traction_capacity == 0 {
            return Err(MpmStatus::EffectNotDeclared);
        }
        w.clear_tractions();
        Ok(())
    })
}

/// Removes the `count` tractions from id `first` (a range `mpm_world_add_tractions` gave, or
/// any part of the table), so that loads applied together can be taken off together. Every
/// other id stays the traction it was; the removed ids' room is free for a later adder that
/// fits it. Needs `MpmEffects::traction_capacity`; `MPM_STATUS_UNKNOWN_TRACTION` if the range
/// is not within the table or holds an id already removed (nothing is removed).
///
/// # Safety
/// `world` is NULL or a world.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_remove_tractions(
    world: *mut MpmWorld,
    first: u32,
    count: u32,
) -> MpmStatus {
    guard(|| {
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        // A range past u32 saturates: its end lies past any table (at most 2^24 entries).
        w.remove_tractions(first..first.saturating_add(count))?;
        Ok(())
    })
}

/// Number of tractions the world holds, added and not removed (0 if it declares none).
///
/// # Safety
/// `world` is NULL or a world; `count_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_traction_count(
    world: *const MpmWorld,
    count_out: *mut usize,
) -> MpmStatus {
    guard(|| {
        non_null(count_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), count_out, 1)?;
        let n = w.traction_count();
        // SAFETY: checked non-NULL.
        unsafe { put(count_out, n) };
        Ok(())
    })
}

/// The thermostat's current alpha, 1/s (`MpmFeedback`; 0 if the world declares none). It is
/// part of the world's memory, so a snapshot carries it.
///
/// # Safety
/// `world` is NULL or a world; `alpha_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_feedback_alpha(
    world: *const MpmWorld,
    alpha_out: *mut f64,
) -> MpmStatus {
    guard(|| {
        non_null(alpha_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), alpha_out, 1)?;
        let alpha = w.feedback_alpha();
        // SAFETY: checked non-NULL.
        unsafe { put(alpha_out, alpha) };
        Ok(())
    })
}
