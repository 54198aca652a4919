//! Shape functions: one file per family, one way to ask any of them for `S_ip` and `G_ip`.
//!
//! Every family is evaluated per axis and combined by tensor product ([`Stencil::for_each_node`],
//! or row by row with [`Stencil::row`]): in 2D and 3D, `S_ip` is the product of the per-axis
//! values and each component of `G_ip` replaces one factor by its derivative (seeds/000 eqs
//! 16-17).
//!
//! A family describes itself once, as polynomial pieces of `S(|xi|)` ([`Shape1D::pieces`]).
//! [`Table::new`] turns that into what the step evaluates: for a particle at offset `f` in
//! `[0, 1]` from the lower node of its cell, the weights of the `K` stencil nodes are
//! polynomials in `f` whose coefficients depend only on which of at most four regions of the
//! cell `f` falls in. So every family costs the same per axis: a region index from up to three
//! comparisons, then one Horner evaluation over a row of four nodes, with no branches and no
//! per-node case analysis.
//!
//! The hot loops work row by row: the `K` nodes of a stencil row along x are contiguous in every
//! node column, so a row is one [`ROW`]-wide vector load, add and store, padded with zero
//! weights. Node columns therefore carry [`ROW`] entries of padding past the last node.
//!
//! Positions are given in cell units relative to the grid origin (`s = (x - origin) / h`), so a
//! node `i` sits at `s = i` and the per-axis offset is `xi = s - i`.

mod bspline;
mod gimp;
mod linear;

pub use bspline::{CubicBspline, QuadraticBspline};
pub use gimp::Gimp;
pub use linear::Linear;

use crate::Real;

/// Width of a stencil row in the hot loops: every family has `K <= 4` nodes per axis, padded
/// with zero weights to 4.
pub const ROW: usize = 4;

/// A row of [`ROW`] values as one SIMD register (glam's SSE2 `Vec4` in f32), so that row
/// arithmetic is vector arithmetic whatever the optimiser decides.
#[cfg(not(feature = "f64"))]
pub type Row4 = glam::Vec4;
/// A row of [`ROW`] values (glam's `DVec4` in f64).
#[cfg(feature = "f64")]
pub type Row4 = glam::DVec4;

/// Most polynomial pieces a family may have (in `|xi|`).
pub const MAX_PIECES: usize = 3;

/// `S(a)` for `a = |xi| >= 0` as consecutive polynomial pieces: piece `k` covers
/// `[hi[k - 1], hi[k])` (`hi[-1] = 0`) with `S = p[k][0] + p[k][1] a + p[k][2] a^2 + p[k][3] a^3`;
/// `S = 0` from `hi[n - 1]` on. Exact coefficients, in f64.
#[derive(Clone, Copy, Debug)]
pub struct Pieces {
    /// Number of pieces used.
    pub n: usize,
    /// Upper end of each piece.
    pub hi: [f64; MAX_PIECES],
    /// Coefficients of each piece, lowest power first.
    pub p: [[f64; 4]; MAX_PIECES],
}

/// One family of 1D shape functions with `K <= 4` nodes of support.
pub trait Shape1D<const K: usize>: Copy {
    /// The family as polynomial pieces in `|xi|`, what the step evaluates (through [`Table`]).
    fn pieces(&self) -> Pieces;

    /// Weight and its derivative with respect to `s` at offset `xi = s - x_i` (cell units),
    /// in closed form: the reference the tables are tested against. Zero outside the support.
    fn eval(&self, xi: Real) -> (Real, Real);
}

/// Most regions of a cell in which every stencil weight is one polynomial.
const MAX_REGIONS: usize = 4;

/// A family's stencil weights as polynomials of the offset `f = s - c` of a particle from the
/// lower node `c` of its cell, region by region (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Table<const K: usize> {
    /// Region boundaries in `f`, ascending; unused ones are `+inf`.
    breaks: [Real; MAX_REGIONS - 1],
    /// First stencil node of each region relative to `c - 1` (0 ..= 4 - K).
    shift: [usize; MAX_REGIONS],
    /// Weight coefficients `w[region][power]`, lane `k` for stencil node `k` (zero for
    /// `k >= K`).
    w: [[Row4; 4]; MAX_REGIONS],
    /// Coefficients of the derivative with respect to `f`, `dw[region][power]`.
    dw: [[Row4; 3]; MAX_REGIONS],
    /// The largest `shift`.
    max_shift: usize,
    /// Point `at[region]` (lane `k` for node `k`) about which the polynomials are expanded:
    /// the coefficients are of powers of `f - at`.
    at: [Row4; MAX_REGIONS],
}

impl<const K: usize> Table<K> {
    /// The table of `shape`. The four nodes `c - 1 ..= c + 2` around a cell cover the support of
    /// every family with `K <= 4`; each region keeps the `K` of them that carry weight.
    pub fn new<S: Shape1D<K>>(shape: &S) -> Self {
        let pc = shape.pieces();
        let n = pc.n.min(MAX_PIECES);
        // Node k of the four sits at c - 1 + k: a = |xi| = sign * (f + 1 - k).
        let node = |k: usize| -> (f64, f64) {
            let sign = if k <= 1 { 1.0 } else { -1.0 };
            (sign, 1.0 - k as f64)
        };
        // Region boundaries: where some node's `a` crosses a piece boundary inside (0, 1).
        let mut cuts = [f64::INFINITY; 4 * MAX_PIECES];
        let mut ncuts = 0;
        for k in 0..4 {
            let (sign, d) = node(k);
            for &b in &pc.hi[..n] {
                let f = sign * b - d;
                let new = cuts[..ncuts].iter().all(|&c: &f64| (c - f).abs() > 1e-12);
                if f > 1e-12 && f < 1.0 - 1e-12 && new {
                    cuts[ncuts] = f;
                    ncuts += 1;
                }
            }
        }
        cuts[..ncuts].sort_unstable_by(|a, b| a.total_cmp(b));
        assert!(ncuts < MAX_REGIONS, "a shape family has too many pieces");
        let mut t = Table {
            breaks: [Real::INFINITY; MAX_REGIONS - 1],
            shift: [0; MAX_REGIONS],
            w: [[Row4::ZERO; 4]; MAX_REGIONS],
            dw: [[Row4::ZERO; 3]; MAX_REGIONS],
            max_shift: 0,
            at: [Row4::ZERO; MAX_REGIONS],
        };
        for r in 0..=ncuts {
            let lo = if r == 0 { 0.0 } else { cuts[r - 1] };
            let hi = if r == ncuts { 1.0 } else { cuts[r] };
            if r > 0 {
                t.breaks[r - 1] = lo as Real;
            }
            let mid = 0.5 * (lo + hi);
            // Polynomial in f of each of the four nodes in this region.
            let mut poly = [[0.0f64; 4]; 4];
            for (k, pk) in poly.iter_mut().enumerate() {
                let (sign, d) = node(k);
                let a = sign * (mid + d);
                let Some(piece) = (0..n).find(|&i| a < pc.hi[i]) else {
                    continue;
                };
                // P(sign f + sign d) expanded in powers of f.
                let p = pc.p[piece];
                let u = sign * d;
                for (deg, &c) in p.iter().enumerate() {
                    for m in 0..=deg {
                        pk[m] += c * binomial(deg, m) * ipow(sign, m) * ipow(u, deg - m);
                    }
                }
            }
            let carries = |k: usize| poly[k].iter().any(|&c| c != 0.0);
            let shift = (0..=4 - K)
                .find(|&s| (0..4).all(|k| !carries(k) || (s..s + K).contains(&k)))
                .expect("a shape family's support exceeds its K nodes");
            t.shift[r] = shift;
            t.max_shift = t.max_shift.max(shift);
            for k in 0..K {
                // Expand about a root at an end of the region when there is one, so that a
                // weight going to zero there (and its slope) keeps its relative precision
                // instead of coming out of a difference of O(1) terms; else about the middle.
                let p = poly[shift + k];
                let at = |x: f64| p.iter().rev().fold(0.0, |acc, &c| acc * x + c);
                let e = if at(lo).abs() < 1e-12 {
                    lo
                } else if at(hi).abs() < 1e-12 {
                    hi
                } else {
                    mid
                };
                t.at[r][k] = e as Real;
                let q = shift_poly(&p, e);
                for m in 0..4 {
                    t.w[r][m][k] = q[m] as Real;
                }
                for m in 0..3 {
                    t.dw[r][m][k] = ((m + 1) as f64 * q[m + 1]) as Real;
                }
            }
        }
        t
    }

    /// The stencil along one axis of a particle at `s` (cell units) on an axis with `nodes`
    /// nodes: the first node, and the `K` weights and derivatives (per cell) padded to [`ROW`].
    /// The cell and the first node are clamped, so the `K` nodes always exist, whatever `s`
    /// (NaN included); inside the admissible region the clamps never act.
    #[inline(always)]
    pub fn axis(&self, s: Real, nodes: usize) -> (usize, Row4, Row4) {
        // The highest cell is the last whose stencil fits in every region; a particle on the
        // upper face of the admissible region takes the cell below it, at f = 1.
        let top = (nodes + 1).saturating_sub(K + self.max_shift).min(1 << 30);
        // Clamped in floating point first (NaN and negatives to 0), so the conversion below
        // is in range.
        let clamped = if s >= 0.0 { s } else { 0.0 }.min(top as Real);
        // SAFETY: `clamped` is finite and in [0, top]: at most 2^30, exact in f32 and f64.
        let c = unsafe { clamped.to_int_unchecked::<i32>() } as usize;
        let f = s - c as Real;
        let r = (f >= self.breaks[0]) as usize
            + (f >= self.breaks[1]) as usize
            + (f >= self.breaks[2]) as usize;
        let first = (c + self.shift[r]).saturating_sub(1).min(nodes - K);
        let (a, b) = (&self.w[r], &self.dw[r]);
        let g = Row4::splat(f) - self.at[r];
        let w = ((a[3] * g + a[2]) * g + a[1]) * g + a[0];
        let dw = (b[2] * g + b[1]) * g + b[0];
        (first, w, dw)
    }
}

/// The coefficients of `p(x)` as a polynomial in `x - e` (lowest power first).
fn shift_poly(p: &[f64; 4], e: f64) -> [f64; 4] {
    core::array::from_fn(|m| (m..4).map(|n| p[n] * binomial(n, m) * ipow(e, n - m)).sum())
}

/// `x^n` for the small powers of the pieces.
fn ipow(x: f64, n: usize) -> f64 {
    (0..n).fold(1.0, |acc, _| acc * x)
}

/// `n choose k` for the small powers of the pieces.
fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// The nodes a particle touches and their per-axis weights and derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Stencil<const D: usize, const K: usize> {
    /// Flat index of the stencil's first node.
    pub base: usize,
    /// Per-axis weights `w[axis][k]`, zero for `k >= K`.
    pub w: [Row4; D],
    /// Per-axis derivatives `dw[axis][k]`, per unit length (already divided by h), zero for
    /// `k >= K`.
    pub dw: [Row4; D],
}

/// One row of a stencil along x: the flat index of its first node, the weights `S[i]` and the
/// gradients `G[axis][i]` of nodes `row + i` for `i < ROW` (zero for `i >= K`).
pub type Row<const D: usize> = (usize, Row4, [Row4; D]);

impl<const D: usize, const K: usize> Stencil<D, K> {
    /// A stencil with every weight zero, at node 0.
    pub const ZERO: Self = Stencil {
        base: 0,
        w: [Row4::ZERO; D],
        dw: [Row4::ZERO; D],
    };

    /// Stencil of a particle at `s` (cell units per axis) on a grid with `nodes[a]` nodes per
    /// axis and flat strides `stride[a]`. The first node is clamped so that all `K` nodes exist:
    /// memory safety never depends on the position being valid (see [`Table::axis`]).
    #[inline(always)]
    pub fn new(
        table: &Table<K>,
        s: [Real; D],
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
    ) -> Self {
        let mut base = 0usize;
        let mut w = [Row4::ZERO; D];
        let mut dw = [Row4::ZERO; D];
        for a in 0..D {
            let (first, wa, dwa) = table.axis(s[a], nodes[a]);
            base += first * stride[a];
            w[a] = wa;
            dw[a] = dwa * inv_h;
        }
        Stencil { base, w, dw }
    }

    /// Offset of the stencil's last row from its first node.
    #[inline(always)]
    pub fn last_row_offset(stride: [usize; D]) -> usize {
        (K - 1) * (stride[1] + if D == 3 { stride[D - 1] } else { 0 })
    }

    /// Number of z layers of rows: K in 3D, 1 in 2D. The rows of a stencil are `row(j, k)` for
    /// `k < layers()` and `j < K`; callers write the two loops themselves, so that their bounds
    /// are constants the compiler unrolls.
    #[inline(always)]
    pub const fn layers() -> usize {
        if D == 3 {
            K
        } else {
            1
        }
    }

    /// Row `j` along y of layer `k` along z (see [`Row`]). `row + ROW` is at most two past the
    /// last node, which the node columns' padding covers.
    #[inline(always)]
    pub fn row(&self, j: usize, k: usize, stride: [usize; D]) -> Row<D> {
        let (w, dw) = (&self.w, &self.dw);
        let row = self.base + j * stride[1] + if D == 3 { k * stride[D - 1] } else { 0 };
        // Weight of the row in y (and z) and its derivatives.
        let (wt, dy, dz) = if D == 3 {
            (
                w[1][j] * w[D - 1][k],
                dw[1][j] * w[D - 1][k],
                w[1][j] * dw[D - 1][k],
            )
        } else {
            (w[1][j], dw[1][j], 0.0)
        };
        let s = w[0] * wt;
        let g: [Row4; D] = core::array::from_fn(|a| match a {
            0 => dw[0] * wt,
            1 => w[0] * dy,
            _ => w[0] * dz,
        });
        (row, s, g)
    }

    /// Calls `f(node, S_ip, G_ip)` for every node of the stencil (K^D of them), x fastest.
    /// Every `node` is below the product of the `nodes` the stencil was made with (the first
    /// node was clamped so that the last one exists).
    #[inline(always)]
    pub fn for_each_node(&self, stride: [usize; D], mut f: impl FnMut(usize, Real, [Real; D])) {
        let (w, dw) = (&self.w, &self.dw);
        if D == 2 {
            for j in 0..K {
                let row = self.base + j * stride[1];
                for i in 0..K {
                    let g: [Real; D] = core::array::from_fn(|a| {
                        if a == 0 {
                            dw[0][i] * w[1][j]
                        } else {
                            w[0][i] * dw[1][j]
                        }
                    });
                    f(row + i, w[0][i] * w[1][j], g);
                }
            }
        } else {
            for k in 0..K {
                for j in 0..K {
                    let row = self.base + j * stride[1] + k * stride[D - 1];
                    let (wjk, djk_y, djk_z) = (
                        w[1][j] * w[D - 1][k],
                        dw[1][j] * w[D - 1][k],
                        w[1][j] * dw[D - 1][k],
                    );
                    for i in 0..K {
                        let g: [Real; D] = core::array::from_fn(|a| match a {
                            0 => dw[0][i] * wjk,
                            1 => w[0][i] * djk_y,
                            _ => w[0][i] * djk_z,
                        });
                        f(row + i, w[0][i] * wjk, g);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random numbers in [0, 1) (no dependency needed for a test).
    fn lcg(state: &mut u64) -> Real {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f64 / (1u64 << 24) as f64) as Real
    }

    /// Partition of unity, zero gradient sum and linear reproduction, for one family, at random
    /// positions plus every node and cell edge of the admissible region [lo, hi] (cell units).
    fn check_family<const K: usize, S: Shape1D<K>>(shape: S, lo: Real, hi: Real) {
        const N: usize = 12; // nodes per axis
        let h: Real = 0.25;
        let nodes = [N, N];
        let stride = [1, N];
        let mut st = 7u64;
        let table = Table::new(&shape);
        let check = |s: [Real; 2]| {
            let stencil = Stencil::<2, K>::new(&table, s, nodes, stride, 1.0 / h);
            // Per axis, the table agrees with the closed form at the stencil's nodes, and the
            // nodes just outside the stencil carry no weight.
            for a in 0..2 {
                let (first, w, dw) = table.axis(s[a], N);
                for k in 0..K {
                    let xi = s[a] - (first + k) as Real;
                    let (we, dwe) = shape.eval(xi);
                    assert!((w[k] - we).abs() < 8.0 * Real::EPSILON, "S at xi = {xi}");
                    // The linear hat's derivative jumps at nodes, where the table takes the
                    // slope of the particle's cell: compare away from nodes only.
                    if xi != (xi as i64) as Real {
                        assert!(
                            (dw[k] - dwe).abs() < 16.0 * Real::EPSILON,
                            "dS at xi = {xi}"
                        );
                    }
                }
                for k in K..ROW {
                    assert_eq!((w[k], dw[k]), (0.0, 0.0));
                }
                for outside in [first as Real - 1.0, (first + K) as Real] {
                    assert_eq!(
                        shape.eval(s[a] - outside).0,
                        0.0,
                        "support beyond the stencil"
                    );
                }
            }
            let (mut sum_w, mut sum_g, mut sum_x) = (0.0, [0.0; 2], [0.0; 2]);
            let mut sum_gx = [[0.0; 2]; 2];
            stencil.for_each_node(stride, |idx, w, g| {
                let node = [(idx % N) as Real * h, (idx / N) as Real * h];
                sum_w += w;
                for a in 0..2 {
                    sum_g[a] += g[a];
                    sum_x[a] += w * node[a];
                    for b in 0..2 {
                        sum_gx[a][b] += g[b] * node[a];
                    }
                }
            });
            let tol = 16.0 * Real::EPSILON;
            assert!((sum_w - 1.0).abs() < tol, "sum S = {sum_w} at {s:?}");
            for a in 0..2 {
                assert!(sum_g[a].abs() < tol / h * 4.0, "sum G = {sum_g:?} at {s:?}");
                assert!(
                    (sum_x[a] - s[a] * h).abs() < tol * 4.0,
                    "sum S x = {sum_x:?} at {s:?}"
                );
                for b in 0..2 {
                    let expect = if a == b { 1.0 } else { 0.0 };
                    assert!(
                        (sum_gx[a][b] - expect).abs() < tol * 8.0,
                        "sum G x at {s:?}"
                    );
                }
            }
        };
        // Every node and cell edge (in 1D they coincide) and every half cell.
        let mut t = lo;
        while t <= hi {
            check([t, lo + 0.37 * (hi - lo)]);
            check([lo + 0.61 * (hi - lo), t]);
            t += 0.5;
        }
        check([hi, hi]);
        check([lo, lo]);
        for _ in 0..2000 {
            let s = [lo + (hi - lo) * lcg(&mut st), lo + (hi - lo) * lcg(&mut st)];
            check(s);
        }
    }

    #[test]
    fn linear_partition_of_unity_gradient_sum_and_linear_reproduction() {
        check_family(Linear, 0.0, 11.0);
    }

    #[test]
    fn gimp_partition_of_unity_gradient_sum_and_linear_reproduction() {
        for ppc in 1..=4 {
            check_family(Gimp::new(ppc), 1.0, 10.0);
        }
    }

    #[test]
    fn quadratic_bspline_partition_of_unity_gradient_sum_and_linear_reproduction() {
        check_family(QuadraticBspline, 1.0, 10.0);
    }

    #[test]
    fn cubic_bspline_partition_of_unity_gradient_sum_and_linear_reproduction() {
        check_family(CubicBspline, 1.0, 10.0);
    }
}
