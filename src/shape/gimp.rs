//! uGIMP (Bardenhagen and Kober 2004): the linear hat integrated over an undeformed particle
//! domain of half-width `l = l_p / h = 1 / (2 n)` (cell units), `n` particles per cell per axis.
//! Three nodes per axis. Closed form (xi in cell units):
//! - `|xi| < l`: `S = 1 - (xi^2 + l^2) / (2 l)`, `dS = -xi / l`
//! - `l <= |xi| <= 1 - l`: `S = 1 - |xi|`, `dS = -sign(xi)`
//! - `1 - l < |xi| < 1 + l`: `S = (1 + l - |xi|)^2 / (4 l)`, `dS = -sign(xi) (1 + l - |xi|) / (2 l)`

use super::{Pieces, Shape1D};
use crate::Real;

/// uGIMP with a fixed particle half-width.
#[derive(Clone, Copy, Debug)]
pub struct Gimp {
    /// Particle half-width in cell units, `1 / (2 n)`.
    l: f64,
}

impl Gimp {
    /// uGIMP for `particles_per_cell` particles per cell per axis (>= 1).
    pub fn new(particles_per_cell: u32) -> Self {
        Gimp {
            l: 0.5 / particles_per_cell.max(1) as f64,
        }
    }
}

impl Shape1D<3> for Gimp {
    fn pieces(&self) -> Pieces {
        let l = self.l;
        let t = 1.0 + l;
        Pieces {
            n: 3,
            hi: [l, 1.0 - l, 1.0 + l],
            p: [
                [1.0 - 0.5 * l, 0.0, -0.5 / l, 0.0],
                [1.0, -1.0, 0.0, 0.0],
                // (1 + l - a)^2 / (4 l)
                [
                    t * t / (4.0 * l),
                    -2.0 * t / (4.0 * l),
                    1.0 / (4.0 * l),
                    0.0,
                ],
            ],
        }
    }

    fn eval(&self, xi: Real) -> (Real, Real) {
        let l = self.l as Real;
        let a = xi.abs();
        let sign: Real = if xi >= 0.0 { 1.0 } else { -1.0 };
        if a < l {
            (1.0 - (xi * xi + l * l) / (2.0 * l), -xi / l)
        } else if a <= 1.0 - l {
            (1.0 - a, -sign)
        } else if a < 1.0 + l {
            let t = 1.0 + l - a;
            (t * t / (4.0 * l), -sign * t / (2.0 * l))
        } else {
            (0.0, 0.0)
        }
    }
}
