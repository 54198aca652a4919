//! Classic MPM linear hat functions: `S = 1 - |xi|` for `|xi| < 1` (seeds/003). Two nodes.
//!
//! The stencil is the two nodes of the particle's cell, and the slope is that cell's, also when
//! the particle sits exactly on a node (where the hat's derivative jumps), so `G` sums to zero
//! there too.

use super::{Pieces, Shape1D};
use crate::Real;

/// Linear hat function.
#[derive(Clone, Copy, Debug, Default)]
pub struct Linear;

impl Shape1D<2> for Linear {
    fn pieces(&self) -> Pieces {
        Pieces {
            n: 1,
            hi: [1.0, 0.0, 0.0],
            p: [[1.0, -1.0, 0.0, 0.0], [0.0; 4], [0.0; 4]],
        }
    }

    fn eval(&self, xi: Real) -> (Real, Real) {
        let a = xi.abs();
        if a < 1.0 {
            (1.0 - a, if xi >= 0.0 { -1.0 } else { 1.0 })
        } else {
            (0.0, 0.0)
        }
    }
}
