//! Heat conduction and diffusion (E54-E64): a scalar on the particles moved
//! through the grid as momentum is, one substep at a time, with the particles where the substep
//! starts. One code path for both fields; they differ only in what a particle's capacity and
//! conductance are:
//!
//! | field | value `phi_p` | capacity `c_p` | conductance `kappa_p` | source `s_p` |
//! |---|---|---|---|---|
//! | heat | temperature T, K | thermal mass `m_p C_p`, J/K (E56) | conductivity k, W/(m K) | W/m^3 |
//! | diffusion | concentration potential mu | current volume `V_p = J V0`, m^3 (E56) | diffusivity D, m^2/s | 1/s |
//!
//! 1. scatter: nodal capacity `c_i = sum S_ip c_p` and momentum `p_i = sum S_ip c_p phi_p`
//!    (E56; Nairn's notes write the nodal thermal mass with `m_p`, where the thermal mass
//!    `m_p C_p` is meant), then `phi_i = p_i / c_i` with the fixed faces applied (E57);
//! 2. flow: `Q_i = sum V_p (q_p . G_ip + s_p S_ip)` with `q_p = -kappa_p sum phi_i G_ip`
//!    (E58, E59), plus the flux faces' inflow (E60), then the rate
//!    `a_i = Q_i / c_i` (E61); on a fixed face the nodes hold the fixed value, so their
//!    rate is 0 and the flow into them leaves the domain;
//! 3. update: `phi_p += dt sum S_ip a_i`, always FLIP (E62: PIC would conduct even
//!    with zero conductivity), and the grid's value at the particle
//!    `phi_g->p = sum S_ip (phi_i + a_i dt)` (E63), which features that depend on the field
//!    read.
//!
//! A fixed face (E64; the notes leave its treatment open) acts on the particles as on the
//! grid:
//! - past the wall plane the field is the material's odd image about the fixed value: the
//!   particles' contributions to nodes past the plane go to their images with value
//!   `2 phi_f - phi` (so a node near the face averages both sides), those nodes take
//!   `2 phi_f - phi` of their image, and their rate the negated rate. A field with a slope at
//!   the face keeps it there; the B-splines, whose stencils reach past the plane, converge at
//!   second order on the grid (first order with a constant value there);
//! - a particle takes the grid's value in the measure `w = sum S_ip` of its weight on the
//!   face's nodes: `phi_p <- flip + w (phi_g->p - flip)`. The FLIP update alone never gives a
//!   particle the jump from its value to the face's: after a step change at the face the
//!   particle next to it stayed most of the step away at every resolution. A particle away
//!   from the face (`w = 0`) keeps its FLIP value exactly. Measured orders are in
//!   `tests/kernel/transport.rs`.
//!
//! The particle loops work as the momentum passes do: chunk by chunk, with the chunk's stencils
//! computed lane-fastest ([`chunk_stencils`]) and each particle's nodes added to or read from
//! in 4-wide stencil rows ([`scatter_rows`], [`gather_rows`]). They run only for a declared
//! field. Each loop is one call ([`particles`] with a [`FieldPass`]), so that the parallel
//! step runs the scatters by tiles of the grid and the update by ranges of particles, as it
//! runs the momentum passes.

use super::{Ctx, Kernels};
use crate::cut::Tile;
use crate::def::{ScalarBoundary, Transport};
use crate::grid::{add_row, load_row, rows_fit, GridCols};
use crate::layout::MaterialRecord;
use crate::material::{volume_ratio_minus_one, Deformation};
use crate::math::Mat;
use crate::particles::ParticleCols;
use crate::shape::{LaneStencil, Row4, Shape1D, Stencil, Stencils};
use crate::simd::lanes::{live_lanes, load, Lane, Lanes};
use crate::Real;

/// The order in which a chunk's lanes are scattered to a field's columns: 0, W/2, 1, W/2 + 1,
/// ... Two particles scattered one after the other then come from two halves of the chunk,
/// which in a lattice fill are cells apart, so the second does not load a stencil row that
/// overlaps, at an offset, a row the first has just stored (a load that partly overlaps a
/// pending store waits for the store to complete instead of taking its value from the store
/// buffer). A table, not a formula per lane: the scatter loop is not unrolled, and the formula
/// cost 10 instructions per particle-step (callgrind); the passes evaluate it at compile time.
pub(super) const fn scatter_order<const W: usize>() -> [usize; W] {
    let mut order = [0; W];
    let mut t = 0;
    while t < W {
        order[t] = (t % 2) * (W / 2) + t / 2;
        t += 1;
    }
    order
}

/// Index of heat conduction in the per-field arrays (diffusion is 1: [`crate::ScalarField`]).
const HEAT: usize = crate::ScalarField::Temperature as usize;

/// One particle loop of a field's substep (the module docs' 1, 2 and 3). Between them come
/// the grid's sides ([`reset`] before the first, [`nodal_values`], [`nodal_rates`]);
/// `world::parallel` runs them in that order, the scatters by tiles of the grid and the update
/// by ranges of particles.
pub(crate) enum FieldPass<'v, 'g, const D: usize> {
    /// 1. The capacity and momentum of the particles onto the nodes of `g` (a tile's, or the
    ///    whole grid's).
    Capacity(&'v mut GridCols<'g, D>),
    /// 2. The flow onto the nodes of `g`, from the nodal values (which a tile reads whole,
    ///    [`GridCols::whole`]).
    Flow(&'v mut GridCols<'g, D>),
    /// 3. The particles' values from the nodal rates of `g`: `value` and `on_grid` are the
    ///    field's particle columns 0 and 1 (taken out of the particle view); `fixed`, whether
    ///    a face is fixed (its nodes marked, [`nodal_rates`]).
    Update {
        g: &'v GridCols<'g, D>,
        value: &'v mut [Real],
        on_grid: &'v mut [Real],
        fixed: bool,
    },
}

/// The particle loop `pass` of field `f` (HEAT or DIFFUSION) over the particles `0..count`
/// (inlined into each instruction set's instance, `world::passes`).
#[inline(always)]
pub(crate) fn particles<
    I: Kernels,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    f: usize,
    pass: FieldPass<'_, '_, D>,
) {
    let stride = ctx.geom.stride;
    let mut st = Stencils::<D, K, W>::default();
    let stencils = I::stencils::<D, K, S, W>;
    // The scatters read the particles' values, the update writes them.
    let values = match &pass {
        FieldPass::Update { value, .. } => value.len(),
        _ => p.scalar[f][0].len(),
    };
    if values < count {
        return; // Unreachable: the field is declared, so its columns exist.
    }
    match pass {
        FieldPass::Capacity(g) => {
            let (n, tile, chunks) = (g.len(), g.tile, g.chunks(count, W, stride[D - 1]));
            let whole_grid = tile == Tile::ALL;
            let [c_col, m_col, _, _] = &mut g.scalar[f];
            if c_col.len() != n || m_col.len() != n {
                return; // Unreachable, as above.
            }
            // A tile's rows are clipped to it (`Tile::own`); the whole grid's must fit.
            let fit = if whole_grid { n } else { usize::MAX };
            for start in chunks {
                let live = chunk_stencils(stencils, &mut st, shape, ctx, p, start, count, fit);
                for ln in const { scatter_order::<W>() } {
                    if live.has(ln) {
                        let i = start + ln;
                        let (cap, _) = capacity_and_conductance(ctx, p, i, f);
                        let phi = p.scalar[f][0][i];
                        let cols = [&mut **c_col, &mut **m_col];
                        // SAFETY: `chunk_stencils` checked the rows of a live lane against the
                        // whole grid's columns; a tile's are clipped.
                        unsafe {
                            scatter_rows::<D, K, W, false, 2>(
                                st.lane(ln),
                                stride,
                                tile,
                                cols,
                                [cap, cap * phi],
                                |r| (r[0], 0.0),
                            );
                        }
                    }
                }
            }
        }
        // The gradient of the nodal values at the particle, then `V_p (q_p . G_ip + s_p S_ip)`
        // on its nodes.
        FieldPass::Flow(g) => {
            let (n, tile, chunks) = (g.len(), g.tile, g.chunks(count, W, stride[D - 1]));
            let whole_grid = tile == Tile::ALL;
            let [_, _, own, q_col] = &mut g.scalar[f];
            let values: &[Real] = if own.is_empty() { g.whole } else { own };
            // The whole grid's flow adds rows where its values are read.
            if q_col.len() != n || (whole_grid && values.len() != n) {
                return; // Unreachable, as above.
            }
            for start in chunks {
                let live =
                    chunk_stencils(stencils, &mut st, shape, ctx, p, start, count, values.len());
                for ln in const { scatter_order::<W>() } {
                    if !live.has(ln) {
                        continue;
                    }
                    let i = start + ln;
                    let (_, kappa) = capacity_and_conductance(ctx, p, i, f);
                    let Some(rec) = ctx.materials.get(p.material[i] as usize) else {
                        continue;
                    };
                    let volume = current_volume(rec, p, i);
                    let source = p.scalar[f][2].get(i).copied().unwrap_or(0.0);
                    let lane = st.lane(ln);
                    // SAFETY: `chunk_stencils` checked the rows against the values.
                    let (_, grad) =
                        unsafe { gather_rows::<D, K, W, true, 1>(lane, stride, [values]) };
                    // V (q . G + s S), q = -kappa grad: per row, wx V (s r_0 + sum_{b >= 1} q_b r_b)
                    // + dwx V q_0 r_0.
                    let vq: [Real; D] = core::array::from_fn(|a| -(volume * kappa) * grad[a]);
                    let vs = volume * source;
                    // SAFETY: the rows fit the flow's column, the values' length (the whole
                    // grid), or are clipped to a tile.
                    unsafe {
                        scatter_rows::<D, K, W, true, 1>(lane, stride, tile, [q_col], [1.0], |r| {
                            (
                                (1..D).fold(vs * r[0], |c, b| c + vq[b] * r[b]),
                                vq[0] * r[0],
                            )
                        });
                    }
                }
            }
        }
        // FLIP update of the particles' values, and the grid's value at each particle.
        FieldPass::Update {
            g,
            value,
            on_grid,
            fixed,
        } => {
            let n = g.len();
            let [marker, values, rate] = [&*g.scalar[f][1], &*g.scalar[f][2], &*g.scalar[f][3]];
            if [marker, values, rate].iter().any(|c| c.len() != n) {
                return; // Unreachable, as above.
            }
            for start in (0..count).step_by(W) {
                let live = chunk_stencils(stencils, &mut st, shape, ctx, p, start, count, n);
                for ln in live.iter() {
                    let i = start + ln;
                    // SAFETY: `chunk_stencils` checked the rows of a live lane.
                    let (a, v, w) = unsafe {
                        let lane = st.lane(ln);
                        if fixed {
                            let ([a, v, w], _) = gather_rows::<D, K, W, false, 3>(
                                lane,
                                stride,
                                [rate, values, marker],
                            );
                            (a, v, w)
                        } else {
                            let ([a, v], _) =
                                gather_rows::<D, K, W, false, 2>(lane, stride, [rate, values]);
                            (a, v, 0.0)
                        }
                    };
                    let grid_value = v + a * ctx.dt;
                    let flip = value[i] + a * ctx.dt;
                    // Next to a fixed face the particle takes the grid's value in the measure
                    // `w` of its weight on the face's nodes.
                    let next = if fixed {
                        flip + w * (grid_value - flip)
                    } else {
                        flip
                    };
                    // A non-finite rate (from a non-finite source or value set by the host)
                    // leaves the values as they were rather than spreading NaN.
                    if next.is_finite() && grid_value.is_finite() {
                        value[i] = next;
                        if let Some(gv) = on_grid.get_mut(i) {
                            *gv = grid_value;
                        }
                    }
                }
            }
        }
    }
}

/// The grid's side of a substep, between the particle loops: functions of the dimension
/// only, one copy each rather than one per shape family and instruction set.
///
/// Resets a field's node columns `cols` on the substep's node box (every node a particle's
/// stencil row reads), before its first particle loop.
pub(crate) fn reset<const D: usize>(ctx: &Ctx<'_, D>, cols: &mut [&mut [Real]; 4]) {
    for c in cols.iter_mut() {
        zero_lines(ctx, c);
    }
}

/// Zeroes `col` on the substep's node box.
pub(crate) fn zero_lines<const D: usize>(ctx: &Ctx<'_, D>, col: &mut [Real]) {
    ctx.active.for_each_line(ctx.geom.stride, col.len(), |r| {
        if let Some(c) = col.get_mut(r) {
            c.fill(0.0);
        }
    });
}

/// After the scatter of capacity `c_i` and momentum `p_i` (`cols` = [c, p, value, rate]): the
/// nodal values `phi_i = p_i / c_i` (E57), with the axis mirror, the fixed faces and
/// their odd images.
pub(crate) fn nodal_values<const D: usize>(
    ctx: &Ctx<'_, D>,
    cols: &mut [&mut [Real]; 4],
    t: &Transport,
) {
    let (geom, bx, cutoff) = (&ctx.geom, &ctx.active, ctx.mass_cutoff);
    let n = cols[0].len();
    let [c_col, m_col, v_col, _] = cols;
    geom.fold_scalar_images(c_col, bx);
    geom.fold_scalar_images(m_col, bx);
    // Past a fixed face the material's odd image about the fixed value: what the particles
    // put on a node past the wall plane, their images put on its image (capacity `c`,
    // value `2 phi_f - phi`), so that a node near the face averages both sides.
    for_each_fixed_image(ctx, t, &mut |ghost, image, value| {
        if let (Some(&cg), Some(&mg), true) = (
            c_col.get(ghost),
            m_col.get(ghost),
            image < c_col.len().min(m_col.len()),
        ) {
            c_col[image] += cg;
            m_col[image] += 2.0 * value * cg - mg;
        }
    });
    bx.for_each_line(geom.stride, n, |r| {
        let (Some(v), Some(m), Some(c)) =
            (v_col.get_mut(r.clone()), m_col.get(r.clone()), c_col.get(r))
        else {
            return; // Unreachable: every line lies within the columns.
        };
        for ((v, &m), &c) in v.iter_mut().zip(m).zip(c) {
            *v = if c > cutoff { m / c } else { 0.0 };
        }
    });
    for_each_face(ctx, t, &mut |node, bc, _, _| {
        if let (ScalarBoundary::Fixed(value), Some(v)) = (bc, v_col.get_mut(node)) {
            *v = value;
        }
    });
    // Past a fixed face's wall plane, the odd extension about the fixed value (a field
    // with a slope at the face keeps it there: the B-splines' wider stencils read these
    // nodes).
    for_each_fixed_image(ctx, t, &mut |ghost, image, value| {
        if let (Some(&vi), true) = (v_col.get(image), ghost < v_col.len()) {
            v_col[ghost] = 2.0 * value - vi;
        }
    });
    geom.read_scalar_images(v_col, bx);
}

/// After the scatter of the flow `Q_i` (`cols` = [c, p, value, rate]): the flux faces'
/// inflow, the rates `a_i = Q_i / c_i` (E61) with the fixed faces and their images,
/// and, when a face is fixed, its nodes marked with 1 in the momentum column (free since the
/// values were formed) for the particle update. Returns whether a face is fixed.
pub(crate) fn nodal_rates<const D: usize>(
    ctx: &Ctx<'_, D>,
    cols: &mut [&mut [Real]; 4],
    t: &Transport,
    axisymmetric: bool,
) -> bool {
    let (geom, bx, cutoff) = (&ctx.geom, &ctx.active, ctx.mass_cutoff);
    let n = cols[0].len();
    {
        // The flux faces' inflow on the wall plane, by the trapezoid rule over the admissible
        // face (per unit thickness in 2D), then the rate; a fixed face's rate takes the node
        // to its value.
        let [c_col, _, _, q_col] = &mut *cols;
        geom.fold_scalar_images(q_col, bx);
        // The odd image's flow: its gradient's normal part is the material's, its other parts
        // and its source flip, and so does the gradient of the image node's shape function
        // along the normal: every term changes sign.
        for_each_fixed_image(ctx, t, &mut |ghost, image, _| {
            if let (Some(&qg), true) = (q_col.get(ghost), image < q_col.len()) {
                q_col[image] -= qg;
            }
        });
        for_each_face(ctx, t, &mut |node, bc, axis, on_wall| {
            if let (ScalarBoundary::Flux(flux), true, Some(q)) = (bc, on_wall, q_col.get_mut(node))
            {
                *q += flux * face_area(geom, axis, node, axisymmetric);
            }
        });
        bx.for_each_line(geom.stride, n, |r| {
            let (Some(q), Some(c)) = (q_col.get_mut(r.clone()), c_col.get(r)) else {
                return; // Unreachable: every line lies within the columns.
            };
            for (q, &c) in q.iter_mut().zip(c) {
                *q = if c > cutoff { *q / c } else { 0.0 };
            }
        });
        for_each_face(ctx, t, &mut |node, bc, _, _| {
            if let (ScalarBoundary::Fixed(_), Some(q)) = (bc, q_col.get_mut(node)) {
                *q = 0.0;
            }
        });
        for_each_fixed_image(ctx, t, &mut |ghost, image, _| {
            if let (Some(&qi), true) = (q_col.get(image), ghost < q_col.len()) {
                q_col[ghost] = -qi;
            }
        });
        geom.read_scalar_images(q_col, bx);
    }
    let fixed = t
        .faces
        .iter()
        .any(|b| matches!(b, ScalarBoundary::Fixed(_)));
    if fixed {
        let [_, m_col, _, _] = cols;
        zero_lines(ctx, m_col);
        for_each_face(ctx, t, &mut |node, bc, _, on_wall| {
            if let (ScalarBoundary::Fixed(_), true, Some(m)) = (bc, on_wall, m_col.get_mut(node)) {
                *m = 1.0;
            }
        });
    }
    fixed
}

/// An instance's stencils of a chunk ([`super::Kernels::stencils`]).
pub(crate) type StencilsFn<const D: usize, const K: usize, S, const W: usize> = fn(
    &mut Stencils<D, K, W>,
    &S,
    &Ctx<'_, D>,
    &[&[Real]; D],
    usize,
    &[Lane<W>; D],
    bool,
    bool,
    bool,
);

/// Replaces `st` by the stencils of the chunk at `start`, computed by the instance's
/// `stencils`, and returns its live lanes: active particles below `count` whose every stencil
/// row fits in node columns of length `len` (always, by construction; the unchecked row
/// accesses rely on it).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn chunk_stencils<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    stencils: StencilsFn<D, K, S, W>,
    st: &mut Stencils<D, K, W>,
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    start: usize,
    count: usize,
    len: usize,
) -> Lanes<W> {
    let x: [Lane<W>; D] = core::array::from_fn(|a| load(p.x[a], start));
    // The shape functions' gradients, with MLS-MPM too.
    let stretch = p.stretch_columns();
    stencils(st, shape, ctx, &stretch, start, &x, false, true, false);
    let last = Stencil::<D, K>::last_row_offset(ctx.geom.stride);
    live_lanes(p, start, count) & Lanes::from_fn(|ln| rows_fit(st.lane(ln).base(), last, len))
}

/// Adds `(wx_i c_x(r) + dwx_i c_dx(r)) scale[c]` to `cols[c]` at every node `i` of the
/// stencil, row by row, `(c_x, c_dx) = factors(r)` from the row's factors `r`
/// ([`Stencil::row`]): `S_ip scale` for `factors(r) = (r_0, 0)`, `G_ip . q` for
/// `(sum_{b >= 1} q_b r_b, q_0 r_0)` and a scale of 1. `DX`: whether `c_dx` is used (else
/// skipped). `cols` are the columns of `tile`, which takes its own rows alone ([`Tile::own`]).
///
/// # Safety
/// Every row of the stencil fits in every column ([`rows_fit`]), or `tile` is a tile's.
#[inline(always)]
pub(super) unsafe fn scatter_rows<
    const D: usize,
    const K: usize,
    const W: usize,
    const DX: bool,
    const N: usize,
>(
    st: LaneStencil<'_, D, K, W>,
    stride: [usize; D],
    tile: Tile,
    cols: [&mut [Real]; N],
    scale: [Real; N],
    factors: impl Fn([Real; D]) -> (Real, Real),
) {
    let (wx, dwx) = (st.wx(), st.dwx());
    for k in 0..Stencil::<D, K>::layers() {
        for j in 0..K {
            let (row, r) = st.row(j, k, stride);
            let Some(at) = tile.own(row) else {
                continue;
            };
            let (c_x, c_dx) = factors(r);
            let v = if DX { wx * c_x + dwx * c_dx } else { wx * c_x };
            for c in 0..N {
                // SAFETY: the caller guarantees that the row fits, or it is the tile's.
                unsafe { add_row(cols[c], at, v * scale[c]) };
            }
        }
    }
}

/// `sum_i S_ip u_i` for the nodal values `u = cols[c]` and, with `GRAD`, `sum_i G_ip u_i` of
/// `cols[0]` (else zeros), row by row as the momentum gathers do.
///
/// # Safety
/// Every row of the stencil fits in every column ([`rows_fit`]).
#[inline(always)]
pub(super) unsafe fn gather_rows<
    const D: usize,
    const K: usize,
    const W: usize,
    const GRAD: bool,
    const N: usize,
>(
    st: LaneStencil<'_, D, K, W>,
    stride: [usize; D],
    cols: [&[Real]; N],
) -> ([Real; N], [Real; D]) {
    let mut ru = [Row4::ZERO; N];
    let mut du = [Row4::ZERO; D];
    for k in 0..Stencil::<D, K>::layers() {
        for j in 0..K {
            let (row, r) = st.row(j, k, stride);
            for c in 0..N {
                // SAFETY: the caller guarantees that the row fits.
                let u = unsafe { load_row(cols[c], row) };
                ru[c] += u * r[0];
                if GRAD && c == 0 {
                    for b in 1..D {
                        du[b] += u * r[b];
                    }
                }
            }
        }
    }
    let values = core::array::from_fn(|c| (st.wx() * ru[c]).element_sum());
    let grad = core::array::from_fn(|b| match (GRAD, b) {
        (false, _) => 0.0,
        (true, 0) => (st.dwx() * ru[0]).element_sum(),
        _ => (st.wx() * du[b]).element_sum(),
    });
    (values, grad)
}

/// Capacity `c_p` and conductance `kappa_p` of particle `i` for field `f` (see the module's
/// table); zeros for a material id that names no material.
#[inline(always)]
fn capacity_and_conductance<const D: usize>(
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    i: usize,
    f: usize,
) -> (Real, Real) {
    let Some(rec) = ctx.materials.get(p.material[i] as usize) else {
        return (0.0, 0.0);
    };
    if f == HEAT {
        (p.mass[i] * rec.heat_capacity, rec.conductivity)
    } else {
        (current_volume(rec, p, i), rec.diffusivity)
    }
}

/// The area the node `node` on a wall plane normal to `axis` stands for: its patch, `h` per
/// other axis (per unit thickness in 2D) halved on the admissible region's edges, zero outside
/// it, so that the areas of a plane's nodes sum to the area of the admissible region's face.
/// `axisymmetric`: per radian, `int r dr` over the patch's radial extent, or the plane's
/// radius times the patch for a plane of constant r.
fn face_area<const D: usize>(
    geom: &crate::grid::Geom<D>,
    axis: usize,
    node: usize,
    axisymmetric: bool,
) -> Real {
    let coord = |b: usize| (node / geom.stride[b]) % geom.nodes[b];
    let radius = |idx: usize| geom.origin[0] + idx as Real * geom.h;
    let mut area = if axisymmetric && axis == 0 {
        radius(coord(0))
    } else {
        1.0
    };
    for b in (0..D).filter(|&b| b != axis) {
        let idx = coord(b);
        let (lo, hi) = (geom.margin, geom.nodes[b] - 1 - geom.margin);
        if idx < lo || idx > hi {
            return 0.0;
        }
        // The patch [x_i - h/2, x_i + h/2] in cell units from the node, cut at the edges.
        let from = if idx == lo { 0.0 } else { -0.5 };
        let to = if idx == hi { 0.0 } else { 0.5 };
        area *= if axisymmetric && b == 0 {
            let (r0, r1) = (radius(idx) + from * geom.h, radius(idx) + to * geom.h);
            0.5 * (r1 * r1 - r0 * r0)
        } else {
            (to - from) * geom.h
        };
    }
    area
}

/// `J V0` of particle `i` of material `rec` (with `F_thetatheta` when axisymmetric, and the
/// volume change a model keeps in its history: snow's `J_p`).
#[inline(always)]
pub(super) fn current_volume<const D: usize>(
    rec: &MaterialRecord,
    p: &ParticleCols<'_, D>,
    i: usize,
) -> Real {
    let h: Mat<D> = core::array::from_fn(|a| core::array::from_fn(|b| p.h[a][b][i]));
    let hoop = p.hoop.get(i).copied().unwrap_or(0.0);
    let plastic = p.plastic.get(i).copied().unwrap_or(0.0);
    let jm1 = volume_ratio_minus_one(rec, Deformation::new(h, hoop).jm1, plastic);
    (1.0 + jm1) * p.vol0[i]
}

/// Calls `f(ghost, image, value)` for every node past the wall plane of each fixed face, with
/// its image across the plane and the face's value.
fn for_each_fixed_image<const D: usize>(
    ctx: &Ctx<'_, D>,
    t: &Transport,
    f: &mut dyn FnMut(usize, usize, Real),
) {
    for axis in 0..D {
        for side in 0..2 {
            if let ScalarBoundary::Fixed(value) = t.faces[2 * axis + side] {
                ctx.geom
                    .for_each_face_image(axis, side, &ctx.active, &mut |g, i| f(g, i, value));
            }
        }
    }
}

/// Calls `f(node, condition, axis, on_wall_plane)` for every node of every face layer (see
/// [`crate::grid::Geom::for_each_face_node`]) whose face is not insulated.
fn for_each_face<const D: usize>(
    ctx: &Ctx<'_, D>,
    t: &Transport,
    f: &mut dyn FnMut(usize, ScalarBoundary, usize, bool),
) {
    for axis in 0..D {
        for side in 0..2 {
            let bc = t.faces[2 * axis + side];
            if bc != ScalarBoundary::Insulated {
                ctx.geom
                    .for_each_face_node(axis, side, &ctx.active, &mut |node, wall| {
                        f(node, bc, axis, wall)
                    });
            }
        }
    }
}
