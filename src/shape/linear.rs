//! Classic MPM linear hat functions: `S = 1 - |xi|` for `|xi| < 1` (seeds/003). Two nodes.

use super::Shape1D;
use crate::Real;

/// Linear hat function.
#[derive(Clone, Copy, Debug, Default)]
pub struct Linear;

impl Shape1D<2> for Linear {
    const SHIFT: Real = 0.0;
    const LEAD: i32 = 0;
    const GRADIENT_AFFINE: bool = true;

    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        let a = xi.abs();
        if a < 1.0 {
            (1.0 - a, if xi >= 0.0 { -1.0 } else { 1.0 })
        } else {
            (0.0, 0.0)
        }
    }

    /// The two nodes of the particle's cell: the slope is that cell's, also when the particle
    /// sits exactly on a node (where the hat's derivative jumps), so G sums to zero there too.
    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 2], [Real; 2]) {
        ([1.0 - f, f], [-1.0, 1.0])
    }
}
