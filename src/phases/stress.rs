//! The stress update (E29-E32): `grad v = sum v_i (x) G_ip` (E29), `dF = exp(grad v dt)` to
//! the configured number of terms (E31), `F <- dF F` (kept as `H = F - I`), `J = det F`
//! (E32), the material's inelastic part and `tau/rho0`, and the viscous stress. Axisymmetric,
//! the hoop rate `v_r / r = sum v_r,i T_ip` (E70) stretches `F_thetatheta` the same way. With
//! thermal expansion or swelling declared, the material sees `F` without the particle's
//! isotropic eigenstrain (E47, [`crate::material::elastic_part`]).
//!
//! [`update_stress`] updates a chunk; USL runs it inside the particle pass
//! ([`super::g2p::particles`]), USF and MUSL in a pass of its own ([`stress`]). A particle whose
//! new state is not finite, whose F inverts, or whose volume ratio `J` leaves `[1 / r, r]` (`r`
//! the definition's `max_volume_ratio`) is frozen.

use super::gather::{commit_gradient_affine, Gathered, Grad, LaneMat};
use super::{Ctx, Kernels};
use crate::def::UpdateOrder;
use crate::grid::GridCols;
use crate::material::{add_viscous_lanes, eigenstrain_part, Deformation};
use crate::math::exp_series_minus_identity;
use crate::num::matrix;
use crate::particles::StepReport;
use crate::particles::{ParticleCols, FROZEN};
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{commit, live_lanes, load, load_into, Block, Lane, Lanes};
use crate::simd::rows;
use crate::simd::wide::Wide;

/// The lane matrices of a stress update, kept by the pass across chunks (see
/// `lanes::load_into`): built per chunk, `exp(grad v dt)`'s copies of whole matrices went
/// through the stack, and 256-bit loads that straddled two earlier stores there waited for
/// them (store forwarding fails for such loads).
#[repr(C, align(64))]
pub(crate) struct StressScratch<const D: usize, const W: usize> {
    h_old: LaneMat<D, W>,
    h: LaneMat<D, W>,
    tau: [Lane<W>; 6],
}

impl<const D: usize, const W: usize> StressScratch<D, W> {
    pub(crate) fn new() -> Self {
        StressScratch {
            h_old: [[[0.0; W]; D]; D],
            h: [[[0.0; W]; D]; D],
            tau: [[0.0; W]; 6],
        }
    }
}

/// Updates H and tau/rho0 of the lanes in `update` from their velocity gradient `l`. Returns
/// per lane whether the update succeeded, and the lanes that failed because their volume ran
/// away (`J - 1` outside [`Ctx::jm1_band`], F not inverted); a lane that fails (non-finite
/// result, inverted F or runaway) keeps its H and stress.
#[inline(always)]
pub(crate) fn update_stress<
    I: Kernels,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
>(
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
    let (zero, dt) = (Wide::<I>::splat(0.0), Wide::<I>::splat(ctx.dt));
    for at in (0..W).step_by(I::N) {
        let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
        let mut a = [[zero; D]; D];
        for r in 0..D {
            for c in 0..D {
                a[r][c] = ld(&l[r][c]) * dt;
            }
        }
        let q = exp_series_minus_identity(&a, n);
        for r in 0..D {
            for c in 0..D {
                let mut v = ld(&h_old[r][c]);
                for m in 0..D {
                    v += q[r][m] * ld(&h_old[m][c]);
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
            let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
            let q = exp_series_minus_identity(&[[ld(&gathered.hoop) * dt]], n)[0][0];
            let old = ld(&old);
            (old + q + q * old).store(&mut hzz, at);
        }
    }
    // J - 1 = tr H + principal minors (+ det H in 3D), without forming I + H; times F_zz in 2D.
    let mut jm1 = [0.0; W];
    for at in (0..W).step_by(I::N) {
        let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
        let f = Deformation::<D, Wide<I>>::new(matrix(|r, c| ld(&h[r][c])), ld(&hzz));
        f.jm1.store(&mut jm1, at);
    }
    // The plastic history, when declared (the plastic models read and change it).
    let mut plastic: Lane<W> = if ctx.plastic {
        load(p.plastic, start)
    } else {
        [0.0; W]
    };
    // Material: the model's chunk path on the instance's vectors, once per material of the
    // chunk's lanes. Most chunks hold one material and run it once in place. A chunk that
    // mixes them runs each material's model on all its lanes from the same start and keeps
    // that material's lanes ([`Mixed`]): every lane gets the bits of its own material's path,
    // at the cost of one vector pass per material (lane by lane on the one-particle path, a
    // scene whose materials mix as they flow spent a third of its step there).
    // The ids stay u32 here and are widened only where a lane's record is looked up (widening
    // all sixteen up front cost 2 instructions per 2D particle-step).
    let ids = load(p.material, start);
    let ns = crate::layout::stress_components(D);
    // The isotropic eigenstrain of each lane (thermal expansion, swelling), when declared.
    let eigen = eigenstrain(ctx, p, start, &ids);
    let (axi, eigen) = (S::AXISYMMETRIC, eigen.as_ref());
    // The eigenstrain must not invert the material either.
    let admissible = match eigen {
        Some(d) => rows::above::<I, W>(d, -1.0),
        None => Lanes::ALL,
    };
    // Compared four lanes at a time (`Lanes::equal`, exact: ids are below the material
    // capacity, at most 2^16; one lane at a time it held 6 % of the stress pass's samples),
    // once per material.
    // Without `Option` combinators: their closures were left out of line (a profile showed
    // `update_stress::{{closure}}` comparing the ids one lane at a time in baseline code).
    let mut id = match update.first() {
        Some(l0) => ids[l0],
        None => 0,
    };
    let mut these = update & Lanes::equal(&ids, id);
    let mut mixed = None;
    if !update.minus(these).is_empty() {
        mixed = Some(Mixed::take(h, &hzz, &jm1, &plastic));
    }
    let (mut left, mut ok) = (update, Lanes::NONE);
    while !these.is_empty() {
        left = left.minus(these);
        if let Some(rec) = ctx.materials.get(id as usize) {
            if let Some(m) = &mixed {
                m.start(h, &mut hzz, &mut jm1, &mut plastic);
            }
            // The inelastic part first (a return mapping, a fluid's projection): the stress is
            // that of the state it leaves. It acts on the elastic part: with an eigenstrain,
            // on `F / (1 + d)`, which then takes the eigenstrain back (E47), so that a free
            // expansion neither yields nor flows.
            I::material::<D, W>(rec, h, &mut hzz, &mut jm1, &mut plastic, axi, eigen, tau);
            ok = ok | (these & admissible & rows::above::<I, W>(&jm1, -1.0));
            if let Some(m) = &mut mixed {
                m.keep(these, h, &hzz, &jm1, &plastic, tau);
            }
        }
        these = match left.first() {
            Some(l0) => {
                id = ids[l0];
                left & Lanes::equal(&ids, id)
            }
            None => Lanes::NONE,
        };
    }
    if let Some(m) = &mixed {
        m.finish(h, &mut hzz, &mut jm1, &mut plastic, tau);
    }
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
    let mut finite = Lanes::NONE;
    for at in (0..W).step_by(I::N) {
        let ld = |c: &Lane<W>| Wide::<I>::load(c, at);
        let mut sum = ld(&jm1) + ld(&hzz);
        for t in &tau[..ns] {
            sum += ld(t);
        }
        for r in 0..D {
            for c in 0..D {
                sum += ld(&h[r][c]);
            }
        }
        if ctx.plastic {
            sum += ld(&plastic);
        }
        finite = finite | sum.is_finite().lanes(at);
    }
    let ok = ok & finite;
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

/// A chunk whose lanes mix materials: the deformation its materials start from, and what each
/// material's pass left in its own lanes. Not inlined: one copy per dimension and width, not
/// one per pass form (chunks that mix materials are few).
struct Mixed<const D: usize, const W: usize> {
    start: ([[Lane<W>; D]; D], [Lane<W>; 3]),
    kept: ([[Lane<W>; D]; D], [Lane<W>; 3], [Lane<W>; 6]),
}

impl<const D: usize, const W: usize> Mixed<D, W> {
    #[inline(never)]
    fn take(h: &[[Lane<W>; D]; D], hzz: &Lane<W>, jm1: &Lane<W>, plastic: &Lane<W>) -> Self {
        let start = (*h, [*hzz, *jm1, *plastic]);
        Mixed {
            start,
            kept: (start.0, start.1, [[0.0; W]; 6]),
        }
    }

    /// Puts the start back before a material's pass.
    #[inline(never)]
    fn start(
        &self,
        h: &mut [[Lane<W>; D]; D],
        hzz: &mut Lane<W>,
        jm1: &mut Lane<W>,
        plastic: &mut Lane<W>,
    ) {
        *h = self.start.0;
        [*hzz, *jm1, *plastic] = self.start.1;
    }

    /// Keeps lanes `these` of a material's pass.
    #[inline(never)]
    fn keep(
        &mut self,
        these: Lanes<W>,
        h: &[[Lane<W>; D]; D],
        hzz: &Lane<W>,
        jm1: &Lane<W>,
        plastic: &Lane<W>,
        tau: &[Lane<W>; 6],
    ) {
        let (kh, ks, kt) = &mut self.kept;
        for ln in these.iter() {
            for r in 0..D {
                for c in 0..D {
                    kh[r][c][ln] = h[r][c][ln];
                }
            }
            for (k, v) in ks.iter_mut().zip([hzz, jm1, plastic]) {
                k[ln] = v[ln];
            }
            for (k, v) in kt.iter_mut().zip(tau) {
                k[ln] = v[ln];
            }
        }
    }

    /// Every material's lanes, as their passes left them.
    #[inline(never)]
    fn finish(
        &self,
        h: &mut [[Lane<W>; D]; D],
        hzz: &mut Lane<W>,
        jm1: &mut Lane<W>,
        plastic: &mut Lane<W>,
        tau: &mut [Lane<W>; 6],
    ) {
        *h = self.kept.0;
        [*hzz, *jm1, *plastic] = self.kept.1;
        *tau = self.kept.2;
    }
}

/// Stress update in its own pass (USF before the momentum update, MUSL after the re-map),
/// from the wall-constrained velocity in the `remap` columns. With MUSL (after the particle
/// pass has moved the particles) it takes the stencils at the positions of the start of the
/// step, kept in the `x_start` columns, and puts a particle it freezes back there.
#[inline(always)]
pub(crate) fn stress<I: Kernels, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
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
    let mut weights = super::momentum::Weights::zero();
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
        super::stencils::<I, D, K, S, W>(&mut st, shape, ctx, p, start, &x, false, false, ctx.mls);
        if ctx.momentum && !S::AXISYMMETRIC {
            use super::momentum::{gather, Differentiate};
            weights.of::<I, K, S>(ctx, &st, &x, g.mass);
            let (which, out) = (Differentiate::Remap, &mut gathered);
            gather::<I, D, K, W>(ctx, &st, &weights, g, which, out, None);
        } else {
            const REMAP: u8 = Grad::Remap as u8;
            let (aff, out) = (&mut unused_affine, &mut gathered);
            I::gather::<D, K, S, W, false, REMAP, false>(ctx, g, &st, aff, out);
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
