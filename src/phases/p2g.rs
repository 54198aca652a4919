//! Particle to grid (E12-E14): nodal mass `m_i = sum S_ip m_p`, momentum
//! `p_i = sum S_ip m_p v_p` and internal force `f_i = -sum m_p (tau_p/rho0) . G_ip`. Gravity
//! and the body force enter in the grid update as `m_i b` (E14, E19).
//!
//! Declared effects add, in the same pass: the particle force `S_ip F_p` (E14) and the APIC
//! affine momentum `S_ip m_p C_p (x_i - x_p)` (E79). Tractions (E15, E16) are a pass of
//! their own over the traction table ([`super::tractions`]).
//!
//! The row-sum engine that adds a chunk's products to the grid, and the modes and products it
//! is compiled for, are the SIMD floor's ([`crate::simd::row_sums`]).

use super::{Ctx, Kernels};
use crate::grid::GridCols;
use crate::layout::sym_pairs;
use crate::num::Num;
use crate::particles::ParticleCols;
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{load_into, Block, Lane};
use crate::simd::row_sums::scatter_chunk;
pub(crate) use crate::simd::row_sums::{rows, Adds, Mode, Products};
use crate::simd::rows::Compare;
use crate::simd::wide::Wide;

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
    if !g.lengths_consistent() || (adds.mode.mass() && g.mass.len() != g.len()) {
        return; // Unreachable by construction; the unchecked row access relies on it.
    }
    if Mode::of(MODE) == Mode::Force && ctx.momentum && !S::AXISYMMETRIC {
        // The momentum approach's force (E75) is a scatter of its own (never axisymmetric: the
        // definition refuses it, and those forms compile none of it).
        return super::momentum::forces::<I, D, K, S, W>(shape, ctx, p, count, g);
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
    // A tile of the parallel scatter takes the chunks whose rows reach its slab (and adds
    // their rows in the slab alone, `row_sums`).
    for start in g.chunks(count, W, ctx.geom.stride[D - 1]) {
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
        super::stencils::<I, D, K, S, W>(&mut st, shape, ctx, p, start, &x, adds.apic, false, mls);
        let live = crate::simd::lanes::live_lanes(p, start, count);
        products.set::<I, K, S>(&st, &mass, &v, &tau, &f_ext, &affine, adds);
        let stride = ctx.geom.stride;
        scatter_chunk::<I, D, K, S, W, MODE>(&mut st, &products, live, stride, g, adds);
    }
}

impl<const D: usize, const W: usize> Products<D, W> {
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

impl<const D: usize, const W: usize> Products<D, W> {
    /// [`Products::set`] for a scatter that adds no force (MUSL's re-map): the momenta alone.
    #[inline(always)]
    pub fn set_momenta<I: Compare, const K: usize, S: Shape1D<K>>(
        &mut self,
        st: &Stencils<D, K, W>,
        mass: &Lane<W>,
        v: &[Lane<W>; D],
        affine: &[[Lane<W>; D]; D],
        adds: Adds,
    ) {
        debug_assert!(!adds.mode.force());
        // Never read: the mode adds no force.
        let (tau, force) = ([[0.0; W]; 6], [[0.0; W]; D]);
        self.set::<I, K, S>(st, mass, v, &tau, &force, affine, adds);
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
