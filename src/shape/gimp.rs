//! uGIMP (Bardenhagen and Kober 2004): the linear hat integrated over an undeformed particle
//! domain of half-width `l = l_p / h = 1 / (2 n)` (cell units), `n` particles per cell per axis.
//! Three nodes per axis. Closed form (E8; xi in cell units):
//! - `|xi| < l`: `S = 1 - (xi^2 + l^2) / (2 l)`, `dS = -xi / l`
//! - `l <= |xi| <= 1 - l`: `S = 1 - |xi|`, `dS = -sign(xi)`
//! - `1 - l < |xi| < 1 + l`: `S = (1 + l - |xi|)^2 / (4 l)`, `dS = -sign(xi) (1 + l - |xi|) / (2 l)`
//!
//! cpGIMP ([`CpGimp`]) is the same closed form with each particle's own half-width per axis
//! (E9).

use super::Shape1D;
use crate::Real;

/// uGIMP with a fixed particle half-width.
#[derive(Clone, Copy, Debug)]
pub struct Gimp {
    /// Particle half-width in cell units, `1 / (2 n)`.
    l: Real,
    /// `1 / l`, `1 / (2 l)` and `1 / (4 l)`, so the hot loop multiplies.
    inv_l: Real,
    inv_2l: Real,
    inv_4l: Real,
}

impl Gimp {
    /// uGIMP for `particles_per_cell` particles per cell per axis (>= 1).
    pub fn new(particles_per_cell: u32) -> Self {
        Gimp::with_half_width(0.5 / particles_per_cell.max(1) as Real)
    }

    /// uGIMP with half-width `l` in cell units, in (0, 1/2] (the closed form's range with 3
    /// nodes per axis).
    #[inline(always)]
    pub fn with_half_width(l: Real) -> Self {
        // One division (cpGIMP makes one of these per particle and axis): scaling by a power
        // of two is exact, so 0.5 * (1 / l) is 0.5 / l to the bit.
        let inv_l = 1.0 / l;
        Gimp {
            l,
            inv_l,
            inv_2l: 0.5 * inv_l,
            inv_4l: 0.25 * inv_l,
        }
    }
}

impl Gimp {
    /// First moment `M = 1/(2l) int_{-l}^{l} N(xi + u) u du` of the hat over the domain (cell
    /// units) and the mean of the hat at the domain's ends, for a particle at offset `xi` from
    /// the node (E69). With `a = |xi|` and `c = 1 - a`:
    /// - `a < l`: `M = xi^3 / (6 l) - xi l / 2`
    /// - `l <= a <= 1 - l`: `M = -sign(xi) l^2 / 3`
    /// - `1 - l < a < 1 + l`: `M = -sign(xi) (l^3 / 3 + c l^2 / 2 - c^3 / 6) / (2 l)`
    ///
    /// (continuous at `a = l` and `a = 1 - l`, zero from `a = 1 + l`).
    ///
    /// Multiplies by 1/3 and 1/6 rather than dividing (divisions are the slowest operations
    /// here; the axisymmetric stencil evaluates this for every particle and node). Like
    /// [`Gimp::eval`], every branch is evaluated and the result selected, so the stencil's loop
    /// over a chunk's lanes vectorises (as jumps it ran one lane at a time).
    #[inline(always)]
    fn moment_and_ends(&self, xi: Real) -> (Real, Real) {
        const THIRD: Real = 1.0 / 3.0;
        const SIXTH: Real = 1.0 / 6.0;
        let l = self.l;
        let a = xi.abs();
        let sign: Real = if xi >= 0.0 { 1.0 } else { -1.0 };
        let c = (1.0 - a).max(-l);
        let m_in = xi * (xi * xi * THIRD - l * l) * 0.5 * self.inv_l;
        let m_mid = -sign * l * l * THIRD;
        let m_out = -sign * (l * l * l * THIRD + c * l * l * 0.5 - c * c * c * SIXTH) * self.inv_2l;
        let (inner, middle) = (a < l, a <= 1.0 - l);
        let m = if inner {
            m_in
        } else if middle {
            m_mid
        } else {
            m_out
        };
        let hat = |x: Real| (1.0 - x.abs()).max(0.0);
        (m, 0.5 * (hat(xi - l) + hat(xi + l)))
    }
}

impl Shape1D<3> for Gimp {
    const SHIFT: Real = 0.5;
    const LEAD: i32 = 1;
    const FINITE_DOMAIN: bool = true;

    #[inline(always)]
    fn domain_half_width(&self, _stretch: Real) -> Real {
        self.l
    }

    #[inline(always)]
    fn radial_terms(&self, f: Real, _stretch: Real) -> ([Real; 3], [Real; 3]) {
        let mut m = [0.0; 3];
        let mut ends = [0.0; 3];
        for k in 0..3 {
            (m[k], ends[k]) = self.moment_and_ends(f - k as Real);
        }
        (m, ends)
    }

    /// Written as selects between the three branches (all evaluated), so the compiler emits no
    /// jumps: the region a particle is in changes from step to step and would mispredict.
    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        let l = self.l;
        let a = xi.abs();
        let sign: Real = if xi >= 0.0 { 1.0 } else { -1.0 };
        let t = (1.0 + l - a).max(0.0);
        let (s_in, d_in) = (1.0 - (xi * xi + l * l) * self.inv_2l, -xi * self.inv_l);
        let (s_mid, d_mid) = (1.0 - a, -sign);
        let (s_out, d_out) = (t * t * self.inv_4l, -sign * t * self.inv_2l);
        let inner = a < l;
        let middle = a <= 1.0 - l;
        let s = if inner {
            s_in
        } else if middle {
            s_mid
        } else {
            s_out
        };
        let d = if inner {
            d_in
        } else if middle {
            d_mid
        } else {
            d_out
        };
        (s, d)
    }

    /// The three nodes at once. For a particle in the admissible region the offset from the
    /// first node is `f` in [1/2, 3/2], so the middle node is within 1/2 (inner or middle
    /// branch) and the outer nodes are at least 1/2 away (middle or outer branch): two
    /// candidates per node instead of three. Live particles are always in the admissible region
    /// (the step puts them back on the wall plane), so `f` is never outside that range for a
    /// weight that is used; memory safety never depends on weights.
    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 3], [Real; 3]) {
        let l = self.l;
        // Middle node, offset xi = f - 1 in [-1/2, 1/2].
        let xi = f - 1.0;
        let a1 = xi.abs();
        let inner = a1 < l;
        let s1 = if inner {
            1.0 - (xi * xi + l * l) * self.inv_2l
        } else {
            1.0 - a1
        };
        let d1 = if inner {
            -xi * self.inv_l
        } else if xi >= 0.0 {
            -1.0
        } else {
            1.0
        };
        // Outer nodes at distance a = f (first node, xi > 0) and 2 - f (last node, xi < 0).
        let outer = |a: Real| -> (Real, Real) {
            let t = (1.0 + l - a).max(0.0);
            if a <= 1.0 - l {
                (1.0 - a, 1.0)
            } else {
                (t * t * self.inv_4l, t * self.inv_2l)
            }
        };
        let (s0, m0) = outer(f);
        let (s2, m2) = outer(2.0 - f);
        ([s0, s1, s2], [-m0, d1, m2])
    }
}

/// cpGIMP (Wallstedt and Guilkey 2008; E9): uGIMP whose particle domain is convected with
/// the deformation. A particle's half-width along an axis is the undeformed `l_0 = 1 / (2 n)`
/// times its domain's stretch there (the deformed extent `sum_b |F_ab|`), kept within
/// `[l_0 / 10, 1 / 2]` cell units: the upper bound keeps the domain within the 3 nodes of the
/// stencil (the closed form's range), the lower one keeps the weights' derivatives bounded.
#[derive(Clone, Copy, Debug)]
pub struct CpGimp {
    l0: Real,
}

impl CpGimp {
    /// cpGIMP for `particles_per_cell` particles per cell per axis (>= 1).
    pub fn new(particles_per_cell: u32) -> Self {
        CpGimp {
            l0: 0.5 / particles_per_cell.max(1) as Real,
        }
    }

    /// uGIMP at the half-width of a domain stretched by `stretch` (NaN-safe: the smallest).
    #[inline(always)]
    fn at(&self, stretch: Real) -> Gimp {
        let (lo, l) = (0.1 * self.l0, self.l0 * stretch);
        let l = if l > lo { l } else { lo };
        Gimp::with_half_width(if l < 0.5 { l } else { 0.5 })
    }
}

impl Shape1D<3> for CpGimp {
    const SHIFT: Real = 0.5;
    const LEAD: i32 = 1;
    const FINITE_DOMAIN: bool = true;

    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        self.at(1.0).eval(xi)
    }

    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 3], [Real; 3]) {
        self.at(1.0).stencil(f)
    }

    #[inline(always)]
    fn stencil_stretched(&self, f: Real, stretch: Real) -> ([Real; 3], [Real; 3]) {
        self.at(stretch).stencil(f)
    }

    #[inline(always)]
    fn domain_half_width(&self, stretch: Real) -> Real {
        self.at(stretch).l
    }

    #[inline(always)]
    fn radial_terms(&self, f: Real, stretch: Real) -> ([Real; 3], [Real; 3]) {
        self.at(stretch).radial_terms(f, stretch)
    }
}
