//! The number types the per-particle formulas are written on, once: [`Num`] is a real of one
//! particle ([`Real`]) or of `W` particles at once ([`Pack`]), with the arithmetic operators and
//! the few functions the models need. A material model or a matrix helper written on `T: Num`
//! serves the reference step (`T = Real`) and a chunk's stress update, which runs it lane by
//! lane in a loop the compiler vectorises (`T = Real` again) or, for a model that asks for it
//! ([`crate::material`]'s `Model::packed`), on one pack of the chunk (`T = Pack<W>`).
//!
//! A [`Pack`] operator is a loop over its `W` lanes that the compiler vectorises inside the
//! instruction set of the pass that inlines it; each lane does the operations of the scalar
//! expression in the same order, so a lane gets the bits one particle would get alone.

use crate::Real;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real of one particle or of a pack of particles, with the operations the models use.
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
    type Mask: Copy;

    /// Every lane `x`.
    fn splat(x: Real) -> Self;
    /// The 3D iteration of [`crate::math::polar_rotation_minus_identity`]: the one place a
    /// formula is not written on the operators, because its number of rounds differs by
    /// particle; [`crate::math::polar_newton_lanes`] runs it over this type's lanes.
    fn polar_newton<const D: usize>(h: &MatOf<Self, D>) -> MatOf<Self, D>;
    /// `f` applied to each lane (`f` branch-free where the loop must vectorise).
    fn map(self, f: impl Fn(Real) -> Real) -> Self;
    /// `self >= b` per lane (false with a NaN).
    fn ge(self, b: Self) -> Self::Mask;
    /// `self > b` per lane (false with a NaN).
    fn gt(self, b: Self) -> Self::Mask;
    /// `a` where `m` holds, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;

    /// Square root, correctly rounded ([`crate::math::sqrt`]).
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(crate::math::sqrt)
    }
}

impl Num for Real {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: Real) -> Self {
        x
    }
    #[inline(always)]
    fn polar_newton<const D: usize>(h: &MatOf<Self, D>) -> MatOf<Self, D> {
        let mut one = [[[0.0; 1]; D]; D];
        for (o, row) in one.iter_mut().zip(h) {
            for (o, v) in o.iter_mut().zip(row) {
                *o = [*v];
            }
        }
        let q = crate::math::polar_newton_lanes(&one);
        matrix(|a, b| q[a][b][0])
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
}

/// `W` reals, one per particle of a chunk, stored as a plain array.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct Pack<const W: usize>(pub [Real; W]);

/// `W` truth values, one per lane of a [`Pack`], each all ones or all zeros in an integer as
/// wide as a [`Real`] (the vector compare's own form: as `bool`s, each select and comparison
/// went through byte inserts and extracts).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct PackMask<const W: usize>(pub [Bits; W]);

/// The unsigned integer as wide as [`Real`].
#[cfg(not(feature = "f64"))]
type Bits = u32;
#[cfg(feature = "f64")]
type Bits = u64;

/// All ones for true.
#[inline(always)]
fn ones(b: bool) -> Bits {
    (b as Bits).wrapping_neg()
}

/// `f(lane)` for each lane. A plain loop: `array::map` and `array::from_fn` went through
/// `try_map` machinery the compiler left out of line (and copied through `memcpy`).
#[inline(always)]
fn lanewise<U: Copy + Default, const W: usize>(f: impl Fn(usize) -> U) -> [U; W] {
    let mut out = [U::default(); W];
    for (i, o) in out.iter_mut().enumerate() {
        *o = f(i);
    }
    out
}

/// `f(a[i], b[i])` lane by lane.
#[inline(always)]
fn zip<T: Copy, U: Copy + Default, const W: usize>(
    a: [T; W],
    b: [T; W],
    f: impl Fn(T, T) -> U,
) -> [U; W] {
    lanewise(|i| f(a[i], b[i]))
}

/// `f(a[i])` lane by lane.
#[inline(always)]
fn each<T: Copy, U: Copy + Default, const W: usize>(a: [T; W], f: impl Fn(T) -> U) -> [U; W] {
    lanewise(|i| f(a[i]))
}

macro_rules! pack_op {
    ($tr:ident, $f:ident, $assign:ident, $fa:ident, $op:tt) => {
        impl<const W: usize> $tr for Pack<W> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Self) -> Self {
                Pack(zip(self.0, b.0, |x, y| x $op y))
            }
        }
        impl<const W: usize> $tr<Real> for Pack<W> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Real) -> Self {
                Pack(each(self.0, |x| x $op b))
            }
        }
        impl<const W: usize> $tr<Pack<W>> for Real {
            type Output = Pack<W>;
            #[inline(always)]
            fn $f(self, b: Pack<W>) -> Pack<W> {
                Pack(each(b.0, |y| self $op y))
            }
        }
        impl<const W: usize> $assign for Pack<W> {
            #[inline(always)]
            fn $fa(&mut self, b: Self) {
                *self = *self $op b;
            }
        }
    };
}

pack_op!(Add, add, AddAssign, add_assign, +);
pack_op!(Sub, sub, SubAssign, sub_assign, -);
pack_op!(Mul, mul, MulAssign, mul_assign, *);
pack_op!(Div, div, DivAssign, div_assign, /);

impl<const W: usize> Neg for Pack<W> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Pack(each(self.0, |x| -x))
    }
}

impl<const W: usize> Num for Pack<W> {
    type Mask = PackMask<W>;
    #[inline(always)]
    fn splat(x: Real) -> Self {
        Pack([x; W])
    }
    #[inline(always)]
    fn polar_newton<const D: usize>(h: &MatOf<Self, D>) -> MatOf<Self, D> {
        let q = crate::math::polar_newton_lanes(unpacked(h));
        *packs(&q)
    }
    #[inline(always)]
    fn map(self, f: impl Fn(Real) -> Real) -> Self {
        Pack(each(self.0, f))
    }
    #[inline(always)]
    fn ge(self, b: Self) -> PackMask<W> {
        PackMask(zip(self.0, b.0, |x, y| ones(x >= y)))
    }
    #[inline(always)]
    fn gt(self, b: Self) -> PackMask<W> {
        PackMask(zip(self.0, b.0, |x, y| ones(x > y)))
    }
    #[inline(always)]
    fn select(m: PackMask<W>, a: Self, b: Self) -> Self {
        Pack(lanewise(|i| {
            Real::from_bits((a.0[i].to_bits() & m.0[i]) | (b.0[i].to_bits() & !m.0[i]))
        }))
    }
}

/// A `D x D` matrix of [`Num`]s, row-major.
pub type MatOf<T, const D: usize> = [[T; D]; D];

/// A chunk's lane array `m[a][b][lane]` seen as a matrix of packs, without a copy (a copy
/// of a 3D matrix of 16 lanes went through `memcpy`).
#[inline(always)]
pub(crate) fn packs<const D: usize, const W: usize>(m: &[[[Real; W]; D]; D]) -> &MatOf<Pack<W>, D> {
    // SAFETY: `Pack<W>` is `repr(transparent)` over `[Real; W]`, so `[[Pack<W>; D]; D]` has
    // the layout and validity of `[[[Real; W]; D]; D]`; the borrow keeps `m`'s lifetime.
    unsafe { &*(m as *const [[[Real; W]; D]; D]).cast::<MatOf<Pack<W>, D>>() }
}

/// A matrix of packs seen as a chunk's lane array `m[a][b][lane]`, without a copy (the
/// inverse of [`packs`]).
#[inline(always)]
pub(crate) fn unpacked<const D: usize, const W: usize>(
    m: &MatOf<Pack<W>, D>,
) -> &[[[Real; W]; D]; D] {
    // SAFETY: as in [`packs`], the other way round.
    unsafe { &*(m as *const MatOf<Pack<W>, D>).cast::<[[[Real; W]; D]; D]>() }
}

/// `f(a, b)` for each entry of a `D x D` matrix: a plain loop (see [`lanewise`]).
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
