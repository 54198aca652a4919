//! C ABI for the `mpm-gimp` kernel.
//!
//! Placeholder: the C interface (cbindgen header, static and shared libraries, C and C++ hosts)
//! is built on top of the kernel's Rust API in a later step. This crate exists now so that the
//! workspace layout is final and the kernel is already checked to build for it.
#![no_std]

/// ABI version of the C interface; bumped on every incompatible change.
pub const MPM_ABI_VERSION: u32 = 0;
