//! Reading a chunk's stencil rows lane-major, in the registers of the instance that runs: for
//! each node `i` along x of a stencil row, one vector of [`Rows::N`] lanes holding that node's
//! value for each of those lanes. The gathers then weight and sum the nodes with vector
//! arithmetic over the lanes (16 per operation in the AVX-512 instance, 8 in the AVX2 one),
//! their sums held in registers, instead of weighting each particle's 4-wide rows and
//! transposing the sums back into lanes.
//!
//! Each instance of the passes ([`super::Isa`]) has its own [`Rows`]: the lanes' rows
//! are loaded as 4-wide vectors and transposed four lanes at a time, in the 128-bit blocks of
//! 256-bit (AVX2) or 512-bit (AVX-512) registers where the instance has them. Every
//! implementation computes the same operations on the same values in the same order, so
//! results do not depend on it.

use super::lanes::{Lanes, Mask4};
use crate::shape::{Row4, ROW};
use crate::Real;

/// The vectors an instance of the passes sums stencil rows with.
///
/// Making a vector ([`Rows::splat`], [`Rows::load`], [`Rows::rows`]) is `unsafe`: only an
/// instance the CPU supports may run it. Arithmetic on vectors made so is safe: the wide
/// instances' vector types can be made by those functions alone.
pub(crate) trait Rows {
    /// Lanes per vector: divides every chunk width ([`super::lanes::width`]).
    const N: usize;
    /// `N` lanes of reals.
    type V: Copy;
    /// An instance with vectors of at most 8 lanes that every CPU running this one supports
    /// (the AVX2 one for AVX-512, else itself).
    type Narrow: Rows;

    /// Every lane `x`.
    ///
    /// # Safety
    /// The CPU supports this instance (the passes are only run by an instance
    /// [`crate::simd`] chose).
    unsafe fn splat(x: Real) -> Self::V;

    /// Lanes `at..at + N` of a chunk's lane array.
    ///
    /// # Safety
    /// As for [`Rows::splat`].
    unsafe fn load<const W: usize>(lanes: &[Real; W], at: usize) -> Self::V;

    /// Writes `v` to lanes `at..at + N` of a chunk's lane array.
    fn store<const W: usize>(v: Self::V, lanes: &mut [Real; W], at: usize);

    fn add(a: Self::V, b: Self::V) -> Self::V;

    fn mul(a: Self::V, b: Self::V) -> Self::V;

    /// The stencil rows (the [`ROW`] reals from `col[base[ln] + off]`) of lanes `ln = at + q`,
    /// `at + q + 4`, ... in the 128-bit blocks of a vector, for `q < 4`.
    ///
    /// # Safety
    /// As for [`Rows::splat`], and `base[ln] + off + ROW <= col.len()` for every lane `ln` of
    /// the chunk (see [`fit`]).
    unsafe fn blocks<const W: usize>(
        col: &[Real],
        base: &[u32; W],
        at: usize,
        off: usize,
        q: usize,
    ) -> Self::V;

    /// The [`ROW`] nodes of a stencil row of lanes `at..at + N` (those past the stencil's own
    /// nodes are read and left for the caller to ignore): lane `q` of result `i` is
    /// `col[base[at + q] + off + i]`. The lanes' rows, four lanes to a vector's blocks, then
    /// transposed within the blocks.
    ///
    /// # Safety
    /// As for [`Rows::blocks`].
    #[inline(always)]
    unsafe fn rows<const W: usize>(
        col: &[Real],
        base: &[u32; W],
        at: usize,
        off: usize,
    ) -> [Self::V; ROW] {
        // SAFETY: as required of the caller.
        unsafe {
            Self::transpose([
                Self::blocks(col, base, at, off, 0),
                Self::blocks(col, base, at, off, 1),
                Self::blocks(col, base, at, off, 2),
                Self::blocks(col, base, at, off, 3),
            ])
        }
    }

    /// [`Rows::rows`] for a chunk whose lanes share their first node four by four (see
    /// [`blocks_share`]): the row of the first lane of each four, its nodes spread over the
    /// four lanes. One row load per four lanes and no transposes; the same values where the
    /// lanes do share (else the first lane's values).
    ///
    /// # Safety
    /// As for [`Rows::blocks`].
    #[inline(always)]
    unsafe fn rows_shared<const W: usize>(
        col: &[Real],
        base: &[u32; W],
        at: usize,
        off: usize,
    ) -> [Self::V; ROW] {
        // SAFETY: as required of the caller.
        let z = unsafe { Self::blocks(col, base, at, off, 0) };
        [
            Self::spread(z, 0),
            Self::spread(z, 1),
            Self::spread(z, 2),
            Self::spread(z, 3),
        ]
    }

    /// The 4 x 4 transpose within each 128-bit block: element `q` of block `c` of result `i`
    /// is element `i` of block `c` of `z[q]`. Turns rows of four lanes into lanes of four
    /// rows, and back.
    fn transpose(z: [Self::V; 4]) -> [Self::V; 4];

    /// Block `c < N / 4` of `v`: lanes `4 c .. 4 c + 4`.
    fn block(v: Self::V, c: usize) -> Row4;

    /// Lane `q < 4` of each 128-bit block of `v`, spread over its block.
    fn spread(v: Self::V, q: usize) -> Self::V;
}

/// Comparisons and selects on an instance's vectors, for the particle update's walls and
/// checks (`g2p::particles`), which run on as many lanes at once as the instance's vectors
/// hold. A comparison is false where either value is NaN, in every instance.
pub(crate) trait Compare: Rows {
    /// One truth value per lane of a [`Rows::V`].
    type M: Copy;

    fn sub(a: Self::V, b: Self::V) -> Self::V;

    fn div(a: Self::V, b: Self::V) -> Self::V;

    /// `-a` (the sign flipped, as the scalar negation does).
    fn neg(a: Self::V) -> Self::V;

    /// Square root per lane, correctly rounded (as [`crate::num::sqrt`]).
    fn sqrt(a: Self::V) -> Self::V;

    /// `a >= b` per lane.
    fn ge(a: Self::V, b: Self::V) -> Self::M;

    /// `a < b` per lane.
    fn lt(a: Self::V, b: Self::V) -> Self::M;

    /// `a > b` per lane.
    fn gt(a: Self::V, b: Self::V) -> Self::M;

    /// Whether each lane of `v` is finite.
    fn finite(v: Self::V) -> Self::M;

    /// `a` where `m` holds, else `b`.
    fn select(m: Self::M, a: Self::V, b: Self::V) -> Self::V;

    fn and(a: Self::M, b: Self::M) -> Self::M;

    fn or(a: Self::M, b: Self::M) -> Self::M;

    /// `a` and not `b`.
    fn and_not(a: Self::M, b: Self::M) -> Self::M;

    /// Every lane `b`.
    ///
    /// # Safety
    /// As for [`Rows::splat`].
    unsafe fn splat_mask(b: bool) -> Self::M;

    /// Bit `q` set where lane `q` holds.
    fn bits(m: Self::M) -> u32;
}

/// The lanes of a chunk whose value is above `bound`, [`Rows::N`] lanes per compare.
#[inline(always)]
pub(crate) fn above<I: Compare, const W: usize>(values: &[Real; W], bound: Real) -> Lanes<W> {
    compared::<I, W, true>(values, bound)
}

/// The lanes of a chunk whose value is below `bound`, [`Rows::N`] lanes per compare.
#[inline(always)]
pub(crate) fn below<I: Compare, const W: usize>(values: &[Real; W], bound: Real) -> Lanes<W> {
    compared::<I, W, false>(values, bound)
}

/// The lanes of a chunk whose value is above (`ABOVE`) or below `bound`.
#[inline(always)]
fn compared<I: Compare, const W: usize, const ABOVE: bool>(
    values: &[Real; W],
    bound: Real,
) -> Lanes<W> {
    let mut set = Lanes::NONE;
    // SAFETY: this instance runs only on a CPU that supports it.
    let b = unsafe { I::splat(bound) };
    for q in (0..W).step_by(I::N) {
        // SAFETY: as above.
        let v = unsafe { I::load(values, q) };
        let m = if ABOVE { I::gt(v, b) } else { I::lt(v, b) };
        set = set | Lanes::at(q, I::bits(m));
    }
    set
}

/// Whether the lanes of a chunk share their stencil's first node four by four (lanes `4 c` to
/// `4 c + 3` for every `c`): what the fills' stencil-bin order gives at 2 particles per cell
/// per axis, 4 or 8 to a bin ([`crate::World::fill_box`]).
#[inline(always)]
pub(crate) fn blocks_share<const W: usize>(base: &[u32; W]) -> bool {
    let mut same = true;
    for ln in 0..W {
        same &= base[ln] == base[ln & !3];
    }
    same
}

/// The nodes of a stencil row of lanes `at..at + N` ([`Rows::rows`], or [`Rows::rows_shared`]
/// where `shared`, from [`blocks_share`]).
///
/// # Safety
/// As for [`Rows::rows`].
#[inline(always)]
pub(crate) unsafe fn read<I: Rows, const W: usize>(
    col: &[Real],
    base: &[u32; W],
    at: usize,
    off: usize,
    shared: bool,
) -> [I::V; ROW] {
    // SAFETY: as required of the caller.
    unsafe {
        if shared {
            I::rows_shared(col, base, at, off)
        } else {
            I::rows(col, base, at, off)
        }
    }
}

/// Whether the stencil rows of every lane fit in columns of `len` entries: the rows of a
/// stencil whose first node is `base` reach `base + last_row_offset + ROW`. Checked once per
/// chunk, so that [`Rows::rows`] may read without a check per lane.
#[inline(always)]
pub(crate) fn fit<const W: usize>(base: &[u32; W], last_row_offset: usize, len: usize) -> bool {
    let mut top = 0;
    for &b in base {
        top = top.max(b);
    }
    crate::grid::rows_fit(top as usize, last_row_offset, len)
}

/// Four lanes per vector, glam's [`Row4`]: each lane's row loaded as one, the four transposed
/// (SSE2 shuffles in f32). What the baseline instance runs, and every instance in f64.
macro_rules! by_four {
    () => {
        const N: usize = 4;
        type V = Row4;
        type Narrow = Self;

        #[inline(always)]
        unsafe fn splat(x: Real) -> Row4 {
            Row4::splat(x)
        }

        #[inline(always)]
        unsafe fn load<const W: usize>(lanes: &[Real; W], at: usize) -> Row4 {
            Row4::from_slice(&lanes[at..at + 4])
        }

        #[inline(always)]
        fn store<const W: usize>(v: Row4, lanes: &mut [Real; W], at: usize) {
            v.write_to_slice(&mut lanes[at..at + 4]);
        }

        #[inline(always)]
        fn add(a: Row4, b: Row4) -> Row4 {
            a + b
        }

        #[inline(always)]
        fn mul(a: Row4, b: Row4) -> Row4 {
            a * b
        }

        #[inline(always)]
        unsafe fn blocks<const W: usize>(
            col: &[Real],
            base: &[u32; W],
            at: usize,
            off: usize,
            q: usize,
        ) -> Row4 {
            // SAFETY: the caller guarantees that every lane's row is inside `col`.
            unsafe { crate::grid::load_row(col, base[at + q] as usize + off) }
        }

        #[inline(always)]
        fn transpose(z: [Row4; 4]) -> [Row4; 4] {
            crate::shape::transpose4_rows(z)
        }

        #[inline(always)]
        fn block(v: Row4, _c: usize) -> Row4 {
            v
        }

        #[inline(always)]
        fn spread(v: Row4, q: usize) -> Row4 {
            use glam::Vec4Swizzles;
            match q {
                0 => v.xxxx(),
                1 => v.yyyy(),
                2 => v.zzzz(),
                _ => v.wwww(),
            }
        }
    };
}

impl Rows for super::Baseline {
    by_four!();
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd", feature = "f64"))]
impl Rows for super::Avx2 {
    by_four!();
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd", feature = "f64"))]
impl Rows for super::Avx512 {
    by_four!();
}

/// [`Compare`] on glam's [`Row4`] and its masks: the baseline instance, and every instance in
/// f64.
macro_rules! by_four_compare {
    () => {
        type M = Mask4;

        #[inline(always)]
        fn sub(a: Row4, b: Row4) -> Row4 {
            a - b
        }

        #[inline(always)]
        fn div(a: Row4, b: Row4) -> Row4 {
            a / b
        }

        #[inline(always)]
        fn neg(a: Row4) -> Row4 {
            -a
        }

        #[inline(always)]
        fn sqrt(a: Row4) -> Row4 {
            use crate::num::sqrt;
            Row4::new(sqrt(a.x), sqrt(a.y), sqrt(a.z), sqrt(a.w))
        }

        #[inline(always)]
        fn ge(a: Row4, b: Row4) -> Mask4 {
            a.cmpge(b)
        }

        #[inline(always)]
        fn lt(a: Row4, b: Row4) -> Mask4 {
            a.cmplt(b)
        }

        #[inline(always)]
        fn gt(a: Row4, b: Row4) -> Mask4 {
            a.cmpgt(b)
        }

        #[inline(always)]
        fn finite(v: Row4) -> Mask4 {
            v.is_finite_mask()
        }

        #[inline(always)]
        fn select(m: Mask4, a: Row4, b: Row4) -> Row4 {
            Row4::select(m, a, b)
        }

        #[inline(always)]
        fn and(a: Mask4, b: Mask4) -> Mask4 {
            a & b
        }

        #[inline(always)]
        fn or(a: Mask4, b: Mask4) -> Mask4 {
            a | b
        }

        #[inline(always)]
        fn and_not(a: Mask4, b: Mask4) -> Mask4 {
            a & !b
        }

        #[inline(always)]
        unsafe fn splat_mask(b: bool) -> Mask4 {
            Mask4::splat(b)
        }

        #[inline(always)]
        fn bits(m: Mask4) -> u32 {
            m.bitmask()
        }
    };
}

impl Compare for super::Baseline {
    by_four_compare!();
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd", feature = "f64"))]
impl Compare for super::Avx2 {
    by_four_compare!();
}

#[cfg(all(target_arch = "x86_64", feature = "wide-simd", feature = "f64"))]
impl Compare for super::Avx512 {
    by_four_compare!();
}

/// The f32 instances with 256-bit and 512-bit registers.
#[cfg(all(target_arch = "x86_64", feature = "wide-simd", not(feature = "f64")))]
mod x86 {
    use super::*;
    use crate::simd::{Avx2, Avx512};
    use core::arch::x86_64::*;

    /// Eight lanes in a 256-bit register. Only [`Rows`] for [`Avx2`] makes one (its field is
    /// private), so holding one means the CPU has AVX2.
    #[derive(Clone, Copy)]
    pub(crate) struct Y(__m256);

    /// Sixteen lanes in a 512-bit register. Only [`Rows`] for [`Avx512`] makes one, so holding
    /// one means the CPU has AVX-512 F.
    #[derive(Clone, Copy)]
    pub(crate) struct Z(__m512);

    /// The stencil rows (4 reals from `p + b[l] + off`) of lanes `q` and `q + 4` in the two
    /// 128-bit blocks of a register.
    ///
    /// # Safety
    /// AVX2, and those rows are inside the column `p` points into.
    #[inline(always)]
    unsafe fn blocks_y(p: *const f32, b: &[u32], off: usize, q: usize) -> __m256 {
        // SAFETY: as required of the caller.
        unsafe {
            let lo = _mm_loadu_ps(p.add(b[q] as usize + off));
            let hi = _mm_loadu_ps(p.add(b[q + 4] as usize + off));
            _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(lo), hi)
        }
    }

    /// The stencil rows of lanes `q`, `q + 4`, `q + 8` and `q + 12` in the four 128-bit blocks
    /// of a register.
    ///
    /// # Safety
    /// AVX-512 F and DQ, and those rows are inside the column `p` points into.
    #[inline(always)]
    unsafe fn blocks_z(p: *const f32, b: &[u32], off: usize, q: usize) -> __m512 {
        // SAFETY: as required of the caller.
        unsafe {
            let lo = blocks_y(p, b, off, q);
            let hi = blocks_y(p, &b[8..], off, q);
            _mm512_insertf32x8::<1>(_mm512_castps256_ps512(lo), hi)
        }
    }

    /// Block `c` (0 or 1) of a 256-bit register.
    ///
    /// # Safety
    /// AVX.
    #[inline(always)]
    unsafe fn block_y(v: __m256, c: usize) -> __m128 {
        // SAFETY: as required of the caller.
        unsafe {
            if c == 0 {
                _mm256_castps256_ps128(v)
            } else {
                _mm256_extractf128_ps::<1>(v)
            }
        }
    }

    /// Block `c` (0 to 3) of a 512-bit register.
    ///
    /// # Safety
    /// AVX-512 F.
    #[inline(always)]
    unsafe fn block_z(v: __m512, c: usize) -> __m128 {
        // SAFETY: as required of the caller.
        unsafe {
            match c {
                0 => _mm512_castps512_ps128(v),
                1 => _mm512_extractf32x4_ps::<1>(v),
                2 => _mm512_extractf32x4_ps::<2>(v),
                _ => _mm512_extractf32x4_ps::<3>(v),
            }
        }
    }

    /// [`Rows`] for an instance whose vector `$v` wraps one register of `$n` lanes,
    /// with the register's intrinsics and `$blocks`, which loads lanes `q`, `q + 4`, ... into
    /// its 128-bit blocks.
    macro_rules! wide_rows {
        (
            $isa:ident, $v:ident, $n:literal, $narrow:ident, $blocks:ident;
            $set1:ident, $loadu:ident, $storeu:ident, $add:ident, $mul:ident;
            $unpacklo:ident, $unpackhi:ident, $unpacklo_pd:ident, $unpackhi_pd:ident,
            $to_pd:ident, $to_ps:ident, $permute:ident, $block:ident
        ) => {
            impl Rows for $isa {
                const N: usize = $n;
                type V = $v;
                type Narrow = $narrow;

                #[inline(always)]
                unsafe fn splat(x: f32) -> $v {
                    // SAFETY: the caller runs this instance only on a CPU that supports it.
                    $v(unsafe { $set1(x) })
                }

                #[inline(always)]
                unsafe fn load<const W: usize>(lanes: &[f32; W], at: usize) -> $v {
                    let l = &lanes[at..at + $n];
                    // SAFETY: `$n` reals; the instance as for splat.
                    $v(unsafe { $loadu(l.as_ptr()) })
                }

                #[inline(always)]
                fn store<const W: usize>(v: $v, lanes: &mut [f32; W], at: usize) {
                    let l = &mut lanes[at..at + $n];
                    // SAFETY: `$n` reals; a vector of this instance exists only where the CPU
                    // supports the instance.
                    unsafe { $storeu(l.as_mut_ptr(), v.0) }
                }

                #[inline(always)]
                fn add(a: $v, b: $v) -> $v {
                    // SAFETY: as for store.
                    $v(unsafe { $add(a.0, b.0) })
                }

                #[inline(always)]
                fn mul(a: $v, b: $v) -> $v {
                    // SAFETY: as for store.
                    $v(unsafe { $mul(a.0, b.0) })
                }

                #[inline(always)]
                unsafe fn blocks<const W: usize>(
                    col: &[f32],
                    base: &[u32; W],
                    at: usize,
                    off: usize,
                    q: usize,
                ) -> $v {
                    // SAFETY: the caller guarantees that every lane's row is inside `col`, and
                    // that the CPU supports the instance.
                    $v(unsafe { $blocks(col.as_ptr(), &base[at..at + $n], off, q) })
                }

                #[inline(always)]
                fn transpose(z: [$v; 4]) -> [$v; 4] {
                    // SAFETY: a vector of this instance exists only where the CPU supports it.
                    unsafe {
                        let t0 = $unpacklo(z[0].0, z[1].0);
                        let t1 = $unpackhi(z[0].0, z[1].0);
                        let t2 = $unpacklo(z[2].0, z[3].0);
                        let t3 = $unpackhi(z[2].0, z[3].0);
                        [
                            $v($to_ps($unpacklo_pd($to_pd(t0), $to_pd(t2)))),
                            $v($to_ps($unpackhi_pd($to_pd(t0), $to_pd(t2)))),
                            $v($to_ps($unpacklo_pd($to_pd(t1), $to_pd(t3)))),
                            $v($to_ps($unpackhi_pd($to_pd(t1), $to_pd(t3)))),
                        ]
                    }
                }

                #[inline(always)]
                fn spread(v: $v, q: usize) -> $v {
                    // SAFETY: as for transpose.
                    unsafe {
                        $v(match q {
                            0 => $permute::<0x00>(v.0),
                            1 => $permute::<0x55>(v.0),
                            2 => $permute::<0xAA>(v.0),
                            _ => $permute::<0xFF>(v.0),
                        })
                    }
                }

                #[inline(always)]
                fn block(v: $v, c: usize) -> Row4 {
                    // SAFETY: as for transpose.
                    Row4::from(unsafe { $block(v.0, c) })
                }
            }
        };
    }

    wide_rows!(
        Avx2, Y, 8, Avx2, blocks_y;
        _mm256_set1_ps, _mm256_loadu_ps, _mm256_storeu_ps, _mm256_add_ps, _mm256_mul_ps;
        _mm256_unpacklo_ps, _mm256_unpackhi_ps, _mm256_unpacklo_pd, _mm256_unpackhi_pd,
        _mm256_castps_pd, _mm256_castpd_ps, _mm256_permute_ps, block_y
    );

    wide_rows!(
        Avx512, Z, 16, Avx2, blocks_z;
        _mm512_set1_ps, _mm512_loadu_ps, _mm512_storeu_ps, _mm512_add_ps, _mm512_mul_ps;
        _mm512_unpacklo_ps, _mm512_unpackhi_ps, _mm512_unpacklo_pd, _mm512_unpackhi_pd,
        _mm512_castps_pd, _mm512_castpd_ps, _mm512_permute_ps, block_z
    );

    /// Eight lanes' truth values: all bits set or clear per lane of a 256-bit register (the
    /// compare results of [`Avx2`]).
    #[derive(Clone, Copy)]
    pub(crate) struct YM(__m256);

    /// Sixteen lanes' truth values in an AVX-512 mask register.
    #[derive(Clone, Copy)]
    pub(crate) struct ZM(__mmask16);

    impl Compare for Avx2 {
        type M = YM;

        #[inline(always)]
        fn sub(a: Y, b: Y) -> Y {
            // SAFETY: a vector of this instance exists only where the CPU supports it.
            Y(unsafe { _mm256_sub_ps(a.0, b.0) })
        }

        #[inline(always)]
        fn div(a: Y, b: Y) -> Y {
            // SAFETY: as for sub.
            Y(unsafe { _mm256_div_ps(a.0, b.0) })
        }

        #[inline(always)]
        fn neg(a: Y) -> Y {
            // SAFETY: as for sub.
            Y(unsafe { _mm256_xor_ps(a.0, _mm256_set1_ps(-0.0)) })
        }

        #[inline(always)]
        fn sqrt(a: Y) -> Y {
            // SAFETY: as for sub.
            Y(unsafe { _mm256_sqrt_ps(a.0) })
        }

        #[inline(always)]
        fn ge(a: Y, b: Y) -> YM {
            // SAFETY: as for sub.
            YM(unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(a.0, b.0) })
        }

        #[inline(always)]
        fn lt(a: Y, b: Y) -> YM {
            // SAFETY: as for sub.
            YM(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(a.0, b.0) })
        }

        #[inline(always)]
        fn gt(a: Y, b: Y) -> YM {
            // SAFETY: as for sub.
            YM(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(a.0, b.0) })
        }

        #[inline(always)]
        fn finite(v: Y) -> YM {
            // SAFETY: as for sub.
            unsafe {
                let abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0), v.0);
                YM(_mm256_cmp_ps::<_CMP_LT_OQ>(
                    abs,
                    _mm256_set1_ps(f32::INFINITY),
                ))
            }
        }

        #[inline(always)]
        fn select(m: YM, a: Y, b: Y) -> Y {
            // SAFETY: as for sub (a mask of this instance exists only where a vector does).
            Y(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
        }

        #[inline(always)]
        fn and(a: YM, b: YM) -> YM {
            // SAFETY: as for select.
            YM(unsafe { _mm256_and_ps(a.0, b.0) })
        }

        #[inline(always)]
        fn or(a: YM, b: YM) -> YM {
            // SAFETY: as for select.
            YM(unsafe { _mm256_or_ps(a.0, b.0) })
        }

        #[inline(always)]
        fn and_not(a: YM, b: YM) -> YM {
            // SAFETY: as for select.
            YM(unsafe { _mm256_andnot_ps(b.0, a.0) })
        }

        #[inline(always)]
        unsafe fn splat_mask(b: bool) -> YM {
            // SAFETY: the caller runs this instance only on a CPU that supports it.
            YM(unsafe { _mm256_castsi256_ps(_mm256_set1_epi32(-(b as i32))) })
        }

        #[inline(always)]
        fn bits(m: YM) -> u32 {
            // SAFETY: as for select.
            unsafe { _mm256_movemask_ps(m.0) as u32 }
        }
    }

    impl Compare for Avx512 {
        type M = ZM;

        #[inline(always)]
        fn sub(a: Z, b: Z) -> Z {
            // SAFETY: a vector of this instance exists only where the CPU supports it.
            Z(unsafe { _mm512_sub_ps(a.0, b.0) })
        }

        #[inline(always)]
        fn div(a: Z, b: Z) -> Z {
            // SAFETY: as for sub.
            Z(unsafe { _mm512_div_ps(a.0, b.0) })
        }

        #[inline(always)]
        fn neg(a: Z) -> Z {
            // SAFETY: as for sub (AVX-512 DQ has the float xor).
            Z(unsafe { _mm512_xor_ps(a.0, _mm512_set1_ps(-0.0)) })
        }

        #[inline(always)]
        fn sqrt(a: Z) -> Z {
            // SAFETY: as for sub.
            Z(unsafe { _mm512_sqrt_ps(a.0) })
        }

        #[inline(always)]
        fn ge(a: Z, b: Z) -> ZM {
            // SAFETY: as for sub.
            ZM(unsafe { _mm512_cmp_ps_mask::<_CMP_GE_OQ>(a.0, b.0) })
        }

        #[inline(always)]
        fn lt(a: Z, b: Z) -> ZM {
            // SAFETY: as for sub.
            ZM(unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a.0, b.0) })
        }

        #[inline(always)]
        fn gt(a: Z, b: Z) -> ZM {
            // SAFETY: as for sub.
            ZM(unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a.0, b.0) })
        }

        #[inline(always)]
        fn finite(v: Z) -> ZM {
            // SAFETY: as for sub.
            unsafe {
                let inf = _mm512_set1_ps(f32::INFINITY);
                ZM(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(_mm512_abs_ps(v.0), inf))
            }
        }

        #[inline(always)]
        fn select(m: ZM, a: Z, b: Z) -> Z {
            // SAFETY: as for sub (a mask of this instance exists only where a vector does).
            Z(unsafe { _mm512_mask_blend_ps(m.0, b.0, a.0) })
        }

        #[inline(always)]
        fn and(a: ZM, b: ZM) -> ZM {
            ZM(a.0 & b.0)
        }

        #[inline(always)]
        fn or(a: ZM, b: ZM) -> ZM {
            ZM(a.0 | b.0)
        }

        #[inline(always)]
        fn and_not(a: ZM, b: ZM) -> ZM {
            ZM(a.0 & !b.0)
        }

        #[inline(always)]
        unsafe fn splat_mask(b: bool) -> ZM {
            ZM(if b { 0xFFFF } else { 0 })
        }

        #[inline(always)]
        fn bits(m: ZM) -> u32 {
            m.0 as u32
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::lanes::width;

    /// Reads the rows of every lane of a chunk with instance `I` and checks them against the
    /// column; where the lanes share their bases four by four, also with the shared read.
    fn check<I: Rows, const W: usize>(col: &[Real], base: &[u32; W], off: usize) {
        for shared in [false, true] {
            if shared && !blocks_share(base) {
                continue;
            }
            for at in (0..W).step_by(I::N) {
                let nodes = unsafe { read::<I, W>(col, base, at, off, shared) };
                for (i, &node) in nodes.iter().enumerate() {
                    let mut lanes = [0.0; W];
                    I::store(node, &mut lanes, at);
                    for q in 0..I::N {
                        let ln = at + q;
                        let expect = col[base[ln] as usize + off + i];
                        assert_eq!(lanes[ln], expect, "node {i} lane {ln} shared {shared}");
                    }
                }
            }
        }
    }

    /// [`check`] for every instance the CPU supports.
    fn check_all<const W: usize>(col: &[Real], base: &[u32; W], off: usize) {
        check::<super::super::Baseline, W>(col, base, off);
        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        {
            use crate::simd::{Instance, Simd};
            if Simd::Detect.instance() >= Instance::Avx2 {
                check::<super::super::Avx2, W>(col, base, off);
            }
            #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
            if Simd::Detect.instance() == Instance::Avx512 {
                check::<super::super::Avx512, W>(col, base, off);
            }
        }
    }

    /// Checks `I`'s compares, selects and mask operations lane by lane against the scalar
    /// definitions, over values that include zeros of both signs, infinities, NaN and the
    /// largest finite values, and [`above`] and [`finite`] over whole chunks.
    fn check_compare<I: Compare, const W: usize>() {
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            Real::INFINITY,
            Real::NEG_INFINITY,
            Real::NAN,
            Real::MAX,
            -Real::MAX,
            Real::MIN_POSITIVE,
            3.0,
            -2.5,
            1.0e-30,
            -1.0e30,
            2.0,
        ];
        let mut a = [0.0; W];
        let mut b = [0.0; W];
        for ln in 0..W {
            a[ln] = special[ln % special.len()];
            b[ln] = special[(ln * 7 + 3) % special.len()];
        }
        for at in (0..W).step_by(I::N) {
            // SAFETY: `check_all` runs only the instances the CPU supports.
            let (va, vb, on, off) = unsafe {
                (
                    I::load(&a, at),
                    I::load(&b, at),
                    I::splat_mask(true),
                    I::splat_mask(false),
                )
            };
            let lt = I::bits(I::lt(va, vb));
            let gt = I::bits(I::gt(va, vb));
            let fin = I::bits(I::finite(va));
            let mut picked = [0.0; W];
            I::store(I::select(I::lt(va, vb), va, vb), &mut picked, at);
            let mut diff = [0.0; W];
            I::store(I::sub(va, vb), &mut diff, at);
            let (mut quot, mut neg, mut root) = ([0.0; W], [0.0; W], [0.0; W]);
            I::store(I::div(va, vb), &mut quot, at);
            I::store(I::neg(va), &mut neg, at);
            I::store(I::sqrt(va), &mut root, at);
            let ge = I::bits(I::ge(va, vb));
            for q in 0..I::N {
                let (x, y) = (a[at + q], b[at + q]);
                assert_eq!(lt >> q & 1 == 1, x < y, "lt lane {q}: {x} {y}");
                assert_eq!(gt >> q & 1 == 1, x > y, "gt lane {q}: {x} {y}");
                assert_eq!(fin >> q & 1 == 1, x.is_finite(), "finite lane {q}: {x}");
                let min = if x < y { x } else { y };
                assert_eq!(picked[at + q].to_bits(), min.to_bits(), "select lane {q}");
                assert_eq!(diff[at + q].to_bits(), (x - y).to_bits(), "sub lane {q}");
                assert_eq!(ge >> q & 1 == 1, x >= y, "ge lane {q}: {x} {y}");
                assert_eq!(neg[at + q].to_bits(), (-x).to_bits(), "neg lane {q}");
                // Every NaN is a NaN; the bits of a NaN result may differ by instance.
                let same =
                    |u: Real, v: Real| u.to_bits() == v.to_bits() || u.is_nan() && v.is_nan();
                assert!(same(quot[at + q], x / y), "div lane {q}: {x} {y}");
                assert!(
                    same(root[at + q], crate::num::sqrt(x)),
                    "sqrt lane {q}: {x}"
                );
            }
            let full = if I::N == 32 {
                u32::MAX
            } else {
                (1u32 << I::N) - 1
            };
            assert_eq!(I::bits(on), full);
            assert_eq!(I::bits(off), 0);
            let (l, g) = (I::lt(va, vb), I::gt(va, vb));
            assert_eq!(I::bits(I::and(l, g)), lt & gt);
            assert_eq!(I::bits(I::or(l, g)), lt | gt);
            assert_eq!(I::bits(I::and_not(l, g)), lt & !gt);
        }
        let expect_above = Lanes::from_fn(|ln| a[ln] > 0.5);
        assert_eq!(above::<I, W>(&a, 0.5), expect_above);
    }

    /// Every instance the CPU supports subtracts, divides, negates, takes square roots,
    /// compares, selects and combines masks as the scalar operations do, NaN and infinities
    /// included.
    #[test]
    fn every_instance_compares_as_scalars_do() {
        compare_all::<{ width(2) }>();
        compare_all::<{ width(3) }>();
    }

    /// [`check_compare`] on chunks of `W` for every instance the CPU supports.
    fn compare_all<const W: usize>() {
        check_compare::<super::super::Baseline, W>();
        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        {
            use crate::simd::{Instance, Simd};
            if Simd::Detect.instance() >= Instance::Avx2 {
                check_compare::<super::super::Avx2, W>();
            }
            #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
            if Simd::Detect.instance() == Instance::Avx512 {
                check_compare::<super::super::Avx512, W>();
            }
        }
    }

    /// Every instance the CPU supports moves the same values: lane `q` of node `i` is
    /// `col[base[at + q] + off + i]`, for lanes spread over the column and for lanes that share
    /// their bases four by four (read either way).
    #[test]
    fn every_instance_reads_every_lanes_row() {
        reads_every_lanes_row::<{ width(2) }>();
        reads_every_lanes_row::<{ width(3) }>();
    }

    /// [`every_instance_reads_every_lanes_row`] for chunks of `W`.
    fn reads_every_lanes_row<const W: usize>() {
        let col: [Real; 1000] = core::array::from_fn(|i| i as Real * 0.5 - 7.0);
        let mut base = [0u32; W];
        for (ln, b) in base.iter_mut().enumerate() {
            *b = ((ln * 613) % 990) as u32;
        }
        let off = 3;
        assert!(fit(&base, off, col.len()));
        assert!(!blocks_share(&base));
        check_all(&col, &base, off);
        // Lanes sharing their bases four by four, as a stencil-bin fill gives.
        let mut shared = [0u32; W];
        for (ln, b) in shared.iter_mut().enumerate() {
            *b = ((ln / 4 * 211) % 990) as u32;
        }
        assert!(blocks_share(&shared));
        check_all(&col, &shared, off);
        // One lane off its block's base: not shared.
        shared[6] += 1;
        assert!(!blocks_share(&shared));
        // A row that would end past the column does not fit.
        base[5] = 997;
        assert!(!fit(&base, off, col.len()));
    }
}
