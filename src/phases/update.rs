//! The particle update's equations, one function per group, on the lane type [`Wide`]: what
//! [`super::g2p::particles`] computes for each vector of a chunk's lanes, from the velocity
//! `v_gp = sum S_ip v_i` and acceleration `a_gp = sum S_ip a_i` it gathered.
//!
//! - the damping acceleration (E24, E53): [`crate::effects::damping::acceleration`].
//! - [`flip`]: FLIP with PIC damping and the position update (E25-E26, or E27).
//! - [`apic`]: the APIC update (E80).
//! - [`xpic`]: XPIC(k) and FMPM(k) (E100, E101).
//! - [`advance`]: the position plus the step's displacement, without rounding error (E28).
//! - [`walls`]: a particle that leaves the admissible region is put back on a wall's plane
//!   with its outward velocity zeroed, or escapes through an open face.

use crate::def::Boundary;
use crate::grid::Geom;
use crate::num::{Num, Truth};
use crate::simd::rows::Compare;
use crate::simd::wide::{Wide, WideMask};
use crate::Real;

/// The constants of a substep's particle update, made once per pass.
#[derive(Clone, Copy)]
pub(crate) struct Step<I: Compare> {
    pub dt: Wide<I>,
    pub half: Wide<I>,
    /// `dt^2 / 2`.
    pub half_dt2: Wide<I>,
    /// The PIC fraction `1 - beta`.
    pub pic: Wide<I>,
    /// FLIP moves the particle with its own new velocity (see [`flip`]).
    pub particle_velocity: bool,
}

impl<I: Compare> Step<I> {
    /// The constants of a substep of length `dt` with FLIP fraction `beta`, FLIP moving the
    /// particles with their own velocity if `particle_velocity`.
    #[inline(always)]
    pub fn new(dt: Real, beta: Real, particle_velocity: bool) -> Self {
        Step {
            dt: Wide::splat(dt),
            half: Wide::splat(0.5),
            half_dt2: Wide::splat(0.5 * dt * dt),
            pic: Wide::splat(1.0 - beta),
            particle_velocity,
        }
    }
}

/// FLIP with PIC damping (E25) and the position update of E26, less the damping
/// acceleration `d` when damping is declared (E24):
/// - `v(n+1) = v_p + a_gp dt - (1 - beta)(v_p - v_gp) - d dt`
/// - `x(n+1) = x_p + dx`, `dx = (v_m + a_m dt / 2 - (1 - beta)(v_p - v_gp) / 2) dt - d dt^2 / 2`,
///   or with `particle_velocity` the particle's own new velocity, `dx = v(n+1) dt` (E27).
///
/// `(v_m, a_m)`, the grid velocity and acceleration the particle moves with, are `(v_gp,
/// a_gp)` in the velocity approach and the mass-weighted ones in the momentum approach (E76,
/// [`super::momentum`]). Returns the new velocity and the displacement `dx` (see [`advance`]).
#[inline(always)]
pub(crate) fn flip<I: Compare>(
    k: &Step<I>,
    v_p: Wide<I>,
    (v_gp, a_gp): (Wide<I>, Wide<I>),
    (v_m, a_m): (Wide<I>, Wide<I>),
    d: Option<Wide<I>>,
) -> (Wide<I>, Wide<I>) {
    let inversion = (v_p - v_gp) * k.pic;
    let v = v_p + a_gp * k.dt - inversion;
    let v = match d {
        Some(d) => v - d * k.dt,
        None => v,
    };
    if k.particle_velocity {
        return (v, v * k.dt);
    }
    let dx = (v_m + a_m * k.half * k.dt - inversion * k.half) * k.dt;
    match d {
        Some(d) => (v, dx - d * k.half_dt2),
        None => (v, dx),
    }
}

/// APIC (E80): the particle takes the grid's velocity, `v(n+1) = v_gp + a_gp dt - d dt`,
/// and moves with it, `x(n+1) = x_p + dx`, `dx = v(n+1) dt`. Returns the new velocity and the
/// displacement `dx` (see [`advance`]).
#[inline(always)]
pub(crate) fn apic<I: Compare>(
    k: &Step<I>,
    v_gp: Wide<I>,
    a_gp: Wide<I>,
    d: Option<Wide<I>>,
) -> (Wide<I>, Wide<I>) {
    let mut v = v_gp + a_gp * k.dt;
    if let Some(d) = d {
        v -= d * k.dt;
    }
    (v, v * k.dt)
}

/// XPIC(k) and FMPM(k) (E100, E101), from the grid as [`crate::phases::xpic`] leaves it:
/// `v_gp + a_gp dt = S (v* + a dt)` (XPIC) or `S v*` (FMPM), and `v_gp = S v^L` (XPIC) or
/// `S v*` (FMPM). The particle takes `v(n+1) = v_gp + a_gp dt - d dt` and moves by
/// `dx = (v_gp + (v(n+1) - v_p) / 2) dt` (XPIC) or `dx = (v_p + v(n+1)) dt / 2` (FMPM).
/// Returns the new velocity and the displacement `dx` (see [`advance`]).
#[inline(always)]
pub(crate) fn xpic<I: Compare>(
    k: &Step<I>,
    v_p: Wide<I>,
    (v_gp, a_gp): (Wide<I>, Wide<I>),
    d: Option<Wide<I>>,
    fmpm: bool,
) -> (Wide<I>, Wide<I>) {
    let (v, _) = apic(k, v_gp, a_gp, d);
    let dx = if fmpm {
        (v_p + v) * k.half * k.dt
    } else {
        (v_gp + (v - v_p) * k.half) * k.dt
    };
    (v, dx)
}

/// The position `x + x_low` moved by `dx`, kept as a new pair `(x, x_low)` (E28): `x` the sum
/// rounded to `Real`, `x_low` what that rounding left out (Dekker's fast two-sum, exact when
/// `|x|` is at least the step's displacement `|dx + x_low|`, so that `x + x_low` is the exact
/// sum of the old pair and `dx`, to the rounding of `dx + x_low`; nearer the origin than one
/// step's displacement, the last bit of `x` is finer than anywhere the particle could come
/// from).
/// Written as `x += dx`, a displacement below half the last bit of `x` was lost every step: a
/// slow particle far from the origin never moved.
#[inline(always)]
pub(crate) fn advance<I: Compare>(x: Wide<I>, x_low: Wide<I>, dx: Wide<I>) -> (Wide<I>, Wide<I>) {
    let s = dx + x_low;
    let sum = x + s;
    (sum, s - (sum - x))
}

/// One axis's two faces, for [`walls`]: the grid's origin and `1 / h`, the admissible range
/// in cells and its ends in metres, which faces are open, and whether the axis is periodic,
/// with its period in metres.
#[derive(Clone, Copy)]
pub(crate) struct Faces<I: Compare> {
    zero: Wide<I>,
    origin: Wide<I>,
    inv_h: Wide<I>,
    lo: Wide<I>,
    hi: Wide<I>,
    lo_x: Wide<I>,
    hi_x: Wide<I>,
    open: [WideMask<I>; 2],
    periodic: bool,
    period: Wide<I>,
}

impl<I: Compare> Faces<I> {
    /// The faces of `axis` of the grid `geom`.
    #[inline(always)]
    pub fn of<const D: usize>(geom: &Geom<D>, axis: usize) -> Self {
        let open = |side: usize| geom.faces[axis][side] == Boundary::Open;
        let (lo_x, hi_x) = (
            geom.origin[axis] + geom.lo[axis] * geom.h,
            geom.origin[axis] + geom.hi[axis] * geom.h,
        );
        Faces {
            zero: Wide::splat(0.0),
            origin: Wide::splat(geom.origin[axis]),
            inv_h: Wide::splat(geom.inv_h),
            lo: Wide::splat(geom.lo[axis]),
            hi: Wide::splat(geom.hi[axis]),
            lo_x: Wide::splat(lo_x),
            hi_x: Wide::splat(hi_x),
            open: [WideMask::splat(open(0)), WideMask::splat(open(1))],
            periodic: geom.faces[axis][0] == Boundary::Periodic,
            period: Wide::splat(hi_x - lo_x),
        }
    }
}

/// What [`walls`] did to a vector of lanes along one axis.
pub(crate) struct AtFaces<I: Compare> {
    /// The position, on a face's plane where the particle left the admissible range.
    pub x: Wide<I>,
    /// The low part of the position (zero on a face's plane).
    pub x_low: Wide<I>,
    /// The velocity, its outward component zeroed at a wall.
    pub v: Wide<I>,
    /// The lanes that crossed an open face (they escape).
    pub open: WideMask<I>,
    /// The lanes that reached a stick or slip wall (stopped).
    pub wall: WideMask<I>,
}

/// The walls and open faces along one axis: a particle at `x + x_low` (m) with velocity `v`
/// that left the admissible range is put on the plane it crossed; at a stick or slip wall its
/// outward velocity is zeroed, and through an open face it escapes. Along a periodic axis it
/// comes back through the other face, moved by the period, its low part keeping what the
/// move rounded off (E95).
#[inline(always)]
pub(crate) fn walls<I: Compare>(
    f: &Faces<I>,
    x: Wide<I>,
    x_low: Wide<I>,
    v: Wide<I>,
) -> AtFaces<I> {
    let zero = f.zero;
    let s = (x - f.origin) * f.inv_h;
    let (below, above) = (s.lt(f.lo), s.gt(f.hi));
    let out = below | above;
    if f.periodic {
        // One branch per axis and chunk, the same for every lane: an axis with walls pays
        // nothing for it.
        let shift = below.select(f.period, -f.period);
        let moved = x + shift;
        let moved_low = x_low + ((x - moved) + shift);
        // Within the range, whatever the rounding of the move.
        let moved = moved.lt(f.lo_x).select(f.lo_x, moved);
        let moved = moved.gt(f.hi_x).select(f.hi_x, moved);
        let none = WideMask::splat(false);
        return AtFaces {
            x: out.select(moved, x),
            x_low: out.select(moved_low, x_low),
            v,
            open: none,
            wall: none,
        };
    }
    let x = below.select(f.lo_x, above.select(f.hi_x, x));
    let x_low = out.select(zero, x_low);
    let open = (below & f.open[0]) | (above & f.open[1]);
    let wall = out.and_not(open);
    let outward = (below & v.lt(zero)) | (above & v.gt(zero));
    let v = (wall & outward).select(zero, v);
    AtFaces {
        x,
        x_low,
        v,
        open,
        wall,
    }
}
