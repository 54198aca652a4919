//! Heat conduction and diffusion (seeds/000 sections 8 and 9): a scalar on the particles moved
//! through the grid as momentum is, one substep at a time, with the particles where the substep
//! starts. One code path for both fields; they differ only in what a particle's capacity and
//! conductance are:
//!
//! | field | value `phi_p` | capacity `c_p` | conductance `kappa_p` | source `s_p` |
//! |---|---|---|---|---|
//! | heat | temperature T, K | thermal mass `m_p C_p`, J/K (eq 133) | conductivity k, W/(m K) | W/m^3 |
//! | diffusion | concentration potential mu | current volume `V_p = J V0`, m^3 (eq 146) | diffusivity D, m^2/s | 1/s |
//!
//! 1. scatter: nodal capacity `c_i = sum S_ip c_p` and momentum `p_i = sum S_ip c_p phi_p`
//!    (eqs 133, 146; eq 138 writes the nodal thermal mass with `m_p`, where the thermal mass
//!    `m_p C_p` of eq 133 is meant), then `phi_i = p_i / c_i` with the fixed faces applied;
//! 2. flow: `Q_i = sum V_p (q_p . G_ip + s_p S_ip)` with `q_p = -kappa_p sum phi_i G_ip`
//!    (eqs 135, 137, 148, 150), plus the flux faces' inflow (eqs 136, 149), then the rate
//!    `a_i = Q_i / c_i` (eqs 140, 152); on a fixed face the nodes hold the fixed value, so their
//!    rate is 0 and the flow into them leaves the domain. (Driving the particles' average at a
//!    fixed node to the fixed value, as a stick wall does with velocity, would pin the
//!    particles next to the wall to the wall's value: an O(h) error there, measured as
//!    order 1.5 convergence instead of 2.)
//! 3. update: `phi_p += dt sum S_ip a_i`, always FLIP (eqs 141, 153: PIC would conduct even
//!    with zero conductivity), and the grid's value at the particle
//!    `phi_g->p = sum S_ip (phi_i + a_i dt)` (eq 144), which features that depend on the field
//!    read (section 8.2).
//!
//! These passes are scalar loops over the particles (the mechanics' vectorised passes are not
//! shared); they run only for a declared field.

use super::Ctx;
use crate::effects::{ScalarBoundary, Transport};
use crate::grid::{GridCols, NodeBox};
use crate::material::Deformation;
use crate::math::Mat;
use crate::particles::{ParticleCols, ACTIVE};
use crate::shape::{Shape1D, Stencil};
use crate::Real;

/// Index of heat conduction in the per-field arrays (diffusion is 1: [`crate::ScalarField`]).
const HEAT: usize = crate::ScalarField::Temperature as usize;

/// One substep of field `f` (HEAT or DIFFUSION) with its definition `t`.
pub(crate) fn substep<const D: usize, const K: usize, S: Shape1D<K>>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
    f: usize,
    t: &Transport,
) {
    let n = g.len();
    if p.scalar[f][0].len() < count || g.scalar[f].iter().any(|c| c.len() != n) {
        return; // Unreachable: the field is declared, so its columns exist.
    }
    for c in g.scalar[f].iter_mut() {
        c.fill(0.0);
    }
    let geom = &ctx.geom;
    // The transported scalars' passes work on the whole grid.
    let all = NodeBox::all(geom.nodes);
    let stencil = |p: &ParticleCols<'_, D>, i: usize| {
        let s: [Real; D] = core::array::from_fn(|a| (p.x[a][i] - geom.origin[a]) * geom.inv_h);
        let stretch = p.domain_stretch::<K, S>(i);
        Stencil::<D, K>::new(shape, s, stretch, geom.nodes, geom.stride, geom.inv_h)
    };
    // 1. Capacity and momentum.
    for i in 0..count {
        if p.status[i] != ACTIVE {
            continue;
        }
        let (cap, _) = capacity_and_conductance(ctx, p, i, f);
        let phi = p.scalar[f][0][i];
        let st = stencil(p, i);
        let [c_col, m_col, _, _] = &mut g.scalar[f];
        st.for_each_node(geom.stride, |node, w, _| {
            if let (Some(c), Some(m)) = (c_col.get_mut(node), m_col.get_mut(node)) {
                *c += w * cap;
                *m += w * cap * phi;
            }
        });
    }
    let cutoff = ctx.mass_cutoff;
    {
        let [c_col, m_col, v_col, _] = &mut g.scalar[f];
        geom.fold_mirror(c_col, 1.0, &all);
        geom.fold_mirror(m_col, 1.0, &all);
        for ((v, &m), &c) in v_col.iter_mut().zip(m_col.iter()).zip(c_col.iter()) {
            *v = if c > cutoff { m / c } else { 0.0 };
        }
        for_each_face(ctx, t, |node, bc, _, _| {
            if let (ScalarBoundary::Fixed(value), Some(v)) = (bc, v_col.get_mut(node)) {
                *v = value;
            }
        });
        geom.mirror(v_col, 1.0, &all);
    }
    // 2. Flow.
    for i in 0..count {
        if p.status[i] != ACTIVE {
            continue;
        }
        let (_, kappa) = capacity_and_conductance(ctx, p, i, f);
        let volume = current_volume(p, i);
        let source = p.scalar[f][2].get(i).copied().unwrap_or(0.0);
        let st = stencil(p, i);
        let [_, _, v_col, q_col] = &mut g.scalar[f];
        let mut grad = [0.0 as Real; D];
        st.for_each_node(geom.stride, |node, _, gw| {
            let v = v_col.get(node).copied().unwrap_or(0.0);
            for a in 0..D {
                grad[a] += v * gw[a];
            }
        });
        st.for_each_node(geom.stride, |node, w, gw| {
            let mut q_dot_g = 0.0;
            for a in 0..D {
                q_dot_g -= kappa * grad[a] * gw[a];
            }
            if let Some(q) = q_col.get_mut(node) {
                *q += volume * (q_dot_g + source * w);
            }
        });
    }
    {
        // The flux faces' inflow on the wall plane, by the trapezoid rule over the admissible
        // face (per unit thickness in 2D), then the rate; a fixed face's rate takes the node
        // to its value.
        let [c_col, _, _, q_col] = &mut g.scalar[f];
        geom.fold_mirror(q_col, 1.0, &all);
        for_each_face(ctx, t, |node, bc, axis, on_wall| {
            if let (ScalarBoundary::Flux(flux), true, Some(q)) = (bc, on_wall, q_col.get_mut(node))
            {
                *q += flux * face_area(geom, axis, node, S::AXISYMMETRIC);
            }
        });
        for (q, &c) in q_col.iter_mut().zip(c_col.iter()) {
            *q = if c > cutoff { *q / c } else { 0.0 };
        }
        for_each_face(ctx, t, |node, bc, _, _| {
            if let (ScalarBoundary::Fixed(_), Some(q)) = (bc, q_col.get_mut(node)) {
                *q = 0.0;
            }
        });
        geom.mirror(q_col, 1.0, &all);
    }
    // 3. FLIP update of the particles' values.
    for i in 0..count {
        if p.status[i] != ACTIVE {
            continue;
        }
        let st = stencil(p, i);
        let [_, _, value, rate] = &g.scalar[f];
        let (mut a, mut on_grid) = (0.0, 0.0);
        st.for_each_node(geom.stride, |node, w, _| {
            let r = rate.get(node).copied().unwrap_or(0.0);
            a += w * r;
            on_grid += w * (value.get(node).copied().unwrap_or(0.0) + r * ctx.dt);
        });
        let next = p.scalar[f][0][i] + a * ctx.dt;
        // A non-finite rate (from a non-finite source or value set by the host) leaves the
        // values as they were rather than spreading NaN.
        if next.is_finite() && on_grid.is_finite() {
            p.scalar[f][0][i] = next;
            if let Some(gv) = p.scalar[f][1].get_mut(i) {
                *gv = on_grid;
            }
        }
    }
}

/// Capacity `c_p` and conductance `kappa_p` of particle `i` for field `f` (see the module's
/// table); zeros for a material id that names no material.
#[inline]
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
        (current_volume(p, i), rec.diffusivity)
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

/// `J V0` of particle `i` (with `F_thetatheta` when axisymmetric).
#[inline]
fn current_volume<const D: usize>(p: &ParticleCols<'_, D>, i: usize) -> Real {
    let h: Mat<D> = core::array::from_fn(|a| core::array::from_fn(|b| p.h[a][b][i]));
    let hoop = p.hoop.get(i).copied().unwrap_or(0.0);
    (1.0 + Deformation::new(h, hoop).jm1) * p.vol0[i]
}

/// Calls `f(node, condition, axis, on_wall_plane)` for every node of every face layer (see
/// [`crate::grid::Geom::for_each_face_node`]) whose face is not insulated.
fn for_each_face<const D: usize>(
    ctx: &Ctx<'_, D>,
    t: &Transport,
    mut f: impl FnMut(usize, ScalarBoundary, usize, bool),
) {
    // The transported scalars' passes work on the whole grid.
    let all = NodeBox::all(ctx.geom.nodes);
    for axis in 0..D {
        for side in 0..2 {
            let bc = t.faces[2 * axis + side];
            if bc != ScalarBoundary::Insulated {
                ctx.geom
                    .for_each_face_node(axis, side, &all, |node, wall| f(node, bc, axis, wall));
            }
        }
    }
}
