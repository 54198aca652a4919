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
    /// Nodal mass m_i (eq 23).
    pub mass: &'a mut [Real],
    /// Momentum p_i (eq 25) after particle-to-grid; velocity v_i = p_i / m_i after the grid update.
    pub vel: [&'a mut [Real]; D],
    /// Force f_i (eq 22) after particle-to-grid; acceleration a_i = f_i / m_i + g after the grid update.
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
    /// the lower r face) are the mirror images of those past the axis ([`Geom::for_each_mirror`]).
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

    /// Calls `f(node, fixed)` for every node between a grid face and its wall plane, for each
    /// stick or slip face, where `fixed[a]` says which velocity components the wall fixes to
    /// zero: all of them at a stick wall, the normal one at a slip wall. A node near an edge
    /// is visited once per face it belongs to.
    pub fn for_each_wall_node(&self, mut f: impl FnMut(usize, [bool; D])) {
        for axis in 0..D {
            for side in 0..2 {
                let fixed: [bool; D] = match self.faces[axis][side] {
                    Boundary::Open => continue,
                    Boundary::Stick => [true; D],
                    Boundary::Slip => core::array::from_fn(|a| a == axis),
                };
                self.for_each_face_node(axis, side, |i, _| f(i, fixed));
            }
        }
    }

    /// Calls `f(node, on_wall_plane)` for every node between the grid face `side` (0 low, 1
    /// high) of `axis` and its wall plane (the admissible region's face), the plane included;
    /// `on_wall_plane` is true on that plane.
    pub fn for_each_face_node(&self, axis: usize, side: usize, mut f: impl FnMut(usize, bool)) {
        let n = self.nodes[axis];
        let (layers, wall) = if side == 0 {
            (0..self.margin + 1, self.margin)
        } else {
            (n - 1 - self.margin..n, n - 1 - self.margin)
        };
        for layer in layers {
            self.for_each_node_in_plane(axis, layer, |i| f(i, layer == wall));
        }
    }

    /// Axisymmetric: calls `f(ghost, image)` for every node before the axis (r < 0) and its
    /// mirror image across the axis (r > 0); nothing otherwise. Material near the axis reaches
    /// those nodes with the wider stencils (B-splines); what it puts there belongs to the image
    /// node (the body is symmetric about the axis), and what the image has is read there, with
    /// the radial component's sign flipped.
    pub fn for_each_mirror(&self, mut f: impl FnMut(usize, usize)) {
        if !self.axis_mirror {
            return;
        }
        for layer in 0..self.margin {
            let shift = 2 * (self.margin - layer) * self.stride[0];
            self.for_each_node_in_plane(0, layer, |i| f(i, i + shift));
        }
    }

    /// Axisymmetric: adds what the particles put on each node before the axis to its image,
    /// times `sign` (-1 for a radial component, 1 otherwise), and empties it. Nothing
    /// otherwise. Every index is below the node count, which every column exceeds: the bound
    /// checks never fail.
    pub fn fold_mirror(&self, col: &mut [Real], sign: Real) {
        self.for_each_mirror(|ghost, image| {
            if let (Some(&v), true) = (col.get(ghost), image < col.len()) {
                col[image] += sign * v;
                col[ghost] = 0.0;
            }
        });
    }

    /// Axisymmetric: each node before the axis takes its image's value times `sign`. Nothing
    /// otherwise.
    pub fn mirror(&self, col: &mut [Real], sign: Real) {
        self.for_each_mirror(|ghost, image| {
            if let (Some(&v), true) = (col.get(image), ghost < col.len()) {
                col[ghost] = sign * v;
            }
        });
    }

    /// Calls `f` with the flat index of every node whose index along `axis` is `layer`.
    fn for_each_node_in_plane(&self, axis: usize, layer: usize, mut f: impl FnMut(usize)) {
        let total: usize = self.nodes.iter().product();
        let plane = total / self.nodes[axis];
        for q in 0..plane {
            // Decompose q over the other axes.
            let mut rem = q;
            let mut idx = layer * self.stride[axis];
            for b in 0..D {
                if b != axis {
                    idx += (rem % self.nodes[b]) * self.stride[b];
                    rem /= self.nodes[b];
                }
            }
            f(idx);
        }
    }
}
