//! The axisymmetric form (E65-E72): any family, with its first axis the radius `r` and its
//! second the axis `z`. The radial weights are r-weighted (E66, E67) and the stencil carries
//! the hoop factors `T_ip` (E68); see [`super::family::radial_stencil`].

use super::{Shape1D, Visit};
use crate::Real;

/// A family `S` used in the r-z plane of an axisymmetric world, whose axis `r = 0` is at the
/// grid coordinate `x = 0`.
///
/// The weights divide by the particle's radius. A particle closer to the axis than its
/// domain's half-width `l_p` (its domain would cross the axis; the step never puts one there,
/// except by compressing the material onto the axis) is evaluated as if at `r = l_p`: the
/// weights keep their partition of unity and stay bounded.
#[derive(Clone, Copy, Debug)]
pub struct Axisymmetric<S> {
    inner: S,
    origin: Real,
    h: Real,
    min_radius: Real,
}

impl<S> Axisymmetric<S> {
    /// `inner` on a grid whose first axis starts at `origin` (m) with spacing `h`, for particle
    /// domains of half-width `half_width` (m, > 0).
    pub fn new(inner: S, origin: Real, h: Real, half_width: Real) -> Self {
        Axisymmetric {
            inner,
            origin,
            h,
            min_radius: half_width,
        }
    }
}

impl<const K: usize, S: Shape1D<K>> Shape1D<K> for Axisymmetric<S> {
    const SHIFT: Real = S::SHIFT;
    const LEAD: i32 = S::LEAD;
    const GRADIENT_AFFINE: bool = S::GRADIENT_AFFINE;
    const AXISYMMETRIC: bool = true;
    const FINITE_DOMAIN: bool = S::FINITE_DOMAIN;

    /// The form around the concrete family the inner one holds.
    #[inline(always)]
    fn visit<V: Visit<K>>(&self, v: V) -> V::Out {
        self.inner.visit(Around { v, form: *self })
    }

    #[inline(always)]
    fn radius(&self, s: Real) -> Real {
        // NaN-safe: a NaN radius becomes the smallest one.
        let r = self.origin + s * self.h;
        if r > self.min_radius {
            r
        } else {
            self.min_radius
        }
    }

    #[inline(always)]
    fn radial_terms(&self, f: Real, stretch: Real) -> ([Real; K], [Real; K]) {
        self.inner.radial_terms(f, stretch)
    }

    #[inline(always)]
    fn stencil_stretched(&self, f: Real, stretch: Real) -> ([Real; K], [Real; K]) {
        self.inner.stencil_stretched(f, stretch)
    }

    #[inline(always)]
    fn domain_half_width(&self, stretch: Real) -> Real {
        self.inner.domain_half_width(stretch)
    }

    #[inline(always)]
    fn eval(&self, xi: Real) -> (Real, Real) {
        self.inner.eval(xi)
    }

    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; K], [Real; K]) {
        self.inner.stencil(f)
    }
}

/// [`Shape1D::visit`] of the axisymmetric form: runs `v` on the form around the concrete
/// family the inner one passes.
struct Around<V, S> {
    v: V,
    form: Axisymmetric<S>,
}

impl<const K: usize, V: Visit<K>, S> Visit<K> for Around<V, S> {
    type Out = V::Out;

    #[inline(always)]
    fn visit<C: Shape1D<K>>(self, inner: &C) -> V::Out {
        let f = self.form;
        self.v.visit(&Axisymmetric {
            inner: *inner,
            origin: f.origin,
            h: f.h,
            min_radius: f.min_radius,
        })
    }
}
