//! Particle forces, tractions and a body force (E14-E16, E72): the
//! per-particle forces and the tractions a host sets, and the traction pass, which integrates
//! each traction over its deformed face ([`Face`]). The particle forces enter the nodal force
//! in the scatter's rows (`S_ip F_p`, [`crate::phases::p2g`]); the body force is added to
//! gravity for the substep ([`crate::Effects::body_force`]).

use crate::grid::GridCols;
use crate::layout::{Layout, TractionRecord};
use crate::particles::{ParticleCols, ACTIVE};
use crate::phases::Ctx;
use crate::shape::{first_node, Shape1D, Stencil};
use crate::world::World;
use crate::{Error, Real, Vec3};
use core::ops::Range;

impl World<'_> {
    /// Sets the external force `F_p` (N; per unit thickness in plane strain) of particles
    /// `first..first + n`, `n` the length of the slices (z may be empty in 2D). Needs
    /// [`crate::Effects::particle_forces`]. The force stays until set again.
    pub fn set_particle_forces(&mut self, first: u32, force: [&[Real]; 3]) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        let group = (layout.force.count > 0).then_some(layout.force.first);
        let columns = &force[..layout.d];
        self.write_particle_columns(
            &layout,
            group,
            first,
            columns,
            Error::NonFiniteInput,
            |_| Ok(()),
        )
    }
    /// Adds one traction per particle of `particles`, each loading the `face` of that
    /// particle's domain with the traction `traction` (Pa: force per area of the deformed face,
    /// per unit thickness in plane strain, per radian axisymmetric); returns the range of their
    /// traction ids. The face is the side of the undeformed square (cube) of side
    /// `2 l_p = h / n` around the particle, carried along by its deformation: what
    /// [`World::add_surface_tractions`] loads with the face's normal and area `(2 l_p)^(D-1)`.
    /// All or nothing. Needs [`crate::Effects::traction_capacity`]. The tractions are
    /// integrated each substep into `f_iT` (E15, E16) while their particle is active.
    pub fn add_tractions(
        &mut self,
        particles: Range<u32>,
        face: crate::Face,
        traction: Vec3,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let d = def.axes();
        if face as usize / 2 >= d {
            return Err(Error::InvalidEffect);
        }
        let mut normal = Vec3::ZERO;
        normal[face as usize / 2] = if (face as usize).is_multiple_of(2) {
            -1.0
        } else {
            1.0
        };
        let side = def.cell_size / def.particles_per_cell as Real;
        let area = (1..d).fold(1.0, |a, _| a * side);
        self.add_surface_tractions(particles, normal, area, traction)
    }

    /// Adds one traction per particle of `particles`, each loading a plane face of outward
    /// normal `normal` and area `area` (m^2; m per unit thickness in plane strain and
    /// axisymmetric, the length of the face's trace in the (r, z) plane), both in the
    /// reference configuration, with the traction `traction` (Pa, per area of the deformed
    /// face; per radian axisymmetric); returns the range of their traction ids. Any normal in
    /// the plane (2D; its z is ignored) or in space: a curved surface is loaded by giving each
    /// particle at it the local normal and its share of the surface's area.
    ///
    /// The face is centred where the normal leaves the particle's undeformed domain (the
    /// square of half-width `l_p` around it), is a segment (2D) or square (3D) across the
    /// normal, and moves and deforms with the particle's `F`. All or nothing;
    /// `InvalidEffect` for a normal of zero length or not finite, an area not positive and
    /// finite, or a traction not finite. Needs [`crate::Effects::traction_capacity`].
    pub fn add_surface_tractions(
        &mut self,
        particles: Range<u32>,
        normal: Vec3,
        area: Real,
        traction: Vec3,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        if layout.traction_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let d = layout.d;
        let finite = (0..d).all(|a| traction[a].is_finite() && normal[a].is_finite());
        let length = crate::math::sqrt((0..d).map(|a| normal[a] * normal[a]).sum());
        // A normal must have a length whose square is a normal float and that is finite.
        let normal_ok = length > 1.0e-15 && length.is_finite();
        if !(finite && normal_ok && area > 0.0 && area.is_finite()) {
            return Err(Error::InvalidEffect);
        }
        if particles.start > particles.end {
            return Err(Error::UnknownParticle);
        }
        let n = (particles.end - particles.start) as usize;
        self.particle_range(particles.start, n)?;
        let used = self.header().traction_count as usize;
        if n > layout.traction_capacity - used {
            return Err(Error::TractionCapacityExceeded);
        }
        let in_plane = |v: Vec3, a: usize| if a < d { v[a] } else { 0.0 };
        let record = TractionRecord {
            particle: 0,
            schedule: 0,
            traction: core::array::from_fn(|a| if a == 3 { area } else { in_plane(traction, a) }),
            normal: core::array::from_fn(|a| in_plane(normal, a) / length),
        };
        let table = self.traction_records_mut(&layout, used, n);
        for (rec, particle) in table.iter_mut().zip(particles) {
            *rec = TractionRecord { particle, ..record };
        }
        self.header_mut().traction_count += n as u64;
        Ok(used as u32..(used + n) as u32)
    }

    /// Makes the tractions `ids` (a range [`World::add_tractions`] returned, or any part of the
    /// table) follow the schedule `schedule` of [`crate::Effects::traction_schedules`] (new
    /// tractions follow the first). All or nothing: `UnknownTraction` if the range is not
    /// within the table, `InvalidEffect` for a schedule past the list (nothing changes);
    /// `EffectNotDeclared` without [`crate::Effects::traction_capacity`].
    pub fn set_traction_schedule(&mut self, ids: Range<u32>, schedule: u32) -> Result<(), Error> {
        let (start, end, used) = self.traction_range(ids)?;
        if schedule as usize >= crate::TRACTION_SCHEDULES {
            return Err(Error::InvalidEffect);
        }
        let layout = Layout::of(&self.def());
        for rec in &mut self.traction_records_mut(&layout, 0, used)[start..end] {
            rec.schedule = schedule;
        }
        Ok(())
    }

    /// Removes every traction (the capacity stays).
    pub fn clear_tractions(&mut self) {
        self.header_mut().traction_count = 0;
    }

    /// Removes the tractions `ids` (a range [`World::add_tractions`] returned, or any part of
    /// the table), so that loads applied together can be taken off together; the tractions
    /// after them move down by `ids.len()`, in their order, and their room is free again.
    /// `UnknownTraction` if the range is not within the table (nothing is removed);
    /// `EffectNotDeclared` without [`crate::Effects::traction_capacity`].
    pub fn remove_tractions(&mut self, ids: Range<u32>) -> Result<(), Error> {
        let (start, end, used) = self.traction_range(ids)?;
        let layout = Layout::of(&self.def());
        self.traction_records_mut(&layout, 0, used)
            .copy_within(end..used, start);
        self.header_mut().traction_count = (used - (end - start)) as u64;
        Ok(())
    }

    /// `ids` as indices of the traction table, `(start, end, used)`, if it lies within the
    /// `used` entries: `EffectNotDeclared` without [`crate::Effects::traction_capacity`],
    /// else `UnknownTraction`.
    fn traction_range(&self, ids: Range<u32>) -> Result<(usize, usize, usize), Error> {
        if self.def().effects.traction_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let used = self.header().traction_count as usize;
        let (start, end) = (ids.start as usize, ids.end as usize);
        if start > end || end > used {
            return Err(Error::UnknownTraction);
        }
        Ok((start, end, used))
    }
}

/// Adds the tractions of the table to the nodal force, `f_iT = int N_i T dS` over each loaded
/// face (E15; E72 axisymmetric, where `dS = r dL` per radian).
///
/// The face ([`Face::of`]) is integrated by Gauss points, two along each of its sides. For the
/// families whose weights integrate over a particle domain (uGIMP, cpGIMP), `N_i` is the grid's
/// linear hat at each point, the points kept inside that domain: every node a point loads
/// then also carries mass of the particle, and the acceleration the traction gives a node of
/// small mass `S_ip m_p` stays within what the node's gradient can carry into a velocity
/// gradient (the hat at a point within `l_p` of the particle falls to zero no slower than the
/// integrated weight `S_ip`). For the point families (linear, B-splines) the hat or B-spline at
/// the face reaches nodes past the particle's own stencil, whose mass from it is zero or
/// vanishing: a force there is an acceleration without bound, which froze a 3D quadratic
/// B-spline block under USL. For them the face's resultant is spread with the particle's
/// weights, `f_iT = S_ip sum_q T dS_q` (E16): exact resultant, point of application moved by
/// `l_p` from the face to the particle.
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
        let t: [Real; D] = core::array::from_fn(|a| rec.traction[a] * scale.unwrap_or(0.0));
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
        if half[0] > 0.0 {
            let first: [usize; D] =
                core::array::from_fn(|a| first_node::<K, S>(s[a], geom.nodes[a]) as usize);
            // The face's weight on each node of the stencil, `sum_q N_i(x_q) dS_q`, x fastest.
            let mut weight = [0.0 as Real; 64];
            for (q, &ds) in face.points.iter().zip(&face.weights) {
                // Per axis, the hat of each stencil node at the point, the point kept inside
                // the domain (cell units, from the stencil's first node).
                let hat: [[Real; K]; D] = core::array::from_fn(|a| {
                    let (lo, hi) = (s[a] - half[a], s[a] + half[a]);
                    let sq = (q[a] - geom.origin[a]) * geom.inv_h;
                    let u = if sq < lo {
                        lo
                    } else if sq > hi {
                        hi
                    } else {
                        sq
                    };
                    let u = u - first[a] as Real;
                    core::array::from_fn(|k| (1.0 - (u - k as Real).abs()).max(0.0))
                });
                let z: [Real; K] = if D == 3 { hat[D - 1] } else { [1.0; K] };
                for (kz, wz) in z.iter().enumerate().take(if D == 3 { K } else { 1 }) {
                    for (ky, wy) in hat[1].iter().enumerate() {
                        let row = ds * wy * wz;
                        for (kx, wx) in hat[0].iter().enumerate() {
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
        } else {
            let total: Real = face.weights.iter().sum();
            let st = Stencil::<D, K>::new(shape, s, stretch, geom.nodes, geom.stride, geom.inv_h);
            st.for_each_node(geom.stride, |node, w, _| add(node, w * total));
        }
    }
}

/// A loaded face as Gauss points (2 in 2D, 2 x 2 in 3D) and their weights, the deformed area
/// (per radian axisymmetric) each stands for.
pub(crate) struct Face<const D: usize> {
    pub points: [[Real; D]; 4],
    pub weights: [Real; 4],
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
        Face { points, weights }
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
