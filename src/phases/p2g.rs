//! Particle to grid (E12-E14): nodal mass `m_i = sum S_ip m_p`, momentum
//! `p_i = sum S_ip m_p v_p` and internal force `f_i = -sum m_p (tau_p/rho0) . G_ip`. Gravity
//! and the body force enter in the grid update as `m_i b` (E14, E19).
//!
//! Declared effects add, in the same pass: the particle force `S_ip F_p` (E14) and the APIC
//! affine momentum `S_ip m_p C_p (x_i - x_p)` (E79). Tractions (E15, E16) are a pass of
//! their own over the traction table ([`tractions`]).
//!
//! The row-sum engine that adds a chunk's products to the grid is [`super::row_sums`].

use super::row_sums::scatter_chunk;
use super::{Ctx, Kernels};
use crate::grid::GridCols;
use crate::layout::sym_pairs;
use crate::num::Num;
use crate::particles::ParticleCols;
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{load_into, Block, Lane};
use crate::simd::rows::Compare;
use crate::simd::wide::Wide;

/// What a particle-to-grid pass accumulates.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[repr(u8)]
pub(crate) enum Mode {
    /// Mass, momentum and internal force (USL, MUSL).
    All,
    /// Mass and momentum (first pass of USF).
    MassMomentum,
    /// Internal force only (second pass of USF, after the stress update).
    Force,
    /// Momentum of the updated particle velocities into the remap columns (MUSL).
    Remap,
}

/// The configuration the scatter's row code is compiled for, its const parameter `MODE`: the
/// [`Mode`] (which grid columns a row adds to, so which sums stay in registers) and, in
/// [`APIC_BIT`], the transfer (whether a row carries the affine momentum). Tested per row as
/// values, they made the default step 1.12 to 1.35 times as long (benches/PERFORMANCE.md); a
/// pass picks the instance once.
pub(crate) const fn rows(mode: Mode, apic: bool) -> u8 {
    mode as u8 | if apic { APIC_BIT } else { 0 }
}

/// The bit of [`rows`] that says APIC.
pub(crate) const APIC_BIT: u8 = 0x10;

/// Whether the row configuration `m` ([`rows`]) carries the affine momentum.
#[inline(always)]
pub(crate) const fn apic_rows(m: u8) -> bool {
    m & APIC_BIT != 0
}

impl Mode {
    /// The mode of the row configuration `m` ([`rows`]).
    #[inline(always)]
    pub(crate) const fn of(m: u8) -> Mode {
        match m & !APIC_BIT {
            0 => Mode::All,
            1 => Mode::MassMomentum,
            2 => Mode::Force,
            _ => Mode::Remap,
        }
    }

    /// Adds the nodal mass (and momentum).
    #[inline(always)]
    pub(crate) const fn mass(self) -> bool {
        matches!(self, Mode::All | Mode::MassMomentum)
    }

    /// Reads the particles' momenta (the momentum columns or the remap columns).
    #[inline(always)]
    pub(crate) const fn momentum(self) -> bool {
        !matches!(self, Mode::Force)
    }

    /// Adds the internal (and particle) force.
    #[inline(always)]
    pub(crate) const fn force(self) -> bool {
        matches!(self, Mode::All | Mode::Force)
    }
}

/// What a scatter adds: its [`Mode`], and whether the particle forces (`S_ip F_p`; only with
/// a mode that adds the force) and APIC's affine momentum (only with a mode that adds
/// momentum) enter. The scatter pass turns the mode and transfer into its row code's
/// configuration ([`rows`]) once; the particle forces stay a value.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Adds {
    pub mode: Mode,
    pub forces: bool,
    pub apic: bool,
}

impl Adds {
    /// What a scatter in `mode` adds in a substep with context `ctx`: the particle forces
    /// where it adds the force, the affine momentum where it adds momentum.
    #[inline(always)]
    pub fn of<const D: usize>(mode: Mode, ctx: &Ctx<'_, D>) -> Self {
        Adds {
            mode,
            forces: ctx.forces && mode.force(),
            apic: ctx.apic && mode.momentum(),
        }
    }
}

/// The scatter pass with the row configuration `MODE` ([`rows`]).
#[inline(always)]
pub(crate) fn scatter_rows<
    I: Kernels,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
    const MODE: u8,
>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
    adds: Adds,
) {
    if !g.lengths_consistent() {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    let mut st = Stencils::<D, K, W>::default();
    // The chunk's particle values as lane vectors (one copy per column, no per-particle
    // bounds checks), in buffers kept across chunks; what this mode does not read stays zero.
    let mut x = Block([[0.0; W]; D]);
    let mut v = Block([[0.0; W]; D]);
    let mut mass = Block([0.0; W]);
    let mut tau = Block([[0.0; W]; 6]);
    let mut f_ext = Block([[0.0; W]; D]);
    let mut affine = Block([[[0.0; W]; D]; D]);
    let mut products = Products::zero();
    for start in (0..count).step_by(W) {
        for a in 0..D {
            load_into(&mut x[a], p.x[a], start);
            load_into(&mut v[a], p.v[a], start);
            if adds.forces {
                load_into(&mut f_ext[a], p.force[a], start);
            }
        }
        load_into(&mut mass, p.mass, start);
        if adds.mode.force() {
            // Axisymmetric, the fourth 2D component (zz) is the hoop stress.
            let n = sym_pairs(D).len() + (S::AXISYMMETRIC as usize);
            for k in 0..n {
                load_into(&mut tau[k], p.tau[k], start);
            }
        }
        if adds.apic {
            for (a, row) in affine.iter_mut().enumerate() {
                for (b, lanes) in row.iter_mut().enumerate() {
                    load_into(lanes, p.affine[a][b], start);
                }
            }
        }
        let mls = ctx.mls;
        I::stencils::<D, K, S, W>(&mut st, shape, ctx, p, start, &x, adds.apic, false, mls);
        let live = crate::simd::lanes::live_lanes(p, start, count);
        products.set::<I, K, S>(&st, &mass, &v, &tau, &f_ext, &affine, adds);
        scatter_chunk::<I, D, K, S, W, MODE>(&mut st, &products, live, ctx.geom.stride, g, adds);
    }
}

/// What the particles of a chunk scatter, per lane (lane-fastest): the products of their
/// values that the row code scales the weights by, formed once per chunk. What a mode does not
/// read stays zero.
#[repr(C, align(64))]
pub(crate) struct Products<const D: usize, const W: usize> {
    /// m_p.
    pub(crate) m: Lane<W>,
    /// m_p v_p (modes with momentum).
    pub(crate) mv: [Lane<W>; D],
    /// m_p C_p (APIC, modes with momentum).
    pub(crate) mc: [[Lane<W>; D]; D],
    /// -m_p tau_p/rho0, symmetric (modes with force).
    pub(crate) mt: [[Lane<W>; D]; D],
    /// Axisymmetric: -m_p tau_thetatheta/rho0 (modes with force).
    pub(crate) mh: Lane<W>,
    /// The particle force F_p (`FORCE`, modes with force).
    pub(crate) f: [Lane<W>; D],
}

impl<const D: usize, const W: usize> Products<D, W> {
    /// All zero; a pass makes one and sets it per chunk.
    pub fn zero() -> Self {
        Products {
            m: [0.0; W],
            mv: [[0.0; W]; D],
            mc: [[[0.0; W]; D]; D],
            mt: [[[0.0; W]; D]; D],
            mh: [0.0; W],
            f: [[0.0; W]; D],
        }
    }

    /// The products of a chunk's masses, velocities, stresses `tau[k]` (the components of
    /// [`sym_pairs`], then the hoop stress), particle forces and stored affine matrices (`B_p`,
    /// or `C_p` for a family that keeps the gradient form: [`affine_velocity`], with the
    /// stencils' `D_p^-1`), for a scatter that `adds`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn set<I: Compare, const K: usize, S: Shape1D<K>>(
        &mut self,
        st: &Stencils<D, K, W>,
        mass: &Lane<W>,
        v: &[Lane<W>; D],
        tau: &[Lane<W>; 6],
        force: &[Lane<W>; D],
        affine: &[[Lane<W>; D]; D],
        adds: Adds,
    ) {
        // Zero where the mode adds no mass, for a compact instance's full rows.
        if adds.mode.mass() {
            self.m = *mass;
        }
        if adds.mode.force() && adds.forces {
            self.f = *force;
        }
        let (momentum, force) = (adds.mode.momentum(), adds.mode.force());
        for at in (0..W).step_by(I::N) {
            let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
            let m = ld(mass);
            if momentum {
                for a in 0..D {
                    (m * ld(&v[a])).store(&mut self.mv[a], at);
                    if adds.apic {
                        for b in 0..D {
                            let inv_d = ld(st.inverse_moments(b));
                            let c = affine_velocity::<K, S, _>(ld(&affine[a][b]), inv_d);
                            (m * c).store(&mut self.mc[a][b], at);
                        }
                    }
                }
            }
            if force {
                // The internal force's `-m_p tau_p / rho0` (E14), symmetric.
                for (k, &(a, b)) in sym_pairs(D).iter().enumerate() {
                    let t = -m * ld(&tau[k]);
                    t.store(&mut self.mt[a][b], at);
                    t.store(&mut self.mt[b][a], at);
                }
                if S::AXISYMMETRIC {
                    (-m * ld(&tau[3])).store(&mut self.mh, at);
                }
            }
        }
    }
}

/// Entry (a, b) of the affine velocity matrix `C_p` from the stored column value and
/// `1 / D_p[b][b]`: the stored `B_p` divided by `D_p`, or the stored `C_p` itself for a family
/// that keeps the gradient form ([`Shape1D::GRADIENT_AFFINE`]).
#[inline(always)]
pub(crate) fn affine_velocity<const K: usize, S: Shape1D<K>, T: Num>(stored: T, inv_d: T) -> T {
    if S::GRADIENT_AFFINE {
        stored
    } else {
        stored * inv_d
    }
}
