//! The tractions' pass (E15-E16, E72): each traction a host set, integrated over its
//! particle's deformed face ([`Face`]), into the nodal force; a follower load along the
//! face's current normal and tangents ([`Face::along_frame`]). (Particle forces enter the nodal
//! force in the scatter's rows, `S_ip F_p`, [`super::p2g`]; the body force is added to gravity
//! for the substep, [`crate::Effects::body_force`].)

use super::Ctx;
use crate::grid::GridCols;
use crate::layout::TractionRecord;
use crate::particles::{ParticleCols, ACTIVE};
use crate::shape::{first_node, Shape1D};
use crate::Real;

/// Adds the tractions of the table to the nodal force, `f_iT = int N_i T dS` over each loaded
/// face (E15; E72 axisymmetric, where `dS = r dL` per radian).
///
/// The face ([`Face::of`]) is integrated by Gauss points, two along each of its sides. For the
/// families whose weights integrate over a particle domain (uGIMP, cpGIMP), `N_i` is the grid's
/// linear hat at each point, the points kept inside that domain: every node a point loads
/// then also carries mass of the particle, and the acceleration the traction gives a node of
/// small mass `S_ip m_p` stays within what the node's gradient can carry into a velocity
/// gradient (the hat at a point within `l_p` of the particle falls to zero no slower than the
/// integrated weight `S_ip`). For the point families (linear, B-splines) `N_i` is the family's
/// own weight at each point on the particle's stencil nodes alone, scaled per axis to add up
/// to 1 (E16): the weight at the face reaches nodes past the stencil, whose mass from the
/// particle is zero or vanishing (a force there is an acceleration without bound, which froze
/// a 3D quadratic B-spline block under USL when the load went there); on the stencil the
/// resultant stays exact and the load sits at the face, not at the particle (spread with
/// `S_ip`, the former rule, the quadratic B-spline's bore hoop stress in Lamé's cylinder was
/// 36 % off; now 1.4 %).
pub(crate) fn tractions<const D: usize, const K: usize, S: Shape1D<K>>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    let geom = &ctx.geom;
    for rec in ctx.tractions {
        let i = rec.particle as usize;
        if i >= count || p.status.get(i) != Some(&ACTIVE) {
            continue;
        }
        let x: [Real; D] = core::array::from_fn(|a| p.x[a][i]);
        let f: [[Real; D]; D] = core::array::from_fn(|a| {
            core::array::from_fn(|b| p.h[a][b][i] + if a == b { 1.0 } else { 0.0 })
        });
        let face = Face::<D>::of(rec, x, &f, ctx.half_width, S::AXISYMMETRIC);
        let scale = ctx.traction_scales.get(rec.schedule as usize).copied();
        let load = if rec.follows() {
            face.along_frame(&rec.traction)
        } else {
            core::array::from_fn(|a| rec.traction[a])
        };
        let t: [Real; D] = load.map(|c| c * scale.unwrap_or(0.0));
        let s: [Real; D] = core::array::from_fn(|a| (x[a] - geom.origin[a]) * geom.inv_h);
        let stretch = p.domain_stretch(i);
        let half: [Real; D] = core::array::from_fn(|a| shape.domain_half_width(stretch[a]));
        let mut add = |node: usize, w: Real| {
            for a in 0..D {
                if let Some(acc) = g.acc[a].get_mut(node) {
                    *acc += w * t[a];
                }
            }
        };
        let first: [usize; D] =
            core::array::from_fn(|a| first_node::<K, S>(s[a], geom.nodes[a]) as usize);
        // The face's weight on each node of the stencil, `sum_q N_i(x_q) dS_q`, x fastest.
        let mut weight = [0.0 as Real; 64];
        for (q, &ds) in face.points.iter().zip(&face.weights) {
            // Per axis, the weight of each stencil node at the point (cell units, from the
            // stencil's first node).
            let at: [[Real; K]; D] = core::array::from_fn(|a| {
                let sq = (q[a] - geom.origin[a]) * geom.inv_h;
                if half[a] > 0.0 {
                    // The grid's hat, the point kept inside the particle's domain.
                    let u = sq.clamp(s[a] - half[a], s[a] + half[a]) - first[a] as Real;
                    core::array::from_fn(|k| (1.0 - (u - k as Real).abs()).max(0.0))
                } else {
                    // The family's own weight, on the particle's nodes only, scaled to add
                    // up to 1 (the resultant stays exact).
                    let u = sq - first[a] as Real;
                    let w: [Real; K] = core::array::from_fn(|k| shape.eval(u - k as Real).0);
                    let sum: Real = w.iter().sum();
                    w.map(|w| if sum > 0.0 { w / sum } else { 0.0 })
                }
            });
            let z: [Real; K] = if D == 3 { at[D - 1] } else { [1.0; K] };
            for (kz, wz) in z.iter().enumerate().take(if D == 3 { K } else { 1 }) {
                for (ky, wy) in at[1].iter().enumerate() {
                    let row = ds * wy * wz;
                    for (kx, wx) in at[0].iter().enumerate() {
                        weight[kx + K * (ky + K * kz)] += wx * row;
                    }
                }
            }
        }
        for kz in 0..if D == 3 { K } else { 1 } {
            for ky in 0..K {
                let row = (first[1] + ky) * geom.stride[1]
                    + if D == 3 {
                        (first[D - 1] + kz) * geom.stride[D - 1]
                    } else {
                        0
                    };
                for kx in 0..K {
                    add(
                        row + (first[0] + kx) * geom.stride[0],
                        weight[kx + K * (ky + K * kz)],
                    );
                }
            }
        }
    }
}

/// A loaded face as Gauss points (2 in 2D, 2 x 2 in 3D) and their weights, the deformed area
/// (per radian axisymmetric) each stands for, and its current frame.
pub(crate) struct Face<const D: usize> {
    pub points: [[Real; D]; 4],
    pub weights: [Real; 4],
    /// The deformed face's unit outward normal `n` (along `F^-T N`), then its unit tangents
    /// `t1` (along `F T1`) and `t2 = n x t1` (zero in 2D).
    pub frame: [[Real; D]; 3],
}

impl<const D: usize> Face<D> {
    /// The face of `rec` on the particle at `x` with deformation gradient `f`, undeformed
    /// half-width `l_p`. In the reference configuration the face lies across the unit normal
    /// `N` at `delta N` from the particle, `delta = l_p / max_a |N_a|` (where `N` leaves the
    /// square of half-width `l_p`): a segment of length `A` along `t = (-N_y, N_x)` in 2D, a
    /// square of side `sqrt(A)` along two unit tangents in 3D. A point `o` of it is at
    /// `x + F o` now, and an element `dA` of it has the area `|F t| dA` (2D) or
    /// `|F t1 x F t2| dA` (3D), times the radius at the point axisymmetric.
    pub fn of(
        rec: &TractionRecord,
        x: [Real; D],
        f: &[[Real; D]; D],
        l_p: Real,
        axisymmetric: bool,
    ) -> Self {
        let n: [Real; D] = core::array::from_fn(|a| rec.normal[a]);
        let area = rec.traction[3];
        let reach = n.iter().fold(0.0 as Real, |m, c| m.max(c.abs()));
        let delta = l_p / reach;
        let tangents = tangents(n);
        let side = if D == 3 {
            crate::math::sqrt(area)
        } else {
            area
        };
        let g = side * 0.5 / crate::math::sqrt(3.0);
        let apply = |v: [Real; D]| -> [Real; D] {
            core::array::from_fn(|a| (0..D).map(|b| f[a][b] * v[b]).sum())
        };
        let ft = tangents.map(apply);
        let element = if D == 3 {
            let c = cross(ft[0], ft[1]);
            crate::math::sqrt(c.iter().map(|c| c * c).sum()) * area / 4.0
        } else {
            crate::math::sqrt(ft[0].iter().map(|c| c * c).sum()) * area / 2.0
        };
        let count = if D == 3 { 4 } else { 2 };
        let mut points = [[0.0; D]; 4];
        let mut weights = [0.0; 4];
        for q in 0..count {
            let u = [
                if q % 2 == 0 { -g } else { g },
                if q / 2 == 0 { -g } else { g },
            ];
            let o: [Real; D] = core::array::from_fn(|a| {
                delta * n[a] + (0..D - 1).map(|k| u[k] * tangents[k][a]).sum::<Real>()
            });
            let fo = apply(o);
            points[q] = core::array::from_fn(|a| x[a] + fo[a]);
            weights[q] = element
                * if axisymmetric {
                    points[q][0].max(0.0)
                } else {
                    1.0
                };
        }
        // The deformed frame: in 2D the normal is the carried tangent turned back by a right
        // angle (as `T1 = (-N_y, N_x)` is `N` turned forward), in 3D `F T1 x F T2`, which is
        // `cof(F) N` because `T1 x T2 = N`.
        let unit = |v: [Real; D]| {
            let len = crate::math::sqrt(v.iter().map(|c| c * c).sum());
            v.map(|c| c / len)
        };
        let t1 = unit(ft[0]);
        let n = if D == 3 {
            unit(cross(ft[0], ft[1]))
        } else {
            let mut n = [0.0; D];
            (n[0], n[1]) = (t1[1], -t1[0]);
            n
        };
        let frame = [n, t1, cross(n, t1)];
        Face {
            points,
            weights,
            frame,
        }
    }

    /// A load given along the frame (normal, then tangents) in the world's axes.
    pub fn along_frame(&self, load: &[Real; 4]) -> [Real; D] {
        core::array::from_fn(|a| (0..3).map(|k| load[k] * self.frame[k][a]).sum())
    }
}

/// Unit tangents of the face of unit normal `n` (the first `D - 1` are used): in 2D `n` turned
/// by a right angle; in 3D `t1 = n x e / |n x e|`, `e` the axis of `n`'s smallest component,
/// and `t2 = n x t1`.
fn tangents<const D: usize>(n: [Real; D]) -> [[Real; D]; 2] {
    if D == 2 {
        let mut t = [[0.0; D]; 2];
        (t[0][0], t[0][1]) = (-n[1], n[0]);
        return t;
    }
    let e = (0..D).fold(0, |k, a| if n[a].abs() < n[k].abs() { a } else { k });
    let axis: [Real; D] = core::array::from_fn(|a| if a == e { 1.0 } else { 0.0 });
    let c = cross(n, axis);
    let len = crate::math::sqrt(c.iter().map(|c| c * c).sum());
    let t1 = c.map(|c| c / len);
    [t1, cross(n, t1)]
}

/// The cross product of two 3-vectors (zero for any other `D`).
fn cross<const D: usize>(a: [Real; D], b: [Real; D]) -> [Real; D] {
    let mut c = [0.0; D];
    if D == 3 {
        c[0] = a[1] * b[2] - a[2] * b[1];
        c[1] = a[2] * b[0] - a[0] * b[2];
        c[2] = a[0] * b[1] - a[1] * b[0];
    }
    c
}
