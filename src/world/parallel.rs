//! The substep's passes on the host's task system ([`crate::tasks`]), bit-identical to one
//! worker's for any number of workers, on the pieces of the cut ([`crate::cut`]).
//!
//! - **Particle passes** (the particle update, the stress update, a transported field's
//!   update): items are ranges of whole
//!   chunks, each with a window of the particle columns of its own ([`ParticleCols::carve_window`])
//!   and the grid to read. A particle's update reads only its own values and the grid, so
//!   it computes the same bits in any item. Each item leaves its part of the report in a slot
//!   of the world's scratch ([`Partial`]); the step merges them in item order, which is
//!   particle order, as one worker fills it.
//! - **Scatter**: the grid is cut into tiles, slabs of whole lines along the slowest axis
//!   ([`Tile`], [`Tiles`]), cut where about as many groups of particles reach each. A tile
//!   takes, in particle order, every chunk whose stencils reach its slab and adds the rows in
//!   its slab alone: each node receives the same values in the same order as from one
//!   worker's scatter, so every sum has the same bits. A row of a slab's last line may add
//!   zeros to the first entries of the next line (a 4-wide row of a 3-node stencil at the
//!   end of its line): so the even tiles run, then the odd ones, and no two neighbours ever
//!   run at once. Heat and diffusion's two scatters take tiles too, their flow's reading the
//!   nodal values whole as the momentum approach's force reads the masses ([`Whole`]).
//! - **MUSL's particle pass** scatters the re-map as it updates, as one worker does: by the
//!   same tiles, each updating the groups of particles it owns and re-mapping in particle
//!   order the rows of every group that reaches it ([`Columns::particles_by_tiles`]). A
//!   group another tile owns is read only once that tile is done ([`RemapCols`]).
//!
//! Races are ruled out by construction: every item's mutable view is carved from a window
//! no other item of the same pass touches (particle ranges, tiles of one colour with a line
//! between them, the groups a tile owns), and what items share they only read. The walls, the tractions and a
//! transported field's nodal values and rates run on the calling thread.

use super::passes::{self, Passes};
use crate::cut::{runs, Partial, Tile, Tiles, MAX_TILES, REACH_GROUP};
use crate::def::Transport;
use crate::grid::{GridCols, Whole};
use crate::layout::{ColliderImpulse, Layout, CHUNK};
use crate::particles::{ParticleCols, RemapCols, StepReport};
use crate::phases::grid_update::Nodes;
use crate::phases::p2g::{Adds, Mode};
use crate::phases::transport::{self, FieldPass};
use crate::phases::volume;
use crate::phases::Ctx;
use crate::shape::{Shape1D, ROW};
use crate::tasks::{self, Shared, TaskSystem};
use core::ops::Range;

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
    /// The scatter's tiles, cut with the node box; `None` where there is one worker or the
    /// grid is too small to cut.
    tiles: Option<Tiles>,
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
                .clamp(1, slots / crate::cut::SLOTS_PER_WORKER)
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
            tiles: None,
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
        let active = passes::node_box::<D, K, S>(simd, &scan, geom, &x, p.status, count, reach);
        // The tiles need lines of at least a row's width (so that a row's spill into the
        // next line stays within it). Where no row reaches past its line's end, one tile per
        // worker, all at once; else two, in two colours.
        let (lo, hi) = (active.lo[D - 1], active.hi[D - 1]);
        let apart = active.hi[0] + active.tail <= geom.nodes[0];
        let n = if self.workers == 1 || geom.nodes[0] < ROW {
            1
        } else {
            let per_worker = if apart { 1 } else { 2 };
            (per_worker * self.workers)
                .min(MAX_TILES)
                .min(hi.saturating_sub(lo))
        };
        self.tiles = (n >= 2).then(|| {
            // SAFETY: the scan is done; the table is only read here.
            let reach = unsafe { self.reach.read(0..count.div_ceil(REACH_GROUP)) };
            let (lines, stride) = (geom.nodes[D - 1], geom.stride[D - 1]);
            Tiles::balanced(n, apart, lo..hi, lines, stride, reach)
        });
        active
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
        self.scatter_tiles(whole, &|p, g| {
            passes::scatter::<I, D, K, S, W>(shape, ctx, p, count, g, adds)
        });
    }

    /// [`Columns::scatter`] with the pass as `run` (one copy per dimension, not per form); the
    /// tiles read the column `whole` of every node, which none of them changes.
    fn scatter_tiles(
        &mut self,
        whole: Option<Whole>,
        run: &(dyn Fn(&ParticleCols<'_, D>, &mut GridCols<'_, D>) + Sync),
    ) {
        let Some(tiles) = self.tiles else {
            let (p, mut g) = self.full();
            return run(&p, &mut g);
        };
        // SAFETY: the particle columns are only read while the tiles run.
        let p = unsafe { ParticleCols::carve_window(&self.particles, self.layout, 0..usize::MAX) };
        // SAFETY: the table is only read while the tiles run (the node box wrote it).
        let reach: &[[u32; 2]] = unsafe { self.reach.read(0..usize::MAX) };
        // The column the tiles read whole and leave out of their own.
        let read: &[crate::Real] = match whole {
            // SAFETY: the tiles carve no view of this column, and nothing else runs.
            Some(w) => unsafe { GridCols::<D>::carve_tile(&self.grid, self.layout, Tile::ALL) }
                .into_whole(w),
            None => &[],
        };
        let (grid, layout, p) = (&self.grid, self.layout, &p);
        for colour in 0..tiles.colours() {
            let item = |i: usize| {
                let tile = tiles.tile(tiles.nth(colour, i));
                // SAFETY: tiles of one colour are apart ([`Tiles`]), so their windows are
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
            tasks::for_each(self.tasks, tiles.of_colour(colour), &item);
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
        let items = (crate::cut::SLOTS_PER_WORKER * self.workers).min(count.div_ceil(CHUNK));
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
            // (benches/PERFORMANCE.md, "Decisions").
            let pad = [0u8; 1536];
            core::hint::black_box(&pad);
            pass(&mut p, r.len(), g, &mut part);
            // SAFETY: item i alone writes slot i.
            if let Some(slot) = unsafe { partials.window(i..i + 1) }.first_mut() {
                *slot = part.to_partial();
            }
        };
        tasks::for_each(self.tasks, items, &item);
        // SAFETY: the items are done; no window of the slots is alive.
        let slots = unsafe { self.partials.read(0..items) };
        let mut merged = Partial::default();
        for (i, slot) in slots.iter().enumerate() {
            merged.absorb(slot, range(i).start as u32);
        }
        report.merge(&merged);
    }

    /// The particle update ([`passes::Passes::particles`]), with MUSL's re-map scatter inside
    /// it: on several workers by tiles ([`Columns::particles_by_tiles`]).
    pub fn particles<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
        report: &mut StepReport,
    ) {
        let musl = ctx.order == crate::UpdateOrder::Musl;
        let tiles = self.tiles;
        if self.workers == 1 || (musl && tiles.is_none()) {
            let (mut p, mut g) = self.full();
            let (read, mut remap) = g.split_remap();
            return I::particles::<D, K, S, W>(
                shape, ctx, &mut p, count, &read, &mut remap, report,
            );
        }
        let Some(tiles) = tiles.filter(|_| musl) else {
            return self.particle_ranges(count, report, &|p, n, g, report| {
                let mut none = GridCols::empty();
                I::particles::<D, K, S, W>(shape, ctx, p, n, g, &mut none, report)
            });
        };
        // A run of particles: updated (with the re-map where `remap` holds its columns), or
        // re-mapped.
        let update = |cols: &mut ParticleCols<'_, D>,
                      n: usize,
                      g: &GridCols<'_, D>,
                      remap: &mut GridCols<'_, D>| {
            let mut part = StepReport::default();
            I::particles::<D, K, S, W>(shape, ctx, cols, n, g, remap, &mut part);
            part.to_partial()
        };
        let read = |cols: &RemapCols<'_, D>, n: usize, remap: &mut GridCols<'_, D>| {
            I::remap::<D, K, S, W>(shape, ctx, cols, n, &GridCols::empty(), remap)
        };
        self.particles_by_tiles(count, &tiles, report, &update, &read);
    }

    /// XPIC's and FMPM's projection of the series columns (`A u = S+ S u`, E99): the velocity
    /// gathered from them at each particle, its momentum scattered to the re-map columns
    /// ([`passes::Passes::remap`]). On the calling thread, whatever the workers: its sums are
    /// one worker's. With the stencils of the particles' current positions, or with
    /// `at_start` of the positions MUSL kept where the substep started.
    pub fn project<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
        at_start: bool,
    ) {
        let (p, mut g) = self.full();
        let (from, mut remap) = g.split_series();
        let mut cols = RemapCols::at_current(&p);
        if at_start {
            cols.x_start = p.x_start.each_ref().map(|c| &**c);
        }
        I::remap::<D, K, S, W>(shape, ctx, &cols, count, &from, &mut remap);
    }

    /// MUSL's particle pass on several workers, with the re-map scatter inside it as one
    /// worker runs it ([`Columns::particles`]): by the scatter's tiles and colours. A tile
    /// takes, in particle order, the groups of particles ([`REACH_GROUP`]) whose stencils
    /// reach its lines; it updates those it owns and re-maps their rows in its slab (`update`),
    /// and re-maps the rows of the others, updated before (`read`). So every node receives
    /// the same values in the same order as from one worker.
    ///
    /// A group that reaches one tile is that tile's. In two colours, one that reaches two
    /// neighbours is the even one's (the first colour's: the odd one reads it after). Any
    /// other group (one that reaches tiles that run at once, or none) is updated before the
    /// tiles run, by ranges (`update` without re-map columns). So no group is changed while
    /// another item reads it.
    fn particles_by_tiles(
        &mut self,
        count: usize,
        tiles: &Tiles,
        report: &mut StepReport,
        update: &Update<'_, D>,
        read: &(dyn Fn(&RemapCols<'_, D>, usize, &mut GridCols<'_, D>) + Sync),
    ) {
        let groups = count.div_ceil(REACH_GROUP);
        // SAFETY: the node box wrote the table; it is only read here.
        let reach: &[[u32; 2]] = unsafe { self.reach.read(0..groups) };
        // The tile that updates group `k`, if one does.
        let owner = |k: usize| -> Option<usize> {
            let &[lo, hi] = reach.get(k)?;
            let (a, b) = (tiles.of_line(lo as usize), tiles.of_line(hi as usize));
            match lo <= hi {
                true if a == b => Some(a),
                true if b == a + 1 && !tiles.apart => Some(a + a % 2),
                _ => None,
            }
        };
        let particles = |k: Range<usize>| k.start * REACH_GROUP..(k.end * REACH_GROUP).min(count);
        // The columns of the particles `r` (whole chunks), to update and to read.
        // SAFETY (both): a group is handed to one item to update, and to others to read only
        // once it is updated and no item changes it (see above).
        let (p, layout) = (&self.particles.clone(), self.layout);
        let update = |r: Range<usize>, g: &GridCols<'_, D>, remap: &mut GridCols<'_, D>| {
            let window = r.start..r.end.next_multiple_of(CHUNK);
            let mut cols = unsafe { ParticleCols::carve_window(p, layout, window) };
            update(&mut cols, r.len(), g, remap)
        };
        let read = |r: Range<usize>, remap: &mut GridCols<'_, D>| {
            let window = r.start..r.end.next_multiple_of(CHUNK);
            read(
                &unsafe { RemapCols::read(p, layout, window) },
                r.len(),
                remap,
            )
        };
        // SAFETY: the grid's columns but the re-map ones are only read while the items run.
        let g = unsafe { GridCols::<D>::carve_all_but_remap(&self.grid, self.layout) };
        let (grid, layout, partials, g) = (&self.grid, self.layout, &self.partials, &g);
        let mut merged = Partial::default();
        // The groups no tile owns, by ranges of groups.
        if (0..groups).any(|k| owner(k).is_none()) {
            let items = (crate::cut::SLOTS_PER_WORKER * self.workers).min(groups);
            tasks::for_each(self.tasks, items, &|i| {
                let mut part = Partial::default();
                let mine = runs(tasks::part(groups, items, 1, i), |k| owner(k).is_none());
                for (_, run) in mine.filter(|&(none, _)| none) {
                    let r = particles(run);
                    part.absorb(
                        &update(r.clone(), g, &mut GridCols::empty()),
                        r.start as u32,
                    );
                }
                // SAFETY: item i alone writes slot i.
                if let Some(slot) = unsafe { partials.window(i..i + 1) }.first_mut() {
                    *slot = part;
                }
            });
            // SAFETY: the items are done; no window of the slots is alive.
            for slot in unsafe { self.partials.read(0..items) } {
                merged.absorb(slot, 0);
            }
        }
        for colour in 0..tiles.colours() {
            tasks::for_each(self.tasks, tiles.of_colour(colour), &|i| {
                let t = tiles.nth(colour, i);
                let tile = tiles.tile(t);
                let slab = tile.slab(tiles.stride).unwrap_or(0..0);
                // SAFETY: tiles of one colour are apart ([`Tiles`]), and only the re-map
                // columns are carved.
                let mut remap = unsafe { GridCols::carve_tile_remap(grid, layout, tile) };
                // Whether tile `t` updates group `k` (`Some(true)`), reads it or passes it.
                let takes = |k: usize| {
                    let [lo, hi] = reach[k];
                    let reaches = (lo as usize) < slab.end && hi as usize >= slab.start;
                    reaches.then(|| owner(k) == Some(t))
                };
                let mut part = Partial::default();
                for (takes, run) in runs(0..groups, takes) {
                    let r = particles(run);
                    match takes {
                        Some(true) => {
                            part.absorb(&update(r.clone(), g, &mut remap), r.start as u32)
                        }
                        Some(false) => read(r, &mut remap),
                        None => {}
                    }
                }
                // SAFETY: tile t alone writes slot t.
                if let Some(slot) = unsafe { partials.window(t..t + 1) }.first_mut() {
                    *slot = part;
                }
            });
        }
        // SAFETY: the items are done; no window of the slots is alive.
        for slot in unsafe { self.partials.read(0..tiles.n) } {
            merged.absorb(slot, 0);
        }
        report.merge(&merged);
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

    /// The fluids' volume relaxation (E97, [`crate::phases::volume`]): the volumes' scatter by
    /// tiles, the fills on the calling thread, the relaxation by ranges. Its nodal column is
    /// the first acceleration column: it runs before the grid's reset.
    pub fn relax_volumes<I: Passes, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        count: usize,
    ) {
        transport::zero_lines(ctx, self.grid().acc[0]);
        self.scatter_tiles(None, &|p, g| {
            volume::scatter::<D, K, S, W>(I::stencils::<D, K, S, W>, shape, ctx, p, count, g)
        });
        volume::fills(ctx, self.grid().acc[0], S::AXISYMMETRIC);
        self.particle_ranges(count, &mut StepReport::default(), &|p, n, g, _| {
            let state = volume::FluidState::take(p);
            volume::relax::<D, K, S, W>(I::stencils::<D, K, S, W>, shape, ctx, p, n, g, state)
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
        self.scatter_tiles(None, &|p, g| run(p, count, FieldPass::Capacity(g)));
        transport::nodal_values(ctx, &mut self.grid().scalar[f], t);
        self.scatter_tiles(Some(Whole::Value(f)), &|p, g| {
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

/// A run of particles' update in MUSL's parallel particle pass: the view, its particles, the
/// grid to read and the re-map columns (or none), giving its part of the report.
type Update<'a, const D: usize> = dyn Fn(&mut ParticleCols<'_, D>, usize, &GridCols<'_, D>, &mut GridCols<'_, D>) -> Partial
    + Sync
    + 'a;

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

    fn with_impulses(&mut self) -> (GridCols<'_, D>, ParticleCols<'_, D>, &mut [ColliderImpulse]) {
        let cols = &mut *self.cols;
        // SAFETY: `&mut self` excludes every other view of the grid and the particles (as
        // `Columns::full`).
        let (g, p) = unsafe {
            (
                GridCols::carve_tile(&cols.grid, cols.layout, Tile::ALL),
                ParticleCols::carve_window(&cols.particles, cols.layout, 0..usize::MAX),
            )
        };
        (g, p, &mut *cols.impulses)
    }

    fn each_slab(&mut self, f: &(dyn Fn(&mut GridCols<'_, D>) + Sync)) {
        let b = &self.ctx.active;
        let lines = b.hi[D - 1].saturating_sub(b.lo[D - 1]);
        let nodes: usize = (0..D).map(|a| b.hi[a].saturating_sub(b.lo[a])).product();
        // A slab of fewer nodes costs less than waking a worker for it.
        let slabs = (crate::cut::SLOTS_PER_WORKER * self.cols.workers)
            .min(lines)
            .min(nodes / MIN_SLAB_NODES);
        if self.cols.workers == 1 || slabs < 2 {
            return f(&mut self.cols.grid());
        }
        self.cols.slabs(self.ctx, slabs, f);
    }
}
