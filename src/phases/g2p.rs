//! Grid to particle (E21-E32).
//!
//! Particle update: from `v_gp = sum S_ip v_i` and `a_gp = sum S_ip a_i` (E21), FLIP with PIC
//! damping and the position update with the acceleration's `dt^2 / 2` term (E25, E26; first
//! order in time, as every position update here), or APIC (E78, E80: the grid's
//! velocity, and the moment matrix `B_p` gathered with it, [`super::gather::gather_chunk`]),
//! less the damping acceleration when damping is declared, then the walls: the equations are
//! [`super::update`]'s, on the lane type [`crate::simd::wide::Wide`].
//!
//! The gathers ([`super::gather`]) also give the velocity gradient the stress update reads
//! ([`super::stress`]; USL runs it in this pass, after the particle update).
//!
//! A particle that reaches a stick or slip wall is put back on the wall plane with its outward
//! velocity zeroed (counted as stopped); one that crosses an open face is marked escaped. A
//! particle whose new state is not finite, whose F inverts, or whose volume ratio `J` runs away
//! (leaves `[1 / r, r]`, `r` the definition's `max_volume_ratio`), is frozen: it keeps its
//! last finite position, F and stress, its velocity is zeroed, and it leaves the grid.
//!
//! Particles are processed in chunks of `W` ([`crate::simd::lanes::width`]): each particle gathers from its stencil rows into
//! the chunk's arrays, then the update and the material run as loops over the chunk's lanes
//! (no calls, no branches: the compiler vectorises them), and the results are committed with
//! selects, so a particle that is not updated keeps its state bit for bit.

use super::gather::{commit_gradient_affine, Gathered, Grad, LaneMat};
use super::p2g::{rows, Adds, Mode, Products};
use super::stress::{update_stress, StressScratch};
use super::update;
use super::{Ctx, Kernels};
use crate::def::UpdateOrder;
use crate::effects::damping;
use crate::grid::GridCols;
use crate::particles::StepReport;
use crate::particles::{ParticleCols, RemapCols, ESCAPED, FROZEN};
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{active_lanes, commit, live_lanes, load_into, Block, Lane, Lanes};
use crate::simd::wide::{Wide, WideMask};
use crate::Real;

/// Particle update: velocity and position from the grid `g`. With USL it also updates the
/// stress from `v_i + a_i dt` in the same pass. With MUSL it also keeps the positions of the
/// start of the step in the `x_start` columns, for the stress pass, and, where `remap` holds
/// the remap columns ([`GridCols::split_remap`]), scatters the new momenta to them (E30) with
/// the stencils already computed (particles contribute as in the scatter pass:
/// [`crate::simd::row_sums::scatter_chunk`]). The parallel step gives it a tile's re-map
/// columns, or none for the particles it updates before the tiles, whose rows [`remap`] adds
/// (the same values).
/// Declared damping adds the damping of the module docs; APIC replaces FLIP. Each of these is
/// a value of the substep ([`Ctx`]), tested once per chunk.
#[inline(always)]
pub(crate) fn particles<
    I: Kernels,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &GridCols<'_, D>,
    remap: &mut GridCols<'_, D>,
    report: &mut StepReport,
) {
    let geom = &ctx.geom;
    let dt = ctx.dt;
    let fused_stress = ctx.order == UpdateOrder::Usl;
    let keep_start = ctx.order == UpdateOrder::Musl;
    let fused_remap = keep_start && !remap.remap[0].is_empty();
    let (damp, apic) = (ctx.damp, ctx.apic);
    // APIC's moment matrices, gathered (a family that keeps the gradient form takes the stress
    // update's gradient instead).
    let moments = apic && !S::GRADIENT_AFFINE;
    if !g.lengths_consistent() {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    let mut st = Stencils::<D, K, W>::default();
    let mut gathered = Gathered::zero();
    // The chunk's positions, velocities, damping rates and new state, in buffers kept across
    // chunks (see `lanes::load_into`).
    let (mut x, mut v) = (Block([[0.0; W]; D]), Block([[0.0; W]; D]));
    let (mut alpha_g, mut alpha_p) = (Block([ctx.alpha_g; W]), Block([ctx.alpha_p; W]));
    let (mut v_new, mut x_new) = (Block([[0.0; W]; D]), Block([[0.0; W]; D]));
    let (mut x_low, mut x_low_new) = (Block([[0.0; W]; D]), Block([[0.0; W]; D]));
    let mut mass = Block([0.0; W]);
    // APIC: the new moment matrix B_p of each live lane (a family that keeps the gradient
    // form takes the stress update's velocity gradient instead: see
    // `commit_gradient_affine`).
    let mut affine = Block([[[0.0; W]; D]; D]);
    let mut scratch = StressScratch::new();
    // The momentum approach: the mass-weighted grid velocity and acceleration each lane moves
    // with (E76).
    let (mut v_move, mut a_move) = (Block([[0.0; W]; D]), Block([[0.0; W]; D]));
    let mut weights = super::momentum::Weights::zero();
    // MUSL: what the re-map scatters.
    let mut products = Products::zero();
    // The constants of the update and the walls, made once per pass.
    let step = update::Step::<I>::new(dt, ctx.beta, ctx.particle_velocity);
    let faces: [_; D] = core::array::from_fn(|a| update::Faces::<I>::of(geom, a));
    let (zero, none) = (Wide::<I>::splat(0.0), WideMask::<I>::splat(false));
    let speed_scale = Wide::<I>::splat(ctx.speed_scale);
    for start in (0..count).step_by(W) {
        let live = live_lanes(p, start, count);
        for a in 0..D {
            load_into(&mut x[a], p.x[a], start);
            load_into(&mut x_low[a], p.x_low[a], start);
            load_into(&mut v[a], p.v[a], start);
        }
        super::stencils::<I, D, K, S, W>(&mut st, shape, ctx, p, start, &x, apic, false, ctx.mls);
        if damp {
            damping::lane_rates::<I, D, W>(
                (ctx.alpha_g, ctx.alpha_p),
                p,
                start,
                &mut alpha_g,
                &mut alpha_p,
            );
        }
        // One gather per (order, transfer), chosen per chunk.
        const NONE: u8 = Grad::None as u8;
        const UPDATED: u8 = Grad::Updated as u8;
        let (aff, out) = (&mut *affine, &mut gathered);
        if ctx.momentum && !S::AXISYMMETRIC {
            use super::momentum::{gather, Differentiate};
            let which = if fused_stress {
                Differentiate::Updated
            } else {
                Differentiate::Nothing
            };
            weights.of::<I, K, S>(ctx, &st, &x, g.mass);
            let moving = Some((&mut *v_move, &mut *a_move));
            gather::<I, D, K, W>(ctx, &st, &weights, g, which, out, moving);
        } else {
            match (fused_stress, moments) {
                (false, false) => I::gather::<D, K, S, W, true, NONE, false>(ctx, g, &st, aff, out),
                (false, true) => I::gather::<D, K, S, W, true, NONE, true>(ctx, g, &st, aff, out),
                (true, false) => {
                    I::gather::<D, K, S, W, true, UPDATED, false>(ctx, g, &st, aff, out)
                }
                (true, true) => I::gather::<D, K, S, W, true, UPDATED, true>(ctx, g, &st, aff, out),
            }
        }
        let (v_gp, a_gp, l) = (&gathered.v_gp, &gathered.a_gp, &gathered.l);
        // The grid velocity and acceleration the particles move with (E26, or E76 in the
        // momentum approach), chosen once per chunk.
        let (v_moves, a_moves) = if ctx.momentum {
            (&*v_move, &*a_move)
        } else {
            (v_gp, a_gp)
        };
        // FLIP with PIC damping (or APIC) and the position update, then the walls and open
        // faces as selects, on as many lanes at once as the instance's vectors hold (the
        // auto-vectoriser left the selects scalar, 13 instructions per lane and axis).
        let (mut finite, mut stopped, mut escaped) = (Lanes::NONE, Lanes::NONE, Lanes::NONE);
        for q in (0..W).step_by(I::N) {
            let ld = |c: &Lane<W>| Wide::<I>::load(c, q);
            let mut sum = zero;
            let (mut open, mut wall) = (none, none);
            for a in 0..D {
                let (v_p, v_gp, a_gp) = (ld(&v[a]), ld(&v_gp[a]), ld(&a_gp[a]));
                let d = if damp {
                    Some(damping::acceleration(v_gp, v_p, ld(&alpha_g), ld(&alpha_p)))
                } else {
                    None
                };
                let (vn, dx) = if apic {
                    update::apic(&step, v_gp, a_gp, d)
                } else if let Some((_, fmpm)) = ctx.series {
                    update::xpic(&step, v_p, (v_gp, a_gp), d, fmpm)
                } else {
                    let moves_with = (ld(&v_moves[a]), ld(&a_moves[a]));
                    update::flip(&step, v_p, (v_gp, a_gp), moves_with, d)
                };
                let (xn, xn_low) = update::advance(ld(&x[a]), ld(&x_low[a]), dx);
                // The speed scaled so that it overflows past `Resolvable::speed`: the one
                // finiteness test below then also freezes a lane whose speed (the sum of its
                // components' magnitudes) no stable step above the floor resolves.
                sum += vn * speed_scale + xn;
                let at = update::walls(&faces[a], xn, xn_low, vn);
                (open, wall) = (open | at.open, wall | at.wall);
                at.x.store(&mut x_new[a], q);
                at.x_low.store(&mut x_low_new[a], q);
                at.v.store(&mut v_new[a], q);
            }
            if apic {
                for r in 0..D {
                    for c in 0..D {
                        sum += ld(&affine[r][c]);
                    }
                }
            }
            finite = finite | sum.is_finite().lanes(q);
            escaped = escaped | open.lanes(q);
            stopped = stopped | wall.lanes(q);
        }
        let moved = live & finite;
        let (ok, runaway) = if fused_stress {
            update_stress::<I, D, K, S, W>(ctx, p, start, moved, &gathered, &mut scratch)
        } else {
            (moved, Lanes::NONE)
        };
        if apic && fused_stress && S::GRADIENT_AFFINE {
            commit_gradient_affine(p, start, l, ok);
        }
        // Commit: updated lanes take the new state; live lanes that failed freeze.
        let frozen = live.minus(ok);
        let zero = [0.0; W];
        for a in 0..D {
            commit(p.v[a], start, &v_new[a], ok);
            commit(p.v[a], start, &zero, frozen);
            commit(p.x[a], start, &x_new[a], ok);
            commit(p.x_low[a], start, &x_low_new[a], ok);
            if keep_start {
                // Whole chunks (the columns are padded to the chunk width): one store per
                // vector, not a select.
                commit(p.x_start[a], start, &x[a], Lanes::ALL);
            }
        }
        if apic && !S::GRADIENT_AFFINE {
            for r in 0..D {
                for c in 0..D {
                    commit(p.affine[r][c], start, &affine[r][c], ok);
                }
            }
        }
        for ln in frozen.iter() {
            p.status[start + ln] = FROZEN;
            // Past the speed bound (its scaled sum overflowed): a runaway too.
            let speed: f64 = (0..D).map(|a| v_new[a][ln].abs() as f64).sum();
            let fast = speed * ctx.speed_scale as f64 >= Real::MAX as f64;
            report.note_frozen((start + ln) as u32, runaway.has(ln) || fast);
        }
        let escaped = ok & escaped;
        for ln in escaped.iter() {
            p.status[start + ln] = ESCAPED;
        }
        report.escaped += escaped.count();
        report.stopped += (ok & stopped).minus(escaped).count();
        if fused_remap {
            let active = live_lanes(p, start, count);
            load_into(&mut mass, p.mass, start);
            // An active lane was committed: its velocity is v_new. The B_p of a family that
            // keeps the gradient form are zero here: its C_p is taken from this re-map (see
            // `commit_gradient_affine`).
            let chunk = (&*mass, &*v_new, &*affine, active);
            remap_rows::<I, D, K, S, W>(ctx, &mut st, &mut products, chunk, remap);
        }
    }
}

/// MUSL's re-map of one chunk (E30): its new momenta (and APIC's affine momenta) weighed with
/// the stencils `st` where the substep started, added to the re-map columns of `remap` for
/// the lanes `active` (the products of a scatter: [`crate::simd::row_sums::scatter_chunk`]).
#[inline(always)]
fn remap_rows<I: Kernels, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    ctx: &Ctx<'_, D>,
    st: &mut Stencils<D, K, W>,
    products: &mut Products<D, W>,
    (mass, v, affine, active): (&Lane<W>, &[Lane<W>; D], &LaneMat<D, W>, Lanes<W>),
    remap: &mut GridCols<'_, D>,
) {
    let apic = ctx.apic;
    let adds = Adds {
        mode: Mode::Remap,
        forces: false,
        apic,
    };
    // What the re-map reads no stress nor force of: those products stay zero.
    products.set_momenta::<I, K, S>(st, mass, v, affine, adds);
    let stride = ctx.geom.stride;
    if apic {
        const REMAP: u8 = rows(Mode::Remap, true);
        I::scatter_chunk::<D, K, S, W, REMAP>(st, products, active, stride, remap, adds);
    } else {
        const REMAP: u8 = rows(Mode::Remap, false);
        I::scatter_chunk::<D, K, S, W, REMAP>(st, products, active, stride, remap, adds);
    }
}

/// MUSL's re-map of particles another item of the parallel step updated (`world::parallel`):
/// the rows of the chunks of `p` (its first `count` particles, updated, with the positions
/// where the substep started) that `remap` holds, the same values [`particles`] adds when it
/// re-maps them in its own pass.
///
/// Where `from` holds velocity columns, the momenta re-mapped are those of the velocities
/// gathered from them, `m_p sum_i S_ip u_i`, not the particles' own: XPIC's projection
/// `A u = S+ S u` ([`super::xpic`]), with the gather and scatter kernels the particle pass
/// compiles already.
#[inline(always)]
pub(crate) fn remap<I: Kernels, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &RemapCols<'_, D>,
    count: usize,
    from: &GridCols<'_, D>,
    remap: &mut GridCols<'_, D>,
) {
    let gathers = !from.vel[0].is_empty();
    if gathers && !from.lengths_consistent() {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    let mut gathered = Gathered::zero();
    let mut st = Stencils::<D, K, W>::default();
    let (mut x, mut v) = (Block([[0.0; W]; D]), Block([[0.0; W]; D]));
    let mut mass = Block([0.0; W]);
    let mut affine = Block([[[0.0; W]; D]; D]);
    let mut products = Products::zero();
    // A family that keeps the gradient form re-maps no affine part (see `particles`).
    let load_affine = ctx.apic && !S::GRADIENT_AFFINE;
    for start in (0..count).step_by(W) {
        for a in 0..D {
            load_into(&mut x[a], p.x_start[a], start);
            if !gathers {
                load_into(&mut v[a], p.v[a], start);
            }
        }
        load_into(&mut mass, p.mass, start);
        if load_affine {
            for (a, row) in affine.iter_mut().enumerate() {
                for (b, lanes) in row.iter_mut().enumerate() {
                    load_into(lanes, p.affine[a][b], start);
                }
            }
        }
        let (apic, mls) = (ctx.apic, ctx.mls);
        I::stencils::<D, K, S, W>(&mut st, shape, ctx, &p.stretch, start, &x, apic, false, mls);
        if gathers {
            const NONE: u8 = Grad::None as u8;
            I::gather::<D, K, S, W, true, NONE, false>(ctx, from, &st, &mut affine, &mut gathered);
            v.0 = gathered.v_gp;
        }
        let active = active_lanes(p.status, start, count);
        let chunk = (&*mass, &*v, &*affine, active);
        remap_rows::<I, D, K, S, W>(ctx, &mut st, &mut products, chunk, remap);
    }
}
