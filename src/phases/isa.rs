//! The particle passes of a substep, instantiated once per instruction set (see
//! [`crate::simd`]). Each pass is one function per instance, with the pass's code inlined into
//! it, so that the AVX2 instance compiles all of it with AVX2 (the AVX-512 one with AVX-512)
//! and every pass keeps its own register allocation (one function for a whole substep measured
//! about 10 % slower). The transported scalars' substep (heat, diffusion) is one such function
//! too. The two scans of the particles before a substep (the node box, the fastest particle
//! for `stable_dt`) are instanced the same way; the node passes (grid update) are short loops
//! and run in the baseline instance.
//!
//! Functions are kept to a size the optimiser handles in proportion: its time grows faster
//! than a function's size (loop rotation, full unrolling and value numbering over one large
//! body). So the scatter is one function per row configuration ([`p2g::rows`]), and a chunk's
//! gather and the particle pass's re-map scatter are functions of their own, called once per
//! chunk: the same code as one function per pass took 3 min 11 s to build with one codegen
//! unit, against 2 min 30 s split (benches/PERFORMANCE.md).

// A pass takes the substep's columns and context, a chunk kernel the chunk's arrays: eight
// arguments for the stencils, which every pass already holds apart.
#![allow(clippy::too_many_arguments)]

use super::{g2p, p2g, row_sums, stress, transport, Ctx};
use crate::def::Transport;
use crate::grid::{Geom, GridCols, NodeBox};
use crate::layout::MaterialRecord;
use crate::particles::ParticleCols;
use crate::particles::StepReport;
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{Lane, Lanes};
use crate::simd::rows::Compare;
use crate::simd::Baseline;
#[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
use crate::simd::{Avx2, Avx512};
use crate::Real;

/// One instance of the passes compiled with more instruction-set features: the type that
/// implements [`Isa`] and the module of `#[target_feature]` functions it calls (the passes are
/// `#[inline(always)]`, so their whole code is compiled there).
macro_rules! wide {
    (
        $(#[$tdoc:meta])* $isa:ident, $module:ident, $features:literal;
        $(
            $(#[$doc:meta])*
            fn $name:ident [$($generics:tt)*] [$($inst:ident)?] [$($garg:ident),*]
                ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $($target:ident)::+;
        )*
    ) => {
        $(#[$tdoc])*
        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        impl Isa for $isa {
            const FULL_ROWS: bool = false;

            $(
                #[inline(always)]
                fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)? {
                    // SAFETY: this instance is only chosen when the CPU and the OS support its
                    // features (`crate::simd::Simd::instance`).
                    unsafe { $module::$name::<$($garg),*>($($arg),*) }
                }
            )*
        }

        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        mod $module {
            use super::*;
            $(
                // Never inlined into the pass that calls it (a chunk kernel is called per
                // chunk): LLVM's time grows faster than a function's size.
                #[inline(never)]
                #[target_feature(enable = $features)]
                pub(super) fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)? {
                    // The instance, for the passes that take it ([`super::crate::simd::rows::Rows`]).
                    #[allow(dead_code)]
                    type I = $isa;
                    $($target)::+::<$($inst,)? $($garg),*>($($arg),*)
                }
            )*
        }
    };
}

/// Declares the [`Isa`] trait with one method per pass, and its implementations: the baseline
/// one (each pass its own function), the AVX2 one and, with the `avx512` feature, the AVX-512
/// one (each pass compiled in a `#[target_feature]` function, [`wide!`]). Each pass is written
/// once, here, by its signature; a pass that reads stencil rows lane-major says `[I]` and takes the instance as
/// its first type argument (its [`crate::simd::rows::Rows`]).
macro_rules! passes {
    ($(
        $(#[$doc:meta])*
        fn $name:ident [$($generics:tt)*] [$($inst:ident)?] [$($garg:ident),*]
            ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $($target:ident)::+;
    )*) => {
        /// One set of particle passes; [`crate::world`] calls a substep's passes through it.
        pub(crate) trait Isa: Compare {
            $($(#[$doc])* fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)?;)*

            /// Whether the instance scatters on the full row configuration
            /// ([`p2g::scatter`]: two scatter functions per form rather than five).
            const FULL_ROWS: bool;
        }

        impl Isa for Baseline {
            // The fallback for CPUs without AVX2 (and the instance valgrind and the fuzzer
            // run) is compiled for size.
            const FULL_ROWS: bool = true;

            $(
                #[inline(never)]
                fn $name<$($generics)*>($($arg: $ty),*) $(-> $ret)? {
                    // The instance, for the passes that take it ([`crate::simd::rows::Rows`]).
                    #[allow(dead_code)]
                    type I = Baseline;
                    $($target)::+::<$($inst,)? $($garg),*>($($arg),*)
                }
            )*
        }

        wide! {
            /// AVX and AVX2 (x86-64). Chosen only when the CPU supports them
            /// ([`crate::simd::Instance::Avx2`]).
            Avx2, avx2, "avx,avx2";
            $($(#[$doc])* fn $name [$($generics)*] [$($inst)?] [$($garg),*] ($($arg: $ty),*)
                $(-> $ret)? => $($target)::+;)*
        }
        wide! {
            /// AVX-512 F, VL, BW and DQ (x86-64). Chosen only when the CPU supports them
            /// ([`crate::simd::Instance::Avx512`]).
            Avx512, avx512, "avx,avx2,avx512f,avx512vl,avx512bw,avx512dq";
            $($(#[$doc])* fn $name [$($generics)*] [$($inst)?] [$($garg),*] ($($arg: $ty),*)
                $(-> $ret)? => $($target)::+;)*
        }
    };
}

passes! {
    /// [`p2g::scatter_rows`]: the scatter pass with the row configuration `MODE`
    /// ([`p2g::rows`]); [`p2g::scatter`] picks it.
    fn scatter [const D: usize, const K: usize, S: Shape1D<K>, const W: usize, const MODE: u8]
        [I] [D, K, S, W, MODE] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &ParticleCols<'_, D>,
        count: usize,
        g: &mut GridCols<'_, D>,
        adds: p2g::Adds,
    ) => p2g::scatter_rows;

    /// [`g2p::particles`].
    fn particles [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &mut GridCols<'_, D>,
        report: &mut StepReport,
    ) => g2p::particles;

    /// [`g2p::stress`].
    fn stress [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &GridCols<'_, D>,
        report: &mut StepReport,
    ) => stress::stress;

    /// [`transport::substep`] (heat conduction or diffusion, one field).
    fn transport [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &mut GridCols<'_, D>,
        f: usize,
        t: &Transport,
    ) => transport::substep;

    /// [`NodeBox::of_particles`] ([`crate::grid::node_box`]).
    fn node_box [const D: usize, const K: usize, S: Shape1D<K>] [] [D, K, S] (
        geom: &Geom<D>,
        x: &[&[Real]; D],
        status: &[u32],
        count: usize,
    ) -> NodeBox<D> => crate::grid::node_box;

    /// [`g2p::gather_chunk`]: one chunk's gather, a function of its own, so that a pass does
    /// not hold a copy of each of the gather's kinds it may run.
    fn gather [
        const D: usize, const K: usize, S: Shape1D<K>, const W: usize,
        const VEL: bool, const GRAD: u8, const MOMENTS: bool
    ] [I] [D, K, S, W, VEL, GRAD, MOMENTS] (
        ctx: &Ctx<'_, D>,
        g: &GridCols<'_, D>,
        st: &Stencils<D, K, W>,
        affine: &mut [[Lane<W>; D]; D],
        out: &mut g2p::Gathered<D, W>,
    ) => g2p::gather_chunk;

    /// [`super::stencils`]: one chunk's stencils (every pass computes them; one function
    /// rather than a copy of the three families' code in each pass).
    fn stencils [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [] [D, K, S, W] (
        st: &mut Stencils<D, K, W>,
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &ParticleCols<'_, D>,
        start: usize,
        x: &[Lane<W>; D],
        affine: bool,
        lanes: bool,
        mls: bool,
    ) => crate::phases::stencils;

    /// [`p2g::scatter_chunk`]: one chunk's scatter with the row configuration `MODE` (the
    /// particle pass's re-map).
    fn scatter_chunk [const D: usize, const K: usize, S: Shape1D<K>, const W: usize, const MODE: u8]
        [I] [D, K, S, W, MODE] (
        st: &mut Stencils<D, K, W>,
        pr: &p2g::Products<D, W>,
        live: Lanes<W>,
        stride: [usize; D],
        g: &mut GridCols<'_, D>,
        adds: p2g::Adds,
    ) => row_sums::scatter_chunk;

    /// [`crate::material::kirchhoff_lanes`]: one chunk's stress from its deformation, a
    /// function of its own per dimension, rather than a copy of every model in each pass that
    /// updates the stress (it made the C host 0.36 MB larger).
    fn kirchhoff [const D: usize, const W: usize] [] [D, W] (
        rec: &MaterialRecord,
        h: &[[Lane<W>; D]; D],
        hzz: &Lane<W>,
        jm1: &Lane<W>,
        plastic: &Lane<W>,
        tau: &mut [Lane<W>; 6],
    ) => crate::material::kirchhoff_lanes;

    /// [`crate::material::inelastic_lanes`]: the inelastic part of one chunk's material
    /// update (return mapping, projection), a function of its own as the stress is.
    fn inelastic [const D: usize, const W: usize] [] [D, W] (
        rec: &MaterialRecord,
        h: &mut [[Lane<W>; D]; D],
        hzz: &mut Lane<W>,
        jm1: &mut Lane<W>,
        plastic: &mut Lane<W>,
        hoop: bool,
    ) => crate::material::inelastic_lanes;

    /// [`crate::world::fastest_squared`].
    fn fastest_squared [] [] [] (v: &[&[Real]; 3], status: &[u32], d: usize) -> f64
        => crate::particles::fastest_squared;
}
