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

use super::{load_h, load_v, load_x, Ctx};
use crate::def::Boundary;
use crate::grid::{load_row, GridCols};
use crate::material::{kirchhoff_over_rho0, model_of, Params};
use crate::math::{det_identity_plus_minus_one, exp_series_minus_identity, mul, Mat};
use crate::particles::{ParticleCols, ACTIVE, ESCAPED, FROZEN};
use crate::shape::{Shape1D, Stencil, ROW};
use crate::{Real, StepReport};

/// Updates F and tau/rho0 of particle `i` from its velocity gradient. Returns false (and
/// changes nothing) if the result is not finite or F inverts.
#[inline(always)]
fn update_stress<const D: usize>(
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    i: usize,
    grad_v: &Mat<D>,
) -> bool {
    let mut l = *grad_v;
    for row in l.iter_mut() {
        for v in row.iter_mut() {
            *v *= ctx.dt;
        }
    }
    // F <- dF F in terms of H = F - I and A = dF - I: H <- H + A + A H.
    let a = exp_series_minus_identity(&l, ctx.exp_terms);
    let h_old = load_h(p, i);
    let ah = mul(&a, &h_old);
    let mut h = h_old;
    for r in 0..D {
        for c in 0..D {
            h[r][c] += a[r][c] + ah[r][c];
        }
    }
    let jm1 = det_identity_plus_minus_one(&h);
    if !(jm1 > -1.0 && jm1.is_finite()) {
        return false;
    }
    // Material ids are validated when particles are added; `get` keeps a corrupted buffer from
    // turning into a panic.
    let id = p.material[i] as usize;
    let Some(rec) = ctx.materials.get(id) else {
        return false;
    };
    let s = kirchhoff_over_rho0(model_of(rec), &Params::of(rec), &h, jm1);
    let finite = s.zz.is_finite() && s.m.iter().flatten().all(|v| v.is_finite());
    if !finite {
        return false;
    }
    for r in 0..D {
        for c in 0..D {
            p.h[r][c][i] = h[r][c];
        }
    }
    for (k, &(a, b)) in super::sym_pairs(D).iter().enumerate() {
        p.tau[k][i] = s.m[a][b];
    }
    if D == 2 {
        p.tau[3][i] = s.zz;
    }
    true
}

/// Freezes particle `i`: zero velocity, status frozen, counted.
#[inline(always)]
fn freeze<const D: usize>(p: &mut ParticleCols<'_, D>, i: usize, report: &mut StepReport) {
    for a in 0..D {
        p.v[a][i] = 0.0;
    }
    p.status[i] = FROZEN;
    report.note_frozen(i as u32);
}

/// Particle update: velocity and position from the grid. `FUSED_STRESS` also updates the stress
/// from `v_i + a_i dt` in the same pass (USL); `TO_NEXT` writes the new positions to the MUSL
/// scratch columns instead of the positions.
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
    g: &GridCols<'_, D>,
    report: &mut StepReport,
) {
    let geom = &ctx.geom;
    let dt = ctx.dt;
    let pic = 1.0 - ctx.beta;
    for i in 0..count {
        let x = load_x(p, i);
        if p.status[i] != ACTIVE {
            if TO_NEXT {
                for a in 0..D {
                    p.x_next[a][i] = x[a];
                }
            }
            continue;
        }
        let st = Stencil::<D, K>::new(shape, geom.cells_of(x), geom.nodes, geom.stride, geom.inv_h);
        // Row-wide partial sums, reduced once at the end.
        let mut v_acc = [[0.0; ROW]; D];
        let mut a_acc = [[0.0; ROW]; D];
        let mut l_acc = [[[0.0; ROW]; D]; D];
        st.for_each_row(geom.stride, |row, w, grad| {
            for a in 0..D {
                let vi = load_row(g.vel[a], row);
                let ai = load_row(g.acc[a], row);
                for i in 0..ROW {
                    v_acc[a][i] += w[i] * vi[i];
                    a_acc[a][i] += w[i] * ai[i];
                }
                if FUSED_STRESS {
                    for b in 0..D {
                        for i in 0..ROW {
                            l_acc[a][b][i] += (vi[i] + dt * ai[i]) * grad[b][i];
                        }
                    }
                }
            }
        });
        let v_gp: [Real; D] = core::array::from_fn(|a| v_acc[a].iter().sum());
        let a_gp: [Real; D] = core::array::from_fn(|a| a_acc[a].iter().sum());
        let l: Mat<D> =
            core::array::from_fn(|a| core::array::from_fn(|b| l_acc[a][b].iter().sum()));
        let v = load_v(p, i);
        let mut v_new = [0.0; D];
        let mut x_new = [0.0; D];
        for a in 0..D {
            let inversion = pic * (v[a] - v_gp[a]);
            v_new[a] = v[a] + a_gp[a] * dt - inversion;
            x_new[a] = x[a] + (v_gp[a] + 0.5 * a_gp[a] * dt - 0.5 * inversion) * dt;
        }
        let finite = x_new.iter().chain(v_new.iter()).all(|c| c.is_finite());
        if !finite || (FUSED_STRESS && !update_stress(ctx, p, i, &l)) {
            freeze(p, i, report);
            if TO_NEXT {
                for a in 0..D {
                    p.x_next[a][i] = x[a];
                }
            }
            continue;
        }
        // Walls and open faces.
        let s = geom.cells_of(x_new);
        let mut status = ACTIVE;
        let mut stopped = false;
        for a in 0..D {
            let (bound, side) = if s[a] < geom.lo[a] {
                (geom.lo[a], 0)
            } else if s[a] > geom.hi[a] {
                (geom.hi[a], 1)
            } else {
                continue;
            };
            x_new[a] = geom.origin[a] + bound * geom.h;
            if geom.faces[a][side] == Boundary::Open {
                status = ESCAPED;
            } else {
                stopped = true;
                let outward = if side == 0 {
                    v_new[a] < 0.0
                } else {
                    v_new[a] > 0.0
                };
                if outward {
                    v_new[a] = 0.0;
                }
            }
        }
        if status == ESCAPED {
            p.status[i] = ESCAPED;
            report.escaped += 1;
        } else if stopped {
            report.stopped += 1;
        }
        for a in 0..D {
            p.v[a][i] = v_new[a];
            if TO_NEXT {
                p.x_next[a][i] = x_new[a];
            } else {
                p.x[a][i] = x_new[a];
            }
        }
    }
}

/// Stress update in its own pass (USF before the momentum update, MUSL after the re-map),
/// from the wall-constrained velocity in the `remap` columns. `COMMIT_NEXT` (MUSL) commits
/// the new positions afterwards.
pub(crate) fn stress<const D: usize, const K: usize, S: Shape1D<K>, const COMMIT_NEXT: bool>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &GridCols<'_, D>,
    report: &mut StepReport,
) {
    let geom = &ctx.geom;
    for i in 0..count {
        if p.status[i] == ACTIVE {
            let x = load_x(p, i);
            let st =
                Stencil::<D, K>::new(shape, geom.cells_of(x), geom.nodes, geom.stride, geom.inv_h);
            let mut l_acc = [[[0.0; ROW]; D]; D];
            st.for_each_row(geom.stride, |row, _w, grad| {
                for a in 0..D {
                    let vi = load_row(g.remap[a], row);
                    for b in 0..D {
                        for i in 0..ROW {
                            l_acc[a][b][i] += vi[i] * grad[b][i];
                        }
                    }
                }
            });
            let l: Mat<D> =
                core::array::from_fn(|a| core::array::from_fn(|b| l_acc[a][b].iter().sum()));
            if !update_stress(ctx, p, i, &l) {
                freeze(p, i, report);
                if COMMIT_NEXT {
                    // Keep the position of the start of the step, as for any frozen particle.
                    for a in 0..D {
                        p.x_next[a][i] = x[a];
                    }
                }
            }
        }
        if COMMIT_NEXT {
            for a in 0..D {
                p.x[a][i] = p.x_next[a][i];
            }
        }
    }
}
