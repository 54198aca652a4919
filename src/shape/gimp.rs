//! uGIMP (Bardenhagen and Kober 2004): the linear hat integrated over an undeformed particle
//! domain of half-width `l = l_p / h = 1 / (2 n)` (cell units), `n` particles per cell per axis.
//! Three nodes per axis. Closed form (xi in cell units):
//! - `|xi| < l`: `S = 1 - (xi^2 + l^2) / (2 l)`, `dS = -xi / l`
//! - `l <= |xi| <= 1 - l`: `S = 1 - |xi|`, `dS = -sign(xi)`
//! - `1 - l < |xi| < 1 + l`: `S = (1 + l - |xi|)^2 / (4 l)`, `dS = -sign(xi) (1 + l - |xi|) / (2 l)`

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
        let l = 0.5 / particles_per_cell.max(1) as Real;
        Gimp {
            l,
            inv_l: 1.0 / l,
            inv_2l: 0.5 / l,
            inv_4l: 0.25 / l,
        }
    }
}

impl Shape1D<3> for Gimp {
    #[inline(always)]
    fn first_node(s: Real) -> i32 {
        (s + 0.5) as i32 - 1
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
}
