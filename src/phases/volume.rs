//! The fluids' volume relaxation (E97): a fluid particle's volume ratio `J` may not claim, for
//! long, more space than its particles fill.
//!
//! A fluid's `J` integrates the grid's velocity divergence at the particle (E29-E32), while the
//! particle moves with the grid's velocity at its point. The two agree in the continuum; on
//! the grid they drift apart where the flow bends within a cell, most of all next to a
//! collider whose contact turns the nodes' velocities (E92): there particles pack closer than
//! their `J` says, the sum of their volumes `J V0` exceeds the space they fill, and the
//! pressure, which reads `J` alone, does not push back. A box floating on such water sinks by
//! the volume the packed particles lose (7 % of its depth within a minute, `examples/float.rs`
//! `--cut-centres`).
//!
//! Each substep, before the scatter, with the particles where the substep starts:
//! 1. scatter: the nodal volume `V_i = sum_p S_ip J_p V0_p` of every active particle, of
//!    every material (a solid takes up space too);
//! 2. the nodal fill `phi_i = V_i / V_cell,i` (`h^d`; axisymmetric, per radian,
//!    `h^2 max(r_i, h / 2)`), the axis and periodic images folded and read;
//! 3. per fluid particle the fill at its place `phi_p = sum_i S_ip phi_i`, and where
//!    `phi_p > c = 1 + 1e-4`, `J <- J / (phi_p / c)^min(1, k dt)`, `k` the material's
//!    [`crate::MaterialDef::volume_relaxation`]: the deformation becomes `J^(1/n) I` (as the
//!    fluid's own projection keeps it, E45) and the stored stress takes the change of the
//!    pressure (the viscous part stays).
//!
//! Only a crowd is corrected. A fill below 1 is a free surface, a wall or a solid next to the
//! particle (whose nodes' support lies partly where no particle can be), not a void: there
//! the estimate is low and nothing is done. In a uniform fill `phi_p` is 1 to the shape
//! functions' partition of unity and nothing changes. A rate in time, not a projection each
//! substep: particles that meet in a splash are pushed apart over a few substeps rather than
//! at once (a full projection turned a 30 % overlap into a pressure jump that threw water),
//! and the result does not depend on the substep. The pass runs only where a fluid with a rate
//! is in the world, and costs one scalar scatter and gather per substep; its nodal column is
//! the first acceleration column, before the grid's reset.

use super::transport::{
    chunk_stencils, current_volume, gather_rows, scatter_order, scatter_rows, StencilsFn,
};
use super::Ctx;
use crate::cut::Tile;
use crate::def::MaterialModel;
use crate::grid::GridCols;
use crate::layout::MaterialRecord;
use crate::material::{eigenstrain_at, fluid_stress, model_of, Deformation};
use crate::math::{exp_m1, ln_1p};
use crate::particles::ParticleCols;
use crate::shape::{Shape1D, Stencils};
use crate::Real;

/// The least crowd the relaxation acts on, `phi - 1`: below it the fill is the sums'
/// round-off and a lattice's shifts, and relaxing it changed nothing but the cost (the
/// logarithms and stresses of most particles of a block at rest).
const CROWD: Real = 1.0e-4;

/// Whether material `r` relaxes its volume (a fluid with a rate).
#[inline(always)]
pub(crate) fn relaxes(r: &MaterialRecord) -> bool {
    model_of(r) == MaterialModel::Fluid && r.volume_relaxation > 0.0
}

/// Step 1 on the nodes of `g` (a tile's, or the whole grid's): `V_i += S_ip J_p V0_p` into
/// its first acceleration column, with the instance's `stencils`. One copy per form (see
/// [`relax`]).
#[inline(never)]
pub(crate) fn scatter<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    stencils: StencilsFn<D, K, S, W>,
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    let stride = ctx.geom.stride;
    let (n, tile, chunks) = (g.len(), g.tile, g.chunks(count, W, stride[D - 1]));
    let col = &mut *g.acc[0];
    if col.len() != n {
        return; // Unreachable: every grid has its acceleration columns.
    }
    // A tile's rows are clipped to it (`Tile::own`); the whole grid's must fit.
    let fit = if tile == Tile::ALL { n } else { usize::MAX };
    let mut st = Stencils::<D, K, W>::default();
    for start in chunks {
        let live = chunk_stencils(stencils, &mut st, shape, ctx, p, start, count, fit);
        for ln in const { scatter_order::<W>() } {
            if !live.has(ln) {
                continue;
            }
            let i = start + ln;
            let Some(rec) = ctx.materials.get(p.material[i] as usize) else {
                continue;
            };
            let volume = current_volume(rec, p, i);
            // SAFETY: `chunk_stencils` checked the rows of a live lane against the whole
            // grid's columns; a tile's are clipped.
            unsafe {
                scatter_rows::<D, K, W, false, 1>(
                    st.lane(ln),
                    stride,
                    tile,
                    [&mut *col],
                    [volume],
                    |r| (r[0], 0.0),
                );
            }
        }
    }
}

/// Step 2: the nodal volumes of `col` become fills, the images folded and read.
pub(crate) fn fills<const D: usize>(ctx: &Ctx<'_, D>, col: &mut [Real], axisymmetric: bool) {
    let (geom, bx) = (&ctx.geom, &ctx.active);
    geom.fold_scalar_images(col, bx);
    let h = geom.h;
    let cell = (0..D).fold(1.0, |v: Real, _| v * h);
    let n = col.len();
    bx.for_each_line(geom.stride, n, |r| {
        for node in r {
            let size = if axisymmetric {
                let i = (node / geom.stride[0]) % geom.nodes[0];
                cell * (geom.origin[0] + i as Real * h).max(0.5 * h)
            } else {
                cell
            };
            if let Some(v) = col.get_mut(node) {
                *v /= size;
            }
        }
    });
    geom.read_scalar_images(col, bx);
}

/// What step 3 changes of the particles, taken out of the particle view (which the pass reads
/// the positions and materials of): `H`, `tau / rho0` and the hoop stretch.
pub(crate) struct FluidState<'a, const D: usize> {
    pub h: [[&'a mut [Real]; D]; D],
    pub tau: [&'a mut [Real]; 6],
    pub hoop: &'a mut [Real],
}

impl<'a, const D: usize> FluidState<'a, D> {
    /// Takes the columns out of `p` (leaving them empty there).
    pub fn take(p: &mut ParticleCols<'a, D>) -> Self {
        FluidState {
            h: p.h.each_mut().map(|r| r.each_mut().map(core::mem::take)),
            tau: p.tau.each_mut().map(core::mem::take),
            hoop: core::mem::take(&mut p.hoop),
        }
    }
}

/// Step 3 on the particles `0..count` of `p`, from the fills of `g`, with the instance's
/// `stencils`. Like [`scatter`], one copy per form, not one per instance: the two loops are
/// scalar per particle but for their stencils, which they call through the instance's table;
/// compiled into every instance they added 0.58 MB to the library, and in the baseline
/// instance alone they made a fluid's step 1.88 times as long, not 1.65.
#[inline(never)]
pub(crate) fn relax<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    stencils: StencilsFn<D, K, S, W>,
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &GridCols<'_, D>,
    state: FluidState<'_, D>,
) {
    let FluidState { h, mut tau, hoop } = state;
    let (n, stride) = (g.len(), ctx.geom.stride);
    let fill = &*g.acc[0];
    let short = h.iter().flatten().any(|c| c.len() < count);
    if fill.len() != n || short || (S::AXISYMMETRIC && hoop.len() < count) {
        return; // Unreachable: the columns are the world's.
    }
    let relaxing = |i: usize| {
        ctx.materials
            .get(p.material[i] as usize)
            .filter(|r| relaxes(r))
    };
    // Relaxed toward the least crowd, not to 1: the map stays continuous where the fill
    // crosses it, so the round-off of the sums cannot switch a particle's J.
    let ln_crowd = ln_1p(CROWD);
    let mut st = Stencils::<D, K, W>::default();
    for start in (0..count).step_by(W) {
        // A chunk without a fluid computes no stencils.
        if !(start..(start + W).min(count)).any(|i| relaxing(i).is_some()) {
            continue;
        }
        let live = chunk_stencils(stencils, &mut st, shape, ctx, p, start, count, n);
        for ln in live.iter() {
            let i = start + ln;
            let Some(rec) = relaxing(i) else {
                continue;
            };
            // SAFETY: `chunk_stencils` checked the rows of a live lane.
            let ([phi], _) =
                unsafe { gather_rows::<D, K, W, false, 1>(st.lane(ln), stride, [fill]) };
            if !(phi > 1.0 + CROWD && phi.is_finite()) {
                continue;
            }
            let share = (rec.volume_relaxation * ctx.dt).min(1.0);
            let old = Deformation::<D>::new(
                core::array::from_fn(|a| core::array::from_fn(|b| h[a][b][i])),
                if S::AXISYMMETRIC { hoop[i] } else { 0.0 },
            );
            let eigen = eigenstrain_at(
                rec,
                core::array::from_fn(|f| {
                    ctx.eigenstrain[f].then(|| p.scalar[f][1].get(i).copied().unwrap_or(0.0))
                }),
            );
            let phim1 = exp_m1((ln_1p(phi - 1.0) - ln_crowd) * share);
            let Some((new, change)) =
                squeeze(rec, &old, phim1, S::AXISYMMETRIC, eigen, ctx.jm1_band[0])
            else {
                continue;
            };
            for (t, c) in tau
                .iter_mut()
                .zip(change)
                .take(crate::layout::stress_components(D))
            {
                t[i] += c;
            }
            for a in 0..D {
                for b in 0..D {
                    h[a][b][i] = new.h[a][b];
                }
            }
            if S::AXISYMMETRIC {
                hoop[i] = new.hzz;
            }
        }
    }
}

/// A fluid particle's deformation `old` with its volume ratio divided by `1 + phim1`, as the
/// fluid keeps it, `J^(1/n) I` (E45), and the change of its stored `tau / rho0` (under the
/// isotropic eigenstrain `eigen`); `None` where the new `J - 1` falls below `lo` or a stress is
/// not finite.
fn squeeze<const D: usize>(
    rec: &MaterialRecord,
    old: &Deformation<D>,
    phim1: Real,
    axisymmetric: bool,
    eigen: Real,
    lo: Real,
) -> Option<(Deformation<D>, [Real; 6])> {
    // `J / (1 + phim1) - 1`, without forming J.
    let jm1 = (old.jm1 - phim1) / (1.0 + phim1);
    if jm1.is_nan() || jm1 < lo {
        return None;
    }
    let dims = if D == 3 || axisymmetric { 3.0 } else { 2.0 };
    let e = exp_m1(ln_1p(jm1) / dims);
    let new = Deformation::<D>::new(
        core::array::from_fn(|a| core::array::from_fn(|b| if a == b { e } else { 0.0 })),
        if axisymmetric { e } else { 0.0 },
    );
    let (was, now) = (
        fluid_stress(rec, old, eigen)?,
        fluid_stress(rec, &new, eigen)?,
    );
    let change: [Real; 6] = core::array::from_fn(|k| now[k] - was[k]);
    change
        .iter()
        .all(|c| c.is_finite())
        .then_some((new, change))
}
