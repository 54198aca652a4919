//! The phases of one explicit step (E12-E32), one file each. The order in which
//! a step calls them lives in [`crate::world`] and only there.
//!
//! Every phase is generic over the dimension `D`, the stencil width `K` and the shape family
//! `S` (and compiled once per instruction set: [`kernels`] and `world::passes`); the world dispatches once per substep
//! to the monomorphised instance. Everything else a substep is configured with (update order,
//! transfer, damping, forces, transported scalars) is a value of [`Ctx`] that the passes test
//! once per chunk of lanes, never per particle.

pub(crate) mod g2p;
pub(crate) mod gather;
pub(crate) mod grid_update;
pub(crate) mod kernels;
pub(crate) mod momentum;
pub(crate) mod p2g;
pub(crate) mod stress;
pub(crate) mod tractions;
pub(crate) mod transport;
pub(crate) mod update;
pub(crate) mod volume;
pub(crate) mod xpic;

pub(crate) use kernels::Kernels;

use crate::grid::{Geom, NodeBox};
use crate::layout::{MaterialRecord, TractionRecord};
use crate::particles::ParticleCols;
use crate::shape::{Shape1D, Stencils};
use crate::simd::lanes::{load, Lane};
use crate::simd::rows::Compare;
use crate::simd::wide::Wide;
use crate::Real;

/// Everything a phase needs that is constant during one substep.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'m, const D: usize> {
    pub geom: Geom<D>,
    /// The nodes this substep touches; the grid passes work on them alone.
    pub active: NodeBox<D>,
    pub dt: Real,
    /// Where the stress update sits in the substep.
    pub order: crate::UpdateOrder,
    /// APIC (E78-E80) in place of FLIP.
    pub apic: bool,
    /// MLS-MPM (with `apic`): the momentum passes' gradients are the MLS gradient
    /// ([`crate::shape::Stencils::use_mls_gradient`]).
    pub mls: bool,
    /// FLIP moves the particles with their own new velocity ([`crate::Transfer::FlipParticleVelocity`]).
    pub particle_velocity: bool,
    /// The momentum approach ([`crate::Transfer::FlipMomentum`], [`momentum`]): its own
    /// gradient, force and position update.
    pub momentum: bool,
    /// XPIC's or FMPM's order and whether it is FMPM ([`crate::Transfer::series`], [`xpic`]).
    pub series: Option<(u32, bool)>,
    /// Particle forces declared: the scatter adds `S_ip F_p`.
    pub forces: bool,
    /// Damping in the particle update declared (a particle rate, per-particle rates, or the
    /// grid rate there): the particle update subtracts the damping acceleration.
    pub damp: bool,
    pub gravity: [Real; D],
    /// The body force's change with position this substep, `G(t)` of `b = b0 + G x`
    /// ([`crate::Effects::body_force_gradient`]); `None` where it is zero.
    pub body_gradient: Option<[[Real; D]; D]>,
    pub beta: Real,
    /// Grid and particle damping this substep, `alpha_g(t)` (thermostat included) and
    /// `alpha_p(t)`, 1/s (0 unless damping is declared).
    pub alpha_g: Real,
    pub alpha_p: Real,
    /// The damping the grid update subtracts from the nodal acceleration (the grid rate on
    /// the force, the zones), if any.
    pub nodal_damping: Option<crate::effects::damping::NodalDamping>,
    /// Half-width of an undeformed particle domain, `h / (2 n)`, m (tractions, colliders).
    pub half_width: Real,
    /// How far outside a collider's surface a node may be in contact, m: the grid functions'
    /// reach (E91, [`crate::ShapeFunction::grid_function_reach`]).
    pub contact_band: Real,
    /// The world's particles (`0..particles`): the colliders' contact reads them (E91).
    pub particles: usize,
    pub exp_terms: u32,
    /// The runaway band of `J - 1`, `[1 / r - 1, r - 1]` with `r` the definition's
    /// `max_volume_ratio`: a particle whose `J - 1` leaves it in a stress update freezes.
    pub jm1_band: [Real; 2],
    /// The largest Real over `Resolvable::speed` (s/m): a speed times it overflows where it
    /// passes what a stable step of `MIN_STABLE_DT` resolves, and the particle freezes.
    pub speed_scale: Real,
    /// Nodes lighter than this are treated as empty (velocity and acceleration zero).
    pub mass_cutoff: Real,
    pub materials: &'m [MaterialRecord],
    /// The traction table's used entries.
    pub tractions: &'m [TractionRecord],
    /// The collider table's used entries, and the world time the substep starts at (their
    /// poses, E90).
    pub colliders: &'m [crate::layout::ColliderRecord],
    /// The distance fields' samples.
    pub sdf: &'m [Real],
    pub time: f64,
    /// The tractions' time factors this substep, one per schedule.
    pub traction_scales: [Real; crate::TRACTION_SCHEDULES],
    /// The transported scalars declared (heat, diffusion).
    pub transport: [Option<crate::Transport>; 2],
    /// Per transported scalar: declared, and some material expands (heat) or swells
    /// (diffusion) with it, so the stress update takes the eigenstrain out.
    pub eigenstrain: [bool; 2],
    /// Plasticity is declared: the plastic history column is read and written.
    pub plastic: bool,
    /// Some material has a viscosity: the stress update adds the viscous stress.
    pub viscous: bool,
    /// Some material is a fluid that relaxes its volume: each substep starts with that (E97,
    /// [`volume`]).
    pub fluid: bool,
}

/// Replaces `st` by the stencils of the chunk (particles `start..start + W` of `p`) at
/// `x[axis][lane]` (with their first moments when `affine`, and each lane's x factors when
/// `lanes`: see [`Stencils::fill_lanes`]). A family whose domain stretches (cpGIMP) also reads the
/// chunk's deformation gradients.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn stencils<
    I: Compare,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
>(
    st: &mut Stencils<D, K, W>,
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    start: usize,
    x: &[Lane<W>; D],
    affine: bool,
    lanes: bool,
    mls: bool,
) {
    let stretch = p.stretch_columns();
    stencils_of::<I, D, K, S, W>(st, shape, ctx, &stretch, start, x, affine, lanes, mls);
}

/// [`stencils`] with the particles' domain stretches (cpGIMP; empty columns for every other
/// family) in place of their columns.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn stencils_of<
    I: Compare,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
>(
    st: &mut Stencils<D, K, W>,
    shape: &S,
    ctx: &Ctx<'_, D>,
    stretch: &[&[Real]; D],
    start: usize,
    x: &[Lane<W>; D],
    affine: bool,
    lanes: bool,
    mls: bool,
) {
    let geom = &ctx.geom;
    // The positions in cell units from the grid's origin.
    let mut s = [[0.0; W]; D];
    for at in (0..W).step_by(I::N) {
        for a in 0..D {
            ((Wide::<I>::load(&x[a], at) - geom.origin[a]) * geom.inv_h).store(&mut s[a], at);
        }
    }
    // cpGIMP's domain stretches; other families read none, and the chunk loads none.
    let stretch: Option<[Lane<W>; D]> = if !stretch[0].is_empty() {
        Some(core::array::from_fn(|a| load(stretch[a], start)))
    } else {
        None
    };
    st.compute::<S>(
        shape,
        &s,
        stretch.as_ref(),
        geom.nodes,
        geom.stride,
        geom.inv_h,
        affine || mls,
    );
    if mls {
        st.use_mls_gradient();
    }
    if lanes {
        st.fill_lanes::<S>(affine);
    }
}
