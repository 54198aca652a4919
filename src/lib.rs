//! # mpm-gimp
//!
//! A fixed-capacity, allocation-free kernel for the Generalized Interpolation Material Point
//! method (GIMP; Bardenhagen and Kober 2004, derived in Nairn's notes). A host hands it one
//! aligned block of memory, adds materials and particles, calls [`World::step`] once per frame
//! or sub-frame and reads particle state back through [`World::particles`].
//!
//! - `#![no_std]`, no heap: all state lives in the caller's buffer, sized by the pure function
//!   [`memory_requirements`]. A byte copy of [`World::as_bytes`] is a snapshot, and
//!   [`World::open`] checks one before use.
//! - Structure of arrays: one contiguous column per scalar component, for particles and nodes;
//!   the particle passes run on SSE2, AVX2 or AVX-512 (`wide-simd`, chosen at run time), bit
//!   for bit alike.
//! - 2D plane strain, 2D axisymmetric and 3D share one code path ([`Dimension`]); f32 by
//!   default, f64 with the `f64` feature.
//! - Shape functions ([`ShapeFunction`]): linear, uGIMP, cpGIMP, quadratic and cubic B-splines.
//!   Stress update order ([`UpdateOrder`]): USF, USL, MUSL. Transfers ([`Transfer`]): FLIP
//!   blended with PIC, FLIP moving with the particle velocity, APIC, MLS-MPM.
//! - Materials ([`MaterialModel`]): neo-Hookean, corotated linear and fixed-corotated
//!   elasticity; a weakly compressible fluid; J2 plasticity (metal), Drucker-Prager (sand)
//!   and snow, whose history column [`Effects::plasticity`] reserves; a Newtonian viscosity on
//!   any material.
//! - Effects, declared in [`Effects`] and paid for only when declared: grid, particle and PIC
//!   damping on schedules, a kinetic-energy thermostat, per-particle damping, zones of damping,
//!   particle forces, tractions on deformed faces of any normal, a body force, heat conduction
//!   and diffusion with thermal expansion and swelling.
//! - Every fallible call returns an [`Error`] and changes nothing; the step reports clamped,
//!   frozen and escaped particles in a [`StepReport`].
//! - A C interface (`mpm-gimp-ffi`, a cbindgen header) exposes all of it to C and C++ hosts.
//!
//! **Debug builds.** The step is written to be optimised: unoptimised, it measured about 170
//! times slower (benches/PERFORMANCE.md in the repository, "What a step costs", which also has
//! the release figures). Keep the kernel optimised in the host's debug profile:
//!
//! ```toml
//! [profile.dev.package.mpm-gimp]
//! opt-level = 3
//! ```
//!
//! ```
//! use mpm_gimp::{memory_requirements, HeapBuffer, MaterialDef, Vec3, World, WorldDef};
//!
//! let def = WorldDef { cells: [40, 40, 1], cell_size: 0.025, ..WorldDef::DEFAULT };
//! let req = memory_requirements(&def).unwrap();
//! // Any buffer of `req.bytes` aligned to `req.align` works; HeapBuffer is one (std only).
//! let mut storage = HeapBuffer::new(req.bytes);
//! let mut world = World::init(&def, storage.as_mut_bytes()).unwrap();
//! let rubber = world.add_material(&MaterialDef::DEFAULT).unwrap();
//! world
//!     .fill_box(Vec3::new(0.3, 0.3, 0.0), Vec3::new(0.7, 0.6, 0.0), rubber, Vec3::ZERO)
//!     .unwrap();
//! let report = world.step(1.0 / 60.0).unwrap();
//! assert!(report.substeps >= 1);
//! assert!(world.diagnostics().center_of_mass[1] < 0.45);
//! ```
//!
//! Symbols follow Nairn's GIMP notes: `S_ip`, `G_ip`, `m_i`, `p_i`, `f_i`, `tau/rho0`, `beta`.
//! Equation numbers in the documentation and comments, written `(E17)` or `eq E17`, refer to
//! `docs/equations.md` in the repository, which states each equation the code uses with its
//! source.
#![no_std]
#![deny(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]
// Small-matrix and per-axis loops index several arrays with one counter; iterator chains would
// hide the tensor notation the equations are written in.
#![allow(clippy::needless_range_loop)]

#[cfg(feature = "std")]
extern crate std;

mod boundary;
mod cut;
mod def;
mod effects;
mod error;
mod grid;
mod layout;
mod material;
pub mod math;
mod num;
mod particles;
mod phases;
pub mod shape;
#[doc(hidden)]
pub mod simd;
mod storage;
pub mod tasks;
mod world;

pub use cut::REACH_GROUP;
pub use def::{
    Boundary, Dimension, Face, FrictionFit, MaterialDef, MaterialModel, Resolvable, ShapeFunction,
    Transfer, UpdateOrder, WorldDef, MAX_FMPM_ORDER, MAX_HARDENING_COEFFICIENT, MAX_SUBSTEPS,
    MAX_TRANSFER_ORDER, MAX_WORKERS, MIN_STABLE_DT, PARALLEL_FROM,
};
pub use def::{
    ColliderDef, ColliderShape, Contact, Damping, DampingZone, Effects, Feedback, ScalarBoundary,
    ScalarField, Schedule, Transport, DAMPING_ZONES, SCHEDULE_POINTS, TRACTION_SCHEDULES,
};
pub use error::Error;
pub use layout::{memory_requirements, MemoryRequirements, ALIGN, CHUNK};
pub use particles::ParticleStatus;
pub use storage::AlignedBuffer;
#[cfg(feature = "std")]
pub use storage::HeapBuffer;
pub use tasks::{Serial, TaskSystem};
pub use world::{
    ColliderState, Diagnostics, ParticleBatch, ParticleDef, ParticleState, ParticlesView, Phase,
    Removal, StepReport, World, WorldRef,
};

/// The scalar type of every column, parameter and result: f32, or f64 with the `f64` feature.
#[cfg(not(feature = "f64"))]
pub type Real = f32;
/// The scalar type of every column, parameter and result: f32, or f64 with the `f64` feature.
#[cfg(feature = "f64")]
pub type Real = f64;

/// Three-component vector of [`Real`] used by definitions and fill helpers.
#[cfg(not(feature = "f64"))]
pub type Vec3 = glam::Vec3;
/// Three-component vector of [`Real`] used by definitions and fill helpers.
#[cfg(feature = "f64")]
pub type Vec3 = glam::DVec3;

/// The README's Rust example, compiled and run as a doctest so it stays true.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
