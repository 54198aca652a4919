//! The passes of a substep, compiled once per instance ([`crate::simd::instances!`]): each pass
//! is one function per instance with the pass's code inlined into it, so that the AVX2 instance
//! compiles all of it with AVX2 (the AVX-512 one with AVX-512) and every pass keeps its own
//! register allocation (one function for a whole substep measured about 10 % slower). The
//! transported scalars' substep (heat, diffusion) is one such function too, and so are the two
//! scans of the particles before a substep (the node box, the fastest particle for
//! `stable_dt`); the node passes (grid update) are short loops and run in the baseline
//! instance. The passes call their chunk kernels through the table of the floor below
//! ([`crate::phases::kernels`]).

// A pass takes the substep's columns and context.
#![allow(clippy::too_many_arguments)]

use crate::def::Transport;
use crate::grid::{Geom, GridCols, NodeBox};
use crate::particles::{ParticleCols, StepReport};
use crate::phases::kernels::Kernels;
use crate::phases::p2g::{self, rows, Adds, Mode};
use crate::phases::{g2p, stress, transport, Ctx};
use crate::shape::Shape1D;
use crate::simd::{with_instance, Simd};
use crate::Real;

crate::simd::instances! {
    /// The passes of one instance; a substep generic over it calls them as `I::particles(..)`.
    trait Passes: Kernels;

    /// [`p2g::scatter_rows`]: the scatter pass with the row configuration `MODE`
    /// ([`p2g::rows`]); [`scatter`] picks it.
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

    /// [`crate::world::fastest_squared`].
    fn fastest_squared [] [] [] (v: &[&[Real]; 3], status: &[u32], d: usize) -> f64
        => crate::particles::fastest_squared;

    /// [`crate::particles::least_plastic`].
    fn least_plastic [] [] [] (plastic: &[Real], material: &[u32], status: &[u32], m: u32) -> Real
        => crate::particles::least_plastic;
}

/// Scatters the active particles `0..count` to the grid, accumulating what `adds` says, in
/// the instance `I`: picks the scatter function compiled for the row configuration ([`rows`]).
///
/// An instance has five per form, one per configuration, except one compiled for size
/// ([`crate::simd::Isa::FULL_ROWS`], the baseline), which has two: every scatter but USF's force scatter
/// runs the full row configuration (mass, momentum with APIC's affine part, force), what it
/// does not add entering as products left zero ([`Products::set`]): finite factors times
/// zero. Those zeros change no bit of the grid: x + 0 is x for every x but -0, and a column
/// they reach holds its reset +0 plus sums, which are -0 only if every term is, so it ends the
/// same either way. USF's force scatter keeps its own rows: it runs after the grid velocities
/// are formed, and a zero added to a velocity of -0 would make it +0. Every instance on full
/// rows would have saved a fifth of the build, but made the USF step 1.2 to 1.5 times as long
/// in 3D (benches/PERFORMANCE.md).
///
/// The re-map scatter (MUSL) is part of the particle pass (`g2p::particles`), which scatters
/// chunk by chunk.
pub(crate) fn scatter<I: Passes, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
    adds: Adds,
) {
    use Mode::*;
    // Branches on the constant alone, so that an instance compiles only the functions it
    // calls.
    if I::FULL_ROWS {
        if adds.mode == Force {
            I::scatter::<D, K, S, W, { rows(Force, false) }>(shape, ctx, p, count, g, adds)
        } else {
            I::scatter::<D, K, S, W, { rows(All, true) }>(shape, ctx, p, count, g, adds)
        }
        return;
    }
    match (adds.mode, adds.apic) {
        (All, false) => {
            I::scatter::<D, K, S, W, { rows(All, false) }>(shape, ctx, p, count, g, adds)
        }
        (All, true) => I::scatter::<D, K, S, W, { rows(All, true) }>(shape, ctx, p, count, g, adds),
        (MassMomentum, false) => {
            I::scatter::<D, K, S, W, { rows(MassMomentum, false) }>(shape, ctx, p, count, g, adds)
        }
        (MassMomentum, true) => {
            I::scatter::<D, K, S, W, { rows(MassMomentum, true) }>(shape, ctx, p, count, g, adds)
        }
        // A force scatter carries no momentum (`Adds::of`).
        (Force, _) => {
            I::scatter::<D, K, S, W, { rows(Force, false) }>(shape, ctx, p, count, g, adds)
        }
        (Remap, _) => debug_assert!(false, "the re-map scatter is the particle pass's"),
    }
}

/// The node box of a substep ([`NodeBox::of_particles`]), scanned in the instruction set
/// `simd`.
pub(crate) fn node_box<const D: usize, const K: usize, S: crate::shape::Shape1D<K>>(
    simd: Simd,
    geom: &Geom<D>,
    x: &[&[Real]; D],
    status: &[u32],
    count: usize,
) -> NodeBox<D> {
    with_instance!(simd, form (D, K), I => I::node_box::<D, K, S>(geom, x, status, count))
}

/// The least plastic history of the active particles of material `m`
/// ([`crate::particles::least_plastic`]), scanned in the instruction set `simd`.
pub(crate) fn least_plastic(
    simd: Simd,
    plastic: &[Real],
    material: &[u32],
    status: &[u32],
    m: u32,
) -> Real {
    with_instance!(simd, I => I::least_plastic(plastic, material, status, m))
}

/// The largest squared speed of the active particles ([`crate::world::fastest_squared`]),
/// scanned in the instruction set `simd`.
pub(crate) fn fastest_squared(simd: Simd, v: &[&[Real]; 3], status: &[u32], d: usize) -> f64 {
    with_instance!(simd, I => I::fastest_squared(v, status, d))
}
