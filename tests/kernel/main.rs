//! The kernel's integration tests, through its public API, in one test binary (a binary per
//! file linked the kernel once each, which made the test build several times slower). Each
//! module states what it checks; `cargo test --release --test kernel -- <module>::` runs one.
//! (`tests/simd_override.rs` stays a binary of its own: it switches the process-wide
//! instruction-set override.) Equation numbers such as `(E17)` refer to `docs/equations.md`.

#[path = "../common/mod.rs"]
mod common;

#[cfg(feature = "effects")]
mod accuracy;
mod api_contract;
#[cfg(feature = "effects")]
mod axisymmetric;
#[cfg(feature = "effects")]
mod colliders;
mod conservation;
#[cfg(feature = "effects")]
mod contact_work;
#[cfg(feature = "effects")]
mod dynamic_colliders;
#[cfg(feature = "effects")]
mod effects;
#[cfg(feature = "effects")]
mod eigenstrain;
#[cfg(feature = "effects")]
mod equilibrium;
mod hard_cases;
mod initial_state;
#[cfg(feature = "effects")]
mod materials;
#[cfg(feature = "effects")]
mod particle_state;
mod periodic;
#[cfg(feature = "effects")]
mod precision;
mod reference;
mod reliability;
mod removal;
mod robustness;
mod threads;
#[cfg(feature = "effects")]
mod transport;
mod verification;
