//! The momentum approach (E73-E77, [`crate::Transfer::FlipMomentum`]): the
//! particle reads the grid through its nodes' momenta over the mass the grid has at the
//! particle, `m_gp = sum_i S_ip m_i`, never through a velocity `p_i / m_i` alone, so that a
//! node that carries a sliver of mass (and a velocity as large as its force over that sliver)
//! weighs in with that sliver.
//!
//! The notes' gradient (E73), `grad v = sum_i G_ip (x) p_i / m_gp`, is the derivative of the
//! momentum field, not of the velocity: where the mass varies (every free surface) a
//! translating body strains. The step takes the gradient of the mass-weighted velocity field
//! `v(x) = sum S_i(x) p_i / sum S_i(x) m_i` at the particle (E74), which is E73 where the mass
//! is uniform and is invariant under a translation everywhere, made exact for every affine
//! velocity field (rigid rotations included) by the particle's moment matrix:
//!
//! - `b_ip = (m_i / m_gp) (G_ip - S_ip g_p)`, `g_p = sum_i G_ip m_i / m_gp`, which sums to zero
//!   over the nodes;
//! - `A_p = sum_i (x_i - x_p) (x) b_ip`, the identity where the mass is uniform;
//! - the particle's gradient weights `B_ip = A_p^-T b_ip`, so `grad v = sum_i v_i (x) B_ip`.
//!
//! The internal force is the work conjugate of that gradient, `f_i = -sum_p m_p (tau_p / rho0)
//! B_ip` (E75: E14 with `B_ip` for `G_ip`): the stress power `sum_p V_p sigma_p : grad v_p` is
//! then exactly `-sum_i f_i . v_i` (in continuous time no energy is made or lost between
//! particles and grid), the internal forces sum to zero (`sum_i B_ip = 0`: momentum is
//! conserved) and exert no torque (`sum_i x_i (x) B_ip = I`). A particle whose `A_p` is
//! ill-conditioned (det below [`MIN_DET`]: its stencil's mass lies on one side of it, as for a
//! lone particle on a node with linear shapes) takes `G_ip`, the velocity approach's weights,
//! for both its gradient and its force, so the pair stays conjugate. The particles move with
//! the mass-weighted grid velocity and acceleration (E76); their velocities take the velocity
//! approach's update (E25), which is E77: the notes' momentum update read with the particle's
//! share `m_p S_ip / m_i` of each nodal force, the reading under which the particle momenta
//! sum to the grid's.
//!
//! The price of the conjugate force: `sum_p V_p B_ip` is not the integral of `grad N_i` over
//! the body where the mass varies, so a uniform stress no longer balances a surface load node
//! by node. A plane-strain block pulled by a traction settled to the load's mean stress within
//! 0.1 %, but with particles by its faces up to 28 % off (uGIMP; 0.2 % with the velocity
//! approach), and a column under gravity with the quadratic B-spline 6 layers' weight off
//! (0.3 with the velocity approach). E14's force `G_ip` with this gradient keeps those at rest
//! (measured 0.1 % and 0.2 layers), but is not the gradient's conjugate, and a free block
//! spinning with pure FLIP gained 77 to 110 times its energy in a quarter turn (uGIMP, linear).
//! The approach is for dynamics.
//!
//! The passes run on the lane type, as the other passes do: a chunk's stencils, then, for as
//! many lanes at once as the instance's vectors hold, each stencil row's nodal masses (and
//! velocities) read as one vector per node and summed along x with the x factors, the row's
//! sums weighted by the row's factors (`S = wx r_0`, `G = (dwx r_0, wx r_1, ..)`, as in
//! [`super::gather::gather_chunk`]). What a particle reads the grid with ([`Weights`]: `m_gp`,
//! `g_p`, `A_p^-T`) is formed once per chunk and pass; a particle that falls back takes
//! `g_p = 0`, `A_p^-T = I` and no mass factor, so every lane runs the same arithmetic.
//!
//! The force (E75) is `f_i = -m_i sum_p (q_p G_ip - (q_p g_p) S_ip)` for the particles with
//! the mass-weighted gradient, `q_p = m_p (tau_p / rho0) A_p^-1 / m_gp`: the sum is the
//! scatter's force rows with `q_p` for the stress and `q_p g_p` for the particle force
//! ([`crate::simd::row_sums`]), into the force columns, which then take the nodal mass as a
//! factor; the particles that fall back (`-m_p (tau_p / rho0) G_ip`) and the particle forces
//! are scattered after that.

use super::gather::{read_row, row_factors, sum_x, Gathered, LaneMat};
use super::{Ctx, Kernels};
use crate::grid::GridCols;
use crate::layout::sym_pairs;
use crate::math::{det, inverse_transpose};
use crate::num::{matrix, Num};
use crate::particles::ParticleCols;
use crate::shape::{first_node, row_start, Shape1D, Stencil, Stencils, ROW};
use crate::simd::lanes::{live_lanes, load_into, Block, Lane, Lanes};
use crate::simd::row_sums::{rows, scatter_chunk, Adds, Mode, Products};
use crate::simd::rows::{self, Compare};
use crate::simd::wide::Wide;
use crate::Real;

/// The smallest `det A_p` with which a particle takes the mass-weighted gradient: below it
/// (its stencil's mass lies mostly on one side of it) it takes the shape functions' `G_ip`.
/// Where the mass is uniform `A_p = I`. Over a spinning disk's half turn (the accuracy
/// report's, 8 cells per radius) the smallest `det A_p` was 0.15 with uGIMP and cpGIMP, 0.52
/// and 0.58 with the B-splines: none of them falls back. With linear shapes it reaches 1e-5
/// (a particle by a node at the surface, the node's mass its own sliver), where it falls
/// back.
pub(crate) const MIN_DET: Real = 0.1;

/// What the particles of a chunk read the grid with (E74), lane-fastest: made by
/// [`Weights::of`] from the chunk's stencils and the nodal masses.
pub(crate) struct Weights<const D: usize, const W: usize> {
    /// `x_i - x_p` of the stencil's `k`-th node along each axis, `dx[axis][k][lane]`, m.
    dx: [[Lane<W>; ROW]; D],
    /// `1 / m_gp`, `m_gp = sum_i S_ip m_i` (0 where the grid does not carry the particle).
    inv_m: Lane<W>,
    /// `g_p = sum_i G_ip m_i / m_gp` (0 where the particle falls back).
    g: [Lane<W>; D],
    /// `1 / m_gp` (1 where the particle falls back).
    scale: Lane<W>,
    /// `A_p^-T` (the identity where the particle falls back).
    inv_at: LaneMat<D, W>,
    /// 1 where the particle takes the mass-weighted gradient, else 0.
    weighted: Lane<W>,
    /// The lanes the grid carries (`m_gp > 0`, not for a NaN): a particle it does not carry
    /// contributes nothing and reads nothing.
    carried: Lanes<W>,
    /// The carried lanes that take the mass-weighted gradient (`det A_p > MIN_DET`).
    with_weights: Lanes<W>,
}

impl<const D: usize, const W: usize> Weights<D, W> {
    /// All zero; a pass makes one and fills it per chunk.
    pub fn zero() -> Self {
        Weights {
            dx: [[[0.0; W]; ROW]; D],
            inv_m: [0.0; W],
            g: [[0.0; W]; D],
            scale: [0.0; W],
            inv_at: [[[0.0; W]; D]; D],
            weighted: [0.0; W],
            carried: Lanes::NONE,
            with_weights: Lanes::NONE,
        }
    }

    /// The weights of the particles at `x` with the stencils `st`, from the grid's masses
    /// `mass`: `m_gp`, `g_p` and `A_p = sum_i (x_i - x_p) (x) b_ip` from the sums `sum S m`,
    /// `sum G m`, `sum S m (x - x_p)` and `sum (x - x_p) (x) G m`, row by row.
    #[inline(always)]
    pub fn of<I: Compare, const K: usize, S: Shape1D<K>>(
        &mut self,
        ctx: &Ctx<'_, D>,
        st: &Stencils<D, K, W>,
        x: &[Lane<W>; D],
        mass: &[Real],
    ) {
        let geom = &ctx.geom;
        for a in 0..D {
            for ln in 0..W {
                let s = (x[a][ln] - geom.origin[a]) * geom.inv_h;
                let first = first_node::<K, S>(s, geom.nodes[a]) as Real;
                for k in 0..K {
                    self.dx[a][k][ln] = (first + k as Real - s) * geom.h;
                }
            }
        }
        let (stride, base) = (geom.stride, st.bases());
        (self.carried, self.with_weights) = (Lanes::NONE, Lanes::NONE);
        if !rows::fit(base, Stencil::<D, K>::last_row_offset(stride), mass.len()) {
            return; // Unreachable (first_node clamps); keeps the unchecked row reads sound.
        }
        let shared = rows::blocks_share(base);
        let (zero, one) = (Wide::<I>::splat(0.0), Wide::<I>::splat(1.0));
        for at in (0..W).step_by(I::N) {
            let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
            // The x factors: S, G_x, S (x - x_p), G_x (x - x_p) over r_0.
            let (mut wx, mut dwx, mut wd, mut dwd) = ([zero; K], [zero; K], [zero; K], [zero; K]);
            for i in 0..K {
                let d = ld(&self.dx[0][i]);
                (wx[i], dwx[i]) = (ld(&st.weights(0)[i]), ld(&st.derivatives(0)[i]));
                (wd[i], dwd[i]) = (wx[i] * d, dwx[i] * d);
            }
            let (mut m_gp, mut sum_g, mut centroid) = (zero, [zero; D], [zero; D]);
            let mut moment = [[zero; D]; D];
            for k in 0..Stencil::<D, K>::layers() {
                for j in 0..K {
                    let r = row_factors::<I, D, K, W>(st, j, k, at, false);
                    // x_i - x_p along the axes past the first (the same along the row).
                    let mut dx = [zero; D];
                    dx[1] = ld(&self.dx[1][j]);
                    if D == 3 {
                        dx[D - 1] = ld(&self.dx[D - 1][k]);
                    }
                    let off = row_start(0, j, k, stride);
                    // SAFETY: `fit` checked every lane's rows above.
                    let n = unsafe { read_row::<I, W>(mass, base, at, off, shared) };
                    let (m0, m1) = (sum_x::<I, K>(&wx, &n), sum_x::<I, K>(&dwx, &n));
                    let (m2, m3) = (sum_x::<I, K>(&wd, &n), sum_x::<I, K>(&dwd, &n));
                    m_gp += m0 * r[0];
                    sum_g[0] += m1 * r[0];
                    centroid[0] += m2 * r[0];
                    moment[0][0] += m3 * r[0];
                    for b in 1..D {
                        sum_g[b] += m0 * r[b];
                        centroid[b] += m0 * r[0] * dx[b];
                        moment[0][b] += m2 * r[b];
                        moment[b][0] += dx[b] * m1 * r[0];
                        for c in 1..D {
                            moment[b][c] += dx[b] * m0 * r[c];
                        }
                    }
                }
            }
            // NaN-safe: a NaN mass is not above zero, a NaN determinant not above the bound.
            let carried = m_gp.gt(zero);
            let inv_m = carried.select(one / m_gp, zero);
            let g: [Wide<I>; D] = core::array::from_fn(|a| sum_g[a] * inv_m);
            let a_p = matrix::<Wide<I>, D>(|r, c| (moment[r][c] - centroid[r] * g[c]) * inv_m);
            let weighted = det(&a_p).gt(Wide::splat(MIN_DET)) & carried;
            let inv_at = inverse_transpose(&a_p);
            inv_m.store(&mut self.inv_m, at);
            weighted.select(inv_m, one).store(&mut self.scale, at);
            weighted.select(one, zero).store(&mut self.weighted, at);
            for r in 0..D {
                weighted.select(g[r], zero).store(&mut self.g[r], at);
                for c in 0..D {
                    let id = if r == c { one } else { zero };
                    weighted
                        .select(inv_at[r][c], id)
                        .store(&mut self.inv_at[r][c], at);
                }
            }
            self.carried = self.carried | carried.lanes(at);
            self.with_weights = self.with_weights | weighted.lanes(at);
        }
    }
}

/// The internal force of every active particle with its gradient weights, `f_i -= m_p
/// (tau_p / rho0) B_ip` (E75), and its particle force `S_ip F_p` when declared (E14), into
/// the force columns (zero until now: the scatter before it adds no force); run after the
/// nodal masses are complete (folded at the walls, see [`mirror_masses`]). Two scatters (see
/// the module docs): the weighted particles' sums, which the nodal masses then multiply, and
/// the particles that fall back with the particle forces. The force scatter of the momentum
/// approach ([`super::p2g::scatter_rows`] in [`Mode::Force`] calls it).
#[inline(always)]
pub(crate) fn forces<I: Kernels, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    let mut st = Stencils::<D, K, W>::default();
    let mut w = Weights::zero();
    let mut x = Block([[0.0; W]; D]);
    let (mut mass, mut tau) = (Block([0.0; W]), Block([[0.0; W]; 6]));
    let mut products = Products::zero();
    const FORCE: u8 = rows(Mode::Force, false);
    let stride = ctx.geom.stride;
    // The second scatter runs where a particle falls back or particle forces are declared.
    let mut rest = ctx.forces;
    for second in [false, true] {
        if second && !rest {
            return;
        }
        // The first scatter adds, for the weighted particles, the rows' stress -q and
        // particle force q g_p, q = m_p (tau_p / rho0) A_p^-1 / m_gp; the second the others'
        // -m_p tau_p / rho0 and every particle's force.
        let adds = Adds {
            mode: Mode::Force,
            forces: !second || ctx.forces,
            apic: false,
        };
        // A tile of the parallel scatter takes the chunks that reach its slab (as `p2g`'s).
        for start in g.chunks(count, W, stride[D - 1]) {
            let live = live_lanes(p, start, count);
            load_chunk(p, start, &mut x, &mut mass, &mut tau);
            let stretch = p.stretch_columns();
            I::stencils::<D, K, S, W>(
                &mut st, shape, ctx, &stretch, start, &x, false, false, false,
            );
            w.of::<I, K, S>(ctx, &st, &x, g.all_masses());
            let (carried, weighted) = (live & w.carried, live & w.with_weights);
            rest |= !carried.minus(weighted).is_empty();
            let lanes = match (second, ctx.forces) {
                (false, _) => weighted,
                (true, true) => carried,
                (true, false) => carried.minus(weighted),
            };
            if lanes.is_empty() {
                continue;
            }
            if second && ctx.forces {
                for a in 0..D {
                    load_into(&mut products.f[a], p.force[a], start);
                }
            }
            for at in (0..W).step_by(I::N) {
                let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
                let t = stress::<I, D, W>(&mass, &tau, at);
                if second {
                    // No stress for a weighted particle: the first scatter added its own.
                    let keep = ld(&w.weighted).gt(Wide::splat(0.0));
                    for a in 0..D {
                        for c in 0..D {
                            let mt = keep.select(Wide::splat(0.0), -t[a][c]);
                            mt.store(&mut products.mt[a][c], at);
                        }
                    }
                    continue;
                }
                let (scale, g_p) = (ld(&w.scale), w.g.each_ref().map(ld));
                let inv_at = w.inv_at.each_ref().map(|r| r.each_ref().map(ld));
                let q = matrix::<Wide<I>, D>(|a, c| {
                    let mut s = t[a][0] * inv_at[0][c];
                    for b in 1..D {
                        s += t[a][b] * inv_at[b][c];
                    }
                    s * scale
                });
                for a in 0..D {
                    let mut qg = q[a][0] * g_p[0];
                    for c in 1..D {
                        qg += q[a][c] * g_p[c];
                    }
                    qg.store(&mut products.f[a], at);
                    for c in 0..D {
                        (-q[a][c]).store(&mut products.mt[a][c], at);
                    }
                }
            }
            scatter_chunk::<I, D, K, S, W, FORCE>(&mut st, &products, lanes, stride, g, adds);
        }
        if !second {
            // f_i = m_i sum_p (..): the nodal mass, a factor of every weighted particle's term,
            // on the nodes this view adds to (a tile's own; the whole grid's).
            let first = g.tile.first;
            let own = first..first.saturating_add(g.tile.nodes).min(first + g.len());
            let m = if g.mass.is_empty() { g.whole } else { &*g.mass };
            let acc = &mut g.acc;
            ctx.active.for_each_line_in(stride, own, |r| {
                let nodes = r.start + first..r.end + first;
                for col in acc.iter_mut() {
                    if let (Some(f), Some(m)) = (col.get_mut(r.clone()), m.get(nodes.clone())) {
                        for (f, &m) in f.iter_mut().zip(m) {
                            *f *= m;
                        }
                    }
                }
            });
        }
    }
}

/// A chunk's positions, masses and stresses `tau / rho0` (the components of [`sym_pairs`]).
#[inline(always)]
fn load_chunk<const D: usize, const W: usize>(
    p: &ParticleCols<'_, D>,
    start: usize,
    x: &mut [Lane<W>; D],
    mass: &mut Lane<W>,
    tau: &mut [Lane<W>; 6],
) {
    for a in 0..D {
        load_into(&mut x[a], p.x[a], start);
    }
    load_into(mass, p.mass, start);
    for (k, t) in tau.iter_mut().enumerate().take(sym_pairs(D).len()) {
        load_into(t, p.tau[k], start);
    }
}

/// `m_p tau_p / rho0` of lanes `at..at + N`, as a symmetric matrix.
#[inline(always)]
fn stress<I: Compare, const D: usize, const W: usize>(
    mass: &Lane<W>,
    tau: &[Lane<W>; 6],
    at: usize,
) -> [[Wide<I>; D]; D] {
    let m = Wide::<I>::load(mass, at);
    let mut t = [[Wide::splat(0.0); D]; D];
    for (k, &(r, c)) in sym_pairs(D).iter().enumerate() {
        let v = Wide::<I>::load(&tau[k], at) * m;
        (t[r][c], t[c][r]) = (v, v);
    }
    t
}

/// Which nodal velocity [`gather`] differentiates.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Differentiate {
    /// None: the particle pass of USF and MUSL (their stress passes take the gradient).
    Nothing,
    /// `v_i + a_i dt` (USL).
    Updated,
    /// The wall-constrained stress-update velocity (USF, MUSL).
    Remap,
}

/// The momentum approach's gather for a chunk with weights `w`, in place of
/// [`super::gather::gather_chunk`]: the velocity gradient `sum_i u_i (x) B_ip` of the velocity
/// `which` says into `out.l` (nothing for [`Differentiate::Nothing`]) and, when `moving` is
/// given, `v_gp = sum_i S_ip v_i` and `a_gp = sum_i S_ip a_i` into `out` (the velocity
/// update's, E21) and the mass-weighted grid velocity and acceleration the particle moves
/// with, `sum_i S_ip m_i v_i / m_gp` and `sum_i S_ip m_i a_i / m_gp` (E76; zero where the grid
/// does not carry the particle), into `moving`.
///
/// The gradient is `(sum w_i u_i (x) G_ip - (sum S_ip w_i u_i) (x) g_p) A_p^-1 / m_gp`, with
/// `w_i = m_i`; for a particle that falls back (or that the grid does not carry) `w_i = 1`,
/// `g_p = 0`, `A_p = I` and no `1 / m_gp` ([`Weights`]), which leaves `sum_i u_i (x) G_ip`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn gather<I: Compare, const D: usize, const K: usize, const W: usize>(
    ctx: &Ctx<'_, D>,
    st: &Stencils<D, K, W>,
    w: &Weights<D, W>,
    g: &GridCols<'_, D>,
    which: Differentiate,
    out: &mut Gathered<D, W>,
    mut moving: Option<(&mut [Lane<W>; D], &mut [Lane<W>; D])>,
) {
    let (stride, base) = (ctx.geom.stride, st.bases());
    let gradient = which != Differentiate::Nothing;
    let read_va = which == Differentiate::Updated || moving.is_some();
    let remap_ok = which != Differentiate::Remap || g.remap.iter().all(|c| c.len() == g.len());
    if !g.lengths_consistent()
        || !remap_ok
        || !rows::fit(base, Stencil::<D, K>::last_row_offset(stride), g.len())
    {
        return; // Unreachable by construction; keeps the unchecked row reads sound.
    }
    let shared = rows::blocks_share(base);
    // SAFETY (every unsafe block below): `fit` checked every lane's rows above, and every
    // column read has g.len() entries.
    let (zero, dt) = (Wide::<I>::splat(0.0), Wide::<I>::splat(ctx.dt));
    for at in (0..W).step_by(I::N) {
        let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
        let weighted = ld(&w.weighted).gt(zero);
        let (mut wx, mut dwx) = ([zero; K], [zero; K]);
        for i in 0..K {
            (wx[i], dwx[i]) = (ld(&st.weights(0)[i]), ld(&st.derivatives(0)[i]));
        }
        // sum w_i u_i (x) G_i, sum S_i w_i u_i, and the mass-weighted sums of v and a.
        let (mut sg, mut ss) = ([[zero; D]; D], [zero; D]);
        let (mut sv, mut sa) = ([zero; D], [zero; D]);
        let (mut v_gp, mut a_gp) = ([zero; D], [zero; D]);
        for k in 0..Stencil::<D, K>::layers() {
            for j in 0..K {
                let r = row_factors::<I, D, K, W>(st, j, k, at, false);
                let off = row_start(0, j, k, stride);
                let nm = unsafe { read_row::<I, W>(g.mass, base, at, off, shared) };
                for a in 0..D {
                    let (mut nv, mut na, mut nu) = ([zero; ROW], [zero; ROW], [zero; ROW]);
                    if read_va {
                        unsafe {
                            nv = read_row::<I, W>(g.vel[a], base, at, off, shared);
                            na = read_row::<I, W>(g.acc[a], base, at, off, shared);
                        }
                    }
                    match which {
                        Differentiate::Remap => {
                            nu = unsafe { read_row::<I, W>(g.remap[a], base, at, off, shared) };
                        }
                        Differentiate::Updated => {
                            for i in 0..K {
                                nu[i] = nv[i] + na[i] * dt;
                            }
                        }
                        Differentiate::Nothing => {}
                    }
                    if moving.is_some() {
                        let (mut mv, mut ma) = ([zero; ROW], [zero; ROW]);
                        for i in 0..K {
                            (mv[i], ma[i]) = (nm[i] * nv[i], nm[i] * na[i]);
                        }
                        sv[a] += r[0] * sum_x::<I, K>(&wx, &mv);
                        sa[a] += r[0] * sum_x::<I, K>(&wx, &ma);
                        v_gp[a] += r[0] * sum_x::<I, K>(&wx, &nv);
                        a_gp[a] += r[0] * sum_x::<I, K>(&wx, &na);
                    }
                    if gradient {
                        let mut wu = [zero; ROW];
                        for i in 0..K {
                            wu[i] = weighted.select(nm[i] * nu[i], nu[i]);
                        }
                        let (p0, p1) = (sum_x::<I, K>(&wx, &wu), sum_x::<I, K>(&dwx, &wu));
                        sg[a][0] += p1 * r[0];
                        for b in 1..D {
                            sg[a][b] += p0 * r[b];
                        }
                        ss[a] += p0 * r[0];
                    }
                }
            }
        }
        if gradient {
            let (scale, g_p) = (ld(&w.scale), w.g.each_ref().map(ld));
            let inv_at = w.inv_at.each_ref().map(|r| r.each_ref().map(ld));
            for a in 0..D {
                let raw: [Wide<I>; D] =
                    core::array::from_fn(|b| (sg[a][b] - ss[a] * g_p[b]) * scale);
                for c in 0..D {
                    let mut v = raw[0] * inv_at[c][0];
                    for b in 1..D {
                        v += raw[b] * inv_at[c][b];
                    }
                    v.store(&mut out.l[a][c], at);
                }
            }
        }
        if let Some((v, a_move)) = moving.as_mut() {
            let inv_m = ld(&w.inv_m);
            for a in 0..D {
                (sv[a] * inv_m).store(&mut v[a], at);
                (sa[a] * inv_m).store(&mut a_move[a], at);
                v_gp[a].store(&mut out.v_gp[a], at);
                a_gp[a].store(&mut out.a_gp[a], at);
            }
        }
    }
}

/// Each node past a wall plane takes its image's mass ([`crate::grid::Geom::for_each_wall_image`]):
/// the material's mirror image, whose velocities those nodes already read, weighs them as the
/// material weighs its image. After the grid update has folded the masses; nothing later reads
/// a mass there but these passes.
pub(crate) fn mirror_masses<const D: usize>(ctx: &Ctx<'_, D>, g: &mut GridCols<'_, D>) {
    let mass = &mut *g.mass;
    ctx.geom
        .for_each_wall_image(&ctx.active, true, &mut |ghost, image, _| {
            if let (Some(&m), true) = (mass.get(image), ghost < mass.len()) {
                mass[ghost] = m;
            }
        });
}
