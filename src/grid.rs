//! Grid node columns and index math; the grid's geometry ([`Geom`]), whose walls and periodic
//! images are the boundary's ([`crate::boundary`]).
//!
//! Nodes sit at `origin + h * (i, j, k)` for `i` in `0..=cells[0]` and so on; node `(i, j, k)`
//! has flat index `i + nx * (j + ny * k)` with `nx = cells[0] + 1`, `ny = cells[1] + 1`.
//!
//! The admissible region for particles is the grid shrunk by the shape function's margin
//! (`m` cells at each face, [`crate::ShapeFunction::margin_cells`]): there every node of a
//! particle's stencil exists. The walls of stick and slip faces act at that region's faces: all
//! nodes in the layer from the grid face to the wall plane are constrained.

use crate::cut::{Chunks, Tile, REACH_GROUP};
use crate::def::{Boundary, WorldDef};
use crate::layout::Layout;
use crate::particles::Carver;
use crate::shape::{Row4, ROW};
use crate::tasks::Shared;
use crate::Real;

/// Mutable views of every node column, each `nodes` long.
pub(crate) struct GridCols<'a, const D: usize> {
    /// Nodal mass m_i (E12).
    pub mass: &'a mut [Real],
    /// Momentum p_i (E13) after particle-to-grid; velocity v_i = p_i / m_i after the grid update.
    pub vel: [&'a mut [Real]; D],
    /// Force f_i (E14) after particle-to-grid; acceleration a_i = f_i / m_i + g after the grid update.
    pub acc: [&'a mut [Real]; D],
    /// The nodal velocity the separate stress pass differentiates, with the walls applied: USF
    /// copies the lagged velocity here; MUSL accumulates the momentum of the updated particle
    /// velocities here and divides by the mass. Empty with USL. XPIC's and FMPM's series
    /// (order 2 and up) projects into them ([`crate::phases::xpic`]).
    pub remap: [&'a mut [Real]; D],
    /// XPIC's and FMPM's series: the term the next projection gathers (empty below order 2).
    pub series: [&'a mut [Real]; D],
    /// Transported scalars (heat, diffusion; empty when not declared), 4 columns each: capacity
    /// (thermal mass `m_T`, or volume), momentum (`m_T T`), value (`T_i`, with the fixed
    /// faces), flow then rate (`Q_i`, then `Q_i / m_T`).
    pub scalar: [[&'a mut [Real]; 4]; 2],
    /// Colliders (empty without): the nodes that material touching the collider being applied
    /// reaches, marked 1 (E91).
    pub contact: &'a mut [Real],
    /// Entries per column (`nodes + ROW`, or a tile's window); a column not reserved is empty.
    pub len: usize,
    /// The nodes these columns hold and whose rows a scatter adds to them.
    pub tile: Tile,
    /// A tile's: the grid lines along the slowest axis that each [`crate::cut::REACH_GROUP`]
    /// particles' stencils may reach ([`reach_lines`]), so that its scatter passes over the
    /// chunks that reach none of its lines; empty otherwise.
    pub reach: &'a [[u32; 2]],
    /// A tile's column read whole, which it leaves out of its own ([`GridCols::carve_tile_reading`],
    /// [`Whole`]); empty otherwise.
    pub whole: &'a [Real],
}

/// The node column a tile of a parallel scatter reads whole, past its own rows, and which none
/// of the tiles changes: the momentum approach's force reads the masses of every stencil node,
/// a transported field's flow the nodal values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Whole {
    Mass,
    /// The nodal values of transported field `f` (`GridCols::scalar[f][2]`).
    Value(usize),
}

/// The node columns a view carves ([`GridCols::carve_columns`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Part {
    All,
    /// All but the column a tile reads whole.
    AllBut(Whole),
    AllButRemap,
    /// The re-map columns alone.
    Remap,
}

/// What a node column holds, for [`Part::holds`].
#[derive(Clone, Copy, PartialEq, Eq)]
enum Column {
    Mass,
    /// Velocity or acceleration.
    Motion,
    Remap,
    /// XPIC's series.
    Series,
    /// A transported field's nodal values.
    Value(usize),
    /// A transported field's other columns.
    Scalar,
    /// The colliders' contact marks.
    Contact,
}

impl Part {
    fn holds(self, column: Column) -> bool {
        match self {
            Part::All => true,
            Part::AllBut(Whole::Mass) => column != Column::Mass,
            Part::AllBut(Whole::Value(f)) => column != Column::Value(f),
            Part::AllButRemap => column != Column::Remap,
            Part::Remap => column == Column::Remap,
        }
    }
}

/// Whether every row of a stencil whose first node is `base` fits in node columns of length
/// `len`: the last row starts at `base + last_row_offset` and spans [`ROW`] entries. The step
/// checks this once per particle (it always holds: the first node is clamped and the columns
/// carry [`ROW`] entries of padding), and the row accessors below rely on it.
#[inline(always)]
pub(crate) fn rows_fit(base: usize, last_row_offset: usize, len: usize) -> bool {
    base + last_row_offset + ROW <= len
}

/// The [`ROW`] values of `col` from `start`.
///
/// # Safety
/// `start + ROW <= col.len()` (see [`rows_fit`]).
#[inline(always)]
pub(crate) unsafe fn load_row(col: &[Real], start: usize) -> Row4 {
    debug_assert!(start + ROW <= col.len());
    // SAFETY: the caller guarantees start + ROW <= col.len(), so the ROW reads are in bounds;
    // an unaligned read of [Real; ROW] has no alignment requirement.
    Row4::from_array(unsafe { core::ptr::read_unaligned(col.as_ptr().add(start).cast()) })
}

/// Adds `v` to the [`ROW`] values of `col` from `start`.
///
/// # Safety
/// `start + ROW <= col.len()` (see [`rows_fit`]).
#[inline(always)]
pub(crate) unsafe fn add_row(col: &mut [Real], start: usize, v: Row4) {
    debug_assert!(start + ROW <= col.len());
    // SAFETY: as for load_row; the write covers the same ROW entries.
    unsafe {
        let p = col.as_mut_ptr().add(start).cast::<[Real; ROW]>();
        let sum = Row4::from_array(core::ptr::read_unaligned(p)) + v;
        core::ptr::write_unaligned(p, sum.to_array());
    }
}

impl<'a, const D: usize> GridCols<'a, D> {
    /// Length shared by every node column (nodes plus padding).
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether every column has the length [`GridCols::len`] (the remap columns may be empty).
    /// True by construction; each pass checks it once so that the per-particle [`rows_fit`]
    /// check covers every column.
    pub fn lengths_consistent(&self) -> bool {
        let len = self.len();
        let group = |cols: &[&mut [Real]]| {
            cols.iter().all(|c| c.len() == len) || cols.iter().all(|c| c.is_empty())
        };
        let tile_fits = self.tile == Tile::ALL || self.tile.rows.saturating_add(ROW - 1) <= len;
        (self.mass.len() == len || (self.mass.is_empty() && !self.whole.is_empty()))
            && group(&self.vel)
            && group(&self.acc)
            && group(&self.remap)
            && group(&self.series)
            && tile_fits
    }

    /// The chunks of `w` particles, of the first `count`, whose stencils may reach this view's
    /// nodes, by their first particle: every chunk for the whole grid; for a tile, those of
    /// the groups of the reach table ([`GridCols::reach`]) that reach its slab, a group
    /// passed over at once. `stride`: the slowest axis's (see [`Tile::slab`]).
    pub fn chunks(&self, count: usize, w: usize, stride: usize) -> Chunks<'a> {
        Chunks::new(count, w, self.reach, self.tile.slab(stride))
    }

    /// The nodal masses by node index: the whole mass column (a force scatter's tile reads
    /// it whole, [`GridCols::whole`]; else this view's, which must hold the whole grid).
    pub fn all_masses(&self) -> &[Real] {
        if self.mass.is_empty() {
            self.whole
        } else {
            self.mass
        }
    }

    /// The column `w` of every node, from a view of the whole grid.
    pub fn into_whole(mut self, w: Whole) -> &'a [Real] {
        match w {
            Whole::Mass => self.mass,
            Whole::Value(f) => core::mem::take::<&mut [Real]>(&mut self.scalar[f][2]),
        }
    }

    /// The node indices these columns hold: entry `k` is node `window().start + k`.
    pub fn window(&self) -> core::ops::Range<usize> {
        self.tile.first..self.tile.first + self.len
    }

    /// No columns at all (length 0): the re-map columns of a particle pass that does not
    /// re-map (`phases::g2p::particles`).
    pub fn empty() -> GridCols<'a, D> {
        let none = || core::array::from_fn(|_| &mut [][..]);
        GridCols {
            mass: &mut [][..],
            vel: none(),
            acc: none(),
            remap: none(),
            series: none(),
            scalar: core::array::from_fn(|_| core::array::from_fn(|_| &mut [][..])),
            contact: &mut [][..],
            len: 0,
            tile: Tile::ALL,
            reach: &[],
            whole: &[],
        }
    }

    /// The columns but the remap ones (which it leaves empty), and the remap ones alone: what
    /// the particle pass reads, and the columns MUSL's re-map scatter adds to in the same pass.
    pub fn split_remap(&mut self) -> (GridCols<'_, D>, GridCols<'_, D>) {
        let GridCols {
            mass,
            vel,
            acc,
            remap,
            series,
            scalar,
            contact,
            len,
            tile,
            reach,
            whole,
        } = self;
        let none = || core::array::from_fn(|_| &mut [][..]);
        let read = GridCols {
            mass,
            vel: vel.each_mut().map(|c| &mut **c),
            acc: acc.each_mut().map(|c| &mut **c),
            remap: none(),
            series: series.each_mut().map(|c| &mut **c),
            scalar: scalar.each_mut().map(|f| f.each_mut().map(|c| &mut **c)),
            contact,
            len: *len,
            tile: *tile,
            reach,
            whole,
        };
        let remap = GridCols {
            mass: &mut [][..],
            vel: none(),
            acc: none(),
            remap: remap.each_mut().map(|c| &mut **c),
            series: none(),
            scalar: core::array::from_fn(|_| core::array::from_fn(|_| &mut [][..])),
            contact: &mut [][..],
            len: *len,
            tile: *tile,
            reach,
            whole,
        };
        (read, remap)
    }

    /// [`GridCols::split_remap`] with the series columns in place of the velocity ones in the
    /// first view: what XPIC's projection gathers from, and the columns it adds to.
    pub fn split_series(&mut self) -> (GridCols<'_, D>, GridCols<'_, D>) {
        let (mut read, remap) = self.split_remap();
        let none = core::array::from_fn(|_| &mut [][..]);
        read.vel = core::mem::replace(&mut read.series, none);
        (read, remap)
    }

    /// The columns of `tile` ([`Tile`]; [`Tile::ALL`] for every node) of the shared grid
    /// region (starting at `layout.grid_offset`): each column `nodes` plus [`ROW`] entries of
    /// padding long (a stencil row may reach two entries past the last node; the padding only
    /// ever receives zero weights), cut to the tile's window.
    ///
    /// # Safety
    /// No other view of the region that overlaps the tile's entries (`tile.first..tile.first
    /// + tile.rows + ROW - 1`) is alive while this one is.
    pub unsafe fn carve_tile(region: &Shared<'a, u8>, layout: &Layout, tile: Tile) -> Self {
        let end = tile.end();
        // SAFETY: as required of the caller.
        Self::carve_columns(
            unsafe { Carver::window(region, tile.first..end) },
            layout,
            tile,
            Part::All,
        )
    }

    /// [`GridCols::carve_tile`] without the column `w`, which the tile reads whole from
    /// `whole` instead ([`Whole`]; [`GridCols::whole`]).
    ///
    /// # Safety
    /// As for [`GridCols::carve_tile`], the column `w` aside: `whole` is that column of every
    /// node, which no view changes while this one is alive.
    pub unsafe fn carve_tile_reading(
        region: &Shared<'a, u8>,
        layout: &Layout,
        tile: Tile,
        w: Whole,
        whole: &'a [Real],
    ) -> Self {
        let end = tile.end();
        // SAFETY: as required of the caller.
        let c = unsafe { Carver::window(region, tile.first..end) };
        let mut g = Self::carve_columns(c, layout, tile, Part::AllBut(w));
        g.whole = whole;
        g
    }

    /// The columns of the nodes `nodes` of the shared grid region: one slab of a grid pass
    /// (a scatter adds nothing to them: their tile holds no row).
    ///
    /// # Safety
    /// No other view of the region that overlaps `nodes` is alive while this one is.
    pub unsafe fn carve_nodes(
        region: &Shared<'a, u8>,
        layout: &Layout,
        nodes: core::ops::Range<usize>,
    ) -> Self {
        let tile = Tile {
            first: nodes.start,
            rows: 0,
            nodes: nodes.len(),
        };
        // SAFETY: as required of the caller.
        Self::carve_columns(
            unsafe { Carver::window(region, nodes) },
            layout,
            tile,
            Part::All,
        )
    }

    /// The re-map columns of `tile` alone (the others empty): what a tile of MUSL's parallel
    /// particle pass adds to ([`GridCols::carve_all_but_remap`] the columns it reads).
    ///
    /// # Safety
    /// As for [`GridCols::carve_tile`], for the re-map columns alone.
    pub unsafe fn carve_tile_remap(region: &Shared<'a, u8>, layout: &Layout, tile: Tile) -> Self {
        let end = tile.end();
        // SAFETY: as required of the caller.
        let c = unsafe { Carver::window(region, tile.first..end) };
        Self::carve_columns(c, layout, tile, Part::Remap)
    }

    /// Every column of every node but the re-map ones (left empty).
    ///
    /// # Safety
    /// No other view of these columns is alive while this one is.
    pub unsafe fn carve_all_but_remap(region: &Shared<'a, u8>, layout: &Layout) -> Self {
        // SAFETY: as required of the caller.
        let c = unsafe { Carver::window(region, 0..usize::MAX) };
        Self::carve_columns(c, layout, Tile::ALL, Part::AllButRemap)
    }

    fn carve_columns(mut c: Carver<'a>, layout: &Layout, tile: Tile, part: Part) -> Self {
        let (b, n) = (layout.node_column_bytes, layout.nodes + ROW);
        let optional = (layout.remap_grid as usize + layout.series_grid as usize) * D;
        let scalars = 4 * layout.scalar_grid.iter().filter(|&&b| b).count();
        debug_assert_eq!(
            layout.grid_columns,
            1 + 2 * D + optional + scalars + layout.contact_grid as usize
        );
        // The next column, or nothing where `part` leaves it out.
        let take = |c: &mut Carver<'a>, column: Column| {
            if part.holds(column) {
                c.take(b, n)
            } else {
                c.skip(b);
                &mut [][..]
            }
        };
        let mass = take(&mut c, Column::Mass);
        let vel = core::array::from_fn(|_| take(&mut c, Column::Motion));
        let acc = core::array::from_fn(|_| take(&mut c, Column::Motion));
        let remap = core::array::from_fn(|_| {
            if layout.remap_grid {
                take(&mut c, Column::Remap)
            } else {
                &mut [][..]
            }
        });
        let series = core::array::from_fn(|_| {
            if layout.series_grid {
                take(&mut c, Column::Series)
            } else {
                &mut [][..]
            }
        });
        let scalar = core::array::from_fn(|f| {
            core::array::from_fn(|k| {
                if layout.scalar_grid[f] {
                    let column = if k == 2 {
                        Column::Value(f)
                    } else {
                        Column::Scalar
                    };
                    take(&mut c, column)
                } else {
                    &mut [][..]
                }
            })
        });
        let contact = if layout.contact_grid {
            take(&mut c, Column::Contact)
        } else {
            &mut [][..]
        };
        let vel: [&mut [Real]; D] = vel;
        let remap: [&mut [Real]; D] = remap;
        GridCols {
            len: vel[0].len().max(remap[0].len()),
            mass,
            vel,
            acc,
            remap,
            series,
            scalar,
            contact,
            tile,
            reach: &[],
            whole: &[],
        }
    }
}

/// The nodes a substep touches: the box `lo[a] <= index along a < hi[a]` that holds the
/// stencil of every active particle (empty without one), computed from the positions where
/// the substep starts ([`NodeBox::first_nodes`], [`NodeBox::of_first_nodes`]). The grid
/// passes work on it alone, so a grid larger than the material costs nothing per node it does
/// not reach: a 32^3-cell block in a 64^3 grid touches one node in six.
///
/// Along x the passes also cover the `ROW - K` entries after each line of the box (the rest of
/// the 4-wide rows the scatter and the gathers load, read with zero weights), so every value
/// the step reads was reset in the same substep: values left outside the box by earlier
/// substeps, or whatever the buffer held before the first one, are never read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct NodeBox<const D: usize> {
    pub lo: [usize; D],
    pub hi: [usize; D],
    /// Entries after each line of the box along x that the passes cover too (`ROW - K`).
    pub tail: usize,
}

/// [`NodeBox::first_nodes`] as a free function, for the instruction-set instances of
/// `world::passes`, and with it (where `reach` is not empty) the [`reach_lines`] of the same
/// particles.
#[inline(always)]
pub(crate) fn first_nodes<const D: usize, const K: usize, S: crate::shape::Shape1D<K>>(
    geom: &Geom<D>,
    x: &[&[Real]; D],
    status: &[u32],
    count: usize,
    reach: &mut [[u32; 2]],
) -> ([i32; D], [i32; D]) {
    if !reach.is_empty() {
        reach_lines::<D, K, S>(geom, x[D - 1], status, count, reach);
    }
    NodeBox::first_nodes::<K, S>(geom, x, status, count)
}

/// The smallest and largest position of the active particles among `x` (`status` as long),
/// in cell units from `origin` (`(x - origin) * inv_h`, as the stencils take them), a NaN
/// counted as the lowest (the stencil clamps it there); `(INFINITY, NEG_INFINITY)` without
/// one. Lane-wise minima and maxima over chunks of 16 (loops the compiler vectorises), the
/// lanes reduced at the end.
#[inline(always)]
fn extremes(x: &[Real], status: &[u32], origin: Real, inv_h: Real) -> (Real, Real) {
    const L: usize = 16;
    let (mut mn, mut mx) = ([Real::INFINITY; L], [Real::NEG_INFINITY; L]);
    let mut lane = |ln: usize, xi: Real, st: u32| {
        let s = (xi - origin) * inv_h;
        let s = if s.is_nan() { Real::NEG_INFINITY } else { s };
        let active = st == crate::particles::ACTIVE;
        let (l, h) = if active {
            (s, s)
        } else {
            (Real::INFINITY, Real::NEG_INFINITY)
        };
        mn[ln] = if l < mn[ln] { l } else { mn[ln] };
        mx[ln] = if h > mx[ln] { h } else { mx[ln] };
    };
    let (xs, sts) = (x.chunks_exact(L), status.chunks_exact(L));
    let (x_rest, st_rest) = (xs.remainder(), sts.remainder());
    for (xs, sts) in xs.zip(sts) {
        for ln in 0..L {
            lane(ln, xs[ln], sts[ln]);
        }
    }
    for (ln, (&xi, &st)) in x_rest.iter().zip(st_rest).enumerate() {
        lane(ln, xi, st);
    }
    let lo = mn
        .iter()
        .fold(Real::INFINITY, |m, &v| if v < m { v } else { m });
    let hi = mx
        .iter()
        .fold(Real::NEG_INFINITY, |m, &v| if v > m { v } else { m });
    (lo, hi)
}

/// For each [`REACH_GROUP`] particles of `0..count` (the slices' first particle starts a
/// group), the grid lines along the slowest axis their stencils may reach, into `out` (one
/// entry per group): from the lowest active first node to the highest plus `K - 1`
/// ([`crate::shape::first_node`], as the stencils clamp it, a NaN position included),
/// `[u32::MAX, 0]` without an active particle. `x` holds the positions along the slowest axis.
#[inline(always)]
pub(crate) fn reach_lines<const D: usize, const K: usize, S: crate::shape::Shape1D<K>>(
    geom: &Geom<D>,
    x: &[Real],
    status: &[u32],
    count: usize,
    out: &mut [[u32; 2]],
) {
    let a = D - 1;
    let (o, inv_h, nodes) = (geom.origin[a], geom.inv_h, geom.nodes[a]);
    let count = count.min(x.len()).min(status.len());
    for (g, out) in out.iter_mut().enumerate() {
        let from = (g * REACH_GROUP).min(count);
        let to = (from + REACH_GROUP).min(count);
        let (lo, hi) = extremes(&x[from..to], &status[from..to], o, inv_h);
        *out = if lo <= hi {
            // The first node is monotonic in the position (a clamped floor).
            let first = |s: Real| crate::shape::first_node::<K, S>(s, nodes);
            lines::<K>(first(lo), first(hi))
        } else {
            [u32::MAX, 0]
        };
    }
}

/// The first and last line the stencils of a group whose first nodes run from `lo` to `hi`
/// reach; `[u32::MAX, 0]` for none (`lo > hi`). Exact, no margin: the positions are taken to
/// cell units as the stencils take them (`(x - origin) * inv_h`, the same operations), so the
/// first nodes are theirs.
fn lines<const K: usize>(lo: i32, hi: i32) -> [u32; 2] {
    if lo <= hi {
        [lo.max(0) as u32, (hi.max(0) as usize + K - 1) as u32]
    } else {
        [u32::MAX, 0]
    }
}

impl<const D: usize> NodeBox<D> {
    /// The smallest and largest first node per axis of the active particles `0..count` (as
    /// the stencils clamp them, [`crate::shape::first_node`], for any position; `i32::MAX`
    /// and `i32::MIN` without one): a part of the particles each, they merge by
    /// `min` and `max` into the whole's, which [`NodeBox::of_first_nodes`] turns into the box.
    #[inline(always)]
    pub fn first_nodes<const K: usize, S: crate::shape::Shape1D<K>>(
        geom: &Geom<D>,
        x: &[&[Real]; D],
        status: &[u32],
        count: usize,
    ) -> ([i32; D], [i32; D]) {
        let count = x
            .iter()
            .map(|c| c.len())
            .fold(count.min(status.len()), usize::min);
        // The first node is monotonic in the position (a clamped floor), so the box follows from
        // the smallest and largest active position per axis.
        let mut lo = [i32::MAX; D];
        let mut hi = [i32::MIN; D];
        for a in 0..D {
            let (mn, mx) = extremes(&x[a][..count], &status[..count], geom.origin[a], geom.inv_h);
            if mn <= mx {
                lo[a] = crate::shape::first_node::<K, S>(mn, geom.nodes[a]);
                hi[a] = crate::shape::first_node::<K, S>(mx, geom.nodes[a]);
            }
        }
        (lo, hi)
    }

    /// The box of the stencils whose first nodes per axis run from `lo` to `hi`
    /// ([`NodeBox::first_nodes`]), widened to the nodes before the axis and their images in
    /// the axisymmetric form, and to the images of the nodes past a wall plane.
    pub fn of_first_nodes<const K: usize>(geom: &Geom<D>, lo: [i32; D], hi: [i32; D]) -> Self {
        if lo[0] > hi[0] {
            // No active particle.
            return NodeBox {
                lo: [0; D],
                hi: [0; D],
                tail: 0,
            };
        }
        let mut b = NodeBox {
            lo: core::array::from_fn(|a| lo[a].max(0) as usize),
            hi: core::array::from_fn(|a| (hi[a].max(0) as usize + K).min(geom.nodes[a])),
            tail: ROW - K,
        };
        if geom.axis_mirror {
            b.lo[0] = 0;
            b.hi[0] = b.hi[0].max((2 * geom.margin + 1).min(geom.nodes[0]));
        }
        // A box that reaches past a wall plane also holds the images of the nodes it reaches
        // there ([`Geom::for_each_wall_image`]); along a periodic axis, the whole axis.
        for a in 0..D {
            let (n, m) = (geom.nodes[a], geom.margin);
            if geom.faces[a][0] == Boundary::Periodic {
                (b.lo[a], b.hi[a]) = (0, n);
                continue;
            }
            if geom.faces[a][0] != Boundary::Open && b.lo[a] < m {
                b.hi[a] = b.hi[a].max((2 * m + 1).min(n));
            }
            if geom.faces[a][1] != Boundary::Open && b.hi[a] + m > n {
                b.lo[a] = b.lo[a].min((n - 1).saturating_sub(2 * m));
            }
        }
        b
    }

    /// Whether the box holds no node.
    pub fn is_empty(&self) -> bool {
        (0..D).any(|a| self.lo[a] >= self.hi[a])
    }

    /// Calls `f` with each line of the box along x as a range of flat indices, `tail` entries
    /// past its end included (within `len`, the columns' length), every entry once.
    #[inline(always)]
    pub fn for_each_line(
        &self,
        stride: [usize; D],
        len: usize,
        mut f: impl FnMut(core::ops::Range<usize>),
    ) {
        self.lines(stride, len, &mut f);
    }

    /// [`NodeBox::for_each_line`] on the entries `window` of the columns alone, passed as
    /// ranges from `window.start` (the columns of a slab of the grid start there): the slabs
    /// of a partition of `0..len` visit every entry `for_each_line` visits, once.
    pub fn for_each_line_in(
        &self,
        stride: [usize; D],
        window: core::ops::Range<usize>,
        mut f: impl FnMut(core::ops::Range<usize>),
    ) {
        let first = window.start;
        self.lines(stride, window.end, &mut |r| {
            let start = r.start.max(first);
            if start < r.end {
                f(start - first..r.end - first);
            }
        });
    }

    /// [`NodeBox::for_each_line`], one copy per dimension: the loop takes its closure by
    /// reference (called once per line), so that the closures of every form of the step do not
    /// each bring their own copy of it.
    fn lines(&self, stride: [usize; D], len: usize, f: &mut dyn FnMut(core::ops::Range<usize>)) {
        if self.is_empty() {
            return;
        }
        let (k_lo, k_hi) = if D == 3 {
            (self.lo[D - 1], self.hi[D - 1])
        } else {
            (0, 1)
        };
        // A line's tail may run into the next line (past the last node along x): each entry is
        // passed once, lines being visited in increasing flat order.
        let mut done = 0;
        for k in k_lo..k_hi {
            for j in self.lo[1]..self.hi[1] {
                let line = j * stride[1] + if D == 3 { k * stride[D - 1] } else { 0 };
                let start = (line + self.lo[0]).clamp(done, len);
                let end = (line + self.hi[0] + self.tail).min(len);
                if start < end {
                    f(start..end);
                    done = end;
                }
            }
        }
    }
}

/// Grid geometry and the admissible region, in the precision and dimension of the step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Geom<const D: usize> {
    pub origin: [Real; D],
    pub h: Real,
    pub inv_h: Real,
    /// Nodes per axis (`cells + 1`).
    pub nodes: [usize; D],
    /// Flat index stride per axis.
    pub stride: [usize; D],
    /// Margin in cells.
    pub margin: usize,
    /// Admissible region, cell units: `[margin, cells - margin]` per axis.
    pub lo: [Real; D],
    pub hi: [Real; D],
    /// Boundary condition of the lower and upper face of each axis.
    pub faces: [[Boundary; 2]; D],
    /// Friction coefficient and velocity of the lower and upper wall of each axis
    /// (`WorldDef::wall_friction`, `WorldDef::wall_velocity`).
    pub wall_friction: [[Real; 2]; D],
    pub wall_velocity: [[[Real; D]; 2]; D],
    /// Axisymmetric: the nodes between the grid's first face and the axis (the wall plane of
    /// the lower r face) are the mirror images of those past the axis, for the momentum as past
    /// any wall ([`Geom::for_each_wall_image`]) and, here only, for heat and diffusion's
    /// scalars ([`Geom::for_each_scalar_image`]).
    pub axis_mirror: bool,
}

impl<const D: usize> Geom<D> {
    pub fn new(def: &WorldDef) -> Self {
        let margin = def.shape.margin_cells() as usize;
        let mut g = Geom {
            origin: [0.0; D],
            h: def.cell_size,
            inv_h: 1.0 / def.cell_size,
            nodes: [0; D],
            stride: [0; D],
            margin,
            lo: [0.0; D],
            hi: [0.0; D],
            faces: [[Boundary::Slip; 2]; D],
            wall_friction: [[0.0; 2]; D],
            wall_velocity: [[[0.0; D]; 2]; D],
            axis_mirror: def.dimension == crate::Dimension::Axisymmetric2D,
        };
        let mut stride = 1;
        for a in 0..D {
            g.origin[a] = def.origin[a];
            g.nodes[a] = def.cells[a] as usize + 1;
            g.stride[a] = stride;
            stride *= g.nodes[a];
            g.lo[a] = margin as Real;
            g.hi[a] = (def.cells[a] as usize - margin) as Real;
            g.faces[a] = [def.faces[2 * a], def.faces[2 * a + 1]];
            g.wall_friction[a] = [def.wall_friction[2 * a], def.wall_friction[2 * a + 1]];
            g.wall_velocity[a] = core::array::from_fn(|side| {
                core::array::from_fn(|b| def.wall_velocity[2 * a + side][b])
            });
        }
        g
    }

    /// The position of node `i` (flat index), m.
    pub fn node_position(&self, i: usize) -> [Real; D] {
        core::array::from_fn(|a| {
            let index = (i / self.stride[a]) % self.nodes[a];
            self.origin[a] + index as Real * self.h
        })
    }
}
