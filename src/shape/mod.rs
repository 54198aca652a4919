//! Shape functions: one file per family, one way to ask any of them for `S_ip` and `G_ip`.
//!
//! Every family is evaluated per axis ([`Shape1D`]) and combined by tensor product
//! ([`Stencil::for_each_node`], or row by row with [`Stencil::row`]): in 2D and 3D,
//! `S_ip` is the product of the per-axis values and each component of `G_ip` replaces one factor
//! by its derivative (E4-E6).
//!
//! The hot loops work row by row: the `K` nodes of a stencil row along x are contiguous in every
//! node column, so a row is one [`ROW`]-wide vector load, add and store, padded with zero
//! weights. Node columns therefore carry [`ROW`] entries of padding past the last node.
//!
//! Positions are given in cell units relative to the grid origin (`s = (x - origin) / h`), so a
//! node `i` sits at `s = i` and the per-axis offset is `xi = s - i`.

mod axisymmetric;
mod bspline;
mod family;
mod gimp;
mod linear;
mod stencil;

pub use axisymmetric::Axisymmetric;
pub use bspline::{CubicBspline, QuadraticBspline};
pub use family::{Row4, Shape1D, Visit, ROW};
pub use gimp::{CpGimp, Gimp};
pub use linear::Linear;
pub(crate) use stencil::{domain_stretch, row_start, transpose4_rows};
pub use stencil::{first_node, LaneStencil, Stencil, Stencils, XFactors};

use crate::Real;

/// The three-node families as one type chosen at run time: uGIMP, cpGIMP and the quadratic
/// B-spline differ only in their weights, so the passes are compiled once for the three and
/// the stencil computations pick the family once per chunk ([`Shape1D::visit`]). The three
/// share the first node of their stencils (`SHIFT` and `LEAD`).
#[derive(Clone, Copy, Debug)]
pub enum ThreeNode {
    /// uGIMP.
    Gimp(Gimp),
    /// cpGIMP.
    CpGimp(CpGimp),
    /// The quadratic B-spline.
    QuadraticBspline(QuadraticBspline),
}

// The first node of a stencil is the same for the three families.
const _: () = assert!(
    <Gimp as Shape1D<3>>::SHIFT == <ThreeNode as Shape1D<3>>::SHIFT
        && <CpGimp as Shape1D<3>>::SHIFT == <ThreeNode as Shape1D<3>>::SHIFT
        && <QuadraticBspline as Shape1D<3>>::SHIFT == <ThreeNode as Shape1D<3>>::SHIFT
        && <Gimp as Shape1D<3>>::LEAD == <ThreeNode as Shape1D<3>>::LEAD
        && <CpGimp as Shape1D<3>>::LEAD == <ThreeNode as Shape1D<3>>::LEAD
        && <QuadraticBspline as Shape1D<3>>::LEAD == <ThreeNode as Shape1D<3>>::LEAD
);

/// A shape family as it is, for [`with_form!`]'s plane strain and 3D forms.
pub(crate) fn plain<S>(shape: S, _: &crate::WorldDef) -> S {
    shape
}

/// A shape family in the axisymmetric form of definition `def`, for [`with_form!`].
#[cfg(feature = "effects")]
pub(crate) fn axisymmetric<S>(inner: S, def: &crate::WorldDef) -> Axisymmetric<S> {
    let half_width = def.cell_size / (2 * def.particles_per_cell) as Real;
    Axisymmetric::new(inner, def.origin.x, def.cell_size, half_width)
}

/// [`with_form!`] with the dimension's axes `$d` and the form's wrapper `$wrap` chosen.
macro_rules! with_family {
    ($def:ident, $d:literal, $wrap:path, $shape:ident => $body:expr) => {
        match $def.shape {
            $crate::ShapeFunction::Linear => {
                const D: usize = $d;
                const K: usize = $crate::ShapeFunction::Linear.stencil_width();
                let $shape = $wrap($crate::shape::Linear, $def);
                $body
            }
            $crate::ShapeFunction::Gimp => {
                const D: usize = $d;
                const K: usize = $crate::ShapeFunction::Gimp.stencil_width();
                let family = $crate::shape::Gimp::new($def.particles_per_cell);
                let $shape = $wrap($crate::shape::ThreeNode::Gimp(family), $def);
                $body
            }
            $crate::ShapeFunction::QuadraticBspline => {
                const D: usize = $d;
                const K: usize = $crate::ShapeFunction::QuadraticBspline.stencil_width();
                let family = $crate::shape::QuadraticBspline;
                let $shape = $wrap($crate::shape::ThreeNode::QuadraticBspline(family), $def);
                $body
            }
            $crate::ShapeFunction::CpGimp => {
                const D: usize = $d;
                const K: usize = $crate::ShapeFunction::CpGimp.stencil_width();
                let family = $crate::shape::CpGimp::new($def.particles_per_cell);
                let $shape = $wrap($crate::shape::ThreeNode::CpGimp(family), $def);
                $body
            }
            $crate::ShapeFunction::CubicBspline => {
                const D: usize = $d;
                const K: usize = $crate::ShapeFunction::CubicBspline.stencil_width();
                let $shape = $wrap($crate::shape::CubicBspline, $def);
                $body
            }
        }
    };
}
pub(crate) use with_family;

/// Evaluates `$body` in the compiled form of the definition `$def` (a `&WorldDef`): with the
/// const items `D` (the dimension's axes) and `K` (the stencil width), and `$shape` the shape
/// the step uses (the family, the three-node families as one [`ThreeNode`], wrapped in
/// [`Axisymmetric`] for the r-z form). The one place that maps a definition to a form.
macro_rules! with_form {
    ($def:expr, $shape:ident => $body:expr) => {{
        let def: &$crate::WorldDef = $def;
        match def.dimension {
            $crate::Dimension::ThreeD => {
                $crate::shape::with_family!(def, 3, $crate::shape::plain, $shape => $body)
            }
            #[cfg(feature = "effects")]
            $crate::Dimension::Axisymmetric2D => {
                $crate::shape::with_family!(def, 2, $crate::shape::axisymmetric, $shape => $body)
            }
            // Without the effects, a definition in the axisymmetric form is refused.
            _ => $crate::shape::with_family!(def, 2, $crate::shape::plain, $shape => $body),
        }
    }};
}
pub(crate) use with_form;

/// Evaluates `$e` with `$s` bound to the family a [`ThreeNode`] holds.
macro_rules! three_node {
    ($shape:expr, $s:ident => $e:expr) => {
        match $shape {
            ThreeNode::Gimp($s) => $e,
            ThreeNode::CpGimp($s) => $e,
            ThreeNode::QuadraticBspline($s) => $e,
        }
    };
}

impl Shape1D<3> for ThreeNode {
    const SHIFT: Real = 0.5;
    const LEAD: i32 = 1;

    #[inline(always)]
    fn visit<V: Visit<3>>(&self, v: V) -> V::Out {
        three_node!(self, s => v.visit(s))
    }

    // The per-particle methods, for completeness: the passes reach the family through `visit`.
    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        three_node!(self, s => s.eval(xi))
    }

    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; 3], [Real; 3]) {
        three_node!(self, s => s.stencil(f))
    }

    #[inline(always)]
    fn stencil_stretched(&self, f: Real, stretch: Real) -> ([Real; 3], [Real; 3]) {
        three_node!(self, s => s.stencil_stretched(f, stretch))
    }

    #[inline(always)]
    fn radial_terms(&self, f: Real, stretch: Real) -> ([Real; 3], [Real; 3]) {
        three_node!(self, s => s.radial_terms(f, stretch))
    }

    #[inline(always)]
    fn domain_half_width(&self, stretch: Real) -> Real {
        three_node!(self, s => s.domain_half_width(stretch))
    }
}
