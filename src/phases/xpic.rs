//! XPIC(k) and FMPM(k) (E98-E101; Hammerquist and Nairn 2017, Nairn and Hammerquist 2021): the
//! grid passes of the series `v* = sum_{r=1..k} (-1)^(r+1) C(k, r) A^(r-1) u`, with `u` the
//! lumped nodal velocity of the step's start `v^L` (XPIC) or the updated one `v^L + a dt`
//! (FMPM), and `A = S+ S`. The terms follow one from the other, `v*_1 = k u` and
//! `v*_r = (k - r + 1) / r A v*_(r-1)` (as `C(k, r) = C(k, r - 1) (k - r + 1) / r`): each is a
//! projection of the one before (the particle pass `world::parallel::Columns::project`: the
//! velocity gathered at the particles from the series columns, its momentum scattered to the
//! re-map columns), then a node pass here that divides by the mass, scales and adds it.
//!
//! The sum is kept where the particle update reads it ([`super::update::xpic`]), in the
//! acceleration columns: XPIC keeps `v^L` in the velocity columns and makes the acceleration
//! `a + (v* - v^L) / dt`, so that `v_gp = S v^L` and `v_gp + a_gp dt = S (v* + a dt)`; FMPM
//! sums `v*` there and ends with `v*` as the velocity and zero acceleration. The colliders and
//! the walls then act on the new updated velocity as on the lumped one
//! ([`super::grid_update::boundary_on_updated`], E100): the series mixes the nodes' values, and
//! a node in contact would otherwise hand the particles a velocity into the solid.

use super::grid_update::{boundary_on_updated, divide_by_mass, mirror_vector, Nodes};
use super::Ctx;
use crate::grid::GridCols;
use crate::Real;

/// The series' first term `v*_1 = k u` into the series columns (order 2 and up), and the sum
/// so far into the acceleration columns: XPIC `a + (k - 1) v^L / dt`, FMPM `k (v^L + a dt)`;
/// the re-map columns zeroed for the first projection.
pub(crate) fn start<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    let Some((k, fmpm)) = ctx.series else { return };
    let (series, k, dt) = (k >= 2, k as Real, ctx.dt);
    nodes.each_slab(&|g| {
        each_node(ctx, g, |g, a, i| {
            let (v, acc) = (g.vel[a][i], g.acc[a][i]);
            let first = if fmpm { k * (v + acc * dt) } else { k * v };
            if series {
                g.series[a][i] = first;
                // USF's stress velocity was there: the projections add to zero.
                g.remap[a][i] = 0.0;
            }
            g.acc[a][i] = if fmpm { first } else { acc + (first - v) / dt };
        });
    });
}

/// FMPM(k) with MUSL (E101): the re-mapped momenta, folded at the walls, divided by the mass
/// and read back past them, start the series again, `u` the re-mapped velocity: `k u` into
/// the series and acceleration columns, the re-map columns zeroed for the projections. The
/// updated velocity the particles read, `v + a dt`, moves to the velocity columns first: the
/// nodes in a collider's contact keep it for the stress update (E92).
pub(crate) fn restart<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    let Some((k, _)) = ctx.series else { return };
    lumped_remap(ctx, nodes);
    let (k, dt) = (k as Real, ctx.dt);
    nodes.each_slab(&|g| {
        each_node(ctx, g, |g, a, i| {
            g.vel[a][i] += g.acc[a][i] * dt;
            let first = k * g.remap[a][i];
            g.series[a][i] = first;
            g.acc[a][i] = first;
            g.remap[a][i] = 0.0;
        });
    });
}

/// The sum of [`restart`]'s series into the re-map columns, for the boundary and the stress
/// update; the acceleration back to zero, so that `v + a dt` is again the particles' velocity.
pub(crate) fn into_remap<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    nodes.each_slab(&|g| {
        each_node(ctx, g, |g, a, i| {
            g.remap[a][i] = g.acc[a][i];
            g.acc[a][i] = 0.0;
        })
    });
}

/// The re-map columns' momenta folded at the walls, divided by the mass (zero at or below the
/// cutoff) and read back past the walls.
fn lumped_remap<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    mirror_vector(ctx, &mut nodes.whole().remap, true);
    nodes.each_slab(&|g| {
        let window = g.window();
        divide_by_mass(ctx, g.mass, &mut g.remap, [0.0; D], window)
    });
    mirror_vector(ctx, &mut nodes.whole().remap, false);
}

/// After the projection of term `r - 1` into the re-map columns: term `r`,
/// `v*_r = (k - r + 1) / r A v*_(r-1)` (the projected momenta folded at the walls, divided by
/// the mass, zero at or below the cutoff, and read back past the walls) into the series
/// columns; the sum takes `(-1)^(r+1) v*_r` (over `dt` with XPIC); the re-map columns are
/// zeroed for the next projection.
pub(crate) fn absorb<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>, r: u32) {
    let Some((k, fmpm)) = ctx.series else { return };
    lumped_remap(ctx, nodes);
    let scale = (k - r + 1) as Real / r as Real;
    let sign = if r.is_multiple_of(2) { -1.0 } else { 1.0 };
    let weight = if fmpm { sign } else { sign / ctx.dt };
    nodes.each_slab(&|g| {
        each_node(ctx, g, |g, a, i| {
            let term = scale * g.remap[a][i];
            g.series[a][i] = term;
            g.acc[a][i] += weight * term;
            g.remap[a][i] = 0.0;
        });
    });
}

/// The end of the series: FMPM's sum becomes the velocity, its acceleration zero; then the
/// colliders and the walls on the updated velocity (E92, E20), the colliders' impulses taking
/// what this second pass changes (E93).
pub(crate) fn finish<const D: usize>(ctx: &Ctx<'_, D>, nodes: &mut impl Nodes<D>) {
    let Some((_, fmpm)) = ctx.series else { return };
    if fmpm {
        nodes.each_slab(&|g| {
            each_node(ctx, g, |g, a, i| {
                g.vel[a][i] = g.acc[a][i];
                g.acc[a][i] = 0.0;
            });
        });
    }
    boundary_on_updated(ctx, nodes);
}

/// Runs `f(g, axis, entry)` on every entry of `g` within the node box, for each axis.
fn each_node<const D: usize>(
    ctx: &Ctx<'_, D>,
    g: &mut GridCols<'_, D>,
    mut f: impl FnMut(&mut GridCols<'_, D>, usize, usize),
) {
    let window = g.window();
    let len = g.len();
    ctx.active.for_each_line_in(ctx.geom.stride, window, |r| {
        for a in 0..D {
            for i in r.clone().filter(|&i| i < len) {
                f(g, a, i);
            }
        }
    });
}
