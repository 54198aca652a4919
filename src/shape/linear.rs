//! Classic MPM linear hat functions: `S = 1 - |xi|` for `|xi| < 1` (seeds/003). Two nodes.

use super::Shape1D;
use crate::Real;

/// Linear hat function.
#[derive(Clone, Copy, Debug, Default)]
pub struct Linear;

impl Shape1D<2> for Linear {
    #[inline(always)]
    fn first_node(s: Real) -> i32 {
        s as i32
    }

    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        let a = xi.abs();
        if a < 1.0 {
            // The derivative at a node (xi = 0) is taken from the cell the particle is in, so
            // that the two nodes of the stencil have opposite slopes and G sums to zero.
            (1.0 - a, if xi >= 0.0 { -1.0 } else { 1.0 })
        } else {
            (0.0, 0.0)
        }
    }
}
