//! Particle to grid (seeds/000 eqs 22, 23, 25): nodal mass `m_i = sum S_ip m_p`, momentum
//! `p_i = sum S_ip m_p v_p` and internal force `f_i = -sum m_p (tau_p/rho0) . G_ip`. Gravity
//! enters in the grid update as `m_i g` (eq 22).

use super::g2p::{load, stencils, Lane, W};
use super::{sym_pairs, Ctx};
use crate::grid::{add_row, rows_fit, GridCols};
use crate::math::Mat;
use crate::particles::{ParticleCols, ACTIVE};
use crate::shape::{Row4, Shape1D, Stencil, Stencils};
use crate::Real;

/// What a particle-to-grid pass accumulates.
pub(crate) mod mode {
    /// Mass, momentum and internal force (USL, MUSL).
    pub const ALL: u8 = 0;
    /// Mass and momentum (first pass of USF).
    pub const MASS_MOMENTUM: u8 = 1;
    /// Internal force only (second pass of USF, after the stress update).
    pub const FORCE: u8 = 2;
    /// Momentum of the updated particle velocities into the remap columns (MUSL).
    pub const REMAP: u8 = 3;
}

/// Scatters the active particles `0..count` to the grid, accumulating what `MODE` says.
#[inline(always)]
pub(crate) fn scatter<const D: usize, const K: usize, S: Shape1D<K>, const MODE: u8>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    if !g.lengths_consistent() {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    let with_force = MODE == mode::ALL || MODE == mode::FORCE;
    let mut st = Stencils::<D, K, W>::default();
    for start in (0..count).step_by(W) {
        // The chunk's particle values as lane vectors (one load per column, no per-particle
        // bounds checks).
        let x: [Lane; D] = core::array::from_fn(|a| load(p.x[a], start));
        let mass = load(p.mass, start);
        let v: [Lane; D] = core::array::from_fn(|a| load(p.v[a], start));
        let mut tau = [[0.0; W]; 6];
        if with_force {
            for k in 0..sym_pairs(D).len() {
                tau[k] = load(p.tau[k], start);
            }
        }
        stencils::<D, K, S>(&mut st, shape, ctx, &x);
        let n = W.min(count - start);
        for t in 0..W {
            let ln = scatter_lane(t);
            if ln >= n || p.status[start + ln] != ACTIVE {
                continue;
            }
            let mut t = [[0.0; D]; D];
            if with_force {
                for (k, &(a, b)) in sym_pairs(D).iter().enumerate() {
                    t[a][b] = tau[k][ln];
                    t[b][a] = tau[k][ln];
                }
            }
            let vp = core::array::from_fn(|a| v[a][ln]);
            scatter_one::<D, K, MODE>(ctx, mass[ln], vp, &t, st.lane(ln), g);
        }
    }
}

/// The lane scattered `t`-th in a chunk: 0, W/2, 1, W/2 + 1, ... Two particles scattered one
/// after the other then come from two halves of the chunk, which in a lattice fill are cells
/// apart, so the second does not load a stencil row that overlaps, at an offset, a row the
/// first has just stored (a load that partly overlaps a pending store waits for the store to
/// complete instead of taking its value from the store buffer).
#[inline(always)]
pub(crate) const fn scatter_lane(t: usize) -> usize {
    (t % 2) * (W / 2) + t / 2
}

/// Scatters one particle of mass `m`, velocity `v` and stress `tau` (tau/rho0; read only by
/// the modes with force) with stencil `st` (also used by the MUSL particle update, which
/// scatters the new momenta as it goes).
#[inline(always)]
pub(crate) fn scatter_one<const D: usize, const K: usize, const MODE: u8>(
    ctx: &Ctx<'_, D>,
    m: Real,
    v: [Real; D],
    tau: &Mat<D>,
    st: &Stencil<D, K>,
    g: &mut GridCols<'_, D>,
) {
    let geom = &ctx.geom;
    // The pass checked that every column has this length.
    let len = g.len();
    if !rows_fit(st.base, Stencil::<D, K>::last_row_offset(geom.stride), len) {
        return; // Unreachable by construction; keeps the unchecked row access below sound.
    }
    // Separable form (seeds/000 eqs 16-17): node (i, j, k) has S = wx_i wy_j wz_k and
    // G = (dwx_i wy_j wz_k, wx_i dwy_j wz_k, wx_i wy_j dwz_k). The particle's factors times the
    // x weights (4-wide vectors) are multiplied by the y factors once per j; each row (j, k)
    // then costs one multiply by wz_k per quantity, plus one by dwz_k for the force (3D).
    let (wx, dwx) = (st.w[0], st.dw[0]);
    let (wy, dwy) = (st.w[1], st.dw[1]);
    let mass_x = wx * m;
    let mom_x: [Row4; D] = core::array::from_fn(|a| wx * (m * v[a]));
    // Force on a node: f_a = -m sum_b tau_ab G_b; force_x[a][b] = -m tau_ab times dwx (b = 0)
    // or wx (b >= 1).
    let force_x: [[Row4; D]; D] = core::array::from_fn(|a| {
        core::array::from_fn(|b| (if b == 0 { dwx } else { wx }) * (-m * tau[a][b]))
    });
    for j in 0..K {
        // Per y node j: mass and momentum times wy_j; the force's terms that carry wz_k
        // (f_wz: the x and y gradients) and dwz_k (f_dwz: the z gradient, 3D only).
        let mass_j = mass_x * wy[j];
        let mom_j: [Row4; D] = core::array::from_fn(|a| mom_x[a] * wy[j]);
        let f_wz: [Row4; D] =
            core::array::from_fn(|a| force_x[a][0] * wy[j] + force_x[a][1] * dwy[j]);
        let f_dwz: [Row4; D] = core::array::from_fn(|a| {
            if D == 3 {
                force_x[a][D - 1] * wy[j]
            } else {
                Row4::ZERO
            }
        });
        for k in 0..Stencil::<D, K>::layers() {
            let row = st.row_start(j, k, geom.stride);
            // The z factors (1 and 0 in 2D, where the products are skipped).
            let (wz, dwz) = if D == 3 {
                (st.w[D - 1][k], st.dw[D - 1][k])
            } else {
                (1.0, 0.0)
            };
            let z = |x: Row4| if D == 3 { x * wz } else { x };
            // SAFETY (every add_row here): rows_fit checked above for this stencil, and all
            // columns share the length it was checked against.
            if MODE == mode::ALL || MODE == mode::MASS_MOMENTUM {
                unsafe { add_row(g.mass, row, z(mass_j)) };
                for a in 0..D {
                    unsafe { add_row(g.vel[a], row, z(mom_j[a])) };
                }
            }
            if MODE == mode::REMAP {
                for a in 0..D {
                    unsafe { add_row(g.remap[a], row, z(mom_j[a])) };
                }
            }
            if MODE == mode::ALL || MODE == mode::FORCE {
                for a in 0..D {
                    let f = if D == 3 {
                        f_wz[a] * wz + f_dwz[a] * dwz
                    } else {
                        f_wz[a]
                    };
                    unsafe { add_row(g.acc[a], row, f) };
                }
            }
        }
    }
}
