//! Colliders (E90-E93, E96): solids that the material meets at the grid, moved by the host
//! (kinematic) or by the step (dynamic, `drive`), and the impulse it puts on them.
//!
//! A collider is a solid in its own frame ([`crate::ColliderShape`]) with a pose that moves
//! with its velocities (E90). A node is in contact with it where material touches the solid:
//! a particle whose domain reaches the surface marks the nodes its weights reach, and each
//! marked node inside the solid or within a band outside it (the grid functions' reach) that
//! carries mass has its updated velocity replaced by what the contact law leaves (E91, E92),
//! relative to the solid's velocity at the node; the momentum it takes from the node is what
//! the material puts on the collider (E93), summed node by node in node order on the calling
//! thread, so that it has one worker's bits for any number of workers.

use crate::def::{ColliderDef, ColliderShape, Contact};
use crate::grid::{Geom, NodeBox};
use crate::layout::{ColliderImpulse, ColliderRecord};
use crate::math::{ceil, floor};
use crate::Real;
use glam::{DQuat, DVec3};

/// A vector of three [`Real`]s (z is 0 in 2D).
type V3 = [Real; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V3, s: Real) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> Real {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: V3) -> Real {
    crate::math::sqrt(dot(a, a))
}

/// The solid's lengths, m.
#[derive(Clone, Copy, Debug)]
enum Solid<'s> {
    HalfSpace,
    Sphere(Real),
    Box(V3),
    Capsule(Real, Real),
    /// Half-length, radius, inner radius.
    Cylinder(Real, Real, Real),
    /// A distance field: its samples (x fastest), points per axis, spacing.
    Sdf(&'s [Real], [usize; 3], Real),
}

/// One collider at one instant, in the world frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Collider<'s> {
    solid: Solid<'s>,
    contact: Contact,
    friction: Real,
    /// The frame's origin, m.
    pub centre: V3,
    /// The frame's axes in the world (rows: x, y, z).
    axes: [V3; 3],
    velocity: V3,
    omega: V3,
}

/// The shape number of `s` in a [`ColliderRecord`], its lengths, and a distance field's
/// first sample and points per axis ([`ColliderShape::parts`]).
pub(crate) fn shape_record(s: &ColliderShape) -> (u64, [f64; 3], [u64; 4]) {
    let (lengths, grid) = s.parts();
    (
        s.number() as u64,
        lengths.map(|l| l as f64),
        grid.map(|g| g as u64),
    )
}

/// The shape of a record's number, lengths and grid (`None`: a number no build writes, or a
/// distance field's numbers past `u32`).
pub(crate) fn shape_of(code: u64, size: [f64; 3], grid: [u64; 4]) -> Option<ColliderShape> {
    let grid = [
        u32::try_from(grid[0]).ok()?,
        u32::try_from(grid[1]).ok()?,
        u32::try_from(grid[2]).ok()?,
        u32::try_from(grid[3]).ok()?,
    ];
    ColliderShape::from_parts(u32::try_from(code).ok()?, size.map(|l| l as Real), grid)
}

/// The contact's number in a record, and back.
pub(crate) fn contact_code(c: Contact) -> u64 {
    c as u64
}
pub(crate) fn contact_of(code: u64) -> Option<Contact> {
    [Contact::Stick, Contact::Slip, Contact::Separate]
        .get(code as usize)
        .copied()
}

impl ColliderRecord {
    /// The definition the record holds, in its pose of `pose_time`, its values rounded to
    /// [`Real`] (what [`crate::WorldRef::collider`] reads back); `None` for a shape or contact
    /// number no build writes, or a distance field's numbers past `u32`.
    pub fn def(&self) -> Option<ColliderDef> {
        let v = |a: [f64; 3]| crate::Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
        Some(ColliderDef {
            shape: shape_of(self.shape, self.size, self.grid)?,
            position: v(self.position),
            rotation: self.rotation.map(|c| c as Real),
            velocity: v(self.velocity),
            angular_velocity: v(self.angular_velocity),
            contact: contact_of(self.contact)?,
            friction: self.friction as Real,
            mass: self.mass as Real,
            inertia: v(self.inertia),
        })
    }

    /// Whether the record is one that [`crate::World::add_collider`] (or `set_collider`)
    /// could have written, and steps moved on since, in a world of time `time`, `samples`
    /// distance samples and `planar` (2D) motion or not: the definition it holds passes
    /// `add_collider`'s checks ([`ColliderDef::is_valid`]: every value the world reads finite
    /// as a [`Real`], lengths positive, friction and mass >= 0, a rotation of non-zero
    /// length); what no step changes (shape, lengths, contact, friction, mass, inertia, the
    /// components the world does not read) and the velocities (which a dynamic collider's
    /// substeps store as [`Real`]s) are what `add_collider` makes of that definition, bit for
    /// bit; the
    /// rotation is of unit length; the pose is of the world's time (the calls pose a record
    /// then, and a step moves it on to the step's end); a distance field lies within the
    /// samples.
    pub fn is_valid(&self, samples: u64, planar: bool, time: f64) -> bool {
        let Some(def) = self.def().filter(|d| d.is_valid(planar)) else {
            return false;
        };
        let again = def.record(planar, time);
        let kept = (
            again.shape,
            again.contact,
            again.friction,
            again.size,
            again.grid,
            again.mass,
            again.inertia,
        ) == (
            self.shape,
            self.contact,
            self.friction,
            self.size,
            self.grid,
            self.mass,
            self.inertia,
        ) && again.velocity == self.velocity
            && again.angular_velocity == self.angular_velocity;
        let read = ColliderDef::read_components(planar)[0];
        let in_plane = (0..3).all(|a| read[a] || self.position[a] == 0.0);
        let q2: f64 = self.rotation.iter().map(|c| c * c).sum();
        let field = match def.shape {
            ColliderShape::Sdf { first, dims, .. } => dims
                .iter()
                .try_fold(1u64, |n, &k| n.checked_mul(k as u64))
                .and_then(|n| n.checked_add(first as u64))
                .is_some_and(|end| end <= samples),
            _ => true,
        };
        kept && in_plane && (q2 - 1.0).abs() < 1e-6 && self.pose_time == time && field
    }
}

impl ColliderImpulse {
    /// The impulse and angular impulse summed so far in the step, as one list.
    fn sums(&self) -> [f64; 6] {
        core::array::from_fn(|a| {
            if a < 3 {
                self.linear[a]
            } else {
                self.angular[a - 3]
            }
        })
    }

    /// What of [`ColliderImpulse::sums`] a dynamic collider has not yet taken into its
    /// velocities: what the material put on it in the substep so far (E96).
    pub(crate) fn untaken(&self) -> [f64; 6] {
        let sums = self.sums();
        core::array::from_fn(|a| sums[a] - self.taken[a])
    }
}

/// The pose of record `r` at world time `t` (E90): its position moved on by `v (t - t_0)`, its
/// rotation turned by `omega (t - t_0)` about its origin.
pub(crate) fn pose_at(r: &ColliderRecord, t: f64) -> (DVec3, DQuat) {
    let tau = t - r.pose_time;
    let position = DVec3::from_array(r.position) + DVec3::from_array(r.velocity) * tau;
    let turn = DQuat::from_scaled_axis(DVec3::from_array(r.angular_velocity) * tau);
    let rotation = (turn * DQuat::from_array(r.rotation)).normalize();
    (position, rotation)
}

/// A dynamic collider (mass > 0) after a substep that ends at world time `end` (E96): its
/// pose moved on with the velocities the substep held, then those velocities changed by what
/// the material put on it in the substep (its impulse sums less what it has `taken`) and by
/// `gravity` over `dt`. Semi-implicit Euler, as the particles: the pose the next substep
/// meets was reached with the velocities this one's contact used. A moment of inertia of 0
/// keeps the turn about that axis; in `planar` motion only the plane's components change.
/// The velocities are stored as [`Real`]s, as the API writes them. A kinematic collider is
/// left as it is (the step moves it at its end).
pub(crate) fn drive(
    r: &mut ColliderRecord,
    sums: &mut ColliderImpulse,
    end: f64,
    dt: f64,
    gravity: DVec3,
    planar: bool,
) {
    if !r.mass.is_finite() || r.mass <= 0.0 {
        return;
    }
    let (position, rotation) = pose_at(r, end);
    r.position = position.to_array();
    r.rotation = rotation.to_array();
    r.pose_time = end;
    let [x, y, z, p, q, s] = sums.untaken();
    let linear = DVec3::new(x, y, z);
    let angular = DVec3::new(p, q, s);
    sums.taken = sums.sums();
    // The angular impulse in the solid's frame, over its principal moments.
    let local = rotation.inverse() * angular;
    let inv = |l: f64, i: f64| if i > 0.0 { l / i } else { 0.0 };
    let inertia = r.inertia;
    let spin = rotation
        * DVec3::new(
            inv(local.x, inertia[0]),
            inv(local.y, inertia[1]),
            inv(local.z, inertia[2]),
        );
    let v = DVec3::from_array(r.velocity) + linear / r.mass + gravity * dt;
    let w = DVec3::from_array(r.angular_velocity) + spin;
    let [_, read_v, read_w] = ColliderDef::read_components(planar);
    let stored = |x: f64, read: bool| if read { x as Real as f64 } else { 0.0 };
    r.velocity = core::array::from_fn(|a| stored(v[a], read_v[a]));
    r.angular_velocity = core::array::from_fn(|a| stored(w[a], read_w[a]));
}

/// The velocities a dynamic collider shares with the nodes its contact holds in a substep
/// (E96): `K xi' = M xi + sum_i m_i G_i^T P_i u_i`, `K = M + sum_i m_i G_i^T P_i G_i`, with
/// `xi = (v, omega)` the body's velocities and mass matrix `M`, `G_i xi = v + omega x r_i` the
/// solid's velocity at node `i`, `u_i` the node's updated velocity and `P_i` what the law
/// holds of it (`n n^T`, all of it for stick). The contact then takes the nodes to the body's
/// new velocities, and the impulse it reads back takes the body there: body and nodes end
/// the substep together, however light the body, as an inelastic collision does.
pub(crate) struct Shared {
    k: [[f64; 6]; 6],
    rhs: [f64; 6],
    /// The velocities the body keeps: off the plane in 2D, about an axis of no moment.
    fixed: [bool; 6],
    xi: [f64; 6],
    /// The nodes held so far, their count and the sum of their masses' bits: which set of
    /// nodes the system holds, to tell when it no longer changes.
    held: (u32, u64),
}

impl Shared {
    /// The body's velocities at the start of the substep, with gravity's `g dt` and the
    /// momenta it has `received` from the material so far in the substep (impulse, then
    /// angular impulse: a second pass after XPIC's series, E100): what it would move at
    /// without more contact, as a node's updated velocity is without contact.
    pub fn new(
        c: &Collider<'_>,
        r: &ColliderRecord,
        planar: bool,
        g_dt: V3,
        received: [f64; 6],
    ) -> Shared {
        let xi: [f64; 6] = core::array::from_fn(|a| {
            if a < 3 {
                (c.velocity[a] + g_dt[a]) as f64
            } else {
                c.omega[a - 3] as f64
            }
        });
        let mut k = [[0.0; 6]; 6];
        let mut fixed = [false; 6];
        for (a, row) in k.iter_mut().enumerate().take(3) {
            row[a] = r.mass;
        }
        // The inertia about the world axes, `A I A^T` (the frame's axes `A`); an axis of no
        // moment keeps its turn.
        for a in 0..3 {
            for b in 0..3 {
                k[3 + a][3 + b] = (0..3)
                    .map(|j| c.axes[j][a] as f64 * r.inertia[j] * c.axes[j][b] as f64)
                    .sum();
            }
        }
        let read = ColliderDef::read_components(planar);
        for a in 0..3 {
            fixed[a] = !read[1][a];
            let moment = k[3 + a][3 + a];
            fixed[3 + a] = !read[2][a] || moment.is_nan() || moment <= 0.0;
        }
        let mut rhs = [0.0; 6];
        for a in 0..6 {
            rhs[a] = (0..6).map(|b| k[a][b] * xi[b]).sum::<f64>() + received[a];
        }
        Shared {
            k,
            rhs,
            fixed,
            xi,
            held: (0, 0),
        }
    }

    /// Adds a node of mass `m` at `x` whose updated velocity is `u`, the surface's normal
    /// there `n`, where the contact holds it: any stick or slip contact, and a separating one
    /// where the node presses on the body moving at `c`'s velocities.
    pub fn add(&mut self, c: &Collider<'_>, x: V3, m: Real, u: V3, n: V3) {
        let rel = sub(u, c.velocity_at(x));
        if c.contact == Contact::Separate && dot(rel, n) >= 0.0 {
            return;
        }
        self.held.0 += 1;
        self.held.1 = self.held.1.wrapping_add((m as f64).to_bits());
        let r = sub(x, c.centre);
        // G's columns: the point's velocity per unit of each of the body's velocities.
        let g: [V3; 6] = core::array::from_fn(|a| {
            let mut e = [0.0; 3];
            e[a % 3] = 1.0;
            if a < 3 {
                e
            } else {
                cross(e, r)
            }
        });
        let held = |v: V3| match c.contact {
            Contact::Stick => v,
            _ => scale(n, dot(v, n)),
        };
        let m = m as f64;
        let pg: [V3; 6] = core::array::from_fn(|a| held(g[a]));
        let pu = held(u);
        for a in 0..6 {
            self.rhs[a] += m * dot(g[a], pu) as f64;
            for b in 0..6 {
                self.k[a][b] += m * dot(g[a], pg[b]) as f64;
            }
        }
    }

    /// Which nodes the system holds (their count and a sum over them).
    pub fn held(&self) -> (u32, u64) {
        self.held
    }

    /// The collider `c` at the shared velocities (its own where the system is singular).
    pub fn solve<'s>(mut self, c: Collider<'s>) -> Collider<'s> {
        // A velocity the body keeps: its row says so, and the other rows take it as known.
        for a in 0..6 {
            if self.fixed[a] {
                for r in 0..6 {
                    self.rhs[r] -= self.k[r][a] * self.xi[a];
                    self.k[r][a] = 0.0;
                }
                self.k[a] = [0.0; 6];
                self.k[a][a] = 1.0;
                self.rhs[a] = self.xi[a];
            }
        }
        // Gaussian elimination with partial pivoting.
        let (mut k, mut x) = (self.k, self.rhs);
        for col in 0..6 {
            let pivot = (col..6).fold(col, |p, r| {
                if k[r][col].abs() > k[p][col].abs() {
                    r
                } else {
                    p
                }
            });
            if k[pivot][col] == 0.0 || k[pivot][col].is_nan() {
                return c;
            }
            k.swap(col, pivot);
            x.swap(col, pivot);
            for r in col + 1..6 {
                let f = k[r][col] / k[col][col];
                for j in col..6 {
                    k[r][j] -= f * k[col][j];
                }
                x[r] -= f * x[col];
            }
        }
        for col in (0..6).rev() {
            let tail: f64 = (col + 1..6).map(|j| k[col][j] * x[j]).sum();
            x[col] = (x[col] - tail) / k[col][col];
        }
        if x.iter().any(|v| !v.is_finite()) {
            return c;
        }
        Collider {
            velocity: core::array::from_fn(|a| x[a] as Real),
            omega: core::array::from_fn(|a| x[3 + a] as Real),
            ..c
        }
    }
}

impl<'s> Collider<'s> {
    /// The collider of record `r` at world time `t`, a distance field's samples in `samples`
    /// (the world's); `None` for a record no build writes or a field past the samples.
    pub fn at(r: &ColliderRecord, t: f64, samples: &'s [Real]) -> Option<Collider<'s>> {
        let (position, rotation) = pose_at(r, t);
        let solid = match shape_of(r.shape, r.size, r.grid)? {
            ColliderShape::HalfSpace => Solid::HalfSpace,
            ColliderShape::Sphere { radius } => Solid::Sphere(radius),
            ColliderShape::Box { half_extents: e } => Solid::Box([e.x, e.y, e.z]),
            ColliderShape::Capsule {
                half_length,
                radius,
            } => Solid::Capsule(half_length, radius),
            ColliderShape::Cylinder {
                half_length,
                radius,
                inner_radius,
            } => Solid::Cylinder(half_length, radius, inner_radius),
            ColliderShape::Sdf {
                first,
                dims,
                spacing,
            } => {
                let [nx, ny, nz] = dims.map(|g| g as usize);
                if nx < 2 || ny < 2 || nz < 1 {
                    return None;
                }
                let (first, n) = (first as usize, nx.checked_mul(ny)?.checked_mul(nz)?);
                let field = samples.get(first..first.checked_add(n)?)?;
                Solid::Sdf(field, [nx, ny, nz], spacing)
            }
        };
        let axis = |a: DVec3| (rotation * a).to_array().map(|c| c as Real);
        Some(Collider {
            solid,
            contact: contact_of(r.contact)?,
            friction: r.friction as Real,
            centre: position.to_array().map(|c| c as Real),
            axes: [axis(DVec3::X), axis(DVec3::Y), axis(DVec3::Z)],
            velocity: r.velocity.map(|c| c as Real),
            omega: r.angular_velocity.map(|c| c as Real),
        })
    }

    /// The signed distance from the solid's surface at `x` (negative inside), m, and the
    /// surface's outward unit normal there (E91).
    pub fn distance(&self, x: V3) -> (Real, V3) {
        self.distance_and(x, true)
    }

    /// [`Collider::distance`], the normal only `with_normal` (a distance field's takes four or
    /// six more samplings: a node outside needs none).
    fn distance_and(&self, x: V3, with_normal: bool) -> (Real, V3) {
        let d = sub(x, self.centre);
        let p: V3 = core::array::from_fn(|a| dot(self.axes[a], d));
        let (phi, n) = local_distance(self.solid, p, with_normal);
        let world = add(
            add(scale(self.axes[0], n[0]), scale(self.axes[1], n[1])),
            scale(self.axes[2], n[2]),
        );
        (phi, world)
    }

    /// Whether the signed distance at `x` ([`Collider::distance`]) is certainly above `t`, m,
    /// from a bound cheaper than the distance itself: `false` where it may not be. The bound
    /// is below the distance by more than the distance's round-off (a margin of 64 ulp of the
    /// coordinates' and lengths' scale), so a point it passes over is one the distance would
    /// put above `t` too: the tests that use it decide as the distance does, bit for bit.
    pub fn farther_than(&self, x: V3, t: Real) -> bool {
        let d = sub(x, self.centre);
        let p: V3 = core::array::from_fn(|a| dot(self.axes[a], d));
        let (bound, size) = match self.solid {
            // A shell's distance is at least its radial and its axial part's (E91).
            Solid::Cylinder(h, r, inner) => {
                let rho = crate::math::sqrt(p[0] * p[0] + p[2] * p[2]);
                (shell_radial(rho, r, inner).0.max(p[1].abs() - h), h.max(r))
            }
            // A box's, its farthest face's.
            Solid::Box(e) => {
                let q = (0..3).fold(Real::MIN, |m, a| m.max(p[a].abs() - e[a]));
                (q, e[0].max(e[1]).max(e[2]))
            }
            // The others cost about their bound: the distance itself decides.
            _ => return false,
        };
        let scale = p.iter().fold(size + t.abs(), |m, c| m.max(c.abs()));
        bound > t + 64.0 * Real::EPSILON * scale
    }

    /// The box `[lo, hi]` (world axes, m) that holds the solid, or `None` where it is
    /// unbounded (a half-space).
    pub fn bounds(&self) -> Option<(V3, V3)> {
        let e: V3 = match self.solid {
            Solid::HalfSpace => return None,
            Solid::Sphere(r) => [r; 3],
            Solid::Box(e) => e,
            Solid::Capsule(h, r) => [r, h + r, r],
            Solid::Cylinder(h, r, _) => [r, h, r],
            // The field's box: distances past it only grow.
            Solid::Sdf(_, n, spacing) => {
                core::array::from_fn(|a| 0.5 * (n[a] - 1) as Real * spacing)
            }
        };
        // Half the box along world axis `i`: the frame's axes' reach, `sum_j |axis_j[i]| e_j`.
        let half: V3 = core::array::from_fn(|i| (0..3).map(|j| self.axes[j][i].abs() * e[j]).sum());
        Some((sub(self.centre, half), add(self.centre, half)))
    }

    /// The velocity of the solid's point at `x`: `v + omega x (x - c)`.
    pub fn velocity_at(&self, x: V3) -> V3 {
        add(self.velocity, cross(self.omega, sub(x, self.centre)))
    }

    /// The velocity the contact leaves a node in contact at `x`, where the surface's outward
    /// normal is `n`, whose updated velocity is `v` (E92), or `None` where it leaves `v` as it
    /// is (separating).
    pub fn contact(&self, x: V3, v: V3, n: V3) -> Option<V3> {
        self.law(self.contact, x, v, n)
    }

    /// [`Collider::contact`] on USF's lagged velocity, which the stress update reads and no
    /// impulse pays for (E92): a separating contact holds it as slip does, in both
    /// directions. Released where the lagged velocity parts from the solid and held where it
    /// presses, a node would keep the noise that moves it apart and drop the noise that
    /// presses: a ratchet that turns the particles' velocity noise into strain energy no
    /// impulse accounts for.
    pub fn hold(&self, x: V3, v: V3, n: V3) -> Option<V3> {
        let law = match self.contact {
            Contact::Separate => Contact::Slip,
            law => law,
        };
        self.law(law, x, v, n)
    }

    /// Sets `contact` to 1 at the nodes of the box `lo..hi` (node indices per axis) that an
    /// active particle of `p` (of the first `count`) reaches whose domain, of half-width `l`,
    /// touches the solid (its centre within `l` of the surface, or inside), and to 0 at the
    /// box's other nodes (E91). A particle reaches the nodes within `band + l` of its centre
    /// along each axis: those whose grid functions, `band` wide, reach its domain.
    #[allow(clippy::too_many_arguments)]
    pub fn mark_reached<const D: usize>(
        &self,
        geom: &Geom<D>,
        p: &crate::particles::ParticleCols<'_, D>,
        count: usize,
        l: Real,
        band: Real,
        (lo, hi): ([usize; D], [usize; D]),
        contact: &mut [Real],
    ) {
        let mut fill = |lo: [usize; D], hi: [usize; D], value: Real| {
            let len = contact.len();
            NodeBox { lo, hi, tail: 0 }.for_each_line(geom.stride, len, |r| contact[r].fill(value));
        };
        fill(lo, hi, 0.0);
        let bounds = self.bounds();
        let reach = band + l;
        for i in 0..count.min(p.status.len()) {
            if p.status[i] != crate::particles::ACTIVE {
                continue;
            }
            let x: V3 = core::array::from_fn(|a| {
                if a < D {
                    p.x[a][i] + p.x_low[a][i]
                } else {
                    0.0
                }
            });
            if let Some((min, max)) = bounds {
                if (0..D).any(|a| !(x[a] >= min[a] - l && x[a] <= max[a] + l)) {
                    continue;
                }
            }
            if self.farther_than(x, l) {
                continue;
            }
            let phi = self.distance_and(x, false).0;
            if phi > l || phi.is_nan() {
                continue;
            }
            // The box's nodes within `reach` of the particle, per axis.
            let mut from = [0usize; D];
            let mut to = [0usize; D];
            for a in 0..D {
                let u = (x[a] - geom.origin[a]) * geom.inv_h;
                let r = reach * geom.inv_h;
                from[a] = (ceil(u - r).max(0.0) as usize).max(lo[a]);
                to[a] = ((floor(u + r).max(-1.0) + 1.0) as usize).min(hi[a]);
            }
            fill(from, to, 1.0);
        }
    }

    fn law(&self, law: Contact, x: V3, v: V3, n: V3) -> Option<V3> {
        let vc = self.velocity_at(x);
        let rel = sub(v, vc);
        let vn = dot(rel, n);
        let tangent = match law {
            Contact::Stick => return Some(vc),
            Contact::Separate if vn >= 0.0 => return None,
            Contact::Slip | Contact::Separate => sub(rel, scale(n, vn)),
        };
        // Coulomb: where the node presses on the solid (`v_n < 0`), the tangential speed falls
        // by `mu |v_n|`, down to sticking; a slip contact pulled apart keeps it.
        let speed = norm(tangent);
        let kept = if speed > 0.0 {
            (1.0 - self.friction * (-vn).max(0.0) / speed).max(0.0)
        } else {
            0.0
        };
        Some(add(vc, scale(tangent, kept)))
    }
}

/// A cylindrical shell's radial distance at `rho` from its axis (outer radius `r`, hollow
/// within `inner` when above 0): past the outer face, or inside the inner one (`true`: the
/// nearer face is the inner, its outward normal pointing to the axis).
fn shell_radial(rho: Real, r: Real, inner: Real) -> (Real, bool) {
    if inner > 0.0 && inner - rho > rho - r {
        (inner - rho, true)
    } else {
        (rho - r, false)
    }
}

/// The signed distance and outward normal of `solid` at `p` in its own frame (E91).
fn local_distance(solid: Solid<'_>, p: V3, with_normal: bool) -> (Real, V3) {
    let up = [0.0, 1.0, 0.0];
    let unit = |v: V3, fallback: V3| {
        let l = norm(v);
        if l > 0.0 {
            scale(v, 1.0 / l)
        } else {
            fallback
        }
    };
    match solid {
        Solid::Sdf(field, n, spacing) => {
            // The normal: the field's gradient, by central differences half a spacing apart.
            let d = 0.5 * spacing;
            let phi = field_distance(field, n, spacing, p);
            if !with_normal {
                return (phi, up);
            }
            let grad: V3 = core::array::from_fn(|a| {
                if n[a] < 2 {
                    return 0.0;
                }
                let (mut lo, mut hi) = (p, p);
                lo[a] -= d;
                hi[a] += d;
                field_distance(field, n, spacing, hi) - field_distance(field, n, spacing, lo)
            });
            (phi, unit(grad, up))
        }
        Solid::HalfSpace => (p[1], up),
        Solid::Sphere(r) => (norm(p) - r, unit(p, up)),
        Solid::Box(e) => {
            let q: V3 = core::array::from_fn(|a| p[a].abs() - e[a]);
            let sign = |a: usize| if p[a] < 0.0 { -1.0 } else { 1.0 };
            let outside: V3 = core::array::from_fn(|a| q[a].max(0.0) * sign(a));
            if q.iter().any(|&c| c > 0.0) {
                (norm(outside), unit(outside, up))
            } else {
                // Inside: the nearest face.
                let a = (0..3).fold(0, |m, a| if q[a] > q[m] { a } else { m });
                let mut n = [0.0; 3];
                n[a] = sign(a);
                (q[a], n)
            }
        }
        Solid::Capsule(h, r) => {
            let d = [p[0], p[1] - p[1].clamp(-h, h), p[2]];
            (norm(d) - r, unit(d, [1.0, 0.0, 0.0]))
        }
        Solid::Cylinder(h, r, inner) => {
            let rho = crate::math::sqrt(p[0] * p[0] + p[2] * p[2]);
            let radial = unit([p[0], 0.0, p[2]], [1.0, 0.0, 0.0]);
            let (dr, inward) = shell_radial(rho, r, inner);
            let radial = if inward { scale(radial, -1.0) } else { radial };
            let axial = [0.0, if p[1] < 0.0 { -1.0 } else { 1.0 }, 0.0];
            let dy = p[1].abs() - h;
            if dr > 0.0 || dy > 0.0 {
                let (or, oy) = (dr.max(0.0), dy.max(0.0));
                let o = add(scale(radial, or), scale(axial, oy));
                (norm(o), unit(o, up))
            } else if dr > dy {
                (dr, radial)
            } else {
                (dy, axial)
            }
        }
    }
}

impl ColliderDef {
    /// The buffer's record of this (checked) definition, posed at `pose_time`: its rotation
    /// normalised; `planar` (2D), the components a 2D world does not read stored as 0
    /// ([`ColliderDef::read_components`]: in the plane z = 0, no z velocity, no turn but
    /// about z).
    pub(crate) fn record(&self, planar: bool, pose_time: f64) -> ColliderRecord {
        let w = |v: crate::Vec3, keep: [bool; 3]| {
            core::array::from_fn(|a| if keep[a] { v[a] as f64 } else { 0.0 })
        };
        let [position, velocity, omega] = ColliderDef::read_components(planar);
        let (shape, size, grid) = shape_record(&self.shape);
        let q = self.rotation.map(|c| c as f64);
        let len = libm::sqrt(q.iter().map(|c| c * c).sum::<f64>());
        ColliderRecord {
            shape,
            contact: contact_code(self.contact),
            friction: self.friction as f64,
            size,
            position: w(self.position, position),
            rotation: q.map(|c| c / len),
            velocity: w(self.velocity, velocity),
            angular_velocity: w(self.angular_velocity, omega),
            pose_time,
            grid,
            mass: self.mass as f64,
            inertia: w(self.inertia, omega),
        }
    }

    /// The signed distance from this collider's surface at `x` (negative inside), m, in the
    /// pose it has: what the step tests each node with (E91), for a host that draws it or
    /// seeds material around it. `None` for a definition [`crate::World::add_collider`]
    /// refuses, and for a distance field, whose samples the world holds
    /// ([`crate::WorldRef::collider_distance`]).
    pub fn distance(&self, x: crate::Vec3) -> Option<Real> {
        if !self.is_valid(false) {
            return None;
        }
        let record = self.record(false, 0.0);
        // A distance field's samples are the world's: `None` here.
        Some(Collider::at(&record, 0.0, &[])?.distance([x.x, x.y, x.z]).0)
    }
}

/// The distance field `field` (points `n` per axis, `spacing` apart, centred on the origin,
/// x fastest) at `p`: interpolated linearly between its points (an axis of one point is
/// constant along it), plus the distance from `p` to the field's box where `p` is outside it.
fn field_distance(field: &[Real], n: [usize; 3], spacing: Real, p: V3) -> Real {
    let mut index = [0usize; 3];
    let mut frac: V3 = [0.0; 3];
    let mut outside: V3 = [0.0; 3];
    for a in 0..3 {
        let half = 0.5 * (n[a] - 1) as Real * spacing;
        let clamped = p[a].clamp(-half, half);
        outside[a] = p[a] - clamped;
        if n[a] < 2 {
            continue;
        }
        let u = (clamped + half) / spacing;
        let i = (u as usize).min(n[a] - 2);
        index[a] = i;
        frac[a] = (u - i as Real).clamp(0.0, 1.0);
    }
    let at = |i: usize, j: usize, k: usize| {
        field
            .get(i + n[0] * (j + n[1] * k))
            .copied()
            .unwrap_or(Real::MAX)
    };
    let lerp = |a: Real, b: Real, t: Real| a + (b - a) * t;
    let (i, j, k) = (index[0], index[1], index[2]);
    let (k1, fz) = if n[2] < 2 { (k, 0.0) } else { (k + 1, frac[2]) };
    let plane = |k: usize| {
        lerp(
            lerp(at(i, j, k), at(i + 1, j, k), frac[0]),
            lerp(at(i, j + 1, k), at(i + 1, j + 1, k), frac[0]),
            frac[1],
        )
    };
    lerp(plane(k), plane(k1), fz) + norm(outside)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(shape: ColliderShape) -> ColliderRecord {
        let (code, size, grid) = shape_record(&shape);
        ColliderRecord {
            shape: code,
            contact: contact_code(Contact::Separate),
            size,
            grid,
            rotation: [0.0, 0.0, 0.0, 1.0],
            ..ColliderRecord::default()
        }
    }

    #[test]
    fn distances_of_each_solid_at_known_points() {
        let at = |shape, x: V3| Collider::at(&record(shape), 0.0, &[]).unwrap().distance(x);
        let close = |a: Real, b: Real| (a - b).abs() < 1e-6;
        assert!(close(
            at(ColliderShape::HalfSpace, [3.0, -0.25, 1.0]).0,
            -0.25
        ));
        let sphere = ColliderShape::Sphere { radius: 1.0 };
        let (phi, n) = at(sphere, [0.0, 0.0, 2.0]);
        assert!(close(phi, 1.0) && close(n[2], 1.0));
        let bx = ColliderShape::Box {
            half_extents: crate::Vec3::new(1.0, 2.0, 3.0),
        };
        assert!(close(at(bx, [0.5, 0.0, 0.0]).0, -0.5));
        assert!(close(at(bx, [4.0, 6.0, 0.0]).0, 5.0));
        let capsule = ColliderShape::Capsule {
            half_length: 1.0,
            radius: 0.5,
        };
        assert!(close(at(capsule, [0.0, 3.0, 0.0]).0, 1.5));
        assert!(close(at(capsule, [1.0, 0.3, 0.0]).0, 0.5));
        let cylinder = ColliderShape::Cylinder {
            half_length: 1.0,
            radius: 0.5,
            inner_radius: 0.0,
        };
        assert!(close(at(cylinder, [0.0, 0.9, 0.0]).0, -0.1));
        assert!(close(at(cylinder, [3.5, 5.0, 0.0]).0, 5.0));
        // A tube of radii 0.3 and 0.5: inside its hole, in its wall, outside it.
        let tube = ColliderShape::Cylinder {
            half_length: 1.0,
            radius: 0.5,
            inner_radius: 0.3,
        };
        let (phi, n) = at(tube, [0.1, 0.0, 0.0]);
        assert!(
            close(phi, 0.2) && close(n[0], -1.0),
            "in the hole: {phi} {n:?}"
        );
        assert!(close(at(tube, [0.0, 0.0, 0.45]).0, -0.05));
        assert!(close(at(tube, [0.7, 0.0, 0.0]).0, 0.2));
    }

    #[test]
    fn a_turned_moving_collider_is_where_its_velocities_take_it() {
        // A floor turned 90 degrees about z after a quarter turn at pi/2 rad/s for 1 s,
        // moved by (1, 0, 0): its normal +y is now -x, its plane through x = 1.
        let mut r = record(ColliderShape::HalfSpace);
        r.velocity = [1.0, 0.0, 0.0];
        r.angular_velocity = [0.0, 0.0, core::f64::consts::FRAC_PI_2];
        let c = Collider::at(&r, 1.0, &[]).unwrap();
        let (phi, n) = c.distance([0.0, 0.0, 0.0]);
        assert!(
            (phi - 1.0).abs() < 1e-5 && (n[0] + 1.0).abs() < 1e-5,
            "{phi} {n:?}"
        );
    }

    #[test]
    fn contact_laws_keep_what_each_promises() {
        let mut r = record(ColliderShape::HalfSpace);
        let inside = [0.0, -0.1, 0.0];
        let v = [2.0, -1.0, 0.0];
        let up = [0.0, 1.0, 0.0];
        r.contact = contact_code(Contact::Stick);
        assert_eq!(
            Collider::at(&r, 0.0, &[]).unwrap().contact(inside, v, up),
            Some([0.0; 3])
        );
        r.contact = contact_code(Contact::Slip);
        assert_eq!(
            Collider::at(&r, 0.0, &[]).unwrap().contact(inside, v, up),
            Some([2.0, 0.0, 0.0])
        );
        // Coulomb with mu = 0.5: the tangential speed 2 falls by 0.5 * 1.
        r.friction = 0.5;
        assert_eq!(
            Collider::at(&r, 0.0, &[]).unwrap().contact(inside, v, up),
            Some([1.5, 0.0, 0.0])
        );
        r.contact = contact_code(Contact::Separate);
        let c = Collider::at(&r, 0.0, &[]).unwrap();
        assert_eq!(c.contact(inside, [2.0, 1.0, 0.0], up), None, "separating");
    }
}
