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
//! These passes are plain loops over each chunk's particles (their stencils are the chunk's,
//! computed as in the other passes), one stencil row at a time: along a row
//! (x) the sums weigh the nodes' values by the x factors, and the row's sums are then weighted
//! by the row's factors (`S = wx r_0`, `G = (dwx r_0, wx r_1, ..)`, as in the SIMD passes), so
//! a node costs a few products whatever the dimension. The force and the gradient take their
//! weights from one function ([`Weighted`]), so both see the same numbers.

use super::{Ctx, Kernels};
use crate::grid::GridCols;
use crate::math::Mat;
use crate::particles::ParticleCols;
use crate::shape::{first_node, Shape1D, Stencil, Stencils};
use crate::simd::lanes::{live_lanes, load_into, Block, Lane, Lanes};
use crate::Real;

/// The smallest `det A_p` with which a particle takes the mass-weighted gradient: below it
/// (its stencil's mass lies mostly on one side of it) it takes the shape functions' `G_ip`.
/// Where the mass is uniform `A_p = I`. Over a spinning disk's half turn (the accuracy
/// report's, 8 cells per radius) the smallest `det A_p` was 0.15 with uGIMP and cpGIMP, 0.52
/// and 0.58 with the B-splines: none of them falls back. With linear shapes it reaches 1e-5
/// (a particle by a node at the surface, the node's mass its own sliver), where it falls
/// back.
pub(crate) const MIN_DET: Real = 0.1;

/// One particle's stencil and what its gradient weights `B_ip` are made of, from the nodal
/// masses it reads.
pub(crate) struct Weighted<const D: usize, const K: usize> {
    st: Stencil<D, K>,
    /// `x_i - x_p` of the stencil's `k`-th node along each axis, m.
    dx: [[Real; K]; D],
    /// `m_gp = sum_i S_ip m_i`, kg.
    m_gp: Real,
    /// `g_p = sum_i G_ip m_i / m_gp`, 1/m.
    g: [Real; D],
    /// `A_p^-T`, when the particle takes the mass-weighted gradient.
    inv_at: Option<Mat<D>>,
}

/// One stencil row: the flat index of its first node, its factors `r` (`S = wx_i r_0`, `G_0 =
/// dwx_i r_0`, `G_b = wx_i r_b`) and `x_i - x_p` along the axes past the first (the same
/// along the row; entry 0 unused).
struct Row<const D: usize> {
    start: usize,
    r: [Real; D],
    dx: [Real; D],
}

impl<const D: usize, const K: usize> Weighted<D, K> {
    /// The stencil `st` of a particle at `x` (m), with the masses `mass` of the grid.
    pub fn new<S: Shape1D<K>>(
        ctx: &Ctx<'_, D>,
        st: Stencil<D, K>,
        x: [Real; D],
        mass: &[Real],
    ) -> Self {
        let geom = &ctx.geom;
        let dx: [[Real; K]; D] = core::array::from_fn(|a| {
            let s = (x[a] - geom.origin[a]) * geom.inv_h;
            let first = first_node::<K, S>(s, geom.nodes[a]) as Real;
            core::array::from_fn(|k| (first + k as Real - s) * geom.h)
        });
        let mut w = Weighted {
            st,
            dx,
            m_gp: 0.0,
            g: [0.0; D],
            inv_at: None,
        };
        // m_gp, sum G m, sum S m (x - x_p) and sum (x - x_p) (x) G m, row by row.
        let (mut m_gp, mut sum_g, mut centroid) = (0.0, [0.0; D], [0.0; D]);
        let mut moment = [[0.0; D]; D];
        let (wx, dwx, dx0) = (w.st.w[0], w.st.dw[0], w.dx[0]);
        w.for_each_row(ctx, |row| {
            let (mut m0, mut m1, mut m2, mut m3) = (0.0, 0.0, 0.0, 0.0);
            for i in 0..K {
                let m = read(mass, row.start + i);
                m0 += m * wx[i];
                m1 += m * dwx[i];
                m2 += m * wx[i] * dx0[i];
                m3 += m * dwx[i] * dx0[i];
            }
            let r = row.r;
            m_gp += m0 * r[0];
            sum_g[0] += m1 * r[0];
            centroid[0] += m2 * r[0];
            moment[0][0] += m3 * r[0];
            for b in 1..D {
                sum_g[b] += m0 * r[b];
                centroid[b] += m0 * r[0] * row.dx[b];
                moment[0][b] += m2 * r[b];
                moment[b][0] += row.dx[b] * m1 * r[0];
                for c in 1..D {
                    moment[b][c] += row.dx[b] * m0 * r[c];
                }
            }
        });
        w.m_gp = m_gp;
        if !w.carried() {
            return w;
        }
        let inv_m = 1.0 / m_gp;
        w.g = core::array::from_fn(|a| sum_g[a] * inv_m);
        let a: Mat<D> = core::array::from_fn(|r| {
            core::array::from_fn(|c| (moment[r][c] - centroid[r] * w.g[c]) * inv_m)
        });
        // NaN-safe: a NaN determinant is not above the bound.
        if crate::math::det(&a) > MIN_DET {
            w.inv_at = Some(crate::math::inverse_transpose(&a));
        }
        w
    }

    /// Whether the grid has mass at the particle (`m_gp > 0`; not for a NaN). A particle the
    /// grid does not carry contributes nothing and reads nothing.
    pub fn carried(&self) -> bool {
        self.m_gp > 0.0
    }

    /// Calls `f` for every row of the stencil.
    fn for_each_row(&self, ctx: &Ctx<'_, D>, mut f: impl FnMut(Row<D>)) {
        for k in 0..Stencil::<D, K>::layers() {
            for j in 0..K {
                let (start, r) = self.st.row(j, k, ctx.geom.stride);
                let dx = core::array::from_fn(|a| match a {
                    0 => 0.0,
                    1 => self.dx[1][j],
                    _ => self.dx[a][k],
                });
                f(Row { start, r, dx });
            }
        }
    }

    /// The gradient `sum_i u_i (x) B_ip` of the nodal field `u` (`u(a, node)` its component
    /// `a`), and the mass-weighted mean `sum_i S_ip m_i u_i / m_gp`.
    fn gradient(
        &self,
        ctx: &Ctx<'_, D>,
        mass: &[Real],
        u: impl Fn(usize, usize) -> Real,
    ) -> (Mat<D>, [Real; D]) {
        let weighted = self.inv_at.is_some();
        let (wx, dwx) = (self.st.w[0], self.st.dw[0]);
        // sum w_i u_i (x) G_i and sum S_i w_i u_i, w_i = m_i (mass-weighted) or 1.
        let (mut sg, mut ss, mut mean) = ([[0.0; D]; D], [0.0; D], [0.0; D]);
        self.for_each_row(ctx, |row| {
            for a in 0..D {
                let (mut p0, mut p1, mut q0) = (0.0, 0.0, 0.0);
                for i in 0..K {
                    let node = row.start + i;
                    let (m, value) = (read(mass, node), u(a, node));
                    let w = if weighted { m * value } else { value };
                    p0 += w * wx[i];
                    p1 += w * dwx[i];
                    q0 += m * value * wx[i];
                }
                sg[a][0] += p1 * row.r[0];
                for b in 1..D {
                    sg[a][b] += p0 * row.r[b];
                }
                ss[a] += p0 * row.r[0];
                mean[a] += q0 * row.r[0];
            }
        });
        let inv_m = 1.0 / self.m_gp;
        let mean = mean.map(|v| v * inv_m);
        let Some(inv_at) = &self.inv_at else {
            return (sg, mean);
        };
        // L = (sum m u (x) G - (sum S m u) (x) g) / m_gp, times A^-1 on the right.
        let raw: Mat<D> = core::array::from_fn(|a| {
            core::array::from_fn(|b| (sg[a][b] - ss[a] * self.g[b]) * inv_m)
        });
        let l = core::array::from_fn(|a| {
            core::array::from_fn(|c| (0..D).map(|b| raw[a][b] * inv_at[c][b]).sum())
        });
        (l, mean)
    }

    /// Adds the particle's forces to the nodes' force columns `acc`: the internal force `-B_ip
    /// . tau` for `tau` its Kirchhoff stress times its mass over rho0 (E75), and `S_ip F_p`.
    fn scatter_force(
        &self,
        ctx: &Ctx<'_, D>,
        mass: &[Real],
        tau: &Mat<D>,
        force: [Real; D],
        acc: &mut [&mut [Real]; D],
    ) {
        // f_i = -m_i (Q (G_i - S_i g)) with Q = tau A^-1 / m_gp (mass-weighted), or -tau G_i:
        // along a row, -(m_i or 1) (dwx_i c1 + wx_i c2) + wx_i r_0 F.
        let q: Mat<D> = match &self.inv_at {
            Some(inv_at) => core::array::from_fn(|a| {
                core::array::from_fn(|c| {
                    (0..D).map(|b| tau[a][b] * inv_at[b][c]).sum::<Real>() / self.m_gp
                })
            }),
            None => *tau,
        };
        let qg: [Real; D] = match self.inv_at {
            Some(_) => core::array::from_fn(|a| (0..D).map(|c| q[a][c] * self.g[c]).sum()),
            None => [0.0; D],
        };
        let weighted = self.inv_at.is_some();
        let (wx, dwx) = (self.st.w[0], self.st.dw[0]);
        self.for_each_row(ctx, |row| {
            let r = row.r;
            let c1: [Real; D] = core::array::from_fn(|a| q[a][0] * r[0]);
            let c2: [Real; D] = core::array::from_fn(|a| {
                (1..D).map(|c| q[a][c] * r[c]).sum::<Real>() - r[0] * qg[a]
            });
            for i in 0..K {
                let node = row.start + i;
                let m = if weighted { read(mass, node) } else { 1.0 };
                for a in 0..D {
                    if let Some(f) = acc[a].get_mut(node) {
                        *f += wx[i] * r[0] * force[a] - m * (dwx[i] * c1[a] + wx[i] * c2[a]);
                    }
                }
            }
        });
    }
}

/// The value of a column at `node`; 0 past its end (never, for a stencil the grid holds).
fn read(col: &[Real], node: usize) -> Real {
    col.get(node).copied().unwrap_or(0.0)
}

/// The internal force of every active particle with its gradient weights, `f_i -= m_p
/// (tau_p / rho0) B_ip` (E75), and its particle force `S_ip F_p` when declared (E14), into
/// the force columns; run after the nodal masses are complete (folded at the walls, see
/// [`mirror_masses`]).
pub(crate) fn forces<I: Kernels, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    let pairs = crate::layout::sym_pairs(D);
    let mut st = Stencils::<D, K, W>::default();
    let mut x = Block([[0.0; W]; D]);
    for start in (0..count).step_by(W) {
        let live: Lanes<W> = live_lanes(p, start, count);
        for a in 0..D {
            load_into(&mut x[a], p.x[a], start);
        }
        I::stencils::<D, K, S, W>(&mut st, shape, ctx, p, start, &x, false, false, false);
        for ln in live.iter() {
            let i = start + ln;
            let xp: [Real; D] = core::array::from_fn(|a| x[a][ln]);
            let w = Weighted::<D, K>::new::<S>(ctx, st.of_lane(ln), xp, g.mass);
            if !w.carried() {
                continue;
            }
            let mut tau = [[0.0; D]; D];
            for (k, &(r, c)) in pairs.iter().enumerate() {
                let t = read(p.tau[k], i) * read(p.mass, i);
                (tau[r][c], tau[c][r]) = (t, t);
            }
            let force: [Real; D] =
                core::array::from_fn(|a| if ctx.forces { read(p.force[a], i) } else { 0.0 });
            w.scatter_force(ctx, g.mass, &tau, force, &mut g.acc);
        }
    }
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

/// For the live lanes of a chunk at positions `x`: the velocity gradient `sum_i u_i (x) B_ip`
/// of the velocity `which` says into `l` (nothing for [`Differentiate::Nothing`]) and, when
/// `moving` is given, the mass-weighted grid velocity and acceleration the particle moves with,
/// `sum_i S_ip m_i v_i / m_gp` and `sum_i S_ip m_i a_i / m_gp` (E76).
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    ctx: &Ctx<'_, D>,
    st: &Stencils<D, K, W>,
    x: &[Lane<W>; D],
    live: Lanes<W>,
    g: &GridCols<'_, D>,
    which: Differentiate,
    l: &mut [[Lane<W>; D]; D],
    mut moving: Option<(&mut [Lane<W>; D], &mut [Lane<W>; D])>,
) {
    for ln in live.iter() {
        let xp: [Real; D] = core::array::from_fn(|a| x[a][ln]);
        let w = Weighted::<D, K>::new::<S>(ctx, st.of_lane(ln), xp, g.mass);
        if !w.carried() {
            continue;
        }
        let field = |col: &[&[Real]; D]| {
            let col = *col;
            w.gradient(ctx, g.mass, move |a, node| read(col[a], node))
        };
        let (vel, acc) = (
            g.vel.each_ref().map(|c| &**c),
            g.acc.each_ref().map(|c| &**c),
        );
        // The velocity's and the acceleration's gradients and means, where read.
        let updated = which == Differentiate::Updated;
        let (lv, la) = if updated || moving.is_some() {
            (field(&vel), field(&acc))
        } else {
            let none = ([[0.0; D]; D], [0.0; D]);
            (none, none)
        };
        let grad = match which {
            Differentiate::Remap => Some(field(&g.remap.each_ref().map(|c| &**c)).0),
            // The gradient of v + a dt, the sum of theirs.
            Differentiate::Updated => Some(core::array::from_fn(|a| {
                core::array::from_fn(|b| lv.0[a][b] + la.0[a][b] * ctx.dt)
            })),
            Differentiate::Nothing => None,
        };
        if let Some(grad) = grad {
            for a in 0..D {
                for c in 0..D {
                    l[a][c][ln] = grad[a][c];
                }
            }
        }
        if let Some((v, a_move)) = moving.as_mut() {
            for a in 0..D {
                v[a][ln] = lv.1[a];
                a_move[a][ln] = la.1[a];
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
