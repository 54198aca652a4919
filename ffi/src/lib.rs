//! C ABI for the `mpm-gimp` kernel: the library `libmpm_gimp.a` / `libmpm_gimp.so` and the
//! header `ffi/include/mpm_gimp.h` (generated from this crate by cbindgen).
//!
//! Where to find an entry point:
//! - [`status`]: `MpmStatus` and `mpm_status_string`.
//! - [`defs`]: `MpmWorldDef`, `MpmMaterialDef`, their `*_default()` functions and the enums.
//! - [`world`]: memory requirements, init, open, the world's bytes and definition, add
//!   material and particles, seeding, the displacement gradient, stable dt, step, and the
//!   instruction-set choice (`mpm_simd_use_*`); `mpm_abi_version` is at the crate root.
//! - [`particles`]: setting particles' position, velocity, affine matrix and material, or
//!   their whole state (`MpmParticleState`, also what particles are added with), and removing
//!   particles (by range, list, box or status).
//! - [`effects`]: the declared effects' data: per-particle forces and damping, tractions, the
//!   thermostat's alpha, temperatures, concentrations and their sources.
//! - [`read`]: the borrowed particle view, copy-out functions and diagnostics.
//! - [`colliders`]: `MpmColliderDef` and `mpm_collider_def_default` (`_f32` / `_f64`),
//!   `mpm_world_add_collider`, `mpm_world_add_distance_field`, `mpm_world_set_collider` (a
//!   new definition: how a host moves a collider) and `mpm_world_get_collider` (its state, and
//!   the impulse, force and torque the material put on it).
//! - [`tasks`]: the host's task system (`MpmTaskSystem`) and `mpm_world_step_tasks`.
//!
//! Conventions (Box2D v3 and rustls-ffi): inputs first, outputs last as `*_out`, every buffer
//! followed by its length, every pointer checked for NULL, no input array or output inside the
//! world's memory (`MPM_STATUS_OVERLAPPING_MEMORY`), nothing written and nothing changed on
//! failure. No panic crosses the boundary: every entry point catches unwinding and answers
//! `MPM_STATUS_INTERNAL` (a host that builds the crate with `panic = "abort"` gets an abort
//! instead).
//!
//! Threads: the library keeps no global state but the instruction-set choice of
//! `mpm_simd_use_*`. Separate worlds may be used from separate threads at once. On one world,
//! calls that take a `const MpmWorld *` may run at the same time as each other, never at the
//! same time as a call that takes an `MpmWorld *` (add, seed, set, step), and the pointers of
//! a particle view may not be read while such a call runs. The library starts no thread:
//! `mpm_world_step_tasks` runs one step on the host's threads, through its `MpmTaskSystem`.
//!
//! A world lives in memory the host owns: `mpm_world_init` lays it out there and hands back
//! the same address as an `MpmWorld *`. The library keeps no state of its own and never
//! allocates. Freeing the world is freeing that memory; a byte copy of `mpm_world_bytes` bytes
//! is a snapshot that `mpm_world_open` opens.
#![deny(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]
// C names on purpose: `mpm_real` is the header's scalar type.
#![allow(non_camel_case_types)]

// Declared in the order the header presents them.
pub mod defs;
pub mod effects;
pub mod read;
pub mod status;
pub mod world;
// After world: setting and removing particles.
pub mod particles;
// After world: the header declares the task system and the colliders after the world's calls.
pub mod colliders;
pub mod tasks;

pub use colliders::*;
pub use defs::*;
pub use effects::*;
pub use particles::*;
pub use read::*;
pub use status::*;
pub use tasks::*;
pub use world::*;

/// The scalar type of every real value: `float` (or `double` for the `f64` build, where the
/// header must be used with `MPM_GIMP_F64` defined).
#[cfg(not(feature = "f64"))]
pub type mpm_real = f32;
/// The scalar type of every real value: `float` (or `double` for the `f64` build, where the
/// header must be used with `MPM_GIMP_F64` defined).
#[cfg(feature = "f64")]
pub type mpm_real = f64;

const _: () = assert!(
    core::mem::size_of::<mpm_real>() == core::mem::size_of::<kernel::Real>(),
    "the kernel's precision differs from the C interface's: enable mpm-gimp-ffi/f64 (not \
     mpm-gimp/f64 alone) for the double-precision library"
);

/// Three components x, y, z (z ignored in 2D).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct MpmVec3 {
    /// x component.
    pub x: mpm_real,
    /// y component.
    pub y: mpm_real,
    /// z component.
    pub z: mpm_real,
}

/// Parses a decimal version component at compile time.
const fn parse_u32(s: &str) -> u32 {
    let b = s.as_bytes();
    let mut v = 0u32;
    let mut i = 0;
    while i < b.len() {
        v = v * 10 + (b[i] - b'0') as u32;
        i += 1;
    }
    v
}

/// ABI version of this library, from the crate version in Cargo.toml:
/// `major * 10000 + minor * 100 + patch`. The header's `MPM_GIMP_ABI_VERSION` is generated from
/// the same numbers.
pub const ABI_VERSION: u32 = parse_u32(env!("CARGO_PKG_VERSION_MAJOR")) * 10000
    + parse_u32(env!("CARGO_PKG_VERSION_MINOR")) * 100
    + parse_u32(env!("CARGO_PKG_VERSION_PATCH"));

/// The library's ABI version; a host compares it with `MPM_GIMP_ABI_VERSION` from the header
/// it was compiled against.
#[no_mangle]
pub extern "C" fn mpm_abi_version() -> u32 {
    ABI_VERSION
}

/// Runs `f`, turning an error into its status and a panic (in builds that unwind) into
/// `MPM_STATUS_INTERNAL`: nothing unwinds into C.
pub(crate) fn guard(f: impl FnOnce() -> Result<(), MpmStatus>) -> MpmStatus {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(Ok(())) => MpmStatus::Ok,
        Ok(Err(s)) => s,
        Err(_) => MpmStatus::Internal,
    }
}

/// `Err(NullPointer)` if `p` is NULL.
pub(crate) fn non_null<T>(p: *const T) -> Result<(), MpmStatus> {
    if p.is_null() {
        Err(MpmStatus::NullPointer)
    } else {
        Ok(())
    }
}

/// `Err(OverlappingMemory)` if the `count` values of `T` at `p` (an input array or an output
/// of the call; NULL or empty: nothing) share a byte with the world's memory `world`. Checked
/// before an input slice is formed or an output written, so that no call reads its input
/// from, or writes its output into, the memory it works on.
pub(crate) fn apart<T>(world: &[u8], p: *const T, count: usize) -> Result<(), MpmStatus> {
    let (start, bytes) = (p as usize, count.saturating_mul(core::mem::size_of::<T>()));
    let (w_start, w_end) = (
        world.as_ptr() as usize,
        world.as_ptr() as usize + world.len(),
    );
    if p.is_null() || bytes == 0 || start >= w_end || start.saturating_add(bytes) <= w_start {
        Ok(())
    } else {
        Err(MpmStatus::OverlappingMemory)
    }
}
