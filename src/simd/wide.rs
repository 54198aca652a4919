//! [`Wide`]: the lanes of one vector of the instance that runs ([`Rows::N`] particles at once),
//! with arithmetic operators, so that an equation on it reads as the seed documents write it
//! (`v + a * dt - inversion`), and [`WideMask`], the truth values its comparisons give.
//!
//! Each operator is one vector instruction of the instance (`#[inline(always)]`, so it is
//! compiled with the instance's features); the values and their order are those of the
//! expression as written, so every instance computes the same bits.

use super::lanes::Lanes;
use super::rows::{Compare, Rows};
use crate::Real;
use core::ops::{Add, BitAnd, BitOr, Mul, Sub};

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
    ///
    /// # Safety
    /// The CPU supports the instance `I` ([`Rows::splat`]).
    #[inline(always)]
    pub unsafe fn splat(x: Real) -> Self {
        // SAFETY: as required of the caller.
        Wide(unsafe { I::splat(x) })
    }

    /// Lanes `at..at + N` of a chunk's lane array.
    ///
    /// # Safety
    /// As for [`Wide::splat`].
    #[inline(always)]
    pub unsafe fn load<const W: usize>(lanes: &[Real; W], at: usize) -> Self {
        // SAFETY: as required of the caller.
        Wide(unsafe { I::load(lanes, at) })
    }

    /// Writes the lanes to `at..at + N` of a chunk's lane array.
    #[inline(always)]
    pub fn store<const W: usize>(self, lanes: &mut [Real; W], at: usize) {
        I::store(self.0, lanes, at)
    }
}

impl<I: Rows> Add for Wide<I> {
    type Output = Self;
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        Wide(I::add(self.0, b.0))
    }
}

impl<I: Rows> Mul for Wide<I> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        Wide(I::mul(self.0, b.0))
    }
}

impl<I: Compare> Sub for Wide<I> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        Wide(I::sub(self.0, b.0))
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

    /// `self > b` per lane.
    #[inline(always)]
    pub fn gt(self, b: Self) -> WideMask<I> {
        WideMask(I::gt(self.0, b.0))
    }

    /// Whether each lane is finite.
    #[inline(always)]
    pub fn is_finite(self) -> WideMask<I> {
        WideMask(I::finite(self.0))
    }
}

impl<I: Compare> WideMask<I> {
    /// Every lane `b`.
    ///
    /// # Safety
    /// As for [`Wide::splat`].
    #[inline(always)]
    pub unsafe fn splat(b: bool) -> Self {
        // SAFETY: as required of the caller.
        WideMask(unsafe { I::splat_mask(b) })
    }

    /// `a` where the mask holds, else `b`.
    #[inline(always)]
    pub fn select(self, a: Wide<I>, b: Wide<I>) -> Wide<I> {
        Wide(I::select(self.0, a.0, b.0))
    }

    /// The mask and not `b`.
    #[inline(always)]
    pub fn and_not(self, b: Self) -> Self {
        WideMask(I::and_not(self.0, b.0))
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
