//! Classic MPM linear hat functions: `S = 1 - |xi|` for `|xi| < 1` (E7). Two nodes.

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
    ///
    /// The offset is taken as at least `Real::EPSILON`: a particle exactly on its first node
    /// would otherwise give the cell's other node a slope but no weight, hence no mass, and at
    /// the edge of the material that node's velocity is zero for want of mass; the velocity
    /// gradient `sum v_i G_ip` then reads `-v / h` for a particle that moves rigidly (a block
    /// translating at 1 m/s took 1.4e4 Pa, 1.4 % of E, the step one of its particles landed on a
    /// node). With the weight `EPSILON` that node carries the particle's own velocity. The
    /// weights move by `EPSILON` of a cell, below the position's own round-off.
    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 2], [Real; 2]) {
        let f = if f > Real::EPSILON { f } else { Real::EPSILON };
        ([1.0 - f, f], [-1.0, 1.0])
    }
}
