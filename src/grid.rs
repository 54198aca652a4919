//! Grid node columns, index math and boundary conditions.
//!
//! Nodes sit at `origin + h * (i, j, k)` for `i` in `0..=cells[0]` and so on; node `(i, j, k)`
//! has flat index `i + nx * (j + ny * k)` with `nx = cells[0] + 1`, `ny = cells[1] + 1`.
//!
//! The admissible region for particles is the grid shrunk by the shape function's margin
//! (`m` cells at each face, [`crate::ShapeFunction::margin_cells`]): there every node of a
//! particle's stencil exists. The walls of stick and slip faces act at that region's faces: all
//! nodes in the layer from the grid face to the wall plane are constrained.

use crate::def::{Boundary, WorldDef};
use crate::layout::Layout;
use crate::particles::Carver;
use crate::shape::{Row4, ROW};
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
    /// velocities here and divides by the mass. Empty with USL.
    pub remap: [&'a mut [Real]; D],
    /// Transported scalars (heat, diffusion; empty when not declared), 4 columns each: capacity
    /// (thermal mass `m_T`, or volume), momentum (`m_T T`), value (`T_i`, with the fixed
    /// faces), flow then rate (`Q_i`, then `Q_i / m_T`).
    pub scalar: [[&'a mut [Real]; 4]; 2],
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
        self.mass.len()
    }

    /// Whether every column has the length [`GridCols::len`] (the remap columns may be empty).
    /// True by construction; each pass checks it once so that the per-particle [`rows_fit`]
    /// check covers every column.
    pub fn lengths_consistent(&self) -> bool {
        let len = self.len();
        self.vel
            .iter()
            .chain(self.acc.iter())
            .all(|c| c.len() == len)
            && (self.remap.iter().all(|c| c.len() == len)
                || self.remap.iter().all(|c| c.is_empty()))
    }

    /// Carves the grid region (starting at `layout.grid_offset`) into columns, each `nodes`
    /// plus [`ROW`] entries of padding long (a stencil row may reach two entries past the last
    /// node; the padding only ever receives zero weights).
    pub fn carve(region: &'a mut [u8], layout: &Layout) -> Self {
        let mut c = Carver::new(region);
        let (b, n) = (layout.node_column_bytes, layout.nodes + ROW);
        let scalars = layout.scalar_grid.iter().filter(|&&b| b).count();
        let has_remap = layout.grid_columns > 1 + 2 * D + 4 * scalars;
        let mass = c.take(b, n);
        let vel = core::array::from_fn(|_| c.take(b, n));
        let acc = core::array::from_fn(|_| c.take(b, n));
        let remap = core::array::from_fn(|_| if has_remap { c.take(b, n) } else { &mut [][..] });
        let scalar = core::array::from_fn(|f| {
            core::array::from_fn(|_| {
                if layout.scalar_grid[f] {
                    c.take(b, n)
                } else {
                    &mut [][..]
                }
            })
        });
        GridCols {
            mass,
            vel,
            acc,
            remap,
            scalar,
        }
    }
}

/// The nodes a substep touches: the box `lo[a] <= index along a < hi[a]` that holds the
/// stencil of every active particle (empty without one), computed from the positions where
/// the substep starts ([`NodeBox::of_particles`]). The grid passes work on it alone, so a
/// grid larger than the material costs nothing per node it does not reach: a 32^3-cell block
/// in a 64^3 grid touches one node in six.
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

/// [`NodeBox::of_particles`] as a free function, for the instruction-set instances of
/// `world::passes`.
#[inline(always)]
pub(crate) fn node_box<const D: usize, const K: usize, S: crate::shape::Shape1D<K>>(
    geom: &Geom<D>,
    x: &[&[Real]; D],
    status: &[u32],
    count: usize,
) -> NodeBox<D> {
    NodeBox::of_particles::<K, S>(geom, x, status, count)
}

impl<const D: usize> NodeBox<D> {
    /// The box of the stencils of the active particles `0..count` (first nodes as the
    /// stencils clamp them, [`crate::shape::first_node`], for any position), widened to the
    /// nodes before the axis and their images in the axisymmetric form.
    #[inline(always)]
    pub fn of_particles<const K: usize, S: crate::shape::Shape1D<K>>(
        geom: &Geom<D>,
        x: &[&[Real]; D],
        status: &[u32],
        count: usize,
    ) -> Self {
        let count = x
            .iter()
            .map(|c| c.len())
            .fold(count.min(status.len()), usize::min);
        // The first node is monotonic in the position (a clamped floor), so the box follows from
        // the smallest and largest position per axis, a NaN counted as the lowest (the stencil
        // clamps it there). Lane-wise minima and maxima over chunks vectorise; the lanes are
        // reduced at the end.
        const L: usize = 16;
        let mut lo = [i32::MAX; D];
        let mut hi = [i32::MIN; D];
        for a in 0..D {
            let (col, status) = (&x[a][..count], &status[..count]);
            let mut mn = [Real::INFINITY; L];
            let mut mx = [Real::NEG_INFINITY; L];
            let (o, inv_h) = (geom.origin[a], geom.inv_h);
            let mut lane = |ln: usize, xi: Real, st: u32| {
                let s = (xi - o) * inv_h;
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
            let (xs, sts) = (col.chunks_exact(L), status.chunks_exact(L));
            let (x_rest, st_rest) = (xs.remainder(), sts.remainder());
            for (xs, sts) in xs.zip(sts) {
                for ln in 0..L {
                    lane(ln, xs[ln], sts[ln]);
                }
            }
            for (ln, (&xi, &st)) in x_rest.iter().zip(st_rest).enumerate() {
                lane(ln, xi, st);
            }
            let mn = mn
                .iter()
                .fold(Real::INFINITY, |m, &v| if v < m { v } else { m });
            let mx = mx
                .iter()
                .fold(Real::NEG_INFINITY, |m, &v| if v > m { v } else { m });
            if mn <= mx {
                lo[a] = crate::shape::first_node::<K, S>(mn, geom.nodes[a]);
                hi[a] = crate::shape::first_node::<K, S>(mx, geom.nodes[a]);
            }
        }
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
        // there ([`Geom::for_each_wall_image`]).
        for a in 0..D {
            let (n, m) = (geom.nodes[a], geom.margin);
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
    /// Axisymmetric: the nodes between the grid's first face and the axis (the wall plane of
    /// the lower r face) are the mirror images of those past the axis, for the momentum as past
    /// any wall ([`Geom::for_each_wall_image`]) and, here only, for heat and diffusion's
    /// scalars ([`Geom::for_each_mirror`]).
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

    /// Calls `f(node, fixed)` for every node between a grid face and its wall plane, for each
    /// stick or slip face, where `fixed[a]` says which velocity components the wall fixes to
    /// zero: all of them at a stick wall, the normal one at a slip wall. A node near an edge
    /// is visited once per face it belongs to.
    pub fn for_each_wall_node(&self, bx: &NodeBox<D>, f: &mut dyn FnMut(usize, [bool; D])) {
        for axis in 0..D {
            for side in 0..2 {
                let fixed: [bool; D] = match self.faces[axis][side] {
                    Boundary::Open => continue,
                    Boundary::Stick => [true; D],
                    Boundary::Slip => core::array::from_fn(|a| a == axis),
                };
                self.for_each_face_node(axis, side, bx, &mut |i, _| f(i, fixed));
            }
        }
    }

    /// Calls `f(node, on_wall_plane)` for every node between the grid face `side` (0 low, 1
    /// high) of `axis` and its wall plane (the admissible region's face), the plane included;
    /// `on_wall_plane` is true on that plane.
    pub fn for_each_face_node(
        &self,
        axis: usize,
        side: usize,
        bx: &NodeBox<D>,
        f: &mut dyn FnMut(usize, bool),
    ) {
        let n = self.nodes[axis];
        let (layers, wall) = if side == 0 {
            (0..self.margin + 1, self.margin)
        } else {
            (n - 1 - self.margin..n, n - 1 - self.margin)
        };
        for layer in layers {
            self.for_each_node_in_plane(axis, layer, bx, &mut |i| f(i, layer == wall));
        }
    }

    /// Calls `f(ghost, image)` for every node of box `bx` between the grid face `side` (0 low,
    /// 1 high) of `axis` and its wall plane, the plane excluded, with its mirror image across
    /// the plane (inside the admissible region).
    pub fn for_each_face_image(
        &self,
        axis: usize,
        side: usize,
        bx: &NodeBox<D>,
        f: &mut dyn FnMut(usize, usize),
    ) {
        let n = self.nodes[axis];
        for k in 1..=self.margin {
            let (ghost, image) = if side == 0 {
                (self.margin - k, self.margin + k)
            } else {
                (n - 1 - self.margin + k, n - 1 - self.margin - k)
            };
            if image >= n {
                continue;
            }
            let shift = image as isize - ghost as isize;
            self.for_each_node_in_plane(axis, ghost, bx, &mut |i| {
                let j = i as isize + shift * self.stride[axis] as isize;
                f(i, j as usize)
            });
        }
    }

    /// Calls `f(ghost, image, signs)` for every node of box `bx` past the wall plane of a stick
    /// or slip face (between the plane and the grid face) and its mirror image across the plane.
    /// A vector's component `a` at the ghost is `signs[a]` times the image's: the wall is a plane
    /// of symmetry for the material near it. At a slip wall the normal component flips
    /// (`signs[axis] = -1`) and the others do not: the image slides with the material and the
    /// velocity is zero across the plane only. At a stick wall every component flips: the
    /// velocity is zero on the plane, where the odd extension keeps a velocity field that is
    /// linear in the distance to the wall linear (the axisymmetric axis, a stick or slip face,
    /// mirrors as a slip wall: the body is symmetric about it). The wider stencils (B-splines)
    /// reach these nodes from material near the wall; without the images, zeroing them with the
    /// wall plane froze the strain of the material's first cell (a settled column's stress near
    /// its floor was off by up to 35 % of its weight).
    ///
    /// Faces in the order x low, x high, y low, ... or, `reversed`, the other way: folding in
    /// that order and reading back in reverse carries a corner node (past two walls) to its
    /// image across both.
    pub fn for_each_wall_image(
        &self,
        bx: &NodeBox<D>,
        reversed: bool,
        f: &mut dyn FnMut(usize, usize, [Real; D]),
    ) {
        for q in 0..2 * D {
            let face = if reversed { 2 * D - 1 - q } else { q };
            let (axis, side) = (face / 2, face % 2);
            let stick = match self.faces[axis][side] {
                Boundary::Open => continue,
                Boundary::Stick => !(self.axis_mirror && axis == 0 && side == 0),
                Boundary::Slip => false,
            };
            let signs: [Real; D] =
                core::array::from_fn(|a| if stick || a == axis { -1.0 } else { 1.0 });
            let (n, m) = (self.nodes[axis], self.margin);
            for k in 1..=m {
                // Ghost layer k past the wall plane, image layer k inside it.
                let (ghost, image) = if side == 0 {
                    (m - k, m + k)
                } else {
                    (n - 1 - m + k, n - 1 - m - k)
                };
                if image >= n {
                    continue;
                }
                self.for_each_node_in_plane(axis, ghost, bx, &mut |i| {
                    let j = if side == 0 {
                        i + 2 * k * self.stride[axis]
                    } else {
                        i - 2 * k * self.stride[axis]
                    };
                    f(i, j, signs)
                });
            }
        }
    }

    /// Adds what the particles put on each node past a wall plane to its image, component `a`
    /// of vector `cols` times the face's `signs[a]`, and empties it
    /// ([`Geom::for_each_wall_image`]; a scalar such as the mass is a vector of one component
    /// that never flips: pass it with `SCALAR`). Every index is below the node count, which
    /// every column exceeds: the bound checks never fail.
    pub fn fold_wall_images<const N: usize, const SCALAR: bool>(
        &self,
        cols: &mut [&mut [Real]; N],
        bx: &NodeBox<D>,
    ) {
        self.for_each_wall_image(bx, false, &mut |ghost, image, signs| {
            for (a, col) in cols.iter_mut().enumerate() {
                let sign = if SCALAR { 1.0 } else { signs[a] };
                if let (Some(&v), true) = (col.get(ghost), image < col.len()) {
                    col[image] += sign * v;
                    col[ghost] = 0.0;
                }
            }
        });
    }

    /// Each node past a wall plane takes its image's value, component `a` of vector `cols`
    /// times the face's `signs[a]` ([`Geom::for_each_wall_image`], faces in reverse).
    pub fn read_wall_images<const N: usize>(&self, cols: &mut [&mut [Real]; N], bx: &NodeBox<D>) {
        self.for_each_wall_image(bx, true, &mut |ghost, image, signs| {
            for (a, col) in cols.iter_mut().enumerate() {
                if let (Some(&v), true) = (col.get(image), ghost < col.len()) {
                    col[ghost] = signs[a] * v;
                }
            }
        });
    }

    /// Axisymmetric: calls `f(ghost, image)` for every node before the axis (r < 0) and its
    /// mirror image across the axis (r > 0); nothing otherwise. Material near the axis reaches
    /// those nodes with the wider stencils (B-splines); what it puts there belongs to the image
    /// node (the body is symmetric about the axis), and what the image has is read there, with
    /// the radial component's sign flipped.
    pub fn for_each_mirror(&self, bx: &NodeBox<D>, f: &mut dyn FnMut(usize, usize)) {
        if !self.axis_mirror {
            return;
        }
        for layer in 0..self.margin {
            let shift = 2 * (self.margin - layer) * self.stride[0];
            self.for_each_node_in_plane(0, layer, bx, &mut |i| f(i, i + shift));
        }
    }

    /// Axisymmetric: adds what the particles put on each node before the axis to its image,
    /// times `sign` (-1 for a radial component, 1 otherwise), and empties it. Nothing
    /// otherwise. Every index is below the node count, which every column exceeds: the bound
    /// checks never fail.
    pub fn fold_mirror(&self, col: &mut [Real], sign: Real, bx: &NodeBox<D>) {
        self.for_each_mirror(bx, &mut |ghost, image| {
            if let (Some(&v), true) = (col.get(ghost), image < col.len()) {
                col[image] += sign * v;
                col[ghost] = 0.0;
            }
        });
    }

    /// Axisymmetric: each node before the axis takes its image's value times `sign`. Nothing
    /// otherwise.
    pub fn mirror(&self, col: &mut [Real], sign: Real, bx: &NodeBox<D>) {
        self.for_each_mirror(bx, &mut |ghost, image| {
            if let (Some(&v), true) = (col.get(image), ghost < col.len()) {
                col[ghost] = sign * v;
            }
        });
    }

    /// Calls `f` with the flat index of every node of box `bx` whose index along `axis` is
    /// `layer`.
    fn for_each_node_in_plane(
        &self,
        axis: usize,
        layer: usize,
        bx: &NodeBox<D>,
        f: &mut dyn FnMut(usize),
    ) {
        if bx.is_empty() || layer < bx.lo[axis] || layer >= bx.hi[axis] {
            return;
        }
        // The box's extent along every other axis.
        let extent = |b: usize| if b == axis { 1 } else { bx.hi[b] - bx.lo[b] };
        let plane: usize = (0..D).map(extent).product();
        for q in 0..plane {
            // Decompose q over the other axes.
            let mut rem = q;
            let mut idx = layer * self.stride[axis];
            for b in 0..D {
                if b != axis {
                    idx += (bx.lo[b] + rem % extent(b)) * self.stride[b];
                    rem /= extent(b);
                }
            }
            f(idx);
        }
    }
}
