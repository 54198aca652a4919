//! Grid update (E17-E20): nodal velocity `v_i = p_i / m_i`, acceleration
//! `a_i = f_i / m_i + g`, so that `p_i(n+1) = p_i + (f_i + m_i g) dt` is `m_i (v_i + a_i dt)`;
//! then the boundary, colliders and walls, from one function ([`boundary`]).
//!
//! The node-by-node parts run on slabs of the grid ([`Nodes::each_slab`], in parallel where
//! the step has several workers: a node's new value depends on that node alone); the
//! boundary, whose walls fold nodes onto their images across lines, on the whole grid.

use super::Ctx;
use crate::boundary::colliders::{Collider, Shared};
use crate::def::UpdateOrder;
use crate::effects::damping::NodalDamping;
use crate::grid::GridCols;
use crate::layout::{ColliderImpulse, ColliderRecord};
use crate::math::{ceil, floor};
use crate::particles::ParticleCols;
use crate::Real;

/// The node columns of a substep, as the grid passes take them: whole, or in slabs of whole
/// lines that partition the node box's entries (each slab's columns start at its first
/// entry, [`GridCols::window`]).
pub(crate) trait Nodes<const D: usize> {
    /// The whole grid.
    fn whole(&mut self) -> GridCols<'_, D>;
    /// Runs `f` on each slab, in any order or at once.
    fn each_slab(&mut self, f: &(dyn Fn(&mut GridCols<'_, D>) + Sync));
    /// The whole grid, the particles (which the colliders' contact reads, E91) and the
    /// colliders' impulses of the step ([`ColliderImpulse`]).
    fn with_impulses(&mut self) -> (GridCols<'_, D>, ParticleCols<'_, D>, &mut [ColliderImpulse]);
}

/// Zeroes every nodal column the step accumulates into, on the nodes of the substep
/// ([`crate::grid::NodeBox`]).
pub(crate) fn reset<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    nodes.each_slab(&|g| zero_all(ctx, g));
}

fn zero_all<const D: usize>(ctx: &Ctx<'_, D>, g: &mut GridCols<'_, D>) {
    let window = g.window();
    ctx.active.for_each_line_in(ctx.geom.stride, window, |r| {
        zero(g.mass, r.clone());
        for a in 0..D {
            zero(g.vel[a], r.clone());
            zero(g.acc[a], r.clone());
            zero(g.remap[a], r.clone());
        }
    });
}

/// Zeroes `col[r]` (nothing for an empty column: the remap columns with USL).
fn zero(col: &mut [Real], r: core::ops::Range<usize>) {
    if let Some(c) = col.get_mut(r) {
        c.fill(0.0);
    }
}

/// `cols[a][i] /= m_i` (zero on nodes at or below the mass cutoff), plus `add[a]`.
pub(crate) fn divide_by_mass<const D: usize>(
    ctx: &Ctx<'_, D>,
    mass: &[Real],
    cols: &mut [&mut [Real]; D],
    add: [Real; D],
    window: core::ops::Range<usize>,
) {
    let cutoff = ctx.mass_cutoff;
    ctx.active.for_each_line_in(ctx.geom.stride, window, |r| {
        for (a, col) in cols.iter_mut().enumerate() {
            if let (Some(col), Some(mass)) = (col.get_mut(r.clone()), mass.get(r.clone())) {
                divide_line(col, mass, cutoff, add[a]);
            }
        }
    });
}

/// The body force's part that changes with position, `a_i += G x_i` (E14,
/// [`crate::Effects::body_force_gradient`]), on the nodes of `window` with mass.
fn add_body_gradient<const D: usize>(
    ctx: &Ctx<'_, D>,
    mass: &[Real],
    cols: &mut [&mut [Real]; D],
    gradient: &[[Real; D]; D],
    window: core::ops::Range<usize>,
) {
    let geom = &ctx.geom;
    let offset = window.start;
    ctx.active.for_each_line_in(geom.stride, window, |r| {
        // A range may run past the end of its grid line (as in `damp_nodes`): one line at
        // a time, each from its first node's position.
        let mut start = r.start;
        while start < r.end {
            let along = (start + offset) % geom.nodes[0];
            let end = r.end.min(start - along + geom.nodes[0]);
            let mut x = geom.node_position(start + offset);
            for node in start..end {
                x[0] = geom.origin[0] + (along + node - start) as Real * geom.h;
                if mass.get(node).is_some_and(|&m| m > ctx.mass_cutoff) {
                    for (a, col) in cols.iter_mut().enumerate() {
                        if let Some(c) = col.get_mut(node) {
                            *c += (0..D).map(|b| gradient[a][b] * x[b]).sum::<Real>();
                        }
                    }
                }
            }
            start = end;
        }
    });
}

/// One line of [`divide_by_mass`]: a function of its own, whose slices the compiler knows
/// apart, so that the loop vectorises (inlined into the closure of a grid pass, it stayed
/// scalar, and the grid passes took four times as long).
#[inline(never)]
fn divide_line(col: &mut [Real], mass: &[Real], cutoff: Real, add: Real) {
    for (c, &m) in col.iter_mut().zip(mass) {
        *c = if m > cutoff { *c / m + add } else { 0.0 };
    }
}

/// Folds the nodes past the wall planes onto their images, or reads the images back into them
/// ([`crate::grid::Geom::for_each_wall_image`]), for every component of a nodal vector.
pub(crate) fn mirror_vector<const D: usize>(
    ctx: &Ctx<'_, D>,
    cols: &mut [&mut [Real]; D],
    fold: bool,
) {
    if fold {
        ctx.geom.fold_wall_images::<D, false>(cols, &ctx.active);
    } else {
        ctx.geom.read_wall_images(cols, &ctx.active);
    }
}

/// Momentum to velocity `v_i = p_i / m_i` (E18). The walls are not applied here: they act
/// on the updated velocity through the acceleration (see [`acceleration`]).
pub(crate) fn velocity<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    {
        let g = &mut nodes.whole();
        ctx.geom
            .fold_wall_images::<1, true>(&mut [&mut *g.mass], &ctx.active);
        mirror_vector(ctx, &mut g.vel, true);
    }
    nodes.each_slab(&|g| {
        let window = g.window();
        divide_by_mass(ctx, g.mass, &mut g.vel, [0.0; D], window)
    });
    mirror_vector(ctx, &mut nodes.whole().vel, false);
}

/// Force to acceleration `a_i = f_i / m_i + g` (E19), the nodal damping, then the boundary
/// on the updated velocity ([`boundary`]). The particle update then sees a wall stop the
/// material (FLIP adds `sum S_ip a_i dt`), instead of keeping velocity the grid no longer has.
pub(crate) fn acceleration<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    mirror_vector(ctx, &mut nodes.whole().acc, true);
    nodes.each_slab(&|g| {
        let window = g.window();
        divide_by_mass(ctx, g.mass, &mut g.acc, ctx.gravity, window.clone());
        if let Some(gradient) = &ctx.body_gradient {
            add_body_gradient(ctx, g.mass, &mut g.acc, gradient, window);
        }
        if let Some(nodal) = &ctx.nodal_damping {
            damp_nodes(ctx, nodal, g);
        }
    });
    boundary_on_updated(ctx, nodes);
}

/// The boundary on the updated velocity `v_i + a_i dt` ([`boundary`]): the colliders, each
/// impulse taking what its contact changes (E92, E93), then the walls (E20). After the
/// lumped update, and again on XPIC's and FMPM's series ([`super::xpic::finish`], E100), so
/// that the velocity the particles read keeps the contact: the second pass changes only what
/// the series moved, and pays for it.
pub(crate) fn boundary_on_updated<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    let (g, p, impulses) = &mut nodes.with_impulses();
    boundary(ctx, g, p, On::Updated(impulses));
}

/// The boundary on the nodes of the substep ([`crate::boundary`]), the one place the grid
/// update applies it: the colliders (E92), then the walls of stick and slip faces, then the
/// nodes past the wall planes take their images' values. On the updated velocity
/// `v_i + a_i dt` through the acceleration: where a wall fixes a component to `w`, the
/// acceleration becomes the wall's reaction `(w - v_i) / dt` (E20). On the re-mapped (MUSL) or
/// lagged (USF) velocity the stress update reads: the wall's values themselves.
fn boundary<const D: usize>(
    ctx: &Ctx<'_, D>,
    g: &mut GridCols<'_, D>,
    p: &ParticleCols<'_, D>,
    on: On<'_>,
) {
    let updated = matches!(on, On::Updated(_));
    collide(ctx, g, p, on);
    if updated {
        return walls_on_updated(ctx, g);
    }
    // On the stress update's velocity itself.
    let (walls, geom) = (&ctx.active, &ctx.geom);
    geom.for_each_wall_node(walls, &mut |i, axis, side| {
        let v: [Real; D] = core::array::from_fn(|a| g.remap[a][i]);
        match geom.wall_law(axis, side, v) {
            Some(w) => {
                for a in 0..D {
                    g.remap[a][i] = w[a];
                }
            }
            None => g.remap[axis][i] = 0.0,
        }
    });
    // Past the wall planes the nodes take their images' values.
    mirror_vector(ctx, &mut g.remap, false);
}

/// The walls of stick and slip faces on the updated velocity `v_i + a_i dt`, through the
/// acceleration: where a wall fixes a component to `w`, the acceleration becomes the wall's
/// reaction `(w - v_i) / dt` (E20); then the nodes past the wall planes take their images'
/// accelerations.
fn walls_on_updated<const D: usize>(ctx: &Ctx<'_, D>, g: &mut GridCols<'_, D>) {
    let (inv_dt, dt) = (1.0 / ctx.dt, ctx.dt);
    let (walls, geom) = (&ctx.active, &ctx.geom);
    geom.for_each_wall_node(walls, &mut |i, axis, side| {
        let v: [Real; D] = core::array::from_fn(|a| g.vel[a][i] + g.acc[a][i] * dt);
        match geom.wall_law(axis, side, v) {
            Some(w) => {
                for a in 0..D {
                    // A wall at rest gives `-v / dt`, the bits of the walls before they moved.
                    g.acc[a][i] = if w[a] == 0.0 {
                        -g.vel[a][i] * inv_dt
                    } else {
                        (w[a] - g.vel[a][i]) * inv_dt
                    };
                }
            }
            None => g.acc[axis][i] = -g.vel[axis][i] * inv_dt,
        }
    });
    mirror_vector(ctx, &mut g.acc, false);
}

/// Nodal damping (E49, E50): `a_i -= alpha_g(t, x_i) v_i`, with the rate of the grid
/// (when it acts on the force) and of the zones at the node. Before the walls: at a wall the
/// fixed components then take the wall's value, damped or not.
fn damp_nodes<const D: usize>(ctx: &Ctx<'_, D>, nodal: &NodalDamping, g: &mut GridCols<'_, D>) {
    let geom = &ctx.geom;
    let n = geom.nodes[0];
    // Node indices: the slab's entry `k` is node `offset + k`.
    let window = g.window();
    let offset = window.start;
    ctx.active.for_each_line_in(geom.stride, window, |r| {
        // A range may run past the end of its grid line: one line at a time.
        let r = r.start + offset..r.end + offset;
        let mut start = r.start;
        while start < r.end {
            let first = start % n;
            let end = r.end.min(start - first + n);
            let line = nodal.on_line(&geom.node_position(start));
            // The rates of up to BLOCK nodes at a time, then `a -= rate v` on each axis.
            const BLOCK: usize = 64;
            let mut rates = [line.at(0.0); BLOCK];
            for from in (start..end).step_by(BLOCK) {
                let to = end.min(from + BLOCK);
                let rates = &mut rates[..to - from];
                if !line.uniform() {
                    for (k, rate) in rates.iter_mut().enumerate() {
                        let index = first + (from - start) + k;
                        *rate = line.at(geom.origin[0] + index as Real * geom.h);
                    }
                }
                for a in 0..D {
                    let local = from - offset..to - offset;
                    let (Some(acc), Some(vel)) =
                        (g.acc[a].get_mut(local.clone()), g.vel[a].get(local))
                    else {
                        return; // Unreachable: every line lies within the columns.
                    };
                    for ((acc, &v), &rate) in acc.iter_mut().zip(vel).zip(rates.iter()) {
                        *acc -= rate * v;
                    }
                }
            }
            start = end;
        }
    });
}

/// MUSL: re-mapped momentum to velocity, with the walls (it is an updated velocity).
pub(crate) fn remap_velocity<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    mirror_vector(ctx, &mut nodes.whole().remap, true);
    nodes.each_slab(&|g| {
        let window = g.window();
        divide_by_mass(ctx, g.mass, &mut g.remap, [0.0; D], window)
    });
    constrain_remapped(ctx, nodes);
}

/// The walls (and colliders) on the re-mapped velocity.
pub(crate) fn constrain_remapped<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    let (g, p, _) = &mut nodes.with_impulses();
    constrain_remap(ctx, g, p);
}

/// USF: the lagged velocity with the walls applied, for the stress update; the unconstrained
/// one stays in `vel` for the particle update and the wall reaction.
pub(crate) fn constrained_velocity<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    nodes.each_slab(&|g| {
        let (window, remap, vel) = (g.window(), &mut g.remap, &g.vel);
        ctx.active.for_each_line_in(ctx.geom.stride, window, |r| {
            for a in 0..D {
                if let (Some(to), Some(from)) = (remap[a].get_mut(r.clone()), vel[a].get(r.clone()))
                {
                    to.copy_from_slice(from);
                }
            }
        });
    });
    let (g, p, _) = &mut nodes.with_impulses();
    constrain_remap(ctx, g, p);
}

fn constrain_remap<const D: usize>(
    ctx: &Ctx<'_, D>,
    g: &mut GridCols<'_, D>,
    p: &ParticleCols<'_, D>,
) {
    let on = match ctx.order {
        UpdateOrder::Musl => On::Remapped,
        _ => On::Lagged,
    };
    boundary(ctx, g, p, on);
}

/// Runs `f` on each node of the box `lo..hi` in contact with `c` (E91), in node order: its
/// index, position, mass and the surface's outward normal there.
fn each_contact<const D: usize>(
    ctx: &Ctx<'_, D>,
    g: &mut GridCols<'_, D>,
    c: &Collider<'_>,
    (lo, hi): ([usize; D], [usize; D]),
    mut f: impl FnMut(&mut GridCols<'_, D>, usize, [Real; 3], Real, [Real; 3]),
) {
    let geom = &ctx.geom;
    let n = g.len();
    let at = |a: usize, index: usize| geom.origin[a] + index as Real * geom.h;
    let layers = if D == 3 { lo[D - 1]..hi[D - 1] } else { 0..1 };
    for z in layers {
        for j in lo[1]..hi[1] {
            let line = j * geom.stride[1] + if D == 3 { z * geom.stride[D - 1] } else { 0 };
            let (y, zz) = (at(1, j), if D == 3 { at(D - 1, z) } else { 0.0 });
            for i in lo[0]..hi[0] {
                let node = line + i;
                let m = g.mass.get(node).copied().unwrap_or(0.0);
                if m <= ctx.mass_cutoff || m.is_nan() || node >= n || g.contact[node] == 0.0 {
                    continue;
                }
                let x = [at(0, i), y, zz];
                let (phi, normal) = c.distance(x);
                if phi < ctx.contact_band {
                    f(g, node, x, m, normal);
                }
            }
        }
    }
}

/// Node `node`'s updated velocity `v_i + a_i dt`, in three components.
fn updated<const D: usize>(g: &GridCols<'_, D>, node: usize, dt: Real) -> [Real; 3] {
    core::array::from_fn(|a| {
        if a < D {
            g.vel[a][node] + g.acc[a][node] * dt
        } else {
            0.0
        }
    })
}

/// The dynamic collider `c` (of record `record`) at the velocities it shares with the nodes of
/// the box `lo..hi` its contact holds in this substep (E96, [`Shared`]), having `received` from
/// the material so far in the substep. A separating contact holds the nodes that press on
/// the body at those velocities: the set is found again at each solution, a few times at
/// most, until it no longer changes.
fn shared<'s, const D: usize>(
    ctx: &Ctx<'_, D>,
    g: &mut GridCols<'_, D>,
    c: Collider<'s>,
    (record, received): (&ColliderRecord, [f64; 6]),
    node_box: ([usize; D], [usize; D]),
) -> Collider<'s> {
    let g_dt = core::array::from_fn(|a| if a < D { ctx.gravity[a] * ctx.dt } else { 0.0 });
    let mut at = c;
    let mut held = None;
    for _ in 0..4 {
        let mut system = Shared::new(&c, record, D == 2, g_dt, received);
        each_contact(ctx, g, &c, node_box, |g, node, x, m, normal| {
            system.add(&at, x, m, updated(g, node, ctx.dt), normal);
        });
        let set = system.held();
        at = system.solve(c);
        if held == Some(set) {
            break;
        }
        held = Some(set);
    }
    at
}

/// What a pass of the colliders acts on (E92).
enum On<'i> {
    /// The updated velocity `v_i + a_i dt`, which becomes what the contact leaves through the
    /// acceleration (as at a wall); each collider's impulse takes what the material puts on it
    /// (E93: `-m_i (v* - (v_i + a_i dt))`, its moment about the collider's origin).
    Updated(&'i mut [ColliderImpulse]),
    /// MUSL's re-mapped velocity: at a node in contact it takes the updated velocity the
    /// contact left, which the impulse paid for (USL's there).
    Remapped,
    /// USF's lagged velocity, which no impulse pays for: the contact holds it in both
    /// directions ([`Collider::hold`]).
    Lagged,
}

/// The colliders on the nodes of the substep's node box that carry mass, one collider after
/// the other, node by node (E92), on the velocity `on` says: at the nodes in contact with each
/// (E91), those within [`Ctx::contact_band`] outside its surface, or inside it, that the
/// particles of `p` whose domains touch it reach ([`Collider::mark_reached`]). On the calling
/// thread, in node order: the impulses' sums have one worker's bits.
fn collide<const D: usize>(
    ctx: &Ctx<'_, D>,
    g: &mut GridCols<'_, D>,
    p: &ParticleCols<'_, D>,
    mut on: On<'_>,
) {
    let (geom, dt) = (&ctx.geom, ctx.dt);
    let n = g.len();
    if !matches!(on, On::Updated(_)) && g.remap[0].len() != n {
        return; // Unreachable: USF and MUSL reserve the remap columns.
    }
    if g.contact.len() != n {
        return; // Unreachable: a world with colliders reserves the contact column.
    }
    let band = ctx.contact_band;
    for (k, record) in ctx.colliders.iter().enumerate() {
        let Some(c) = Collider::at(record, ctx.time, ctx.sdf) else {
            continue;
        };
        // The node box's nodes within the band around the solid's bounds (a half-space: all).
        let (mut lo, mut hi) = (ctx.active.lo, ctx.active.hi);
        if let Some((min, max)) = c.bounds() {
            for a in 0..D {
                // One node more at each end: the product may round a node on the band's edge
                // out of `ceil`'s reach.
                let from = (ceil((min[a] - band - geom.origin[a]) * geom.inv_h) - 1.0).max(0.0);
                let to = floor((max[a] + band - geom.origin[a]) * geom.inv_h) + 2.0;
                lo[a] = lo[a].max(from as usize);
                hi[a] = hi[a].min(to.max(0.0) as usize);
            }
        }
        if (0..D).any(|a| lo[a] >= hi[a]) {
            continue;
        }
        c.mark_reached(
            geom,
            p,
            ctx.particles,
            ctx.half_width,
            band,
            (lo, hi),
            g.contact,
        );
        // A dynamic collider meets the material at the velocities it shares with the nodes it
        // holds (E96): solved for first, so that a light body under heavy material does not
        // overshoot.
        let c = match &on {
            On::Updated(impulses) if record.mass > 0.0 && record.mass.is_finite() => {
                let received = impulses.get(k).map_or([0.0; 6], |s| s.untaken());
                shared(ctx, g, c, (record, received), (lo, hi))
            }
            _ => c,
        };
        let (mut linear, mut angular) = ([0.0f64; 3], [0.0f64; 3]);
        each_contact(ctx, g, &c, (lo, hi), |g, node, x, m, normal| match &on {
            On::Updated(_) => {
                let v = updated(g, node, dt);
                let Some(w) = c.contact(x, v, normal) else {
                    return;
                };
                for a in 0..D {
                    g.acc[a][node] = (w[a] - g.vel[a][node]) / dt;
                }
                let dp: [f64; 3] = core::array::from_fn(|a| (m * (w[a] - v[a])) as f64);
                let arm: [f64; 3] = core::array::from_fn(|a| (x[a] - c.centre[a]) as f64);
                for a in 0..3 {
                    let (b, e) = ((a + 1) % 3, (a + 2) % 3);
                    linear[a] -= dp[a];
                    angular[a] -= arm[b] * dp[e] - arm[e] * dp[b];
                }
            }
            On::Remapped => {
                for a in 0..D {
                    g.remap[a][node] = g.vel[a][node] + g.acc[a][node] * dt;
                }
            }
            On::Lagged => {
                let v: [Real; 3] =
                    core::array::from_fn(|a| if a < D { g.remap[a][node] } else { 0.0 });
                if let Some(w) = c.hold(x, v, normal) {
                    for a in 0..D {
                        g.remap[a][node] = w[a];
                    }
                }
            }
        });
        if let Some(sum) = match &mut on {
            On::Updated(impulses) => impulses.get_mut(k),
            _ => None,
        } {
            for a in 0..3 {
                sum.linear[a] += linear[a];
                sum.angular[a] += angular[a];
            }
        }
    }
}
