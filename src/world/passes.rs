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

use crate::cut::{REACH_GROUP, SLOTS_PER_WORKER};
use crate::grid::{Geom, GridCols, NodeBox};
use crate::layout::CHUNK;
use crate::particles::{ParticleCols, RemapCols, StepReport};
use crate::phases::kernels::Kernels;
use crate::phases::p2g::{self, rows, Adds, Mode};
use crate::phases::{g2p, stress, transport, Ctx};
use crate::shape::Shape1D;
use crate::simd::{with_instance, Simd};
use crate::tasks::{self, Shared, TaskSystem};
use crate::Real;
use core::ops::Range;

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
        g: &GridCols<'_, D>,
        remap: &mut GridCols<'_, D>,
        report: &mut StepReport,
    ) => g2p::particles;

    /// [`g2p::remap`]: MUSL's re-map of particles another item of the parallel step updated,
    /// and XPIC's projection.
    fn remap [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &RemapCols<'_, D>,
        count: usize,
        from: &GridCols<'_, D>,
        remap: &mut GridCols<'_, D>,
    ) => g2p::remap;

    /// [`crate::phases::stress::stress`].
    fn stress [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &GridCols<'_, D>,
        report: &mut StepReport,
    ) => stress::stress;

    /// [`transport::particles`]: one particle loop of heat conduction or diffusion.
    fn transport [const D: usize, const K: usize, S: Shape1D<K>, const W: usize] [I] [D, K, S, W] (
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &ParticleCols<'_, D>,
        count: usize,
        f: usize,
        pass: transport::FieldPass<'_, '_, D>,
    ) => transport::particles;

    /// [`NodeBox::first_nodes`] and the reach table ([`crate::grid::first_nodes`]).
    fn first_nodes [const D: usize, const K: usize, S: Shape1D<K>] [] [D, K, S] (
        geom: &Geom<D>,
        x: &[&[Real]; D],
        status: &[u32],
        count: usize,
        reach: &mut [[u32; 2]],
    ) -> ([i32; D], [i32; D]) => crate::grid::first_nodes;

    /// [`crate::particles::fastest_squared`].
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
/// ([`crate::simd::Isa::FULL_ROWS`], the baseline), which has two: every scatter but USF's
/// force scatter runs the full row configuration (mass, momentum with APIC's affine part,
/// force), what it does not add entering as products left zero
/// ([`crate::simd::row_sums::Products::set`]): finite factors times zero. Those zeros change no
/// bit of the grid: x + 0 is x for every x but -0, and a column they reach holds its reset +0
/// plus sums, which are -0 only if every term is, so it ends the same either way. USF's force
/// scatter keeps its own rows: it runs after the grid velocities are formed, and a zero added
/// to a velocity of -0 would make it +0. Every instance on full rows would have saved a fifth
/// of the build, but made the USF step 1.2 to 1.5 times as long in 3D (benches/PERFORMANCE.md).
///
/// MUSL's re-map scatter is part of the particle pass (`g2p::particles`, and `g2p::remap` for
/// the particles another item of the parallel step updated), never a scatter of its own.
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
        (All | Remap, false) => {
            I::scatter::<D, K, S, W, { rows(All, false) }>(shape, ctx, p, count, g, adds)
        }
        (All | Remap, true) => {
            I::scatter::<D, K, S, W, { rows(All, true) }>(shape, ctx, p, count, g, adds)
        }
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
    }
}

/// The task system the scans of the particles below run on, and the workers they are cut
/// for ([`tasks::reduce`]: four ranges per worker).
pub(crate) struct Scan<'t> {
    pub tasks: &'t dyn TaskSystem,
    pub workers: usize,
}

impl Scan<'_> {
    fn cut(&self, n: usize) -> (usize, usize, usize) {
        (n, SLOTS_PER_WORKER * self.workers, CHUNK)
    }
}

/// The node box of a substep ([`NodeBox::of_first_nodes`]), scanned in the instruction set
/// `simd` on `scan`'s task system: the ranges' first nodes merge by `min` and `max`, so the
/// box is one worker's.
pub(crate) fn node_box<const D: usize, const K: usize, S: crate::shape::Shape1D<K>>(
    simd: Simd,
    scan: &Scan<'_>,
    geom: &Geom<D>,
    x: &[&[Real]; D],
    status: &[u32],
    count: usize,
    reach: Option<&Shared<'_, [u32; 2]>>,
) -> NodeBox<D> {
    let count = x
        .iter()
        .fold(count.min(status.len()), |n, c| n.min(c.len()));
    let none = ([i32::MAX; D], [i32::MIN; D]);
    // Whole groups of the reach table per range.
    let (n, parts, _) = scan.cut(count);
    let cut = (n, parts, REACH_GROUP);
    let merge = |a: ([i32; D], [i32; D]), b: ([i32; D], [i32; D])| {
        (
            core::array::from_fn(|k| a.0[k].min(b.0[k])),
            core::array::from_fn(|k| a.1[k].max(b.1[k])),
        )
    };
    // The instance is picked here, on the calling thread, once: the ranges call it.
    let (lo, hi) = with_instance!(simd, form (D, K), I => {
        let range = |r: Range<usize>| {
            let x = x.each_ref().map(|c| &c[r.clone()]);
            let status = &status[r.clone()];
            // The ranges are whole groups.
            let groups = r.start / REACH_GROUP..r.end.div_ceil(REACH_GROUP);
            // SAFETY: the ranges of distinct items are disjoint, and so are their groups.
            let out = reach.map_or(&mut [][..], |t| unsafe { t.window(groups) });
            I::first_nodes::<D, K, S>(geom, &x, status, r.len(), out)
        };
        tasks::reduce(scan.tasks, cut, none, &range, merge)
    });
    NodeBox::of_first_nodes::<K>(geom, lo, hi)
}

/// The least plastic history of the active particles of material `m`
/// ([`crate::particles::least_plastic`]), scanned in the instruction set `simd` on `scan`'s
/// task system (a minimum: the same for any cut).
pub(crate) fn least_plastic(
    simd: Simd,
    scan: &Scan<'_>,
    plastic: &[Real],
    material: &[u32],
    status: &[u32],
    m: u32,
) -> Real {
    let n = status.len().min(plastic.len()).min(material.len());
    let least = |a: Real, b: Real| if b < a { b } else { a };
    // The instance is picked here, on the calling thread, once: the ranges call it.
    with_instance!(simd, I => {
        let range = |r: Range<usize>| {
            let (p, mat, st) = (&plastic[r.clone()], &material[r.clone()], &status[r]);
            I::least_plastic(p, mat, st, m)
        };
        tasks::reduce(scan.tasks, scan.cut(n), Real::INFINITY, &range, least)
    })
}

/// The largest squared speed of the active particles ([`crate::particles::fastest_squared`]),
/// scanned in the instruction set `simd` on `scan`'s task system (a maximum: the same for any
/// cut).
pub(crate) fn fastest_squared(
    simd: Simd,
    scan: &Scan<'_>,
    v: &[&[Real]; 3],
    status: &[u32],
    d: usize,
) -> f64 {
    let n = v.iter().take(d).fold(status.len(), |n, c| n.min(c.len()));
    // The instance is picked here, on the calling thread, once: the ranges call it.
    with_instance!(simd, I => {
        let range = |r: Range<usize>| {
            let v = v.each_ref().map(|c| c.get(r.clone()).unwrap_or(&[]));
            I::fastest_squared(&v, &status[r], d)
        };
        tasks::reduce(scan.tasks, scan.cut(n), 0.0, &range, f64::max)
    })
}
