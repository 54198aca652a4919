//! Walls and periodic faces (E20, E95): a stick or slip face's wall law on the nodes between
//! the grid face and the wall plane, and the images those nodes, and a periodic face's, fold
//! onto and read back, for the momentum and for heat and diffusion's scalars. Methods of the
//! grid's geometry ([`Geom`]), which holds the faces.

use crate::def::Boundary;
use crate::grid::{Geom, NodeBox};
use crate::Real;

impl<const D: usize> Geom<D> {
    /// Calls `f(node, axis, side)` for every node between a grid face and its wall plane, for
    /// each stick or slip face (`side` 0 low, 1 high, of `axis`). A node near an edge is
    /// visited once per face it belongs to.
    pub fn for_each_wall_node(&self, bx: &NodeBox<D>, f: &mut dyn FnMut(usize, usize, usize)) {
        for axis in 0..D {
            for side in 0..2 {
                if matches!(self.faces[axis][side], Boundary::Stick | Boundary::Slip) {
                    self.for_each_face_node(axis, side, bx, &mut |i, _| f(i, axis, side));
                }
            }
        }
    }

    /// The velocity the wall of face `side` of `axis` leaves a node whose updated velocity is
    /// `v` (E20, E94): a stick wall's own (along its plane); a slip wall's `v` without its
    /// normal part, and with Coulomb friction, where the node presses on it, on the part along
    /// the plane relative to the wall's velocity. `None` where it leaves `v` as it is but its
    /// normal part (a frictionless slip wall). An open or periodic face has no wall (the
    /// callers pass stick and slip faces, [`Geom::for_each_wall_node`]): `v` as it is.
    pub fn wall_law(&self, axis: usize, side: usize, v: [Real; D]) -> Option<[Real; D]> {
        let wall = self.wall_velocity[axis][side];
        match self.faces[axis][side] {
            Boundary::Open | Boundary::Periodic => Some(v),
            Boundary::Stick => Some(core::array::from_fn(
                |a| {
                    if a == axis {
                        0.0
                    } else {
                        wall[a]
                    }
                },
            )),
            Boundary::Slip => {
                let mu = self.wall_friction[axis][side];
                if mu == 0.0 {
                    return None;
                }
                let press = if side == 0 { -v[axis] } else { v[axis] };
                let t: [Real; D] =
                    core::array::from_fn(|a| if a == axis { 0.0 } else { v[a] - wall[a] });
                let speed = crate::math::sqrt(t.iter().map(|c| c * c).sum());
                let kept = if speed > 0.0 {
                    (1.0 - mu * press.max(0.0) / speed).max(0.0)
                } else {
                    0.0
                };
                Some(core::array::from_fn(|a| {
                    if a == axis {
                        0.0
                    } else {
                        wall[a] + t[a] * kept
                    }
                }))
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
    /// A periodic face's ghosts are the nodes from the grid face to its wall plane (the plane
    /// included on the high side, where it is the low plane's node), each the image of the
    /// node one period (E95) away, every component as it is.
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
                Boundary::Periodic => {
                    self.for_each_periodic_image(axis, side, bx, &mut |g, i| f(g, i, [1.0; D]));
                    continue;
                }
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

    /// Calls `f(ghost, image)` for every node of box `bx` between the periodic face `side` of
    /// `axis` and its wall plane (included on the high side), with its image one period
    /// (`cells - 2 margin` nodes) inward. Each image lies in the admissible region: an axis
    /// has at least `2 + 2 margin` cells (`layout::validate`), and no margin exceeds 1.
    fn for_each_periodic_image(
        &self,
        axis: usize,
        side: usize,
        bx: &NodeBox<D>,
        f: &mut dyn FnMut(usize, usize),
    ) {
        let (n, m) = (self.nodes[axis], self.margin);
        let shift = (n - 1 - 2 * m) * self.stride[axis];
        let layers = if side == 0 { 0..m } else { n - 1 - m..n };
        for layer in layers {
            self.for_each_node_in_plane(axis, layer, bx, &mut |i| {
                f(i, if side == 0 { i + shift } else { i - shift })
            });
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

    /// The images of a transported scalar's nodes: calls `f(ghost, image)` for every node
    /// before the axis (r < 0) and its mirror image across it (r > 0), axisymmetric, and for
    /// every node past a periodic face and its image ([`Geom::for_each_periodic_image`]);
    /// `reversed`, in the reverse order (as [`Geom::for_each_wall_image`], so that a corner
    /// node reads its image across both). Material near the axis reaches the nodes before it
    /// with the wider stencils (B-splines); what it puts there belongs to the image node (the
    /// body is symmetric about the axis), and what the image has is read there. A scalar
    /// wall needs no image: insulated, fixed and flux faces act on the nodes themselves.
    fn for_each_scalar_image(
        &self,
        bx: &NodeBox<D>,
        reversed: bool,
        f: &mut dyn FnMut(usize, usize),
    ) {
        let axis = |f: &mut dyn FnMut(usize, usize)| {
            if self.axis_mirror {
                for layer in 0..self.margin {
                    let shift = 2 * (self.margin - layer) * self.stride[0];
                    self.for_each_node_in_plane(0, layer, bx, &mut |i| f(i, i + shift));
                }
            }
        };
        if !reversed {
            axis(f);
        }
        for q in 0..2 * D {
            let face = if reversed { 2 * D - 1 - q } else { q };
            if self.faces[face / 2][face % 2] == Boundary::Periodic {
                self.for_each_periodic_image(face / 2, face % 2, bx, f);
            }
        }
        if reversed {
            axis(f);
        }
    }

    /// Adds what the particles put on each scalar ghost node to its image and empties it
    /// ([`Geom::for_each_scalar_image`]). Every index is below the node count, which every
    /// column exceeds: the bound checks never fail.
    pub fn fold_scalar_images(&self, col: &mut [Real], bx: &NodeBox<D>) {
        self.for_each_scalar_image(bx, false, &mut |ghost, image| {
            if let (Some(&v), true) = (col.get(ghost), image < col.len()) {
                col[image] += v;
                col[ghost] = 0.0;
            }
        });
    }

    /// Each scalar ghost node takes its image's value ([`Geom::for_each_scalar_image`]).
    pub fn read_scalar_images(&self, col: &mut [Real], bx: &NodeBox<D>) {
        self.for_each_scalar_image(bx, true, &mut |ghost, image| {
            if let (Some(&v), true) = (col.get(image), ghost < col.len()) {
                col[ghost] = v;
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
