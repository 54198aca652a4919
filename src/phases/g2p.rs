//! Grid to particle (E21-E32).
//!
//! Particle update: from `v_gp = sum S_ip v_i` and `a_gp = sum S_ip a_i` (E21), FLIP with PIC
//! damping and the second-order position update (E25, E26), or APIC (E78, E80: the grid's
//! velocity, and the moment matrix `B_p` gathered with it, [`gather_chunk`]), less the damping
//! acceleration when damping is declared, then the walls: the equations are
//! [`super::update`]'s, on the lane type [`crate::simd::wide::Wide`].
//!
//! Stress update: `grad v = sum v_i (x) G_ip` (E29), `dF = exp(grad v dt)` to the configured
//! number of terms (E31), `F <- dF F` (kept as `H = F - I`), `J = det F` (E32), and `tau/rho0`
//! from the material. Axisymmetric, the hoop rate `v_r / r = sum v_r,i T_ip` (E70) stretches
//! `F_thetatheta` the same way. With thermal expansion or swelling declared, the material
//! sees `F` without the particle's isotropic eigenstrain (E47,
//! [`crate::material::elastic_part`]).
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

use super::p2g::{rows, Adds, Mode, Products};
use super::update;
use super::{Ctx, Isa};
use crate::def::UpdateOrder;
use crate::effects::damping;
use crate::grid::GridCols;
use crate::material::{
    add_viscous_lanes, eigenstrain_part, elastic_part, inelastic, model_of, on_elastic_part,
    particle_inelastic, particle_stress, with_eigenstrain, Deformation, Params,
};
use crate::math::INV;
use crate::pack::{matrix, packs, unpacked, Pack};
use crate::particles::StepReport;
use crate::particles::{ParticleCols, ESCAPED, FROZEN};
use crate::shape::{Shape1D, Stencil, Stencils, ROW};
use crate::simd::lanes::{commit, live_lanes, load, load_into, Block, Lane, Lanes};
use crate::simd::rows::{self, Rows};
use crate::simd::wide::{Wide, WideMask};
use crate::Real;

/// A D x D matrix per lane, `m[a][b][lane]`.
type LaneMat<const D: usize, const W: usize> = [[Lane<W>; D]; D];

/// Which nodal velocity a gather differentiates for the velocity gradient. With whether it
/// gathers the velocities and the moments, a const parameter of the gather (`Grad::X as u8`):
/// its loads and sums sit in the innermost loop, and tested there as values they made the
/// default step 1.2 to 1.4 times as long (benches/PERFORMANCE.md).
#[derive(Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
enum Grad {
    /// None (the stress is updated in its own pass).
    None,
    /// `v_i + a_i dt` (USL).
    Updated,
    /// The wall-constrained stress-update velocity (USF, MUSL).
    Remap,
}

/// What a chunk's gathers return: `v_gp[a]`, `a_gp[a]`, the velocity gradient `l[a][b]` and,
/// axisymmetric, the hoop rate `v_r / r` of every lane. What a pass does not gather stays
/// zero; lanes that hold no active particle carry values that are never committed.
#[repr(C, align(64))]
pub(crate) struct Gathered<const D: usize, const W: usize> {
    v_gp: [Lane<W>; D],
    a_gp: [Lane<W>; D],
    l: LaneMat<D, W>,
    hoop: Lane<W>,
}

impl<const D: usize, const W: usize> Gathered<D, W> {
    /// All zero. A pass makes one and [`gather_chunk`] overwrites what it gathers for every
    /// chunk (a new one per chunk was a memset of every field).
    fn zero() -> Self {
        Gathered {
            v_gp: [[0.0; W]; D],
            a_gp: [[0.0; W]; D],
            l: [[[0.0; W]; D]; D],
            hoop: [0.0; W],
        }
    }
}

/// The sum along x of a stencil row's nodes `n` weighted by `w` (weights, derivatives, moments
/// or hoop factors), in node order.
#[inline(always)]
fn sum_x<I: Rows, const K: usize>(w: &[Wide<I>; K], n: &[Wide<I>; ROW]) -> Wide<I> {
    let mut s = w[0] * n[0];
    for i in 1..K {
        s = s + w[i] * n[i];
    }
    s
}

/// [`rows::read`] as [`Wide`]s.
///
/// # Safety
/// As for [`rows::read`].
#[inline(always)]
unsafe fn read_row<I: Rows, const W: usize>(
    col: &[Real],
    base: &[u32; W],
    at: usize,
    off: usize,
    shared: bool,
) -> [Wide<I>; ROW] {
    // SAFETY: as required of the caller.
    let r = unsafe { rows::read::<I, W>(col, base, at, off, shared) };
    [Wide(r[0]), Wide(r[1]), Wide(r[2]), Wide(r[3])]
}

/// Gathers, for every lane of a chunk, `v_gp` and `a_gp` (when `VEL`), the velocity gradient
/// (per `GRAD`; with the hoop rate `sum u_r,i T_ip` axisymmetric) and, with `MOMENTS` (APIC,
/// with `VEL`), the moment matrix `B_p = sum_i (v_i + a_i dt) (x) S_ip (x_i - x_p)` (E78) into
/// `affine` (not for a family that keeps the gradient form, [`Shape1D::GRADIENT_AFFINE`]:
/// see `commit_gradient_affine`).
///
/// Lane-major, [`Rows::N`] lanes at a time in the instance's vectors: each stencil row of
/// those lanes is read as one vector per node ([`Rows::rows`]), summed along x with the x
/// weights (`X = sum_i w_i u_i`, `DX = sum_i dw_i u_i`, the moments or hoop factors in place
/// of `w` where needed), and the sums weighted by the row's factors into sums held in
/// registers (E6, separable: node (i, j, k) has `S = wx_i wy_j wz_k` and
/// `G = (dwx_i wy_j wz_k, wx_i dwy_j wz_k, wx_i wy_j dwz_k)`).
#[inline(always)]
pub(crate) fn gather_chunk<
    I: Rows,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
    const VEL: bool,
    const GRAD: u8,
    const MOMENTS: bool,
>(
    ctx: &Ctx<'_, D>,
    g: &GridCols<'_, D>,
    st: &Stencils<D, K, W>,
    affine: &mut [[Lane<W>; D]; D],
    out: &mut Gathered<D, W>,
) {
    // The moments take v + a dt, which only a gather of the velocities reads.
    const { assert!(!MOMENTS || (VEL && GRAD != Grad::Remap as u8)) };
    let moments = MOMENTS && !S::GRADIENT_AFFINE;
    let (vel, grad) = (VEL, GRAD);
    let (gradient, updated) = (grad != Grad::None as u8, grad == Grad::Updated as u8);
    let (stride, base) = (ctx.geom.stride, st.bases());
    // The pass checked that every column read has g.len() entries (and that the remap columns
    // exist when `grad` reads them).
    if !rows::fit(base, Stencil::<D, K>::last_row_offset(stride), g.len()) {
        return; // Unreachable (first_node clamps); keeps the unchecked row reads sound.
    }
    // Lanes sharing their first node four by four (a stencil-bin fill) read one row per four.
    let shared = rows::blocks_share(base);
    // SAFETY (every unsafe block below): this instance runs only on a CPU that supports it;
    // `fit` checked every lane's rows above, and every column read has g.len() entries.
    let (zero, dt) = unsafe { (Wide::<I>::splat(0.0), Wide::<I>::splat(ctx.dt)) };
    for at in (0..W).step_by(I::N) {
        // The x factors of each node: weights, derivatives, moments (APIC), hoop factors.
        let (mut wx, mut dwx, mut ex, mut tx) = ([zero; K], [zero; K], [zero; K], [zero; K]);
        for i in 0..K {
            unsafe {
                wx[i] = Wide::load(&st.weights(0)[i], at);
                if gradient {
                    dwx[i] = Wide::load(&st.derivatives(0)[i], at);
                }
                if moments {
                    ex[i] = Wide::load(&st.moments(0)[i], at);
                }
                if S::AXISYMMETRIC && gradient {
                    tx[i] = Wide::load(&st.hoop_factors()[i], at);
                }
            }
        }
        let (mut v_gp, mut a_gp) = ([zero; D], [zero; D]);
        let (mut l, mut b_p) = ([[zero; D]; D], [[zero; D]; D]);
        let mut hoop = zero;
        for k in 0..Stencil::<D, K>::layers() {
            for j in 0..K {
                let off = crate::shape::row_start(0, j, k, stride);
                // The row's factors: r[0] = wy_j wz_k (S and G_x), r[b] the same with axis
                // b's factor differentiated (G_b), re[b] with the moment on axis b (APIC).
                let (mut r, mut re) = ([zero; D], [zero; D]);
                unsafe {
                    let (wy, dwy) = (
                        Wide::load(&st.weights(1)[j], at),
                        Wide::load(&st.derivatives(1)[j], at),
                    );
                    let ey = if moments {
                        Wide::load(&st.moments(1)[j], at)
                    } else {
                        zero
                    };
                    if D == 3 {
                        let wz = Wide::load(&st.weights(D - 1)[k], at);
                        r[0] = wy * wz;
                        r[1] = dwy * wz;
                        r[D - 1] = wy * Wide::load(&st.derivatives(D - 1)[k], at);
                        if moments {
                            re[1] = ey * wz;
                            re[D - 1] = wy * Wide::load(&st.moments(D - 1)[k], at);
                        }
                    } else {
                        (r[0], r[1], re[1]) = (wy, dwy, ey);
                    }
                }
                for a in 0..D {
                    let (mut nv, mut na, mut nu) = ([zero; ROW], [zero; ROW], [zero; ROW]);
                    if vel || updated {
                        unsafe {
                            nv = read_row::<I, W>(g.vel[a], base, at, off, shared);
                            na = read_row::<I, W>(g.acc[a], base, at, off, shared);
                        }
                    }
                    // The differentiated velocity: v + a dt (USL's gradient, APIC's moments)
                    // or the re-mapped one (USF, MUSL).
                    if grad == Grad::Remap as u8 {
                        nu = unsafe { read_row::<I, W>(g.remap[a], base, at, off, shared) };
                    } else if updated || moments {
                        for i in 0..K {
                            nu[i] = nv[i] + na[i] * dt;
                        }
                    }
                    // v_gp = sum S_ip v_i, a_gp = sum S_ip a_i, S_ip = wx_i r_0.
                    if vel {
                        v_gp[a] = v_gp[a] + r[0] * sum_x::<I, K>(&wx, &nv);
                        a_gp[a] = a_gp[a] + r[0] * sum_x::<I, K>(&wx, &na);
                    }
                    let su = if gradient || moments {
                        sum_x::<I, K>(&wx, &nu)
                    } else {
                        zero
                    };
                    // grad v = sum u_i (x) G_ip (E29), G_ip = (dwx_i r_0, wx_i r_1, ...).
                    if gradient {
                        l[a][0] = l[a][0] + r[0] * sum_x::<I, K>(&dwx, &nu);
                        for b in 1..D {
                            l[a][b] = l[a][b] + r[b] * su;
                        }
                        if S::AXISYMMETRIC && a == 0 {
                            // v_r / r = sum_i u_r,i T_ip (E70), T_ip = t_i wy_j.
                            hoop = hoop + r[0] * sum_x::<I, K>(&tx, &nu);
                        }
                    }
                    // B_p = sum u_i (x) S_ip (x_i - x_p) (E78).
                    if moments {
                        b_p[a][0] = b_p[a][0] + r[0] * sum_x::<I, K>(&ex, &nu);
                        for b in 1..D {
                            b_p[a][b] = b_p[a][b] + re[b] * su;
                        }
                    }
                }
            }
        }
        for a in 0..D {
            if vel {
                v_gp[a].store(&mut out.v_gp[a], at);
                a_gp[a].store(&mut out.a_gp[a], at);
            }
            for b in 0..D {
                if gradient {
                    l[a][b].store(&mut out.l[a][b], at);
                }
                if moments {
                    b_p[a][b].store(&mut affine[a][b], at);
                }
            }
        }
        if gradient && S::AXISYMMETRIC {
            hoop.store(&mut out.hoop, at);
        }
    }
}

/// APIC for a family that keeps the gradient form ([`Shape1D::GRADIENT_AFFINE`], linear):
/// `C_p` is the velocity gradient the stress update just used (E81), committed for the lanes
/// in `ok`. That gradient comes from the lagged (USF), re-mapped (MUSL) or updated (USL) nodal
/// velocities; the updated ones are unbounded at a node that carries a sliver of a particle's
/// mass (linear weights' cell-crossing instability, see [`crate::UpdateOrder::Usl`]), which
/// would enter the next transfer through `C_p`, so USF and MUSL keep linear APIC stable where
/// USL does not. Does nothing when the affine columns are not reserved.
#[inline(always)]
fn commit_gradient_affine<const D: usize, const W: usize>(
    p: &mut ParticleCols<'_, D>,
    start: usize,
    l: &LaneMat<D, W>,
    ok: Lanes<W>,
) {
    for r in 0..D {
        for c in 0..D {
            commit(p.affine[r][c], start, &l[r][c], ok);
        }
    }
}

/// The lane matrices of a stress update, kept by the pass across chunks (see
/// `lanes::load_into`): built per chunk, `exp(grad v dt)`'s copies of whole matrices went
/// through the stack, and 256-bit loads that straddled two earlier stores there waited for
/// them (store forwarding fails for such loads).
#[repr(C, align(64))]
struct StressScratch<const D: usize, const W: usize> {
    h_old: LaneMat<D, W>,
    h: LaneMat<D, W>,
    tau: [Lane<W>; 6],
}

impl<const D: usize, const W: usize> StressScratch<D, W> {
    fn new() -> Self {
        StressScratch {
            h_old: [[[0.0; W]; D]; D],
            h: [[[0.0; W]; D]; D],
            tau: [[0.0; W]; 6],
        }
    }
}

/// [`crate::math::exp_series_minus_identity`] on the instance's vectors.
///
/// # Safety
/// The CPU supports the instance `I` (as for [`Wide::splat`]).
#[inline(always)]
unsafe fn exp_minus_identity<I: Rows, const D: usize>(
    a: &[[Wide<I>; D]; D],
    n: usize,
) -> [[Wide<I>; D]; D] {
    // SAFETY: as required of the caller.
    crate::math::exp_series_minus_identity(a, n, |k| unsafe { Wide::<I>::splat(INV[k]) })
}

/// Updates H and tau/rho0 of the lanes in `update` from their velocity gradient `l`. Returns
/// per lane whether the update succeeded, and the lanes that failed because their volume ran
/// away (`J - 1` outside [`Ctx::jm1_band`], F not inverted); a lane that fails (non-finite
/// result, inverted F or runaway) keeps its H and stress.
#[inline(always)]
fn update_stress<I: Isa, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    start: usize,
    update: Lanes<W>,
    gathered: &Gathered<D, W>,
    scratch: &mut StressScratch<D, W>,
) -> (Lanes<W>, Lanes<W>) {
    let l = &gathered.l;
    let StressScratch { h_old, h, tau } = scratch;
    // dF = exp(L dt) (E31), kept as Q = dF - I, and H <- H + Q + Q H (F <- dF F, E32), on as
    // many lanes at once as the instance's vectors hold.
    let n = ctx.exp_terms.clamp(1, 8) as usize;
    for r in 0..D {
        for c in 0..D {
            load_into(&mut h_old[r][c], p.h[r][c], start);
        }
    }
    // SAFETY (every unsafe block below): this instance runs only on a CPU that supports it.
    let (zero, dt) = unsafe { (Wide::<I>::splat(0.0), Wide::<I>::splat(ctx.dt)) };
    for at in (0..W).step_by(I::N) {
        let ld = |c: &Lane<W>| unsafe { Wide::<I>::load(c, at) };
        let mut a = [[zero; D]; D];
        for r in 0..D {
            for c in 0..D {
                a[r][c] = ld(&l[r][c]) * dt;
            }
        }
        let q = unsafe { exp_minus_identity::<I, D>(&a, n) };
        for r in 0..D {
            for c in 0..D {
                let mut v = ld(&h_old[r][c]);
                for m in 0..D {
                    v = v + q[r][m] * ld(&h_old[m][c]);
                }
                (v + q[r][c]).store(&mut h[r][c], at);
            }
        }
    }
    // Axisymmetric: F_thetatheta <- exp(v_r / r dt) F_thetatheta, by the same series, kept
    // as `F_thetatheta - 1` (the out-of-plane `hzz` the materials read; 0 in plane strain).
    let mut hzz = [0.0; W];
    if S::AXISYMMETRIC {
        let old: Lane<W> = load(p.hoop, start);
        for at in (0..W).step_by(I::N) {
            // SAFETY: as above.
            let ld = |c: &Lane<W>| unsafe { Wide::<I>::load(c, at) };
            let q = unsafe { exp_minus_identity::<I, 1>(&[[ld(&gathered.hoop) * dt]], n) }[0][0];
            let old = ld(&old);
            (old + q + q * old).store(&mut hzz, at);
        }
    }
    // J - 1 = tr H + principal minors (+ det H in 3D), without forming I + H; times F_zz in 2D.
    let mut jm1 = Deformation::new(*packs(h), Pack(hzz)).jm1.0;
    // The plastic history, when declared (the plastic models read and change it).
    let mut plastic: Lane<W> = if ctx.plastic {
        load(p.plastic, start)
    } else {
        [0.0; W]
    };
    // Material: the model's chunk path when every lane shares one material (the common case,
    // vectorised); otherwise lane by lane.
    // Without `Option` combinators: their closures were left out of line (a profile showed
    // `update_stress::{{closure}}` comparing the ids one lane at a time in baseline code).
    // The ids stay u32 here and are widened only where a lane's record is looked up (widening
    // all sixteen up front cost 2 instructions per 2D particle-step).
    let ids = load(p.material, start);
    let mut uniform = None;
    if let Some(l0) = update.first() {
        let id = ids[l0];
        // Compared four lanes at a time (`Lanes::equal`, exact: ids are below the material
        // capacity, at most 2^16; one lane at a time it held 6 % of the stress pass's samples).
        let same = update.minus(Lanes::equal(&ids, id)).is_empty();
        if let Some(r) = ctx.materials.get(id as usize) {
            if same {
                uniform = Some(r);
            }
        }
    }
    let ns = crate::layout::stress_components(D);
    // The isotropic eigenstrain of each lane (thermal expansion, swelling), when declared.
    let eigen = eigenstrain(ctx, p, start, &ids);
    let ok = if let Some(rec) = uniform {
        let (model, params) = (model_of(rec), Params::of(rec));
        // The inelastic part first (a return mapping, a fluid's projection): the stress is
        // that of the state it leaves. It acts on the elastic part: with an eigenstrain, on
        // `F / (1 + d)`, which then takes the eigenstrain back (E47), so that a free
        // expansion neither yields nor flows.
        if inelastic(model) {
            let f = Deformation {
                h: *packs(h),
                hzz: Pack(hzz),
                jm1: Pack(jm1),
                plastic: Pack(plastic),
            };
            let (mut e, d) = match &eigen {
                Some(d) if on_elastic_part(model) => (elastic_part(&f, Pack(*d)).0, Some(Pack(*d))),
                _ => (f, None),
            };
            let mut eh = *unpacked(&e.h);
            let (mut ezz, mut ejm1) = (e.hzz.0, e.jm1.0);
            let axi = S::AXISYMMETRIC;
            I::inelastic::<D, W>(
                model,
                &params,
                &mut eh,
                &mut ezz,
                &mut ejm1,
                &mut plastic,
                axi,
            );
            (e.h, e.hzz, e.jm1, e.plastic) = (*packs(&eh), Pack(ezz), Pack(ejm1), Pack(plastic));
            let back = match d {
                Some(d) => with_eigenstrain(&e, d),
                None => e,
            };
            *h = *unpacked(&back.h);
            (hzz, jm1) = (back.hzz.0, back.jm1.0);
        }
        let mut admissible = Lanes::ALL;
        match &eigen {
            None => I::kirchhoff::<D, W>(model, &params, h, &hzz, &jm1, &plastic, tau),
            Some(d) => {
                let f = Deformation {
                    h: *packs(h),
                    hzz: Pack(hzz),
                    jm1: Pack(jm1),
                    plastic: Pack(plastic),
                };
                let (e, cube) = elastic_part(&f, Pack(*d));
                let he = *unpacked(&e.h);
                // The eigenstrain must not invert the material either.
                admissible = rows::above::<I, W>(d, -1.0);
                I::kirchhoff::<D, W>(model, &params, &he, &e.hzz.0, &e.jm1.0, &plastic, tau);
                for row in tau.iter_mut() {
                    *row = (Pack(*row) * cube).0;
                }
            }
        }
        admissible & update & rows::above::<I, W>(&jm1, -1.0)
    } else {
        stress_lane_by_lane(
            ctx.materials,
            &ids,
            LaneDeformation {
                h,
                hzz: &mut hzz,
                jm1: &mut jm1,
                plastic: &mut plastic,
            },
            S::AXISYMMETRIC,
            eigen.as_ref(),
            update,
            tau,
        )
    };
    if ctx.viscous {
        let zero = [0.0; W];
        let lzz = if S::AXISYMMETRIC {
            &gathered.hoop
        } else {
            &zero
        };
        add_viscous_lanes(ctx.materials, &ids, l, lzz, &jm1, &plastic, tau);
    }
    // The runaway bound: an updated lane whose volume ratio left the band freezes (the
    // inverted and NaN lanes failed above).
    let [lo, hi] = ctx.jm1_band;
    let runaway = ok.minus(rows::above::<I, W>(&jm1, lo) & rows::below::<I, W>(&jm1, hi));
    let ok = ok.minus(runaway);
    // One finiteness test per lane: a sum is finite only if every term is (an overflowing sum
    // of finite values is a false alarm that freezes a particle already at 1e38: acceptable).
    let mut sum = [0.0; W];
    for ln in 0..W {
        sum[ln] = jm1[ln] + hzz[ln];
        for k in 0..ns {
            sum[ln] += tau[k][ln];
        }
        for r in 0..D {
            for c in 0..D {
                sum[ln] += h[r][c][ln];
            }
        }
    }
    if ctx.plastic {
        for ln in 0..W {
            sum[ln] += plastic[ln];
        }
    }
    let ok = ok & rows::finite::<I, W>(&sum);
    for r in 0..D {
        for c in 0..D {
            commit(p.h[r][c], start, &h[r][c], ok);
        }
    }
    for k in 0..ns {
        commit(p.tau[k], start, &tau[k], ok);
    }
    if S::AXISYMMETRIC {
        commit(p.hoop, start, &hzz, ok);
    }
    if ctx.plastic {
        commit(p.plastic, start, &plastic, ok);
    }
    (ok, runaway)
}

/// The isotropic eigenstrain `d` of each lane (`F_0 = (1 + d) I`, E47): `alpha (T - T_0)` with
/// heat conduction plus `beta (c - c_0)` with diffusion, from the grid values at the particles
/// (E63: features read the grid's value, not the particle's) and each lane's material; `None`
/// when no declared field has a material that expands or swells.
#[inline(always)]
fn eigenstrain<const D: usize, const W: usize>(
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    start: usize,
    ids: &[u32; W],
) -> Option<Lane<W>> {
    if !ctx.eigenstrain.iter().any(|&e| e) {
        return None;
    }
    let mut d = [0.0; W];
    for (f, &on) in ctx.eigenstrain.iter().enumerate() {
        if !on {
            continue;
        }
        let value: Lane<W> = load(p.scalar[f][1], start);
        for ln in 0..W {
            if let Some(r) = ctx.materials.get(ids[ln] as usize) {
                d[ln] += eigenstrain_part(r, f, value[ln]);
            }
        }
    }
    Some(d)
}

/// A chunk's deformation lane arrays, borrowed for the lane-by-lane material update.
struct LaneDeformation<'a, const D: usize, const W: usize> {
    h: &'a mut [[Lane<W>; D]; D],
    hzz: &'a mut Lane<W>,
    jm1: &'a mut Lane<W>,
    plastic: &'a mut Lane<W>,
}

/// The material update of the lanes in `update` of a chunk whose lanes do not share one
/// material, one lane at a time: the inelastic part ([`particle_inelastic`]) on `f` in place,
/// then the stress ([`particle_stress`]); returns the lanes it updated (not those inverted or
/// of an unknown material). A function of its own per dimension, not inlined into every pass
/// form: chunks that mix materials are few, and each inlined copy cost build time and size.
#[inline(never)]
fn stress_lane_by_lane<const D: usize, const W: usize>(
    materials: &[crate::layout::MaterialRecord],
    ids: &[u32; W],
    f: LaneDeformation<'_, D, W>,
    hoop: bool,
    eigen: Option<&Lane<W>>,
    update: Lanes<W>,
    tau: &mut [Lane<W>; 6],
) -> Lanes<W> {
    let mut ok = Lanes::NONE;
    for ln in update.iter() {
        let Some(rec) = materials.get(ids[ln] as usize) else {
            continue;
        };
        let one = Deformation::<D> {
            h: matrix(|r, c| f.h[r][c][ln]),
            hzz: f.hzz[ln],
            jm1: f.jm1[ln],
            plastic: f.plastic[ln],
        };
        // The return on the elastic part, as the chunk path does (E47).
        let one = match eigen {
            Some(d) if on_elastic_part(model_of(rec)) => {
                let e = elastic_part(&one, d[ln]).0;
                with_eigenstrain(&particle_inelastic(rec, &e, hoop), d[ln])
            }
            _ => particle_inelastic(rec, &one, hoop),
        };
        for r in 0..D {
            for c in 0..D {
                f.h[r][c][ln] = one.h[r][c];
            }
        }
        (f.hzz[ln], f.jm1[ln], f.plastic[ln]) = (one.hzz, one.jm1, one.plastic);
        let d = eigen.map_or(0.0, |d| d[ln]);
        if let Some(s) = particle_stress(rec, &one, d) {
            for (row, &v) in tau
                .iter_mut()
                .zip(&s)
                .take(crate::layout::stress_components(D))
            {
                row[ln] = v;
            }
            ok = ok | Lanes::one(ln);
        }
    }
    ok
}

/// Particle update: velocity and position from the grid. With USL it also updates the stress
/// from `v_i + a_i dt` in the same pass. With MUSL it also keeps the positions of the start of
/// the step in the `x_start` columns, for the stress pass, and scatters the new momenta to the
/// remap columns (E30) with the stencils already computed (the pass reads only `vel` and `acc`, so
/// the remap columns are free to fill; particles contribute as in the scatter pass:
/// [`scatter_chunk`]). Declared damping adds the damping of the module docs; APIC replaces
/// FLIP. Each of these is a value of the substep ([`Ctx`]), tested once per chunk.
#[inline(always)]
pub(crate) fn particles<I: Isa, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
    report: &mut StepReport,
) {
    let geom = &ctx.geom;
    let dt = ctx.dt;
    let fused_stress = ctx.order == UpdateOrder::Usl;
    let keep_start = ctx.order == UpdateOrder::Musl;
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
    // MUSL: what the re-map scatters (it reads no stress).
    let mut products = Products::zero();
    let (no_tau, no_force) = ([[0.0; W]; 6], [[0.0; W]; D]);
    // The constants of the update and the walls, made once per pass. SAFETY: this instance
    // runs only on a CPU that supports it.
    let (step, faces, zero, none, speed2_limit) = unsafe {
        (
            update::Step::<I>::new(dt, ctx.beta, ctx.particle_velocity),
            core::array::from_fn::<_, D, _>(|a| update::Faces::<I>::of(geom, a)),
            Wide::<I>::splat(0.0),
            WideMask::<I>::splat(false),
            Wide::<I>::splat(ctx.speed2_limit),
        )
    };
    for start in (0..count).step_by(W) {
        let live = live_lanes(p, start, count);
        for a in 0..D {
            load_into(&mut x[a], p.x[a], start);
            load_into(&mut x_low[a], p.x_low[a], start);
            load_into(&mut v[a], p.v[a], start);
        }
        I::stencils::<D, K, S, W>(&mut st, shape, ctx, p, start, &x, apic, false, ctx.mls);
        if damp {
            damping::lane_rates(ctx, p, start, &mut alpha_g, &mut alpha_p);
        }
        // One gather per (order, transfer), chosen per chunk.
        const NONE: u8 = Grad::None as u8;
        const UPDATED: u8 = Grad::Updated as u8;
        let (aff, out) = (&mut *affine, &mut gathered);
        match (fused_stress, moments) {
            (false, false) => I::gather::<D, K, S, W, true, NONE, false>(ctx, g, &st, aff, out),
            (false, true) => I::gather::<D, K, S, W, true, NONE, true>(ctx, g, &st, aff, out),
            (true, false) => I::gather::<D, K, S, W, true, UPDATED, false>(ctx, g, &st, aff, out),
            (true, true) => I::gather::<D, K, S, W, true, UPDATED, true>(ctx, g, &st, aff, out),
        }
        if ctx.momentum {
            use super::momentum::{gather, Differentiate};
            let which = if fused_stress {
                Differentiate::Updated
            } else {
                Differentiate::Nothing
            };
            let (l, moving) = (&mut gathered.l, Some((&mut *v_move, &mut *a_move)));
            gather::<D, K, S, W>(ctx, &st, &x, live, g, which, l, moving);
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
        let mut fast = Lanes::NONE;
        for q in (0..W).step_by(I::N) {
            // SAFETY: this instance runs only on a CPU that supports it.
            let ld = |c: &Lane<W>| unsafe { Wide::<I>::load(c, q) };
            let (mut sum, mut speed2) = (zero, zero);
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
                } else {
                    let moves_with = (ld(&v_moves[a]), ld(&a_moves[a]));
                    update::flip(&step, v_p, (v_gp, a_gp), moves_with, d)
                };
                let (xn, xn_low) = update::advance(ld(&x[a]), ld(&x_low[a]), dx);
                sum = sum + (vn + xn);
                speed2 = speed2 + vn * vn;
                let at = update::walls(&faces[a], xn, xn_low, vn);
                (open, wall) = (open | at.open, wall | at.wall);
                at.x.store(&mut x_new[a], q);
                at.x_low.store(&mut x_low_new[a], q);
                at.v.store(&mut v_new[a], q);
            }
            if apic {
                for r in 0..D {
                    for c in 0..D {
                        sum = sum + ld(&affine[r][c]);
                    }
                }
            }
            finite = finite | sum.is_finite().lanes(q);
            fast = fast | speed2.gt(speed2_limit).lanes(q);
            escaped = escaped | open.lanes(q);
            stopped = stopped | wall.lanes(q);
        }
        // A lane faster than any stable step above the floor resolves runs away.
        let too_fast = live & finite & fast;
        let moved = (live & finite).minus(too_fast);
        let (ok, runaway) = if fused_stress {
            update_stress::<I, D, K, S, W>(ctx, p, start, moved, &gathered, &mut scratch)
        } else {
            (moved, Lanes::NONE)
        };
        let runaway = runaway | too_fast;
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
            report.note_frozen((start + ln) as u32, runaway.has(ln));
        }
        let escaped = ok & escaped;
        for ln in escaped.iter() {
            p.status[start + ln] = ESCAPED;
        }
        report.escaped += escaped.count();
        report.stopped += (ok & stopped).minus(escaped).count();
        if keep_start {
            let active = live_lanes(p, start, count);
            load_into(&mut mass, p.mass, start);
            // An active lane was committed: its velocity is v_new. The B_p of a family that
            // keeps the gradient form are zero here: its C_p is taken from this re-map (see
            // `commit_gradient_affine`).
            let adds = Adds {
                mode: Mode::Remap,
                forces: false,
                apic,
            };
            products.set::<K, S>(&st, &mass, &v_new, &no_tau, &no_force, &affine, adds);
            let (stride, pr) = (geom.stride, &products);
            if apic {
                const REMAP: u8 = rows(Mode::Remap, true);
                I::scatter_chunk::<D, K, S, W, REMAP>(&mut st, pr, active, stride, g, adds);
            } else {
                const REMAP: u8 = rows(Mode::Remap, false);
                I::scatter_chunk::<D, K, S, W, REMAP>(&mut st, pr, active, stride, g, adds);
            }
        }
    }
}

/// Stress update in its own pass (USF before the momentum update, MUSL after the re-map),
/// from the wall-constrained velocity in the `remap` columns. With MUSL (after the particle
/// pass has moved the particles) it takes the stencils at the positions of the start of the
/// step, kept in the `x_start` columns, and puts a particle it freezes back there.
#[inline(always)]
pub(crate) fn stress<I: Isa, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
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
    let mut st = Stencils::<D, K, W>::default();
    let mut gathered = Gathered::zero();
    // The moment matrices this pass does not gather.
    let mut unused_affine = [[[0.0; W]; D]; D];
    let mut x = Block([[0.0; W]; D]);
    let mut scratch = StressScratch::new();
    let from_start = ctx.order == UpdateOrder::Musl;
    for start in (0..count).step_by(W) {
        let live = live_lanes(p, start, count);
        // The stencils at the positions of the start of the step (MUSL: the particle pass has
        // moved the particles).
        for a in 0..D {
            load_into(
                &mut x[a],
                if from_start { &*p.x_start[a] } else { &*p.x[a] },
                start,
            );
        }
        I::stencils::<D, K, S, W>(&mut st, shape, ctx, p, start, &x, false, false, ctx.mls);
        const REMAP: u8 = Grad::Remap as u8;
        I::gather::<D, K, S, W, false, REMAP, false>(
            ctx,
            g,
            &st,
            &mut unused_affine,
            &mut gathered,
        );
        if ctx.momentum {
            use super::momentum::{gather, Differentiate};
            let (which, l) = (Differentiate::Remap, &mut gathered.l);
            gather::<D, K, S, W>(ctx, &st, &x, live, g, which, l, None);
        }
        let (ok, runaway) =
            update_stress::<I, D, K, S, W>(ctx, p, start, live, &gathered, &mut scratch);
        if S::GRADIENT_AFFINE {
            commit_gradient_affine(p, start, &gathered.l, ok);
        }
        for ln in live.minus(ok).iter() {
            let i = start + ln;
            for a in 0..D {
                p.v[a][i] = 0.0;
                if from_start {
                    // Back to the position of the start of the step, as for any frozen
                    // particle (to the last bit of x: the low part is not kept).
                    p.x[a][i] = p.x_start[a][i];
                    p.x_low[a][i] = 0.0;
                }
            }
            p.status[i] = FROZEN;
            report.note_frozen(i as u32, runaway.has(ln));
        }
    }
}
