//! Particle to grid (seeds/000 eqs 22, 23, 25): nodal mass `m_i = sum S_ip m_p`, momentum
//! `p_i = sum S_ip m_p v_p` and internal force `f_i = -sum m_p (tau_p/rho0) . G_ip`. Gravity
//! and the body force enter in the grid update as `m_i b` (eq 22).
//!
//! Declared effects add, in the same pass: the particle force `S_ip F_p` (eq 20) and the APIC
//! affine momentum `S_ip m_p C_p (x_i - x_p)` (seeds/001). Tractions (eq 21) are a pass of
//! their own over the traction table ([`tractions`]).

use super::g2p::stencils;
use super::lanes::{load, Lane, W};
use super::{sym_pairs, Ctx};
use crate::grid::{add_row, rows_fit, GridCols};
use crate::math::Mat;
use crate::particles::{ParticleCols, ACTIVE};
use crate::shape::{LaneStencil, Row4, Shape1D, Stencil, Stencils};
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

/// Scatters the active particles `0..count` to the grid, accumulating what `MODE` says, plus
/// the particle forces (`FORCE`, with the force) and the affine momentum (`APIC`, with the
/// momentum).
#[inline(always)]
pub(crate) fn scatter<
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const MODE: u8,
    const FORCE: bool,
    const APIC: bool,
>(
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
    let with_momentum = MODE != mode::FORCE;
    let mut st = Stencils::<D, K, W>::default();
    let mut run = RunSums::new();
    for start in (0..count).step_by(W) {
        // The chunk's particle values as lane vectors (one load per column, no per-particle
        // bounds checks).
        let x: [Lane; D] = core::array::from_fn(|a| load(p.x[a], start));
        let mass = load(p.mass, start);
        let v: [Lane; D] = core::array::from_fn(|a| load(p.v[a], start));
        let mut tau = [[0.0; W]; 6];
        if with_force {
            // Axisymmetric, the fourth 2D component (zz) is the hoop stress.
            let n = sym_pairs(D).len() + (S::AXISYMMETRIC as usize);
            for k in 0..n {
                tau[k] = load(p.tau[k], start);
            }
        }
        let f_ext: [Lane; D] = core::array::from_fn(|a| {
            if FORCE && with_force {
                load(p.force[a], start)
            } else {
                [0.0; W]
            }
        });
        // Loops rather than `core::array::from_fn`, whose closures were left out of line.
        let mut affine = [[[0.0; W]; D]; D];
        if APIC && with_momentum {
            for (a, row) in affine.iter_mut().enumerate() {
                for (b, lanes) in row.iter_mut().enumerate() {
                    *lanes = load(p.affine[a][b], start);
                }
            }
        }
        stencils::<D, K, S, APIC>(&mut st, shape, ctx, p, start, &x);
        let live = super::g2p::live_lanes(p, start, count);
        for ln in 0..W {
            if !live.has(ln) {
                continue;
            }
            let mut t = [[0.0; D]; D];
            if with_force {
                for (k, &(a, b)) in sym_pairs(D).iter().enumerate() {
                    t[a][b] = tau[k][ln];
                    t[b][a] = tau[k][ln];
                }
            }
            let stn = st.lane(ln);
            let pt = Scattered {
                m: mass[ln],
                v: core::array::from_fn(|a| v[a][ln]),
                tau: t,
                hoop: tau[3][ln],
                force: core::array::from_fn(|a| f_ext[a][ln]),
                affine: core::array::from_fn(|a| {
                    core::array::from_fn(|b| {
                        affine_velocity::<K, S>(affine[a][b][ln], stn.inv_d(b))
                    })
                }),
            };
            run.scatter::<D, K, S, MODE, FORCE, APIC>(ctx, &pt, stn, g);
        }
    }
    run.flush::<D, K, MODE>(g, ctx.geom.stride);
}

/// The grid columns a scatter adds to, numbered for [`RunSums`]: the mass, then the momentum,
/// force and remap columns of each axis (room for three axes each).
pub(crate) mod slot {
    pub const MASS: usize = 0;
    pub const MOMENTUM: usize = 1;
    pub const FORCE: usize = 4;
    pub const REMAP: usize = 7;
    /// Number of slots.
    pub const COUNT: usize = 10;
}

/// Grid column `c` (a [`slot`]).
#[inline(always)]
fn column<'g, const D: usize>(g: &'g mut GridCols<'_, D>, c: usize) -> &'g mut [Real] {
    if c == slot::MASS {
        g.mass
    } else if c < slot::FORCE {
        g.vel[c - slot::MOMENTUM]
    } else if c < slot::REMAP {
        g.acc[c - slot::FORCE]
    } else {
        g.remap[c - slot::REMAP]
    }
}

/// Whether a scatter in `MODE` adds to slot `c` of a `D`-dimensional grid.
#[inline(always)]
fn slot_used<const D: usize>(mode: u8, c: usize) -> bool {
    let axis_ok = |first: usize| c >= first && c < first + D;
    let mass = mode == mode::ALL || mode == mode::MASS_MOMENTUM;
    (mass && (c == slot::MASS || axis_ok(slot::MOMENTUM)))
        || ((mode == mode::ALL || mode == mode::FORCE) && axis_ok(slot::FORCE))
        || (mode == mode::REMAP && axis_ok(slot::REMAP))
}

/// Largest number of stencil rows (cubic B-spline in 3D: 4 x 4).
const MAX_ROWS: usize = 16;

/// The row values of a run of consecutive particles that share a stencil base, summed before
/// they are added to the grid: one load, add and store per row and column for the whole run
/// instead of one per particle. Particles seeded in a lattice come in such runs (see
/// [`crate::World::fill_box`]). The sum is formed in the particles' order, then added to the
/// node, so the result does not depend on the instruction set.
pub(crate) struct RunSums {
    sums: [[Row4; slot::COUNT]; MAX_ROWS],
    /// The run's stencil base, [`RunSums::NONE`] when empty.
    pub base: usize,
}

impl RunSums {
    /// The base of an empty run.
    pub const NONE: usize = usize::MAX;

    /// Adds `v` to slot `c` (a [`slot`]) of stencil row `r` (`j + K k`).
    #[inline(always)]
    fn add(&mut self, r: usize, c: usize, v: Row4) {
        self.sums[r][c] += v;
    }

    #[inline(always)]
    pub fn new() -> Self {
        RunSums {
            sums: [[Row4::ZERO; slot::COUNT]; MAX_ROWS],
            base: Self::NONE,
        }
    }

    /// Scatters one particle: adds its rows to the run when it shares the run's stencil base,
    /// else flushes the run and starts a new one with it.
    #[inline(always)]
    pub fn scatter<
        const D: usize,
        const K: usize,
        S: Shape1D<K>,
        const MODE: u8,
        const FORCE: bool,
        const APIC: bool,
    >(
        &mut self,
        ctx: &Ctx<'_, D>,
        pt: &Scattered<D>,
        st: LaneStencil<'_, D, K, W>,
        g: &mut GridCols<'_, D>,
    ) {
        if st.base() != self.base {
            self.flush::<D, K, MODE>(g, ctx.geom.stride);
            self.base = st.base();
        }
        scatter_one::<D, K, S, MODE, FORCE, APIC>(pt, st, self);
    }

    /// Adds the run's sums to the grid (the rows are checked against it here) and empties it.
    #[inline(always)]
    pub fn flush<const D: usize, const K: usize, const MODE: u8>(
        &mut self,
        g: &mut GridCols<'_, D>,
        stride: [usize; D],
    ) {
        let base = self.base;
        self.base = Self::NONE;
        if base == Self::NONE || !rows_fit(base, Stencil::<D, K>::last_row_offset(stride), g.len())
        {
            return;
        }
        for k in 0..Stencil::<D, K>::layers() {
            for j in 0..K {
                let r = j + K * k;
                let row = crate::shape::row_start(base, j, k, stride);
                for c in 0..slot::COUNT {
                    if slot_used::<D>(MODE, c) {
                        // SAFETY: rows_fit checked above; every column has g.len() entries.
                        unsafe { add_row(column(g, c), row, self.sums[r][c]) };
                        self.sums[r][c] = Row4::ZERO;
                    }
                }
            }
        }
    }
}

/// Entry (a, b) of the affine velocity matrix `C_p` from the stored column value and
/// `1 / D_p[b][b]`: the stored `B_p` divided by `D_p`, or the stored `C_p` itself for a family
/// that keeps the gradient form ([`Shape1D::GRADIENT_AFFINE`]).
#[inline(always)]
pub(crate) fn affine_velocity<const K: usize, S: Shape1D<K>>(stored: Real, inv_d: Real) -> Real {
    if S::GRADIENT_AFFINE {
        stored
    } else {
        stored * inv_d
    }
}

/// What one particle scatters.
pub(crate) struct Scattered<const D: usize> {
    /// Mass m_p.
    pub m: Real,
    /// Velocity v_p.
    pub v: [Real; D],
    /// tau/rho0 (read only by the modes with force).
    pub tau: Mat<D>,
    /// Axisymmetric: the hoop stress tau_thetatheta/rho0 (read as `tau`).
    pub hoop: Real,
    /// External force F_p (read only with `FORCE` and force).
    pub force: [Real; D],
    /// APIC affine velocity matrix C_p (read only with `APIC` and momentum).
    pub affine: Mat<D>,
}

/// Adds one particle's row values, for stencil `st`, to the run sums (the grid gets them when
/// the run is flushed).
#[inline(always)]
pub(crate) fn scatter_one<
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const MODE: u8,
    const FORCE: bool,
    const APIC: bool,
>(
    pt: &Scattered<D>,
    st: LaneStencil<'_, D, K, W>,
    sums: &mut RunSums,
) {
    let (m, v, tau) = (pt.m, &pt.v, &pt.tau);
    // Separable form (seeds/000 eqs 16-17): node (i, j, k) has S = wx_i wy_j wz_k and
    // G = (dwx_i wy_j wz_k, wx_i dwy_j wz_k, wx_i wy_j dwz_k). The particle's factors times the
    // x weights (4-wide vectors) are multiplied by the y factors once per j; each row (j, k)
    // then costs one multiply by wz_k per quantity, plus one by dwz_k for the force (3D).
    let (wx, dwx) = (st.wx(), st.dwx());
    let mass_x = wx * m;
    // Momentum on a node: m S (v_a + sum_b C_ab (x_b,i - x_b,p)) (APIC); S (x_b,i - x_b,p)
    // has the form of G_b with the moments e in place of dw: mom_x[a][b] = m C_ab times ex
    // (b = 0) or wx (b >= 1), plus m v_a wx in b = 0.
    let ex = st.ex();
    let mom_x: [[Row4; D]; D] = core::array::from_fn(|a| {
        core::array::from_fn(|b| {
            let plain = if b == 0 { wx * (m * v[a]) } else { Row4::ZERO };
            if APIC {
                plain + (if b == 0 { ex } else { wx }) * (m * pt.affine[a][b])
            } else {
                plain
            }
        })
    });
    // Force on a node: f_a = -m sum_b tau_ab G_b + S F_a; force_x[a][b] = -m tau_ab times dwx
    // (b = 0) or wx (b >= 1), plus F_a wx in b = 0. Axisymmetric, the radial force also has
    // the hoop term -m tau_thetatheta T_ip (eq 120), T_ip = t_i w_z: in b = 0 with t.
    let force_x: [[Row4; D]; D] = core::array::from_fn(|a| {
        core::array::from_fn(|b| {
            let mut f = (if b == 0 { dwx } else { wx }) * (-m * tau[a][b]);
            if FORCE && b == 0 {
                f += wx * pt.force[a];
            }
            if S::AXISYMMETRIC && a == 0 && b == 0 {
                f += st.t() * (-m * pt.hoop);
            }
            f
        })
    });
    for j in 0..K {
        // Per y node j: mass times wy_j; the momentum's and force's terms that carry wz_k
        // (`_wz`: x and y factors) and the z factor dwz_k or ez_k (`_dz`, 3D only).
        let (wy, dwy, ey) = (st.w(1, j), st.dw(1, j), st.e(1, j));
        let mass_j = mass_x * wy;
        let mom_wz: [Row4; D] = core::array::from_fn(|a| {
            if APIC {
                mom_x[a][0] * wy + mom_x[a][1] * ey
            } else {
                mom_x[a][0] * wy
            }
        });
        let mom_dz: [Row4; D] = core::array::from_fn(|a| {
            if APIC && D == 3 {
                mom_x[a][D - 1] * wy
            } else {
                Row4::ZERO
            }
        });
        let f_wz: [Row4; D] = core::array::from_fn(|a| force_x[a][0] * wy + force_x[a][1] * dwy);
        let f_dwz: [Row4; D] = core::array::from_fn(|a| {
            if D == 3 {
                force_x[a][D - 1] * wy
            } else {
                Row4::ZERO
            }
        });
        for k in 0..Stencil::<D, K>::layers() {
            // The z factors (1 and 0 in 2D, where the products are skipped).
            let (wz, dwz, ez) = if D == 3 {
                (st.w(D - 1, k), st.dw(D - 1, k), st.e(D - 1, k))
            } else {
                (1.0, 0.0, 0.0)
            };
            let z = |x: Row4| if D == 3 { x * wz } else { x };
            let mom = |a: usize| {
                if APIC && D == 3 {
                    mom_wz[a] * wz + mom_dz[a] * ez
                } else {
                    z(mom_wz[a])
                }
            };
            let r = j + K * k;
            if MODE == mode::ALL || MODE == mode::MASS_MOMENTUM {
                sums.add(r, slot::MASS, z(mass_j));
                for a in 0..D {
                    sums.add(r, slot::MOMENTUM + a, mom(a));
                }
            }
            if MODE == mode::REMAP {
                for a in 0..D {
                    sums.add(r, slot::REMAP + a, mom(a));
                }
            }
            if MODE == mode::ALL || MODE == mode::FORCE {
                for a in 0..D {
                    let f = if D == 3 {
                        f_wz[a] * wz + f_dwz[a] * dwz
                    } else {
                        f_wz[a]
                    };
                    sums.add(r, slot::FORCE + a, f);
                }
            }
        }
    }
}

/// Adds the tractions of the table to the nodal force (eq 21): each loads one face of one
/// active particle's domain, a square (segment in 2D) of side `2 l_p`, `l_p = h / (2 n)` for
/// `n` particles per cell per axis (the undeformed domain uGIMP uses), so its resultant is
/// `T A` with `A = (2 l_p)^(D-1)` (per unit thickness in 2D). The resultant is spread over the
/// nodes with the particle's own weights, `f_iT = S_ip T A`.
///
/// Why not the face integral `sum_q N_i(x_q) T A / q` at Gauss points `x_q` on the face: it
/// gives the nodes just past the material's surface a force out of proportion to the sliver of
/// mass they carry (`N_i` at the face against `S_ip` at the particle), an acceleration that
/// grows without bound as that mass vanishes; USL differentiates it into the velocity
/// gradient, and a 3D quadratic B-spline block under USL froze (f64 hard case). With `S_ip`
/// the acceleration a traction gives any node is at most `T A / m_p`. The cost is the point of
/// application, moved by `l_p` from the face to the particle: the resultant is exact, its
/// moment is off by `T A l_p` per particle.
///
/// Axisymmetric, the force is per radian: `A = 2 l_p (r_p -+ l_p)` for the faces of constant
/// r at `r_p -+ l_p`, `2 l_p r_p` for those of constant z. There the point of application
/// matters more: a radial load `F` applied at radius `r` balances a uniform stress `F / r`,
/// so a load on the outer face of a pressurised solid cylinder of radius `R` stresses its
/// interior `~l_p / R` too much (measured: 1.3 % for `l_p / R = 1/40`).
pub(crate) fn tractions<const D: usize, const K: usize, S: Shape1D<K>>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    let geom = &ctx.geom;
    let area = (1..D).fold(1.0 as Real, |a, _| a * 2.0 * ctx.half_width);
    for rec in ctx.tractions {
        let i = rec.particle as usize;
        if i >= count || (rec.face / 2) as usize >= D || p.status.get(i) != Some(&ACTIVE) {
            continue;
        }
        let s: [Real; D] = core::array::from_fn(|a| (p.x[a][i] - geom.origin[a]) * geom.inv_h);
        let stretch = p.domain_stretch::<K, S>(i);
        let st = Stencil::<D, K>::new(shape, s, stretch, geom.nodes, geom.stride, geom.inv_h);
        let area = if S::AXISYMMETRIC {
            let (r, l) = (p.x[0][i], ctx.half_width);
            area * match rec.face {
                0 => (r - l).max(0.0),
                1 => r + l,
                _ => r,
            }
        } else {
            area
        };
        st.for_each_node(geom.stride, |node, w, _| {
            for a in 0..D {
                if let Some(f) = g.acc[a].get_mut(node) {
                    *f += w * rec.traction[a] * area;
                }
            }
        });
    }
}
