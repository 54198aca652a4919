//! The substep's passes on the host's task system ([`crate::tasks`]), bit-identical to one
//! worker's for any number of workers.
//!
//! - **Particle passes** (the particle update, the stress update, a transported field's
//!   update): items are ranges of whole
//!   chunks, each with a window of the particle columns of its own ([`ParticleCols::carve_window`])
//!   and the grid to read. A particle's update reads only its own values and the grid, so
//!   it computes the same bits in any item. Each item leaves its part of the report in a slot
//!   of the world's scratch ([`Partial`]); the step merges them in item order, which is
//!   particle order, as one worker fills it.
//! - **Scatter**: the grid is cut into tiles, slabs of whole lines along the slowest axis
//!   ([`Tile`]). A tile takes, in particle order, every chunk whose stencils reach its slab
//!   and adds the rows in its slab alone: each node receives the same values in the same
//!   order as from one worker's scatter, so every sum has the same bits. A row of a slab's
//!   last line may add zeros to the first entries of the next line (a 4-wide row of a
//!   3-node stencil at the end of its line): so the even tiles run, then the odd ones, and no
//!   two neighbours ever run at once.
//! - MUSL's re-map, which one worker scatters in the particle pass, is a scatter of its own
//!   here (`p2g::scatter_rows` in `Mode::Remap`): the same rows from the stencils where the
//!   substep started. Heat and diffusion's two scatters take tiles too, their flow's reading
//!   the nodal values whole as the momentum approach's force reads the masses ([`Whole`]).
//!
//! Races are ruled out by construction: every item's mutable view is carved from a window
//! no other item of the same pass touches (particle ranges, tiles of one colour with a line
//! between them), and what items share they only read. The walls, the tractions and a
//! transported field's nodal values and rates run on the calling thread.

use super::passes::{self, Passes};
use crate::def::Transport;
use crate::grid::{GridCols, Tile, Whole};
use crate::layout::{ColliderImpulse, Layout, Partial, CHUNK};
use crate::particles::{ParticleCols, StepReport};
use crate::phases::grid_update::Nodes;
use crate::phases::p2g::{Adds, Mode};
use crate::phases::transport::{self, FieldPass};
use crate::phases::Ctx;
use crate::shape::{Shape1D, ROW};
use crate::tasks::{self, Shared, TaskSystem};

/// The columns of a substep and the task system its passes run on: views carved on demand,
/// the whole of them ([`Columns::full`]) or the windows of a parallel pass's items.
pub(crate) struct Columns<'b, const D: usize> {
    particles: Shared<'b, u8>,
    grid: Shared<'b, u8>,
    partials: Shared<'b, Partial>,
    /// The grid lines each group of particles reaches ([`GridCols::reach`]), filled with the
    /// node box.
    reach: Shared<'b, [u32; 2]>,
    /// The colliders' impulses of the step (the grid update adds to them).
    impulses: &'b mut [ColliderImpulse],
    layout: &'b Layout,
    tasks: &'b dyn TaskSystem,
    /// Workers the passes are cut for: 1 runs every pass as one call on the calling thread.
    workers: usize,
}

impl<'b, const D: usize> Columns<'b, D> {
    /// The particle region, the grid region and the scratch of a world's buffer.
    pub fn new(
        particles: &'b mut [u8],
        grid: &'b mut [u8],
        scratch: &'b mut [u8],
        impulses: &'b mut [ColliderImpulse],
        layout: &'b Layout,
        tasks: &'b dyn TaskSystem,
    ) -> Self {
        let (slots, groups) = (layout.scratch_slots, layout.reach_groups);
        let (partials, reach) = scratch.split_at_mut(slots * size_of::<Partial>());
        let partials: &mut [Partial] = bytemuck::cast_slice_mut(partials);
        let reach: &mut [[u32; 2]] =
            bytemuck::cast_slice_mut(&mut reach[..groups * size_of::<[u32; 2]>()]);
        let workers = if slots == 0 {
            1
        } else {
            tasks
                .worker_count()
                .clamp(1, slots / crate::layout::SLOTS_PER_WORKER)
        };
        Columns {
            particles: Shared::new(particles),
            grid: Shared::new(grid),
            partials: Shared::new(partials),
            reach: Shared::new(reach),
            impulses,
            layout,
            tasks,
            workers,
        }
    }

    /// Every node column.
    pub fn grid(&mut self) -> GridCols<'_, D> {
        self.full().1
    }

    /// How the scans of the particles are cut ([`passes::Scan`]).
    pub fn scan(&self) -> passes::Scan<'b> {
        passes::Scan {
            tasks: self.tasks,
            workers: self.workers,
        }
    }

    /// The node box of the substep ([`passes::node_box`]), and with it the lines each group
    /// of particles reaches where the scatter runs in tiles.
    pub fn node_box<const K: usize, S: Shape1D<K>>(
        &mut self,
        simd: crate::simd::Simd,
        geom: &crate::grid::Geom<D>,
        count: usize,
    ) -> crate::grid::NodeBox<D> {
        let scan = self.scan();
        // SAFETY: `&mut self` excludes every other view; the reach table is written by the
        // scan's ranges, each its own groups.
        let p = unsafe { ParticleCols::carve_window(&self.particles, self.layout, 0..usize::MAX) };
        let reach = (self.workers > 1).then_some(&self.reach);
        let x = p.x.each_ref().map(|c| &**c);
        passes::node_box::<D, K, S>(simd, &scan, geom, &x, p.status, count, reach)
    }

    /// Every particle and node column.
    pub fn full(&mut self) -> (ParticleCols<'_, D>, GridCols<'_, D>) {
        // SAFETY: `&mut self` excludes every other view: the parallel passes carve theirs
        // inside calls that take `&mut self` and drop them before returning.
        unsafe {
            (
                ParticleCols::carve_window(&self.particles, self.layout, 0..usize::MAX),
                GridCols::carve_tile(&self.grid, self.layout, Tile::ALL),
            )
        }
    }

    /// The scatter of the particles `0..count` that `adds` says ([`passes::scatter`]), by
    /// tiles of the grid where there are several workers.
    pub fn scatter<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
        adds: Adds,
    ) {
        // The momentum approach's force reads the masses of every stencil node, past its tile
        // too.
        let whole = (ctx.momentum && adds.mode == Mode::Force).then_some(Whole::Mass);
        self.scatter_tiles(ctx, whole, &|p, g| {
            passes::scatter::<I, D, K, S, W>(shape, ctx, p, count, g, adds)
        });
    }

    /// [`Columns::scatter`] with the pass as `run` (one copy per dimension, not per form); the
    /// tiles read the column `whole` of every node, which none of them changes.
    fn scatter_tiles(
        &mut self,
        ctx: &Ctx<'_, D>,
        whole: Option<Whole>,
        run: &(dyn Fn(&ParticleCols<'_, D>, &mut GridCols<'_, D>) + Sync),
    ) {
        let stride = ctx.geom.stride[D - 1];
        let lines = ctx.geom.nodes[D - 1];
        // Tiles need lines of at least a row's width (so that a row's spill into the next
        // line stays within it).
        let tiles = if self.workers == 1 || ctx.geom.nodes[0] < ROW {
            1
        } else {
            (2 * self.workers).min(ctx.active.hi[D - 1].saturating_sub(ctx.active.lo[D - 1]))
        };
        if tiles < 2 {
            let (p, mut g) = self.full();
            return run(&p, &mut g);
        }
        // The lines of tile `t`: the node box's lines cut evenly, the first tile from line 0
        // and the last to the grid's end (no stencil reaches past the box; the chunks a tile
        // takes are those whose rows reach it, `GridCols::chunks`).
        let (lo, hi) = (ctx.active.lo[D - 1], ctx.active.hi[D - 1]);
        let bound = |t: usize| match t {
            0 => 0,
            t if t == tiles => lines,
            t => lo + tasks::part(hi - lo, tiles, 1, t).start,
        };
        // SAFETY: the particle columns are only read while the tiles run.
        let p = unsafe { ParticleCols::carve_window(&self.particles, self.layout, 0..usize::MAX) };
        // SAFETY: the table is only read while the tiles run (the node box wrote it).
        let reach: &[[u32; 2]] = unsafe { self.reach.window(0..usize::MAX) };
        // The column the tiles read whole and leave out of their own.
        let read: &[crate::Real] = match whole {
            // SAFETY: the tiles carve no view of this column, and nothing else runs.
            Some(w) => unsafe { GridCols::<D>::carve_tile(&self.grid, self.layout, Tile::ALL) }
                .into_whole(w),
            None => &[],
        };
        let (grid, layout, p) = (&self.grid, self.layout, &p);
        for colour in 0..2 {
            let item = |i: usize| {
                let t = 2 * i + colour;
                let tile = Tile::of_lines(bound(t)..bound(t + 1), stride);
                // SAFETY: tiles of one colour have a tile of at least one line, which is at
                // least ROW entries, between them, so their windows (rows + ROW entries) are
                // disjoint; the particle view and `read` are read only.
                let mut g = unsafe {
                    match whole {
                        Some(w) => GridCols::carve_tile_reading(grid, layout, tile, w, read),
                        None => GridCols::carve_tile(grid, layout, tile),
                    }
                };
                g.reach = reach;
                run(p, &mut g);
            };
            tasks::for_each(self.tasks, (tiles - colour).div_ceil(2), &item);
        }
    }

    /// Runs `pass` on the particles `0..count` cut into ranges of whole chunks, each with a
    /// view of its particles (the first its particle 0) and of the grid to read, and merges
    /// their reports into `report` in particle order.
    fn particle_ranges(
        &mut self,
        count: usize,
        report: &mut StepReport,
        pass: &(dyn Fn(&mut ParticleCols<'_, D>, usize, &GridCols<'_, D>, &mut StepReport) + Sync),
    ) {
        let items = (crate::layout::SLOTS_PER_WORKER * self.workers).min(count.div_ceil(CHUNK));
        if self.workers == 1 || items < 2 {
            let (mut p, g) = self.full();
            return pass(&mut p, count, &g, report);
        }
        let range = |i: usize| tasks::part(count, items, CHUNK, i);
        // SAFETY: the grid is only read while the ranges run.
        let g = unsafe { GridCols::carve_tile(&self.grid, self.layout, Tile::ALL) };
        let (particles, partials, layout, g) = (&self.particles, &self.partials, self.layout, &g);
        let item = |i: usize| {
            let r = range(i);
            // Whole chunks: the last range's window runs to the columns' padding.
            let window = r.start..r.end.next_multiple_of(CHUNK);
            // SAFETY: the ranges of distinct items are disjoint (multiples of CHUNK apart).
            let mut p = unsafe { ParticleCols::carve_window(particles, layout, window) };
            let mut part = StepReport::default();
            // The pass's frame 1.5 KiB further down the stack: called right below this frame,
            // a store of the particle pass's and the loads of this frame's view were 4 KiB
            // apart (4K aliasing), and the pass took twice as long on rayon's threads
            // (benches/PERFORMANCE.md, "Threads").
            let pad = [0u8; 1536];
            core::hint::black_box(&pad);
            pass(&mut p, r.len(), g, &mut part);
            // SAFETY: item i alone writes slot i.
            if let Some(slot) = unsafe { partials.window(i..i + 1) }.first_mut() {
                *slot = part.to_partial();
            }
        };
        tasks::for_each(self.tasks, items, &item);
        // SAFETY: the items are done; this is the only view of the slots.
        let slots = unsafe { self.partials.window(0..items) };
        for (i, slot) in slots.iter().enumerate() {
            report.merge(slot, range(i).start as u32);
        }
    }

    /// The particle update ([`passes::Passes::particles`]); with MUSL, the re-map scatter
    /// after it where there are several workers (one worker scatters it within the pass).
    pub fn particles<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
        report: &mut StepReport,
    ) {
        if self.workers == 1 {
            let (mut p, mut g) = self.full();
            let (read, mut remap) = g.split_remap();
            return I::particles::<D, K, S, W>(
                shape, ctx, &mut p, count, &read, &mut remap, report,
            );
        }
        self.particle_ranges(count, report, &|p, n, g, report| {
            let mut none = GridCols::empty();
            I::particles::<D, K, S, W>(shape, ctx, p, n, g, &mut none, report)
        });
        if ctx.order == crate::UpdateOrder::Musl {
            let adds = Adds {
                mode: Mode::Remap,
                forces: false,
                apic: ctx.apic,
            };
            self.scatter::<I, K, S, W>(shape, ctx, count, adds);
        }
    }

    /// Runs `f` on the grid cut into `slabs` slabs of whole lines along the slowest axis (the
    /// node box's lines cut evenly; the first slab from the grid's start, the last to its
    /// end), each with the columns of its own nodes.
    fn slabs(&mut self, ctx: &Ctx<'_, D>, slabs: usize, f: &(dyn Fn(&mut GridCols<'_, D>) + Sync)) {
        let stride = ctx.geom.stride[D - 1];
        let (lo, hi) = (ctx.active.lo[D - 1], ctx.active.hi[D - 1]);
        let len = self.layout.nodes + ROW;
        let bound = |t: usize| match t {
            0 => 0,
            t if t == slabs => len,
            t => (lo + tasks::part(hi - lo, slabs, 1, t).start) * stride,
        };
        let (grid, layout) = (&self.grid, self.layout);
        tasks::for_each(self.tasks, slabs, &|t| {
            // SAFETY: the slabs' node ranges are disjoint.
            let mut g = unsafe { GridCols::carve_nodes(grid, layout, bound(t)..bound(t + 1)) };
            f(&mut g);
        });
    }

    /// The stress update ([`passes::Passes::stress`]).
    pub fn stress<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
        report: &mut StepReport,
    ) {
        self.particle_ranges(count, report, &|p, n, g, report| {
            I::stress::<D, K, S, W>(shape, ctx, p, n, g, report)
        });
    }

    /// One substep of the transported field `f` (heat or diffusion) defined by `t`, in the
    /// order of [`crate::phases::transport`]: its two scatters by tiles, its particle update
    /// by ranges, the grid's sides between them on the calling thread.
    pub fn transport<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
        f: usize,
        t: &Transport,
    ) {
        let axisymmetric = S::AXISYMMETRIC;
        self.transport_loops(ctx, count, f, t, axisymmetric, &|p, n, pass| {
            I::transport::<D, K, S, W>(shape, ctx, p, n, f, pass)
        });
    }

    /// [`Columns::transport`] with the particle loops as `run` (one copy per dimension, not
    /// per form).
    fn transport_loops(
        &mut self,
        ctx: &Ctx<'_, D>,
        count: usize,
        f: usize,
        t: &Transport,
        axisymmetric: bool,
        run: &(dyn Fn(&ParticleCols<'_, D>, usize, FieldPass<'_, '_, D>) + Sync),
    ) {
        transport::reset(ctx, &mut self.grid().scalar[f]);
        self.scatter_tiles(ctx, None, &|p, g| run(p, count, FieldPass::Capacity(g)));
        transport::nodal_values(ctx, &mut self.grid().scalar[f], t);
        self.scatter_tiles(ctx, Some(Whole::Value(f)), &|p, g| {
            run(p, count, FieldPass::Flow(g))
        });
        let fixed = transport::nodal_rates(ctx, &mut self.grid().scalar[f], t, axisymmetric);
        self.particle_ranges(count, &mut StepReport::default(), &|p, n, g, _| {
            // The update writes the field's values, which it takes out of the window.
            let value = core::mem::take(&mut p.scalar[f][0]);
            let on_grid = core::mem::take(&mut p.scalar[f][1]);
            let pass = FieldPass::Update {
                g,
                value,
                on_grid,
                fixed,
            };
            run(p, n, pass)
        });
    }
}

/// The fewest nodes a slab of a grid pass holds: the grid passes are a few operations per
/// node, and a slab of fewer nodes took less time than handing it to a worker.
const MIN_SLAB_NODES: usize = 1 << 14;

/// The grid passes' view of the columns: slabs of lines on the workers.
pub(crate) struct GridPasses<'c, 'b, 'x, const D: usize> {
    pub cols: &'c mut Columns<'b, D>,
    pub ctx: &'c Ctx<'x, D>,
}

impl<const D: usize> Nodes<D> for GridPasses<'_, '_, '_, D> {
    fn whole(&mut self) -> GridCols<'_, D> {
        self.cols.grid()
    }

    fn with_impulses(&mut self) -> (GridCols<'_, D>, &mut [ColliderImpulse]) {
        let cols = &mut *self.cols;
        // SAFETY: `&mut self` excludes every other view of the grid (as `Columns::full`).
        let g = unsafe { GridCols::carve_tile(&cols.grid, cols.layout, Tile::ALL) };
        (g, &mut *cols.impulses)
    }

    fn each_slab(&mut self, f: &(dyn Fn(&mut GridCols<'_, D>) + Sync)) {
        let b = &self.ctx.active;
        let lines = b.hi[D - 1].saturating_sub(b.lo[D - 1]);
        let nodes: usize = (0..D).map(|a| b.hi[a].saturating_sub(b.lo[a])).product();
        // A slab of fewer nodes costs less than waking a worker for it.
        let slabs = (crate::layout::SLOTS_PER_WORKER * self.cols.workers)
            .min(lines)
            .min(nodes / MIN_SLAB_NODES);
        if self.cols.workers == 1 || slabs < 2 {
            return f(&mut self.cols.grid());
        }
        self.cols.slabs(self.ctx, slabs, f);
    }
}
