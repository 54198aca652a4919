//! The chunk kernels a pass calls out of line, compiled once per instance
//! ([`crate::simd::instances!`]): each is called once per chunk, a function of its own so that a
//! pass does not hold a copy of each kind it may run (and the optimiser's time stays in
//! proportion to the functions' sizes). The passes are generic over [`Kernels`]; the substep
//! calls the passes through the table of the floor above (`world::passes`).

// A kernel takes the chunk's arrays: eight arguments for the stencils, which every pass
// already holds apart.
#![allow(clippy::too_many_arguments)]

use super::{gather, Ctx};
use crate::grid::GridCols;
use crate::layout::MaterialRecord;
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{Lane, Lanes};
use crate::simd::Isa;

crate::simd::instances! {
    /// The chunk kernels of one instance; a pass generic over it calls them as `I::gather(..)`.
    trait Kernels: Isa;

    /// [`gather::gather_chunk`]: one chunk's gather, a function of its own, so that a pass does
    /// not hold a copy of each of the gather's kinds it may run.
    fn gather [
        const D: usize, const K: usize, S: Shape1D<K>, const W: usize,
        const VEL: bool, const GRAD: u8, const MOMENTS: bool
    ] [I] [D, K, S, W, VEL, GRAD, MOMENTS] (
        ctx: &Ctx<'_, D>,
        g: &GridCols<'_, D>,
        st: &Stencils<D, K, W>,
        affine: &mut [[Lane<W>; D]; D],
        out: &mut gather::Gathered<D, W>,
    ) => gather::gather_chunk;

    /// [`super::stencils_of`]: one chunk's stencils, for the transport and momentum passes
    /// and MUSL's re-map of particles another item updated (one function rather than a copy
    /// of the three families' code in each). The scatter, particle and stress passes inline
    /// theirs: called out of line they made the default step 1.03 to 1.05 times as long
    /// (benches/PERFORMANCE.md, "Decisions").
    fn stencils [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        st: &mut Stencils<D, K, W>,
        shape: &S,
        ctx: &Ctx<'_, D>,
        stretch: &[&[crate::Real]; D],
        start: usize,
        x: &[Lane<W>; D],
        affine: bool,
        lanes: bool,
        mls: bool,
    ) => crate::phases::stencils_of;

    /// [`crate::simd::row_sums::scatter_chunk`]: one chunk's scatter with the row
    /// configuration `MODE` (the particle pass's re-map).
    fn scatter_chunk [const D: usize, const K: usize, S: Shape1D<K>, const W: usize, const MODE: u8]
        [I] [D, K, S, W, MODE] (
        st: &mut Stencils<D, K, W>,
        pr: &crate::simd::row_sums::Products<D, W>,
        live: Lanes<W>,
        stride: [usize; D],
        g: &mut GridCols<'_, D>,
        adds: crate::simd::row_sums::Adds,
    ) => crate::simd::row_sums::scatter_chunk;

    /// [`crate::material::chunk_lanes`]: one chunk's material update (the inelastic part,
    /// then the stress) when its lanes share one material, a function of its own per
    /// dimension, rather than a copy of every model in each pass that updates the stress (it
    /// made the C host 0.36 MB larger).
    fn material [const D: usize, const W: usize] [I] [D, W] (
        rec: &MaterialRecord,
        h: &mut [[Lane<W>; D]; D],
        hzz: &mut Lane<W>,
        jm1: &mut Lane<W>,
        plastic: &mut Lane<W>,
        hoop: bool,
        eigen: Option<&Lane<W>>,
        tau: &mut [Lane<W>; 6],
    ) => crate::material::chunk_lanes;
}
