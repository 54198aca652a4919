//! The number type the per-particle formulas are written on, once: [`Num`] is a real of one
//! particle ([`Real`]: the reference step, and a chunk's lane-by-lane loops, which the compiler
//! vectorises) or of the lanes of one vector of the instance that runs (`simd::wide::Wide`:
//! a chunk's passes, a model that asks for it), with the arithmetic operators, comparisons,
//! selects and the few functions the models need. A material model or a matrix helper written
//! on `T: Num` serves both.
//!
//! Each lane does the operations of the scalar expression in the same order, so a lane gets
//! the bits one particle would get alone.

use crate::Real;
use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real of one particle or of a vector of particles, with the operations the models use.
pub trait Num:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<Real, Output = Self>
    + Sub<Real, Output = Self>
    + Mul<Real, Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// Truth values of comparisons, one per lane.
    type Mask: Truth;

    /// Every lane `x`.
    fn splat(x: Real) -> Self;
    /// `f` applied to each lane (`f` branch-free where the loop must vectorise).
    fn map(self, f: impl Fn(Real) -> Real) -> Self;
    /// `self >= b` per lane (false with a NaN).
    fn ge(self, b: Self) -> Self::Mask;
    /// `self > b` per lane (false with a NaN).
    fn gt(self, b: Self) -> Self::Mask;
    /// `a` where `m` holds, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Square root, correctly rounded ([`sqrt`]).
    fn sqrt(self) -> Self;
}

/// Truth values, one per lane of a [`Num`].
pub trait Truth: Copy + BitAnd<Output = Self> + BitOr<Output = Self> {
    /// Where `self` holds and `b` does not.
    fn and_not(self, b: Self) -> Self;
    /// Whether any lane holds.
    fn any(self) -> bool;
}

impl Truth for bool {
    #[inline(always)]
    fn and_not(self, b: bool) -> bool {
        self && !b
    }
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
}

impl Num for Real {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: Real) -> Self {
        x
    }
    #[inline(always)]
    fn map(self, f: impl Fn(Real) -> Real) -> Self {
        f(self)
    }
    #[inline(always)]
    fn ge(self, b: Self) -> bool {
        self >= b
    }
    #[inline(always)]
    fn gt(self, b: Self) -> bool {
        self > b
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m {
            a
        } else {
            b
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        sqrt(self)
    }
}

/// Square root, correctly rounded. On x86-64 through the SSE2 intrinsic, which the compiler
/// knows as a square root: it vectorises loops over lanes and takes the VEX form inside AVX
/// code. libm's `sqrtss` is inline assembly, which does neither, and in legacy encoding it
/// also waits for the register's previous value (the corotated model's lane loop took 3 times
/// as long with it).
#[inline(always)]
pub fn sqrt(x: Real) -> Real {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::*;
        // SAFETY: SSE and SSE2 are part of x86-64 itself: every x86-64 CPU has them.
        #[cfg(not(feature = "f64"))]
        unsafe {
            _mm_cvtss_f32(_mm_sqrt_ss(_mm_set_ss(x)))
        }
        // SAFETY: as above.
        #[cfg(feature = "f64")]
        unsafe {
            _mm_cvtsd_f64(_mm_sqrt_pd(_mm_set_sd(x)))
        }
    }
    #[cfg(all(not(target_arch = "x86_64"), not(feature = "f64")))]
    {
        libm::sqrtf(x)
    }
    #[cfg(all(not(target_arch = "x86_64"), feature = "f64"))]
    {
        libm::sqrt(x)
    }
}

/// `f(i)` for each of `N` entries: a plain loop, as [`matrix`] (`array::from_fn` left a
/// closure of vector arithmetic out of line, compiled without the instance's features). `f`
/// itself is a closure too, and LLVM may leave one out of line where it is larger than a few
/// operations (a select per entry, a `map`): its vector operations are then calls, one per
/// operator. A model writes those entries in a loop of its own.
#[inline(always)]
pub fn vector<T: Num, const N: usize>(mut f: impl FnMut(usize) -> T) -> [T; N] {
    let mut v = [T::splat(0.0); N];
    for (i, x) in v.iter_mut().enumerate() {
        *x = f(i);
    }
    v
}

/// A `D x D` matrix of [`Num`]s, row-major.
pub type MatOf<T, const D: usize> = [[T; D]; D];

/// `f(a, b)` for each entry of a `D x D` matrix: a plain loop (`array::from_fn` went through
/// `try_map` machinery the compiler left out of line, and copied through `memcpy`).
#[inline(always)]
pub fn matrix<T: Num, const D: usize>(f: impl Fn(usize, usize) -> T) -> MatOf<T, D> {
    let mut m = [[T::splat(0.0); D]; D];
    for (a, row) in m.iter_mut().enumerate() {
        for (b, v) in row.iter_mut().enumerate() {
            *v = f(a, b);
        }
    }
    m
}
