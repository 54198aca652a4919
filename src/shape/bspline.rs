//! Quadratic and cubic B-splines (seeds/003), `xi` in cell units.
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
}
