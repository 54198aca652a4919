//! [`Wide`]: the lanes of one vector of the instance that runs ([`Rows::N`] particles at once),
//! the one lane type of the passes: the [`Num`] the materials are written on, with the full
//! set of operators (`+ - * /`, negation, `+=`, a [`Real`] operand), comparisons and selects,
//! so that an equation on it reads as docs/equations.md writes it (`v + a * dt - inversion`);
//! and [`WideMask`], the truth values its comparisons give.
//!
//! Each operator is one vector instruction of the instance (`#[inline(always)]`, so it is
//! compiled with the instance's features); the values and their order are those of the
//! expression as written, so every instance computes the same bits, and the bits of the same
//! expression on one [`Real`].
//!
//! Making a `Wide` from reals ([`Wide::splat`], [`Wide::load`], [`Num::splat`]) runs the
//! instance's instructions, and is safe for the reason every function generic over an
//! instance is: it runs only inside the passes of an instance the CPU supports
//! (`crate::simd::Simd::instance` chose it; the tables of `crate::simd::instances!` are the
//! only way in). The unsafe operations of the instances' vectors ([`Rows`]) stay in this
//! floor.

use super::lanes::Lanes;
use super::rows::{Compare, Rows};
use crate::num::{Num, Truth};
use crate::Real;
use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// [`Rows::N`] reals, one per lane, of the instance `I`.
#[repr(transparent)]
pub(crate) struct Wide<I: Rows>(pub I::V);

impl<I: Rows> Clone for Wide<I> {
    #[inline(always)]
    fn clone(&self) -> Self {
        *self
    }
}

impl<I: Rows> Copy for Wide<I> {}

impl<I: Rows> Wide<I> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(x: Real) -> Self {
        // SAFETY: a function generic over an instance runs only inside the passes of an
        // instance the CPU supports (module docs).
        Wide(unsafe { I::splat(x) })
    }

    /// Lanes `at..at + N` of a chunk's lane array.
    #[inline(always)]
    pub fn load<const W: usize>(lanes: &[Real; W], at: usize) -> Self {
        // SAFETY: as for splat.
        Wide(unsafe { I::load(lanes, at) })
    }

    /// Writes the lanes to `at..at + N` of a chunk's lane array.
    #[inline(always)]
    pub fn store<const W: usize>(self, lanes: &mut [Real; W], at: usize) {
        I::store(self.0, lanes, at)
    }
}

/// `Wide op Wide`, `Wide op Real` and `Wide op= Wide` for one operator.
macro_rules! wide_op {
    ($tr:ident, $f:ident, $assign:ident, $fa:ident, $op:tt, $via:ident) => {
        impl<I: Compare> $tr for Wide<I> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Self) -> Self {
                Wide(I::$via(self.0, b.0))
            }
        }
        impl<I: Compare> $tr<Real> for Wide<I> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Real) -> Self {
                self $op <Self as Num>::splat(b)
            }
        }
        impl<I: Compare> $assign for Wide<I> {
            #[inline(always)]
            fn $fa(&mut self, b: Self) {
                *self = *self $op b;
            }
        }
    };
}

wide_op!(Add, add, AddAssign, add_assign, +, add);
wide_op!(Sub, sub, SubAssign, sub_assign, -, sub);
wide_op!(Mul, mul, MulAssign, mul_assign, *, mul);

impl<I: Compare> Div for Wide<I> {
    type Output = Self;
    #[inline(always)]
    fn div(self, b: Self) -> Self {
        Wide(I::div(self.0, b.0))
    }
}

impl<I: Compare> Neg for Wide<I> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Wide(I::neg(self.0))
    }
}

impl<I: Compare> Num for Wide<I> {
    type Mask = WideMask<I>;

    #[inline(always)]
    fn splat(x: Real) -> Self {
        Wide::splat(x)
    }

    /// Each lane through `f` in a loop over the vector's lanes (which the compiler vectorises
    /// where `f` has no branches).
    #[inline(always)]
    fn map(self, f: impl Fn(Real) -> Real) -> Self {
        const { assert!(I::N <= 16) };
        let mut lanes = [0.0; 16];
        self.store(&mut lanes, 0);
        for v in lanes.iter_mut().take(I::N) {
            *v = f(*v);
        }
        Wide::load(&lanes, 0)
    }

    #[inline(always)]
    fn ge(self, b: Self) -> WideMask<I> {
        WideMask(I::ge(self.0, b.0))
    }

    #[inline(always)]
    fn gt(self, b: Self) -> WideMask<I> {
        WideMask(I::gt(self.0, b.0))
    }

    #[inline(always)]
    fn select(m: WideMask<I>, a: Self, b: Self) -> Self {
        m.select(a, b)
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        Wide(I::sqrt(self.0))
    }
}

impl<I: Compare> Truth for WideMask<I> {
    #[inline(always)]
    fn and_not(self, b: Self) -> Self {
        WideMask(I::and_not(self.0, b.0))
    }

    #[inline(always)]
    fn any(self) -> bool {
        I::bits(self.0) != 0
    }
}

/// One truth value per lane of a [`Wide`]; a comparison with a NaN is false.
pub(crate) struct WideMask<I: Compare>(pub I::M);

impl<I: Compare> Clone for WideMask<I> {
    #[inline(always)]
    fn clone(&self) -> Self {
        *self
    }
}

impl<I: Compare> Copy for WideMask<I> {}

impl<I: Compare> Wide<I> {
    /// `self < b` per lane.
    #[inline(always)]
    pub fn lt(self, b: Self) -> WideMask<I> {
        WideMask(I::lt(self.0, b.0))
    }

    /// Whether each lane is finite.
    #[inline(always)]
    pub fn is_finite(self) -> WideMask<I> {
        WideMask(I::finite(self.0))
    }
}

impl<I: Compare> WideMask<I> {
    /// Every lane `b`.
    #[inline(always)]
    pub fn splat(b: bool) -> Self {
        // SAFETY: as for [`Wide::splat`].
        WideMask(unsafe { I::splat_mask(b) })
    }

    /// `a` where the mask holds, else `b`.
    #[inline(always)]
    pub fn select(self, a: Wide<I>, b: Wide<I>) -> Wide<I> {
        Wide(I::select(self.0, a.0, b.0))
    }

    /// The lanes `q..q + N` of a chunk where the mask holds (`q` a multiple of `N`).
    #[inline(always)]
    pub fn lanes<const W: usize>(self, q: usize) -> Lanes<W> {
        Lanes::at(q, I::bits(self.0))
    }
}

impl<I: Compare> BitAnd for WideMask<I> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, b: Self) -> Self {
        WideMask(I::and(self.0, b.0))
    }
}

impl<I: Compare> BitOr for WideMask<I> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, b: Self) -> Self {
        WideMask(I::or(self.0, b.0))
    }
}
