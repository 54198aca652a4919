//! Particle to grid (seeds/000 eqs 22, 23, 25): nodal mass `m_i = sum S_ip m_p`, momentum
//! `p_i = sum S_ip m_p v_p` and internal force `f_i = -sum m_p (tau_p/rho0) . G_ip`. Gravity
//! and the body force enter in the grid update as `m_i b` (eq 22).
//!
//! Declared effects add, in the same pass: the particle force `S_ip F_p` (eq 20) and the APIC
//! affine momentum `S_ip m_p C_p (x_i - x_p)` (seeds/001). Tractions (eq 21) are a pass of
//! their own over the traction table ([`tractions`]).

use super::g2p::stencils;
use super::lanes::{load_into, Block, W};
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
    // The chunk's particle values as lane vectors (one copy per column, no per-particle
    // bounds checks), in buffers kept across chunks; what this mode does not read stays zero.
    let mut x = Block([[0.0; W]; D]);
    let mut v = Block([[0.0; W]; D]);
    let mut mass = Block([0.0; W]);
    let mut tau = Block([[0.0; W]; 6]);
    let mut f_ext = Block([[0.0; W]; D]);
    let mut affine = Block([[[0.0; W]; D]; D]);
    for start in (0..count).step_by(W) {
        for a in 0..D {
            load_into(&mut x[a], p.x[a], start);
            load_into(&mut v[a], p.v[a], start);
            if FORCE && with_force {
                load_into(&mut f_ext[a], p.force[a], start);
            }
        }
        load_into(&mut mass, p.mass, start);
        if with_force {
            // Axisymmetric, the fourth 2D component (zz) is the hoop stress.
            let n = sym_pairs(D).len() + (S::AXISYMMETRIC as usize);
            for k in 0..n {
                load_into(&mut tau[k], p.tau[k], start);
            }
        }
        if APIC && with_momentum {
            for (a, row) in affine.iter_mut().enumerate() {
                for (b, lanes) in row.iter_mut().enumerate() {
                    load_into(lanes, p.affine[a][b], start);
                }
            }
        }
        stencils::<D, K, S, APIC, true>(&mut st, shape, ctx, p, start, &x);
        let live = super::g2p::live_lanes(p, start, count);
        let make = |ln: usize| {
            let mut t = [[0.0; D]; D];
            if with_force {
                for (k, &(a, b)) in sym_pairs(D).iter().enumerate() {
                    t[a][b] = tau[k][ln];
                    t[b][a] = tau[k][ln];
                }
            }
            let stn = st.lane(ln);
            Scattered {
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
            }
        };
        scatter_lanes::<D, K, S, MODE, FORCE, APIC>(
            &st,
            |ln| live.has(ln),
            make,
            ctx.geom.stride,
            g,
        );
    }
}

/// The grid columns a scatter adds to, numbered for [`scatter_group`]: the mass, then the momentum,
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

/// The grid rows of a stencil, checked against the grid when made.
pub(crate) struct Direct<'a, 'g, const D: usize> {
    g: &'a mut GridCols<'g, D>,
    base: usize,
    stride: [usize; D],
}

impl<'a, 'g, const D: usize> Direct<'a, 'g, D> {
    /// The rows of the `K`-node stencil at `base`, or `None` if they do not fit in the grid.
    #[inline(always)]
    pub fn new<const K: usize>(
        g: &'a mut GridCols<'g, D>,
        base: usize,
        stride: [usize; D],
    ) -> Option<Self> {
        rows_fit(base, Stencil::<D, K>::last_row_offset(stride), g.len()).then_some(Direct {
            g,
            base,
            stride,
        })
    }
}

impl<const D: usize> Direct<'_, '_, D> {
    /// Adds `v` to slot `c` (a [`slot`]) of stencil row `j` along y, layer `k` along z.
    #[inline(always)]
    fn add<const K: usize>(&mut self, j: usize, k: usize, c: usize, v: Row4) {
        let row = crate::shape::row_start(self.base, j, k, self.stride);
        // SAFETY: `new` checked the stencil's rows (j, k < K) against the grid, and every
        // column has g.len() entries.
        unsafe { add_row(column(self.g, c), row, v) };
    }
}

/// Scatters the live lanes of a chunk (`make(ln)` gives lane `ln`'s values) straight to the
/// grid in groups of consecutive live lanes that share a stencil base ([`scatter_group`]):
/// four where four do, else two where two do, else one (particles seeded in a lattice come in
/// runs of a cell's worth: see [`crate::World::fill_box`]). The grouping depends on the
/// particle order alone, so the result does not depend on the instruction set.
#[inline(always)]
pub(crate) fn scatter_lanes<
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const MODE: u8,
    const FORCE: bool,
    const APIC: bool,
>(
    st: &Stencils<D, K, W>,
    live: impl Fn(usize) -> bool,
    make: impl Fn(usize) -> Scattered<D>,
    stride: [usize; D],
    g: &mut GridCols<'_, D>,
) {
    let mut ln = 0;
    while ln < W {
        if !live(ln) {
            ln += 1;
            continue;
        }
        let base = st.lane(ln).base();
        let Some(mut sink) = Direct::new::<K>(g, base, stride) else {
            ln += 1;
            continue; // Unreachable by construction (first_node clamps).
        };
        let shares = |n: usize| ln + n < W && live(ln + n) && st.lane(ln + n).base() == base;
        let n = if shares(1) && shares(2) && shares(3) {
            // Literal arrays: `core::array::from_fn`'s closures were left out of line here.
            let pts = [make(ln), make(ln + 1), make(ln + 2), make(ln + 3)];
            scatter_group::<D, K, S, MODE, FORCE, APIC, 4>(
                [&pts[0], &pts[1], &pts[2], &pts[3]],
                [
                    st.lane(ln),
                    st.lane(ln + 1),
                    st.lane(ln + 2),
                    st.lane(ln + 3),
                ],
                &mut sink,
            );
            4
        } else if shares(1) {
            let (a, b) = (make(ln), make(ln + 1));
            scatter_group::<D, K, S, MODE, FORCE, APIC, 2>(
                [&a, &b],
                [st.lane(ln), st.lane(ln + 1)],
                &mut sink,
            );
            2
        } else {
            let a = make(ln);
            scatter_group::<D, K, S, MODE, FORCE, APIC, 1>([&a], [st.lane(ln)], &mut sink);
            1
        };
        ln += n;
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

/// One particle's factors along x, the part of its row values that does not depend on the row.
struct XFactors<const D: usize> {
    /// m wx.
    mass: Row4,
    /// Momentum on a node: m S (v_a + sum_b C_ab (x_b,i - x_b,p)) (APIC); S (x_b,i - x_b,p)
    /// has the form of G_b with the moments e in place of dw: `mom[a][b]` = m C_ab times ex
    /// (b = 0) or wx (b >= 1), plus m v_a wx in b = 0.
    mom: [[Row4; D]; D],
    /// Force on a node: f_a = -m sum_b tau_ab G_b + S F_a; `force[a][b]` = -m tau_ab times
    /// dwx (b = 0) or wx (b >= 1), plus F_a wx in b = 0. Axisymmetric, the radial force also
    /// has the hoop term -m tau_thetatheta T_ip (eq 120), T_ip = t_i w_z: in b = 0 with t.
    force: [[Row4; D]; D],
}

impl<const D: usize> XFactors<D> {
    const ZERO: Self = XFactors {
        mass: Row4::ZERO,
        mom: [[Row4::ZERO; D]; D],
        force: [[Row4::ZERO; D]; D],
    };

    #[inline(always)]
    fn new<const K: usize, S: Shape1D<K>, const FORCE: bool, const APIC: bool>(
        pt: &Scattered<D>,
        st: &LaneStencil<'_, D, K, W>,
    ) -> Self {
        let (m, v, tau) = (pt.m, &pt.v, &pt.tau);
        let (wx, dwx, ex) = (st.wx(), st.dwx(), st.ex());
        XFactors {
            mass: wx * m,
            mom: core::array::from_fn(|a| {
                core::array::from_fn(|b| {
                    let plain = if b == 0 { wx * (m * v[a]) } else { Row4::ZERO };
                    if APIC {
                        plain + (if b == 0 { ex } else { wx }) * (m * pt.affine[a][b])
                    } else {
                        plain
                    }
                })
            }),
            force: core::array::from_fn(|a| {
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
            }),
        }
    }
}

/// One particle's factors for the rows of y node `j`: mass times wy_j; the momentum's and
/// force's terms that carry wz_k (`_wz`: x and y factors) and the z factor dwz_k or ez_k
/// (`_dz`, 3D only).
struct YFactors<const D: usize> {
    mass: Row4,
    mom_wz: [Row4; D],
    mom_dz: [Row4; D],
    f_wz: [Row4; D],
    f_dwz: [Row4; D],
}

impl<const D: usize> YFactors<D> {
    const ZERO: Self = YFactors {
        mass: Row4::ZERO,
        mom_wz: [Row4::ZERO; D],
        mom_dz: [Row4::ZERO; D],
        f_wz: [Row4::ZERO; D],
        f_dwz: [Row4::ZERO; D],
    };

    #[inline(always)]
    fn new<const K: usize, const APIC: bool>(
        x: &XFactors<D>,
        st: &LaneStencil<'_, D, K, W>,
        j: usize,
    ) -> Self {
        let (wy, dwy, ey) = (st.w(1, j), st.dw(1, j), st.e(1, j));
        YFactors {
            mass: x.mass * wy,
            mom_wz: core::array::from_fn(|a| {
                if APIC {
                    x.mom[a][0] * wy + x.mom[a][1] * ey
                } else {
                    x.mom[a][0] * wy
                }
            }),
            mom_dz: core::array::from_fn(|a| {
                if APIC && D == 3 {
                    x.mom[a][D - 1] * wy
                } else {
                    Row4::ZERO
                }
            }),
            f_wz: core::array::from_fn(|a| x.force[a][0] * wy + x.force[a][1] * dwy),
            f_dwz: core::array::from_fn(|a| {
                if D == 3 {
                    x.force[a][D - 1] * wy
                } else {
                    Row4::ZERO
                }
            }),
        }
    }

    /// Adds this particle's values of row (j, k), per [`slot`], to `acc`, or with `FIRST`
    /// writes them there (the slots `MODE` fills; the others stay as they are). The first
    /// particle of a group writes: adding to zeros would cost an add per value (the compiler
    /// keeps `0 + x`, which is not `x` for `x = -0`).
    #[inline(always)]
    fn add_row<const K: usize, const MODE: u8, const APIC: bool, const FIRST: bool>(
        &self,
        st: &LaneStencil<'_, D, K, W>,
        k: usize,
        acc: &mut [Row4; slot::COUNT],
    ) {
        // The z factors (1 and 0 in 2D, where the products are skipped).
        let (wz, dwz, ez) = if D == 3 {
            (st.w(D - 1, k), st.dw(D - 1, k), st.e(D - 1, k))
        } else {
            (1.0, 0.0, 0.0)
        };
        let z = |x: Row4| if D == 3 { x * wz } else { x };
        let mom = |a: usize| {
            if APIC && D == 3 {
                self.mom_wz[a] * wz + self.mom_dz[a] * ez
            } else {
                z(self.mom_wz[a])
            }
        };
        let mut put = |c: usize, v: Row4| {
            if FIRST {
                acc[c] = v;
            } else {
                acc[c] += v;
            }
        };
        if MODE == mode::ALL || MODE == mode::MASS_MOMENTUM {
            put(slot::MASS, z(self.mass));
            for a in 0..D {
                put(slot::MOMENTUM + a, mom(a));
            }
        }
        if MODE == mode::REMAP {
            for a in 0..D {
                put(slot::REMAP + a, mom(a));
            }
        }
        if MODE == mode::ALL || MODE == mode::FORCE {
            for a in 0..D {
                let f = if D == 3 {
                    self.f_wz[a] * wz + self.f_dwz[a] * dwz
                } else {
                    self.f_wz[a]
                };
                put(slot::FORCE + a, f);
            }
        }
    }
}

/// Scatters `N` particles that share a stencil base to `sink`, row by row: each row's values
/// are summed over the particles in registers, in the particles' order, and then added to the
/// sink once ([`slot_used`] names what `MODE` adds), so a group of N costs one load, add and
/// store per row and column where N single particles cost N.
///
/// Separable form (seeds/000 eqs 16-17): node (i, j, k) has S = wx_i wy_j wz_k and
/// G = (dwx_i wy_j wz_k, wx_i dwy_j wz_k, wx_i wy_j dwz_k). The particle's factors times the
/// x weights (4-wide vectors) are multiplied by the y factors once per j; each row (j, k) then
/// costs one multiply by wz_k per quantity, plus one by dwz_k for the force (3D).
#[inline(always)]
pub(crate) fn scatter_group<
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const MODE: u8,
    const FORCE: bool,
    const APIC: bool,
    const N: usize,
>(
    pts: [&Scattered<D>; N],
    sts: [LaneStencil<'_, D, K, W>; N],
    sink: &mut Direct<'_, '_, D>,
) {
    const { assert!(N >= 1) };
    // Loops over the particles, not `core::array::from_fn`, whose closures are not always
    // inlined (ARCHITECTURE.md, "Performance").
    let mut x = [XFactors::ZERO; N];
    for ((xn, pt), stn) in x.iter_mut().zip(pts).zip(&sts) {
        *xn = XFactors::new::<K, S, FORCE, APIC>(pt, stn);
    }
    for j in 0..K {
        let mut y = [YFactors::ZERO; N];
        for ((yn, xn), stn) in y.iter_mut().zip(&x).zip(&sts) {
            *yn = YFactors::new::<K, APIC>(xn, stn, j);
        }
        for k in 0..Stencil::<D, K>::layers() {
            let mut acc = [Row4::ZERO; slot::COUNT];
            y[0].add_row::<K, MODE, APIC, true>(&sts[0], k, &mut acc);
            for (yn, stn) in y.iter().zip(&sts).skip(1) {
                yn.add_row::<K, MODE, APIC, false>(stn, k, &mut acc);
            }
            for (c, v) in acc.into_iter().enumerate() {
                if slot_used::<D>(MODE, c) {
                    sink.add::<K>(j, k, c, v);
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
