//! Colliders from C (`mpm_gimp::ColliderDef`, E90-E93 and E96 of docs/equations.md): solids
//! the material meets at the grid, moved by the host (kinematic) or by the step (dynamic), and
//! what the material puts on them, read back for the host's rigid bodies. Declared with
//! `MpmEffects::collider_capacity`.

use crate::defs::c_vec3;
use crate::defs::vec3;
use crate::status::MpmStatus;
use crate::world::{put, world_at, world_ref, MpmWorld};
use crate::{apart, guard, mpm_real, non_null, MpmVec3};
use kernel::{ColliderDef, ColliderShape, Contact};

/// A collider's solid (`mpm_gimp::ColliderShape`), in its own frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmColliderShape {
    /// The half-space below the plane through the position whose normal is the frame's y
    /// axis (a floor with no rotation).
    HalfSpace = 0,
    /// A sphere (a circle in 2D) of `radius`.
    Sphere = 1,
    /// A box (a rectangle in 2D) of `half_extents`.
    Box = 2,
    /// The points within `radius` of the segment from `-half_length` to `half_length` along
    /// the frame's y axis.
    Capsule = 3,
    /// A cylinder of `radius` along the frame's y axis, `2 half_length` long, hollow inside
    /// `inner_radius`.
    Cylinder = 4,
    /// A signed distance field (`mpm_world_add_distance_field`): `sdf_dims` samples
    /// `sdf_spacing` apart from sample `sdf_first`, centred on the frame's origin.
    Sdf = 5,
}

// The C values are the kernel's shape numbers (`ColliderShape::number`, the one table).
const _: () = {
    let (l, e) = (0.0, kernel::Vec3::ZERO);
    assert!(MpmColliderShape::HalfSpace as u32 == ColliderShape::HalfSpace.number());
    assert!(MpmColliderShape::Sphere as u32 == ColliderShape::Sphere { radius: l }.number());
    assert!(MpmColliderShape::Box as u32 == ColliderShape::Box { half_extents: e }.number());
    let capsule = ColliderShape::Capsule {
        half_length: l,
        radius: l,
    };
    assert!(MpmColliderShape::Capsule as u32 == capsule.number());
    let cylinder = ColliderShape::Cylinder {
        half_length: l,
        radius: l,
        inner_radius: l,
    };
    assert!(MpmColliderShape::Cylinder as u32 == cylinder.number());
    let sdf = ColliderShape::Sdf {
        first: 0,
        dims: [2, 2, 1],
        spacing: l,
    };
    assert!(MpmColliderShape::Sdf as u32 == sdf.number());
};

/// How the material meets a collider (`mpm_gimp::Contact`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmContact {
    /// The nodes inside move with the collider.
    Stick = 0,
    /// No normal velocity relative to it, either way; Coulomb friction where the node presses.
    Slip = 1,
    /// As slip while the node approaches it; free while it moves away.
    Separate = 2,
}

/// An `MpmColliderShape` as C passes it.
pub type MpmColliderShapeValue = u32;
/// An `MpmContact` as C passes it.
pub type MpmContactValue = u32;

/// A collider, kinematic or dynamic: the C form of `mpm_gimp::ColliderDef`. Get one from
/// `mpm_collider_def_default()` (a frictionless separating floor through the origin).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmColliderDef {
    /// Default `MPM_COLLIDER_SHAPE_HALF_SPACE`.
    pub shape: MpmColliderShapeValue,
    /// Default `MPM_CONTACT_SEPARATE`.
    pub contact: MpmContactValue,
    /// Sphere, capsule, cylinder: m, > 0. Default 0.5.
    pub radius: mpm_real,
    /// Capsule (>= 0) and cylinder (> 0): half the length of the axis, m. Default 0.5.
    pub half_length: mpm_real,
    /// Box: half-extents along the frame's axes, m, each > 0. Default (0.5, 0.5, 0.5).
    pub half_extents: MpmVec3,
    /// Cylinder: the radius of its hole (a tube, a drum's shell), m, in `[0, radius)`.
    /// Default 0 (solid).
    pub inner_radius: mpm_real,
    /// Distance field: its first sample (from `mpm_world_add_distance_field`). Default 0.
    pub sdf_first: u32,
    /// Distance field: its samples along x, y, z (x fastest; at least 2, 2, 1; z 1 in 2D).
    /// Default (2, 2, 1).
    pub sdf_dims: [u32; 3],
    /// Distance field: the distance between samples, m, > 0. Default 1.
    pub sdf_spacing: mpm_real,
    /// The frame's origin, m: the solid's centre, about which it turns and its torque is
    /// reported. In 2D z is not read, as no z of a 2D call is (the origin lies in the plane
    /// z = 0 and reads back with z = 0). Default (0, 0, 0).
    pub position: MpmVec3,
    /// The frame's rotation, a quaternion (x, y, z, w), normalised when set. Default
    /// (0, 0, 0, 1).
    pub rotation: [mpm_real; 4],
    /// Velocity of the origin, m/s (2D: z is not read and reads back 0). Default (0, 0, 0).
    pub velocity: MpmVec3,
    /// Angular velocity about the origin, rad/s (2D: only z is read; x and y read back 0).
    /// Default (0, 0, 0).
    pub angular_velocity: MpmVec3,
    /// Coulomb friction coefficient, >= 0. Default 0.
    pub friction: mpm_real,
    /// The solid's mass, kg (per metre of thickness in plane strain, as the impulse), >= 0.
    /// Default 0: kinematic, the host moves it and its velocity holds through the step.
    /// Above 0: dynamic, each substep moves it by the impulse the material puts on it and
    /// the world's gravity, from the pose and velocity last set; read the pose back after
    /// the step (`mpm_world_get_collider`).
    pub mass: mpm_real,
    /// A dynamic solid's principal moments of inertia about its origin along its frame's
    /// axes, kg m^2 (2D: only z is read), each >= 0; 0 keeps that turn as set. Default
    /// (0, 0, 0).
    pub inertia: MpmVec3,
    /// Set by `mpm_collider_def_default`; do not change.
    pub internal_cookie: u32,
}

/// A collider as the world holds it (`mpm_world_get_collider`): its definition with its pose
/// now, and what the material put on it over the last step, summed in a fixed order (the
/// same bits for any number of workers).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmColliderState {
    /// The definition, with the position and rotation of now.
    pub def: MpmColliderDef,
    /// Impulse over the last step, N s (per unit thickness in plane strain, per radian
    /// axisymmetric).
    pub impulse: MpmVec3,
    /// Angular impulse about the origin over the last step, N m s.
    pub angular_impulse: MpmVec3,
    /// `impulse / duration`, N (0 before a step).
    pub force: MpmVec3,
    /// `angular_impulse / duration`, N m (0 before a step).
    pub torque: MpmVec3,
    /// The last step's length, s (0 before the first step).
    pub duration: mpm_real,
}

/// The cookie of a collider definition of this precision.
const COLLIDER_COOKIE: u32 =
    u32::from_le_bytes(*b"MPMC") ^ (core::mem::size_of::<mpm_real>() as u32);

/// The C form of a Rust collider (with the cookie).
fn collider_def_to_c(d: &ColliderDef) -> MpmColliderDef {
    let (mut sdf_first, mut sdf_dims, mut sdf_spacing) = (0, [2, 2, 1], 1.0);
    let (radius, half_length, half_extents, inner_radius) = match d.shape {
        ColliderShape::Sdf {
            first,
            dims,
            spacing,
        } => {
            (sdf_first, sdf_dims, sdf_spacing) = (first, dims, spacing);
            (0.5, 0.5, None, 0.0)
        }
        ColliderShape::HalfSpace => (0.5, 0.5, None, 0.0),
        ColliderShape::Sphere { radius } => (radius, 0.5, None, 0.0),
        ColliderShape::Box { half_extents } => (0.5, 0.5, Some(half_extents), 0.0),
        ColliderShape::Capsule {
            half_length,
            radius,
        } => (radius, half_length, None, 0.0),
        ColliderShape::Cylinder {
            half_length,
            radius,
            inner_radius,
        } => (radius, half_length, None, inner_radius),
    };
    MpmColliderDef {
        shape: d.shape.number(),
        contact: d.contact as u32,
        radius,
        half_length,
        half_extents: c_vec3(half_extents.unwrap_or(kernel::Vec3::splat(0.5))),
        inner_radius,
        sdf_first,
        sdf_dims,
        sdf_spacing,
        position: c_vec3(d.position),
        rotation: d.rotation,
        velocity: c_vec3(d.velocity),
        angular_velocity: c_vec3(d.angular_velocity),
        friction: d.friction,
        mass: d.mass,
        inertia: c_vec3(d.inertia),
        internal_cookie: COLLIDER_COOKIE,
    }
}

/// The Rust collider of a C one: the cookie and the enum values checked (the values
/// themselves by the kernel).
fn collider_def_from_c(d: &MpmColliderDef) -> Result<ColliderDef, MpmStatus> {
    if d.internal_cookie != COLLIDER_COOKIE {
        return Err(MpmStatus::DefNotFromDefault);
    }
    // The shape whose number (`ColliderShape::number`, the one table) is the C value.
    let shape = [
        ColliderShape::HalfSpace,
        ColliderShape::Sphere { radius: d.radius },
        ColliderShape::Box {
            half_extents: vec3(d.half_extents),
        },
        ColliderShape::Capsule {
            half_length: d.half_length,
            radius: d.radius,
        },
        ColliderShape::Cylinder {
            half_length: d.half_length,
            radius: d.radius,
            inner_radius: d.inner_radius,
        },
        ColliderShape::Sdf {
            first: d.sdf_first,
            dims: d.sdf_dims,
            spacing: d.sdf_spacing,
        },
    ]
    .into_iter()
    .find(|s| s.number() == d.shape)
    .ok_or(MpmStatus::InvalidEnum)?;
    let contact = match d.contact {
        0 => Contact::Stick,
        1 => Contact::Slip,
        2 => Contact::Separate,
        _ => return Err(MpmStatus::InvalidEnum),
    };
    Ok(ColliderDef {
        shape,
        position: vec3(d.position),
        rotation: d.rotation,
        velocity: vec3(d.velocity),
        angular_velocity: vec3(d.angular_velocity),
        contact,
        friction: d.friction,
        mass: d.mass,
        inertia: vec3(d.inertia),
    })
}

/// The documented collider defaults (`mpm_gimp::ColliderDef::DEFAULT`, a frictionless
/// separating floor through the origin), with the cookie `mpm_world_add_collider` checks.
/// Precision-specific symbol, as `mpm_world_def_default`.
#[cfg(not(feature = "f64"))]
#[no_mangle]
pub extern "C" fn mpm_collider_def_default_f32() -> MpmColliderDef {
    collider_def_to_c(&ColliderDef::DEFAULT)
}

/// The documented collider defaults (`mpm_gimp::ColliderDef::DEFAULT`), with the cookie
/// `mpm_world_add_collider` checks. Precision-specific symbol, as `mpm_world_def_default`.
#[cfg(feature = "f64")]
#[no_mangle]
pub extern "C" fn mpm_collider_def_default_f64() -> MpmColliderDef {
    collider_def_to_c(&ColliderDef::DEFAULT)
}

/// Adds a collider, posed as `def` says now, and returns its id in `id_out`. Needs
/// `MpmEffects::collider_capacity` (`MPM_STATUS_EFFECT_NOT_DECLARED`); a value not finite or
/// out of range is `MPM_STATUS_INVALID_EFFECT`, an enum out of range
/// `MPM_STATUS_INVALID_ENUM`, one past the capacity `MPM_STATUS_COLLIDER_CAPACITY_EXCEEDED`.
/// In 2D the position's and velocity's z and the angular velocity's x and y are not read
/// (not checked, stored as 0). `mpm_world_open` checks a stored collider as this call checks
/// a definition.
///
/// # Safety
/// `world` is NULL or a world; the other pointers are NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_collider(
    world: *mut MpmWorld,
    def: *const MpmColliderDef,
    id_out: *mut u32,
) -> MpmStatus {
    guard(|| {
        non_null(def)?;
        non_null(id_out)?;
        // SAFETY: checked non-NULL; the caller promises a valid definition.
        let c = collider_def_from_c(unsafe { &*def })?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), id_out, 1)?;
        let id = w.add_collider(&c)?;
        // SAFETY: checked non-NULL.
        unsafe { put(id_out, id) };
        Ok(())
    })
}

/// Adds `count` samples of a signed distance field (m, negative inside) to the world's and
/// returns the index of the first in `first_out`: what an `MPM_COLLIDER_SHAPE_SDF` collider
/// names. Needs `MpmEffects::sdf_capacity` (`MPM_STATUS_EFFECT_NOT_DECLARED`); a sample not
/// finite is `MPM_STATUS_NON_FINITE_INPUT`, samples past the capacity
/// `MPM_STATUS_INVALID_CAPACITY` (checked before any is read).
///
/// # Safety
/// `world` is NULL or a world; `samples` is NULL or valid for reads of `count` values;
/// `first_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_add_distance_field(
    world: *mut MpmWorld,
    samples: *const mpm_real,
    count: usize,
    first_out: *mut u32,
) -> MpmStatus {
    guard(|| {
        non_null(samples)?;
        non_null(first_out)?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        let def = w.def();
        if def.effects.sdf_capacity == 0 {
            return Err(MpmStatus::EffectNotDeclared);
        }
        if count > def.effects.sdf_capacity as usize {
            return Err(MpmStatus::InvalidCapacity);
        }
        apart(w.as_bytes(), samples, count)?;
        apart(w.as_bytes(), first_out, 1)?;
        // SAFETY: non-NULL, valid for `count` reads (the caller), `count` bounded by the
        // capacity, and apart from the world.
        let values = unsafe { core::slice::from_raw_parts(samples, count) };
        let first = w.add_distance_field(values)?;
        // SAFETY: checked non-NULL.
        unsafe { put(first_out, first) };
        Ok(())
    })
}

/// Replaces collider `id`'s definition: a host moves a collider by setting its pose and
/// velocities between steps. Checked as `mpm_world_add_collider`;
/// `MPM_STATUS_UNKNOWN_COLLIDER` for an id not added.
///
/// # Safety
/// `world` is NULL or a world; `def` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_set_collider(
    world: *mut MpmWorld,
    id: u32,
    def: *const MpmColliderDef,
) -> MpmStatus {
    guard(|| {
        non_null(def)?;
        // SAFETY: checked non-NULL; the caller promises a valid definition.
        let c = collider_def_from_c(unsafe { &*def })?;
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        w.set_collider(id, &c)?;
        Ok(())
    })
}

/// Collider `id` as it is now, and the impulse, force and torque the material put on it over
/// the last step, into `state_out`; `MPM_STATUS_UNKNOWN_COLLIDER` for an id not added.
///
/// # Safety
/// `world` is NULL or a world; `state_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_get_collider(
    world: *const MpmWorld,
    id: u32,
    state_out: *mut MpmColliderState,
) -> MpmStatus {
    guard(|| {
        non_null(state_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), state_out, 1)?;
        let s = w.collider(id)?;
        let state = MpmColliderState {
            def: collider_def_to_c(&s.def),
            impulse: c_vec3(s.impulse),
            angular_impulse: c_vec3(s.angular_impulse),
            force: c_vec3(s.force()),
            torque: c_vec3(s.torque()),
            duration: s.duration,
        };
        // SAFETY: checked non-NULL.
        unsafe { put(state_out, state) };
        Ok(())
    })
}
