//! What a family of shape functions is ([`Shape1D`]): its 1D weights and derivatives per
//! axis, the first node of its stencil, and its radial form (E66-E69); the families implement
//! it, one file each.

use crate::Real;

/// Width of a stencil row in the hot loops: every family has `K <= 4` nodes per axis, padded
/// with zero weights to 4.
pub const ROW: usize = 4;

/// [`ROW`] values in one SIMD register (glam's SSE2 `Vec4` in f32, `DVec4` in f64): the per-axis
/// weights of a stencil, and one stencil row of a node column.
#[cfg(not(feature = "f64"))]
pub type Row4 = glam::Vec4;
/// [`ROW`] values in one SIMD register (glam's SSE2 `Vec4` in f32, `DVec4` in f64): the per-axis
/// weights of a stencil, and one stencil row of a node column.
#[cfg(feature = "f64")]
pub type Row4 = glam::DVec4;

/// One family of 1D shape functions with `K` nodes of support.
pub trait Shape1D<const K: usize>: Copy + Sync {
    /// The first node of the stencil of a particle at `s` (cell units) is
    /// `floor(s + SHIFT) - LEAD`, before clamping to the grid.
    const SHIFT: Real;
    /// See [`Shape1D::SHIFT`].
    const LEAD: i32;
    /// APIC keeps this family's affine matrix in its gradient form `C_p = sum_i v_i G_ip^T`
    /// rather than as the moment matrix `B_p` (which the next scatter divides by `D_p`): for
    /// weights whose `D_p` vanishes at a node (linear), `B_p / D_p` taken at the new position
    /// is unbounded, while the gradient form, equal to `B_p D_p^-1` at the old one, is not
    /// (E78, E81).
    const GRADIENT_AFFINE: bool = false;
    /// Whether the first axis is the radius of the axisymmetric form (E65-E72); set by
    /// [`Axisymmetric`](super::Axisymmetric) only, which then gives that axis r-weighted
    /// weights and the hoop factors `T_ip` ([`Stencil::t`](super::Stencil::t)).
    const AXISYMMETRIC: bool = false;
    /// Whether the weights integrate the grid functions over a particle domain (uGIMP) rather
    /// than sample them at a point: then the r-weighted weights of the axisymmetric form differ
    /// from the Cartesian ones, by [`Shape1D::radial_terms`].
    const FINITE_DOMAIN: bool = false;

    /// Axisymmetric only: the radius of a particle at `s` (cell units on the first axis), and
    /// the smallest radius the weights are evaluated at (see
    /// [`Axisymmetric`](super::Axisymmetric)).
    #[inline(always)]
    fn radius(&self, _s: Real) -> Real {
        0.0
    }

    /// A finite-domain family's terms of the r-weighted weights, per stencil node at offset
    /// `f` from the first node: the first moment of the grid function over the domain,
    /// `M = 1/(2l) int_{-l}^{l} N(xi + u) u du` (cell units, `xi` the particle's offset from
    /// the node), and the mean of `N` at the domain's two ends. Zero for point families.
    #[inline(always)]
    fn radial_terms(&self, _f: Real, _stretch: Real) -> ([Real; K], [Real; K]) {
        ([0.0; K], [0.0; K])
    }

    /// Half-width of the particle domain the weights integrate over, cell units, along an axis
    /// stretched by `stretch` (1 undeformed): `l_p / h` for uGIMP, cpGIMP's stretched and
    /// clamped half-width, 0 for a point family (linear, B-splines). The tractions' face
    /// integral keeps its points inside this domain (`phases::tractions::tractions`).
    #[inline(always)]
    fn domain_half_width(&self, _stretch: Real) -> Real {
        0.0
    }

    /// Runs `v` on the family as a concrete type: `self`, except for a family chosen at run
    /// time ([`ThreeNode`](super::ThreeNode)), which passes the family it holds. The stencil
    /// computations go through it once per chunk, so their lane loops always see one concrete
    /// family.
    #[inline(always)]
    fn visit<V: Visit<K>>(&self, v: V) -> V::Out {
        v.visit(self)
    }

    /// [`Shape1D::stencil`] for a particle whose domain is stretched by `stretch` along this
    /// axis (1 undeformed); only a family whose domain stretches (cpGIMP) reads it.
    #[inline(always)]
    fn stencil_stretched(&self, f: Real, _stretch: Real) -> ([Real; K], [Real; K]) {
        self.stencil(f)
    }

    /// Weight and its derivative with respect to `s` at offset `xi = s - x_i` (cell units).
    /// Zero outside the support.
    fn eval(&self, xi: Real) -> (Real, Real);

    /// Weights and derivatives of the `K` stencil nodes for a particle at offset `f = s - first`
    /// from the first node. By default [`Shape1D::eval`] at each node; a family whose
    /// derivative is defined by the cell rather than the offset (linear) overrides it.
    #[inline(always)]
    fn stencil(&self, f: Real) -> ([Real; K], [Real; K]) {
        let mut w = [0.0; K];
        let mut dw = [0.0; K];
        for k in 0..K {
            (w[k], dw[k]) = self.eval(f - k as Real);
        }
        (w, dw)
    }
}

/// A computation on one concrete family ([`Shape1D::visit`]).
pub trait Visit<const K: usize> {
    /// What the computation returns.
    type Out;
    /// Runs the computation with the family `shape`.
    fn visit<S: Shape1D<K>>(self, shape: &S) -> Self::Out;
}

/// The radial axis of the axisymmetric form for a particle at offset `f` from its first node
/// and `s` (cell units): the r-weighted weights `S = 1/(A_p r_p) int chi_p N r dA` and their
/// derivatives (E66, E67; per unit length), and the hoop factors `T = S_cart / r_p` (E68,
/// 1/m), with `r_p` no smaller than [`Shape1D::radius`] allows (E69). For a point family the
/// weights are the Cartesian ones; for a finite domain of half-width `l`,
/// `S = S_cart + h M / r_p` and `G = G_cart + (N_ends - S_cart) / r_p` (the integral of
/// `N' r` by parts), with `M` and `N_ends` from [`Shape1D::radial_terms`].
#[inline(always)]
pub(crate) fn radial_stencil<const K: usize, S: Shape1D<K>>(
    shape: &S,
    f: Real,
    s: Real,
    stretch: Real,
    h: Real,
) -> ([Real; K], [Real; K], [Real; K]) {
    let (mut w, mut dw) = shape.stencil_stretched(f, stretch);
    let inv_h = 1.0 / h;
    let inv_r = 1.0 / shape.radius(s);
    let mut t = [0.0; K];
    let (m, ends) = shape.radial_terms(f, stretch);
    for k in 0..K {
        t[k] = w[k] * inv_r;
        dw[k] *= inv_h;
        if S::FINITE_DOMAIN {
            dw[k] += (ends[k] - w[k]) * inv_r;
            w[k] += m[k] * h * inv_r;
        }
    }
    (w, dw, t)
}
