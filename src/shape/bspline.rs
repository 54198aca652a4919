//! Quadratic and cubic B-splines (E10, E11), `xi` in cell units.
//! - Quadratic: `3/4 - xi^2` for `|xi| <= 1/2`; `(3/2 - |xi|)^2 / 2` for `1/2 <= |xi| <= 3/2`. 3 nodes.
//! - Cubic: `|xi|^3 / 2 - xi^2 + 2/3` for `|xi| < 1`; `(2 - |xi|)^3 / 6` for `1 <= |xi| < 2`. 4 nodes.

use super::Shape1D;
use crate::Real;

/// Quadratic B-spline.
#[derive(Clone, Copy, Debug, Default)]
pub struct QuadraticBspline;

/// Cubic B-spline.
#[derive(Clone, Copy, Debug, Default)]
pub struct CubicBspline;

impl Shape1D<3> for QuadraticBspline {
    const SHIFT: Real = 0.5;
    const LEAD: i32 = 1;

    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        let a = xi.abs();
        let sign = if xi >= 0.0 { 1.0 } else { -1.0 };
        if a <= 0.5 {
            (0.75 - xi * xi, -2.0 * xi)
        } else if a < 1.5 {
            let t = 1.5 - a;
            (0.5 * t * t, -sign * t)
        } else {
            (0.0, 0.0)
        }
    }

    /// The three nodes at once, without branches: with `t = f - 1` in [-1/2, 1/2) the outer
    /// nodes are `(1/2 - t)^2 / 2` and `(1/2 + t)^2 / 2`, and the middle one is their complement
    /// to 1, so the weights sum to 1 to the last bit (and the derivatives to 0), which keeps
    /// the transfers' conservation at round-off in f32.
    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 3], [Real; 3]) {
        let t = f - 1.0;
        let (a, b) = (0.5 - t, 0.5 + t);
        let (w0, w2) = (0.5 * a * a, 0.5 * b * b);
        ([w0, 1.0 - w0 - w2, w2], [-a, a - b, b])
    }
}

impl Shape1D<4> for CubicBspline {
    const SHIFT: Real = 0.0;
    const LEAD: i32 = 1;

    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        let a = xi.abs();
        let sign = if xi >= 0.0 { 1.0 } else { -1.0 };
        if a < 1.0 {
            (0.5 * a * a * a - a * a + 2.0 / 3.0, (1.5 * a - 2.0) * xi)
        } else if a < 2.0 {
            let t = 2.0 - a;
            (t * t * t / 6.0, -0.5 * sign * t * t)
        } else {
            (0.0, 0.0)
        }
    }

    /// The four nodes at once, without branches: with `t = f - 1` in [0, 1), the weights are
    /// `(1 - t)^3 / 6`, `t^3 / 2 - t^2 + 2/3`, the complement to 1, and `t^3 / 6` (the
    /// complement makes them sum to 1 to the last bit, and the derivatives to 0).
    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 4], [Real; 4]) {
        let t = f - 1.0;
        let u = 1.0 - t;
        let (w0, w3) = (u * u * u / 6.0, t * t * t / 6.0);
        let w1 = (0.5 * t - 1.0) * t * t + 2.0 / 3.0;
        let (d0, d1, d3) = (-0.5 * u * u, (1.5 * t - 2.0) * t, 0.5 * t * t);
        (
            [w0, w1, 1.0 - w0 - w1 - w3, w3],
            [d0, d1, -(d0 + d1 + d3), d3],
        )
    }
}
