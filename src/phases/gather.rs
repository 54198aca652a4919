//! The gathers of the velocity approach (E21, E78): what a chunk of particles reads from the
//! grid through its stencils, `v_gp = sum S_ip v_i`, `a_gp = sum S_ip a_i`, the velocity
//! gradient and APIC's moment matrix, one stencil row at a time on the lane type. The particle
//! pass ([`super::g2p`]) and the stress pass ([`super::stress`]) call them; the momentum
//! approach's gather, which reads through its weights, is [`super::momentum::gather`].

use super::Ctx;
use crate::grid::GridCols;
use crate::particles::ParticleCols;
use crate::shape::{Shape1D, Stencil, Stencils, ROW};
use crate::simd::lanes::{commit, Lane, Lanes};
use crate::simd::rows::{self, Compare};
use crate::simd::wide::Wide;
use crate::Real;

/// A D x D matrix per lane, `m[a][b][lane]`.
pub(crate) type LaneMat<const D: usize, const W: usize> = [[Lane<W>; D]; D];

/// Which nodal velocity a gather differentiates for the velocity gradient. With whether it
/// gathers the velocities and the moments, a const parameter of the gather (`Grad::X as u8`):
/// its loads and sums sit in the innermost loop, and tested there as values they made the
/// default step 1.2 to 1.4 times as long (benches/PERFORMANCE.md).
#[derive(Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum Grad {
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
    pub(crate) v_gp: [Lane<W>; D],
    pub(crate) a_gp: [Lane<W>; D],
    pub(crate) l: LaneMat<D, W>,
    pub(crate) hoop: Lane<W>,
}

impl<const D: usize, const W: usize> Gathered<D, W> {
    /// All zero. A pass makes one and [`gather_chunk`] overwrites what it gathers for every
    /// chunk (a new one per chunk was a memset of every field).
    pub(crate) fn zero() -> Self {
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
pub(crate) fn sum_x<I: Compare, const K: usize>(w: &[Wide<I>; K], n: &[Wide<I>; ROW]) -> Wide<I> {
    let mut s = w[0] * n[0];
    for i in 1..K {
        s += w[i] * n[i];
    }
    s
}

/// The factors `r` of stencil row `j` along y, layer `k` along z, for lanes `at..at + N`:
/// `r_0 = wy_j wz_k` and, for `b >= 1`, the same with axis b's factor replaced by its
/// derivative (`G_0 = dwx_i r_0`, `G_b = wx_i r_b`) or, with `moments`, by its first moment
/// (APIC's `S_ip (x_i - x_p)` along b, `ex_i r_0` and `wx_i r_b`).
#[inline(always)]
pub(crate) fn row_factors<I: Compare, const D: usize, const K: usize, const W: usize>(
    st: &Stencils<D, K, W>,
    j: usize,
    k: usize,
    at: usize,
    moments: bool,
) -> [Wide<I>; D] {
    let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
    let other = |a: usize| {
        if moments {
            st.moments(a)
        } else {
            st.derivatives(a)
        }
    };
    let wy = ld(&st.weights(1)[j]);
    let mut r = [wy; D];
    if D == 3 {
        let wz = ld(&st.weights(D - 1)[k]);
        r[0] = wy * wz;
        r[1] = ld(&other(1)[j]) * wz;
        r[D - 1] = wy * ld(&other(D - 1)[k]);
    } else {
        r[1] = ld(&other(1)[j]);
    }
    r
}

/// [`rows::read`] as [`Wide`]s.
///
/// # Safety
/// As for [`rows::read`].
#[inline(always)]
pub(crate) unsafe fn read_row<I: Compare, const W: usize>(
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
/// Lane-major, [`rows::Rows::N`] lanes at a time in the instance's vectors: each stencil row of
/// those lanes is read as one vector per node ([`rows::Rows::rows`]), summed along x with the x
/// weights (`X = sum_i w_i u_i`, `DX = sum_i dw_i u_i`, the moments or hoop factors in place
/// of `w` where needed), and the sums weighted by the row's factors into sums held in
/// registers (E6, separable: node (i, j, k) has `S = wx_i wy_j wz_k` and
/// `G = (dwx_i wy_j wz_k, wx_i dwy_j wz_k, wx_i wy_j dwz_k)`).
#[inline(always)]
pub(crate) fn gather_chunk<
    I: Compare,
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
    // SAFETY (every unsafe block below): `fit` checked every lane's rows above, and every
    // column read has g.len() entries.
    let (zero, dt) = (Wide::<I>::splat(0.0), Wide::<I>::splat(ctx.dt));
    for at in (0..W).step_by(I::N) {
        // The x factors of each node: weights, derivatives, moments (APIC), hoop factors.
        let (mut wx, mut dwx, mut ex, mut tx) = ([zero; K], [zero; K], [zero; K], [zero; K]);
        for i in 0..K {
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
        let (mut v_gp, mut a_gp) = ([zero; D], [zero; D]);
        let (mut l, mut b_p) = ([[zero; D]; D], [[zero; D]; D]);
        let mut hoop = zero;
        for k in 0..Stencil::<D, K>::layers() {
            for j in 0..K {
                let off = crate::shape::row_start(0, j, k, stride);
                // The row's factors: r[0] = wy_j wz_k (S and G_x), r[b] the same with axis
                // b's factor differentiated (G_b), re[b] with the moment on axis b (APIC).
                let r = row_factors::<I, D, K, W>(st, j, k, at, false);
                let re = if moments {
                    row_factors::<I, D, K, W>(st, j, k, at, true)
                } else {
                    [zero; D]
                };
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
                        v_gp[a] += r[0] * sum_x::<I, K>(&wx, &nv);
                        a_gp[a] += r[0] * sum_x::<I, K>(&wx, &na);
                    }
                    let su = if gradient || moments {
                        sum_x::<I, K>(&wx, &nu)
                    } else {
                        zero
                    };
                    // grad v = sum u_i (x) G_ip (E29), G_ip = (dwx_i r_0, wx_i r_1, ...).
                    if gradient {
                        l[a][0] += r[0] * sum_x::<I, K>(&dwx, &nu);
                        for b in 1..D {
                            l[a][b] += r[b] * su;
                        }
                        if S::AXISYMMETRIC && a == 0 {
                            // v_r / r = sum_i u_r,i T_ip (E70), T_ip = t_i wy_j.
                            hoop += r[0] * sum_x::<I, K>(&tx, &nu);
                        }
                    }
                    // B_p = sum u_i (x) S_ip (x_i - x_p) (E78).
                    if moments {
                        b_p[a][0] += r[0] * sum_x::<I, K>(&ex, &nu);
                        for b in 1..D {
                            b_p[a][b] += re[b] * su;
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
pub(crate) fn commit_gradient_affine<const D: usize, const W: usize>(
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
