//! A chunk of particles seen as lanes: the chunk width ([`width`]), one value per lane ([`Lane`]), a
//! set of lanes ([`Lanes`]), a chunk's slice of a column loaded ([`load`]) and written back
//! lane by lane ([`commit`]) and its live lanes ([`live_lanes`]); its stencils come from
//! [`crate::phases::stencils`].
//! The particle passes work chunk by chunk with these; what the scatter and the gathers share
//! lives here, so the phases do not import each other for it.

use crate::particles::{ParticleCols, ACTIVE};
use crate::shape::Row4;
use crate::Real;

/// Particles per chunk in a `D`-dimensional world: a multiple of 4 (the vector code works
/// on groups of 4 lanes) that divides the particle columns' padding ([`crate::CHUNK`]), so a
/// chunk never reads or writes past a column. Every pass takes it as its const parameter `W`
/// ([`crate::world`] picks it with the dimension). In 2D, 32: a chunk's lane loops then run
/// two 512-bit registers per value (four 256-bit ones in the AVX2 instance), whose work
/// overlaps, and each chunk's fixed costs are shared by twice the particles (the default 2D
/// step 0.90 of its time with 16 in the AVX-512 instance, 0.87 in the AVX2 one); in 3D, 16:
/// with 32 the 3D passes' larger lane state took 1.2 to 1.4 times as long. 16 measured
/// faster than 8 in the AVX2 instance. With the `f64` feature 16 in 2D as well: a value of 32
/// f64 lanes is eight 256-bit registers, and the 2D f64 step took 1.17 times as long in the
/// AVX2 instance (1.03 with 16, against the step before chunks of 32; 5 interleaved rounds).
pub(crate) const fn width(d: usize) -> usize {
    if d == 3 || cfg!(feature = "f64") {
        16
    } else {
        32
    }
}

/// The widest chunk ([`width`]): the chunk buffers' bit sets hold this many lanes.
pub(crate) const MAX_W: usize = 32;
const _: () = assert!(
    width(2).is_multiple_of(4)
        && width(3).is_multiple_of(4)
        && width(2) <= MAX_W
        && width(3) <= MAX_W
        && crate::CHUNK.is_multiple_of(width(2))
        && crate::CHUNK.is_multiple_of(width(3))
);

/// The comparison mask of four [`Row4`] lanes.
#[cfg(not(feature = "f64"))]
pub(crate) type Mask4 = glam::BVec4A;
#[cfg(feature = "f64")]
pub(crate) type Mask4 = glam::BVec4;

/// One value per lane of a chunk of `W`.
pub(crate) type Lane<const W: usize> = [Real; W];

/// A set of a chunk's lanes, one bit each (bit `ln` for lane `ln`). The passes keep their
/// per-lane flags (live, updated, frozen, stopped, escaped) as such sets: an array of `bool`s
/// cost a byte insert per lane and flag, about 7 % of the default step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Lanes<const W: usize>(u32);

const _: () = assert!(MAX_W <= 32);

impl<const W: usize> Lanes<W> {
    pub const NONE: Self = Lanes(0);
    pub const ALL: Self = Lanes(u32::MAX >> (32 - W));

    /// The lanes `ln` for which `f(ln)` holds.
    #[inline(always)]
    pub fn from_fn(mut f: impl FnMut(usize) -> bool) -> Self {
        let mut bits = 0;
        for ln in 0..W {
            bits |= (f(ln) as u32) << ln;
        }
        Lanes(bits)
    }

    /// Lanes `q..q + 4` where the compare mask `mask` of those four lanes holds (`q` a
    /// multiple of 4 below `W`).
    #[inline(always)]
    pub fn group(q: usize, mask: Mask4) -> Self {
        Lanes::at(q, mask.bitmask())
    }

    /// Lanes `q..q + n` from `bits`, bit `i` for lane `q + i` (a [`crate::simd::rows::Compare`]
    /// mask's bits; `q` a multiple of the vectors' lane count `n`, below `W`).
    #[inline(always)]
    pub fn at(q: usize, bits: u32) -> Self {
        Lanes((bits << q) & Self::ALL.0)
    }

    /// The lanes whose value equals `v`, for a `v` below 2^24 (statuses): compared as reals,
    /// four lanes at a time, since converting four integers and one vector compare is what
    /// both instruction sets have (a plain loop of integer compares ran lane by lane, 6.5
    /// instructions per particle-step in the baseline instance). Exact: such a `v` converts
    /// exactly, and a value converts to `v` only if it is `v` (one above 2^24 rounds to a
    /// real above 2^24).
    #[inline(always)]
    pub fn equal(values: &[u32; W], v: u32) -> Self {
        let mut set = Lanes::NONE;
        for q in (0..W).step_by(4) {
            let row = Row4::new(
                values[q] as i32 as Real,
                values[q + 1] as i32 as Real,
                values[q + 2] as i32 as Real,
                values[q + 3] as i32 as Real,
            );
            set = set | Lanes::group(q, row.cmpeq(Row4::splat(v as i32 as Real)));
        }
        set
    }

    /// These lanes among the first `n` (all of them from `n >= W`).
    #[inline(always)]
    pub fn first_n(self, n: usize) -> Self {
        if n >= W {
            self
        } else {
            Lanes(self.0 & ((1u32 << n) - 1))
        }
    }

    #[inline(always)]
    pub fn has(self, ln: usize) -> bool {
        self.0 >> ln & 1 != 0
    }

    #[inline(always)]
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0.count_ones()
    }

    /// The lowest lane in the set.
    #[inline(always)]
    pub fn first(self) -> Option<usize> {
        if self.0 == 0 {
            None
        } else {
            Some(self.0.trailing_zeros() as usize)
        }
    }

    /// The lanes in the set, in increasing order.
    #[inline(always)]
    pub fn iter(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0;
        core::iter::from_fn(move || {
            (bits != 0).then(|| {
                let ln = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                ln
            })
        })
    }

    /// The lanes in `self` but not in `other`.
    #[inline(always)]
    pub fn minus(self, other: Self) -> Self {
        Lanes(self.0 & !other.0)
    }
}

impl<const W: usize> core::ops::BitAnd for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Lanes(self.0 & o.0)
    }
}

impl<const W: usize> core::ops::BitOr for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Lanes(self.0 | o.0)
    }
}

/// `dst[lane] = if keep has lane { new[lane] } else { dst[lane] }` over a column slice.
#[inline(always)]
pub(crate) fn commit<const W: usize>(
    dst: &mut [Real],
    start: usize,
    new: &Lane<W>,
    keep: Lanes<W>,
) {
    if let Some(d) = dst.get_mut(start..start + W) {
        if keep == Lanes::ALL {
            // The common case: every lane was updated.
            d.copy_from_slice(new);
        } else {
            for l in keep.iter() {
                d[l] = new[l];
            }
        }
    }
}

/// A chunk buffer that starts on a cache line. Lane arrays of reals are otherwise only
/// 4-byte aligned, and their vector loads and stores then straddle lines and each other
/// (benches/PERFORMANCE.md: the default 2D step about 1.5 % faster).
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub(crate) struct Block<T>(pub T);

impl<T> core::ops::Deref for Block<T> {
    type Target = T;
    #[inline(always)]
    fn deref(&self) -> &T {
        &self.0
    }
}

impl<T> core::ops::DerefMut for Block<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut T {
        &mut self.0
    }
}

/// Loads lanes `start..start + W` of a column (zeros past its end), with one bounds check for
/// the chunk (a check per lane kept `from_fn` from being inlined).
#[inline(always)]
pub(crate) fn load<T: Copy + Default, const W: usize>(col: &[T], start: usize) -> [T; W] {
    let mut lanes = [T::default(); W];
    load_into(&mut lanes, col, start);
    lanes
}

/// [`load`] into a buffer the pass keeps across chunks. The chunk loops load into such
/// buffers rather than into new arrays: arrays built per chunk (by `core::array::from_fn` or
/// returned through an `Option`) were copied two or three times on the stack before use.
#[inline(always)]
pub(crate) fn load_into<T: Copy + Default, const W: usize>(
    dst: &mut [T; W],
    col: &[T],
    start: usize,
) {
    match col.get(start..start + W) {
        Some(c) => dst.copy_from_slice(c),
        None => dst.fill(T::default()),
    }
}

/// Lanes `start..start + W` that hold active particles (`< count`).
#[inline(always)]
pub(crate) fn live_lanes<const D: usize, const W: usize>(
    p: &ParticleCols<'_, D>,
    start: usize,
    count: usize,
) -> Lanes<W> {
    active_lanes(p.status, start, count)
}

/// [`live_lanes`] from the status column `status`.
#[inline(always)]
pub(crate) fn active_lanes<const W: usize>(status: &[u32], start: usize, count: usize) -> Lanes<W> {
    let n = W.min(count.saturating_sub(start));
    Lanes::equal(&load(status, start), ACTIVE).first_n(n)
}
