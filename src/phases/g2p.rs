//! Grid to particle (seeds/000 section 5.1).
//!
//! Particle update with FLIP fraction beta and no other damping (eqs 44-45, 51-52 with
//! `alpha_g' = alpha_p' = 0`), from `v_gp = sum S_ip v_i` and `a_gp = sum S_ip a_i`:
//! - `v_p(n+1) = v_p + a_gp dt - (1 - beta)(v_p - v_gp)`
//! - `x_p(n+1) = x_p + v_gp dt + a_gp dt^2 / 2 - (1 - beta)(v_p - v_gp) dt / 2`
//!
//! Stress update: `grad v = sum v_i (x) G_ip` (eq 27), `dF = exp(grad v dt)` to the configured
//! number of terms (eq 26), `F <- dF F` (kept as `H = F - I`), `J = det F`, and `tau/rho0`
//! from the material.
//!
//! A particle that reaches a stick or slip wall is put back on the wall plane with its outward
//! velocity zeroed (counted as stopped); one that crosses an open face is marked escaped. A
//! particle whose new state is not finite, or whose F inverts, is frozen: it keeps its last
//! finite position, F and stress, its velocity is zeroed, and it leaves the grid.
//!
//! Particles are processed in chunks of [`W`]: each particle gathers from its stencil rows into
//! the chunk's arrays, then the update and the material run as loops over the chunk's lanes
//! (no calls, no branches: the compiler vectorises them), and the results are committed with
//! selects, so a particle that is not updated keeps its state bit for bit.

use super::p2g::{mode, scatter_one};
use super::Ctx;
use crate::def::{Boundary, MaterialModel};
use crate::grid::{load_row, rows_fit, GridCols};
use crate::material::{kirchhoff_over_rho0, model_of, neo_hookean_lanes, Params};
use crate::math::INV;
use crate::particles::{ParticleCols, ACTIVE, ESCAPED, FROZEN};
use crate::shape::{Row4, Shape1D, Stencil, Stencils};
use crate::{Real, StepReport};

/// Particles per chunk.
pub(crate) const W: usize = 8;

/// One value per lane of a chunk.
pub(crate) type Lane = [Real; W];
/// A D x D matrix per lane, `m[a][b][lane]`.
type LaneMat<const D: usize> = [[Lane; D]; D];

/// Which nodal velocity a gather differentiates for the velocity gradient (a const parameter,
/// so each instance has straight-line loops).
mod grad {
    /// None (the stress is updated in its own pass).
    pub const NONE: u8 = 0;
    /// `v_i + a_i dt` (USL).
    pub const UPDATED: u8 = 1;
    /// The wall-constrained stress-update velocity (USF, MUSL).
    pub const REMAP: u8 = 2;
}

/// Lanes `start..start + W` that hold active particles (`< count`).
#[inline(always)]
fn live_lanes<const D: usize>(p: &ParticleCols<'_, D>, start: usize, count: usize) -> [bool; W] {
    core::array::from_fn(|l| start + l < count && p.status[start + l] == ACTIVE)
}

/// Gathers `v_gp`, `a_gp` (when `VEL`) and the velocity gradient (per `GRAD`) of the particle
/// with stencil `st` into lane `lane`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn gather<const D: usize, const K: usize, const VEL: bool, const GRAD: u8>(
    ctx: &Ctx<'_, D>,
    g: &GridCols<'_, D>,
    st: &Stencil<D, K>,
    lane: usize,
    v_gp: &mut [Lane; D],
    a_gp: &mut [Lane; D],
    l: &mut LaneMat<D>,
) {
    let geom = &ctx.geom;
    let dt = ctx.dt;
    // The pass checked that every column has this length (and that the remap columns exist
    // when GRAD reads them).
    let len = g.len();
    if !rows_fit(st.base, Stencil::<D, K>::last_row_offset(geom.stride), len) {
        return; // Unreachable by construction; keeps the unchecked row access below sound.
    }
    // Separable form ([`Stencil::row`]): per row, the nodal values are weighted by the row's
    // scalar factors r[b] into 4-wide partial sums over the rows; the x weights are applied once
    // at the end, in one horizontal sum per result.
    let (wx, dwx) = (st.w[0], st.dw[0]);
    // sum_rows r[0] v_i, sum_rows r[0] a_i (over x still separate).
    let mut rv = [Row4::ZERO; D];
    let mut ra = [Row4::ZERO; D];
    // sum_rows r[0] u_i (REMAP only; USL uses rv + dt ra) and sum_rows r[b] u_i for b >= 1, u
    // the differentiated velocity.
    let mut ru = [Row4::ZERO; D];
    let mut du = [[Row4::ZERO; D]; D];
    for k in 0..Stencil::<D, K>::layers() {
        for j in 0..K {
            let (row, r) = st.row(j, k, geom.stride);
            for a in 0..D {
                // SAFETY (every load_row here): rows_fit checked above for this stencil, and every
                // column read has the length it was checked against.
                let (vi, ai) = if VEL || GRAD == grad::UPDATED {
                    unsafe { (load_row(g.vel[a], row), load_row(g.acc[a], row)) }
                } else {
                    (Row4::ZERO, Row4::ZERO)
                };
                if VEL || GRAD == grad::UPDATED {
                    rv[a] += vi * r[0];
                    ra[a] += ai * r[0];
                }
                if GRAD != grad::NONE {
                    let u = if GRAD == grad::UPDATED {
                        vi + ai * dt
                    } else {
                        let u = unsafe { load_row(g.remap[a], row) };
                        ru[a] += u * r[0];
                        u
                    };
                    for b in 1..D {
                        du[a][b] += u * r[b];
                    }
                }
            }
        }
    }
    for a in 0..D {
        if VEL {
            v_gp[a][lane] = (wx * rv[a]).element_sum();
            a_gp[a][lane] = (wx * ra[a]).element_sum();
        }
        if GRAD != grad::NONE {
            let ux = if GRAD == grad::UPDATED {
                rv[a] + ra[a] * dt
            } else {
                ru[a]
            };
            l[a][0][lane] = (dwx * ux).element_sum();
            for b in 1..D {
                l[a][b][lane] = (wx * du[a][b]).element_sum();
            }
        }
    }
}

/// The stencils of the chunk's particles at `x[axis][lane]`.
#[inline(always)]
pub(crate) fn stencils<const D: usize, const K: usize, S: Shape1D<K>>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    x: &[Lane; D],
) -> Stencils<D, K, W> {
    let geom = &ctx.geom;
    let s: [Lane; D] = core::array::from_fn(|a| {
        core::array::from_fn(|ln| (x[a][ln] - geom.origin[a]) * geom.inv_h)
    });
    Stencils::new(shape, &s, geom.nodes, geom.stride, geom.inv_h)
}

/// `dst[lane] = if keep[lane] { new[lane] } else { dst[lane] }` over a column slice.
#[inline(always)]
fn commit(dst: &mut [Real], start: usize, new: &Lane, keep: &[bool; W]) {
    if let Some(d) = dst.get_mut(start..start + W) {
        if keep.iter().all(|&k| k) {
            // The common case: every lane was updated.
            d.copy_from_slice(new);
        } else {
            for l in 0..W {
                if keep[l] {
                    d[l] = new[l];
                }
            }
        }
    }
}

/// Loads lanes `start..start + W` of a column (zeros past its end).
#[inline(always)]
pub(crate) fn load(col: &[Real], start: usize) -> Lane {
    match col.get(start..start + W) {
        Some(c) => core::array::from_fn(|l| c[l]),
        None => [0.0; W],
    }
}

/// `acc += x y`, lane by lane.
#[inline(always)]
fn mul_add_lanes<const D: usize>(acc: &mut LaneMat<D>, x: &LaneMat<D>, y: &LaneMat<D>) {
    for r in 0..D {
        for c in 0..D {
            for m in 0..D {
                for ln in 0..W {
                    acc[r][c][ln] += x[r][m][ln] * y[m][c][ln];
                }
            }
        }
    }
}

/// Updates H and tau/rho0 of the lanes in `update` from their velocity gradient `l`. Returns
/// per lane whether the update succeeded; a lane that fails (non-finite result or inverted F)
/// keeps its H and stress.
#[inline(always)]
fn update_stress<const D: usize>(
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    start: usize,
    update: &[bool; W],
    l: &LaneMat<D>,
) -> [bool; W] {
    let dt = ctx.dt;
    // A = L dt; Q = exp(A) - I by Horner (`math::exp_series_minus_identity`, lane by lane).
    let a: LaneMat<D> = core::array::from_fn(|r| {
        core::array::from_fn(|c| core::array::from_fn(|ln| l[r][c][ln] * dt))
    });
    let n = ctx.exp_terms.clamp(1, 8) as usize;
    let mut q: LaneMat<D> = core::array::from_fn(|r| {
        core::array::from_fn(|c| core::array::from_fn(|ln| a[r][c][ln] * INV[n]))
    });
    for k in (1..n).rev() {
        let mut next = a;
        mul_add_lanes(&mut next, &a, &q);
        for r in 0..D {
            for c in 0..D {
                for ln in 0..W {
                    next[r][c][ln] *= INV[k];
                }
            }
        }
        q = next;
    }
    // H <- H + Q + Q H.
    let h_old: LaneMat<D> =
        core::array::from_fn(|r| core::array::from_fn(|c| load(p.h[r][c], start)));
    let mut h = h_old;
    mul_add_lanes(&mut h, &q, &h_old);
    for r in 0..D {
        for c in 0..D {
            for ln in 0..W {
                h[r][c][ln] += q[r][c][ln];
            }
        }
    }
    // J - 1 = tr H + principal minors (+ det H in 3D), without forming I + H.
    let mut jm1 = [0.0; W];
    for ln in 0..W {
        let m: [[Real; D]; D] = core::array::from_fn(|r| core::array::from_fn(|c| h[r][c][ln]));
        jm1[ln] = crate::math::det_identity_plus_minus_one(&m);
    }
    // Material: one set of parameters for the chunk when every lane shares a neo-Hookean
    // material (the common case, vectorised); otherwise lane by lane.
    let ids: [usize; W] = core::array::from_fn(|ln| p.material[start + ln] as usize);
    let first = (0..W).find(|&ln| update[ln]).map(|ln| ids[ln]);
    let uniform = first.and_then(|id| {
        let same = (0..W).all(|ln| !update[ln] || ids[ln] == id);
        ctx.materials
            .get(id)
            .filter(|r| same && model_of(r) == MaterialModel::NeoHookean)
    });
    let ns = crate::layout::stress_components(D);
    let mut tau = [[0.0; W]; 6];
    let mut ok = [false; W];
    if let Some(rec) = uniform {
        neo_hookean_lanes(&Params::of(rec), &h, &jm1, &mut tau);
        for ln in 0..W {
            ok[ln] = update[ln] && jm1[ln] > -1.0;
        }
    } else {
        for ln in 0..W {
            // NaN-safe: a NaN jm1 is not > -1.
            let inverted = !matches!(
                jm1[ln].partial_cmp(&-1.0),
                Some(core::cmp::Ordering::Greater)
            );
            if !update[ln] || inverted {
                continue;
            }
            let Some(rec) = ctx.materials.get(ids[ln]) else {
                continue;
            };
            let m: [[Real; D]; D] = core::array::from_fn(|r| core::array::from_fn(|c| h[r][c][ln]));
            let s = kirchhoff_over_rho0(model_of(rec), &Params::of(rec), &m, jm1[ln]);
            for (k, &(r, c)) in super::sym_pairs(D).iter().enumerate() {
                tau[k][ln] = s.m[r][c];
            }
            if D == 2 {
                tau[3][ln] = s.zz;
            }
            ok[ln] = true;
        }
    }
    // One finiteness test per lane: a sum is finite only if every term is (an overflowing sum
    // of finite values is a false alarm that freezes a particle already at 1e38: acceptable).
    for ln in 0..W {
        let mut sum = jm1[ln];
        for k in 0..ns {
            sum += tau[k][ln];
        }
        for r in 0..D {
            for c in 0..D {
                sum += h[r][c][ln];
            }
        }
        ok[ln] = ok[ln] && sum.is_finite();
    }
    for r in 0..D {
        for c in 0..D {
            commit(p.h[r][c], start, &h[r][c], &ok);
        }
    }
    for k in 0..ns {
        commit(p.tau[k], start, &tau[k], &ok);
    }
    ok
}

/// Particle update: velocity and position from the grid. `FUSED_STRESS` also updates the stress
/// from `v_i + a_i dt` in the same pass (USL). `TO_NEXT` (MUSL) writes the new positions to
/// the scratch columns instead of the positions, and scatters the new momenta to the remap
/// columns with the stencils already computed (the pass reads only `vel` and `acc`, so the
/// remap columns are free to fill; particles contribute in index order, as a separate pass
/// would).
#[inline(always)]
pub(crate) fn particles<
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const FUSED_STRESS: bool,
    const TO_NEXT: bool,
>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
    report: &mut StepReport,
) {
    let geom = &ctx.geom;
    let dt = ctx.dt;
    let pic = 1.0 - ctx.beta;
    if !g.lengths_consistent() {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    for start in (0..count).step_by(W) {
        let live = live_lanes(p, start, count);
        let x: [Lane; D] = core::array::from_fn(|a| load(p.x[a], start));
        let v: [Lane; D] = core::array::from_fn(|a| load(p.v[a], start));
        let mut v_gp = [[0.0; W]; D];
        let mut a_gp = [[0.0; W]; D];
        let mut l = [[[0.0; W]; D]; D];
        let st = stencils::<D, K, S>(shape, ctx, &x);
        for ln in 0..W {
            if live[ln] {
                let st = st.lane(ln);
                if FUSED_STRESS {
                    gather::<D, K, true, { grad::UPDATED }>(
                        ctx, g, st, ln, &mut v_gp, &mut a_gp, &mut l,
                    );
                } else {
                    gather::<D, K, true, { grad::NONE }>(
                        ctx, g, st, ln, &mut v_gp, &mut a_gp, &mut l,
                    );
                }
            }
        }
        // FLIP with PIC damping and the second-order position update.
        let mut v_new = [[0.0; W]; D];
        let mut x_new = [[0.0; W]; D];
        let mut sum = [0.0; W];
        for a in 0..D {
            for ln in 0..W {
                let inversion = pic * (v[a][ln] - v_gp[a][ln]);
                v_new[a][ln] = v[a][ln] + a_gp[a][ln] * dt - inversion;
                x_new[a][ln] =
                    x[a][ln] + (v_gp[a][ln] + 0.5 * a_gp[a][ln] * dt - 0.5 * inversion) * dt;
                sum[ln] += v_new[a][ln] + x_new[a][ln];
            }
        }
        let moved: [bool; W] = core::array::from_fn(|ln| live[ln] && sum[ln].is_finite());
        // Walls and open faces, as selects.
        let mut stopped = [false; W];
        let mut escaped = [false; W];
        for a in 0..D {
            let [lo_bc, hi_bc] = geom.faces[a];
            let (lo_x, hi_x) = (
                geom.origin[a] + geom.lo[a] * geom.h,
                geom.origin[a] + geom.hi[a] * geom.h,
            );
            for ln in 0..W {
                let s = (x_new[a][ln] - geom.origin[a]) * geom.inv_h;
                let below = s < geom.lo[a];
                let above = s > geom.hi[a];
                x_new[a][ln] = if below {
                    lo_x
                } else if above {
                    hi_x
                } else {
                    x_new[a][ln]
                };
                let open = (below && lo_bc == Boundary::Open) || (above && hi_bc == Boundary::Open);
                let wall = (below || above) && !open;
                let outward = (below && v_new[a][ln] < 0.0) || (above && v_new[a][ln] > 0.0);
                v_new[a][ln] = if wall && outward { 0.0 } else { v_new[a][ln] };
                escaped[ln] |= open;
                stopped[ln] |= wall;
            }
        }
        let ok = if FUSED_STRESS {
            update_stress(ctx, p, start, &moved, &l)
        } else {
            moved
        };
        // Commit: updated lanes take the new state; live lanes that failed freeze.
        let frozen: [bool; W] = core::array::from_fn(|ln| live[ln] && !ok[ln]);
        let zero = [0.0; W];
        for a in 0..D {
            commit(p.v[a], start, &v_new[a], &ok);
            commit(p.v[a], start, &zero, &frozen);
            if TO_NEXT {
                let keep_all = [true; W];
                let next: Lane =
                    core::array::from_fn(|ln| if ok[ln] { x_new[a][ln] } else { x[a][ln] });
                commit(p.x_next[a], start, &next, &keep_all);
            } else {
                commit(p.x[a], start, &x_new[a], &ok);
            }
        }
        for ln in 0..W {
            if frozen[ln] {
                p.status[start + ln] = FROZEN;
                report.note_frozen((start + ln) as u32);
            } else if ok[ln] && escaped[ln] {
                p.status[start + ln] = ESCAPED;
                report.escaped += 1;
            } else if ok[ln] && stopped[ln] {
                report.stopped += 1;
            }
        }
        if TO_NEXT {
            for ln in 0..W.min(count - start) {
                if p.status[start + ln] == ACTIVE {
                    scatter_one::<D, K, { mode::REMAP }>(ctx, p, start + ln, st.lane(ln), g);
                }
            }
        }
    }
}

/// Stress update in its own pass (USF before the momentum update, MUSL after the re-map),
/// from the wall-constrained velocity in the `remap` columns. `COMMIT_NEXT` (MUSL) commits
/// the new positions afterwards.
#[inline(always)]
pub(crate) fn stress<const D: usize, const K: usize, S: Shape1D<K>, const COMMIT_NEXT: bool>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &GridCols<'_, D>,
    report: &mut StepReport,
) {
    if !g.lengths_consistent() || g.remap.iter().any(|c| c.len() != g.len()) {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    for start in (0..count).step_by(W) {
        let live = live_lanes(p, start, count);
        let mut unused = [[0.0; W]; D];
        let mut unused2 = [[0.0; W]; D];
        let mut l = [[[0.0; W]; D]; D];
        let x: [Lane; D] = core::array::from_fn(|a| load(p.x[a], start));
        let st = stencils::<D, K, S>(shape, ctx, &x);
        for ln in 0..W {
            if live[ln] {
                gather::<D, K, false, { grad::REMAP }>(
                    ctx,
                    g,
                    st.lane(ln),
                    ln,
                    &mut unused,
                    &mut unused2,
                    &mut l,
                );
            }
        }
        let ok = update_stress(ctx, p, start, &live, &l);
        for ln in 0..W.min(count - start) {
            let i = start + ln;
            if live[ln] && !ok[ln] {
                for a in 0..D {
                    p.v[a][i] = 0.0;
                    if COMMIT_NEXT {
                        // Keep the position of the start of the step, as for any frozen particle.
                        p.x_next[a][i] = p.x[a][i];
                    }
                }
                p.status[i] = FROZEN;
                report.note_frozen(i as u32);
            }
            if COMMIT_NEXT {
                for a in 0..D {
                    p.x[a][i] = p.x_next[a][i];
                }
            }
        }
    }
}
