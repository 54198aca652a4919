//! Shape functions: one file per family, one way to ask any of them for `S_ip` and `G_ip`.
//!
//! Every family is evaluated per axis ([`Shape1D`]) and combined by tensor product
//! ([`Stencil::for_each_node`], or row by row with [`Stencil::row`]): in 2D and 3D,
//! `S_ip` is the product of the per-axis values and each component of `G_ip` replaces one factor
//! by its derivative (seeds/000 eqs 16-17).
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

/// One family of 1D shape functions with `K` nodes of support.
pub trait Shape1D<const K: usize>: Copy {
    /// Index of the first node of the stencil of a particle at `s` (cell units), before
    /// clamping to the grid. Positions are never negative inside the grid, so a truncating
    /// cast is a floor there; outside (or NaN) the result is clamped by [`Stencil::new`].
    fn first_node(s: Real) -> i32;

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

/// The nodes a particle touches and their per-axis weights and derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Stencil<const D: usize, const K: usize> {
    /// Flat index of the stencil's first node.
    pub base: usize,
    /// Per-axis weights `w[axis][k]`, zero for `k >= K`.
    pub w: [[Real; ROW]; D],
    /// Per-axis derivatives `dw[axis][k]`, per unit length (already divided by h), zero for
    /// `k >= K`.
    pub dw: [[Real; ROW]; D],
}

/// One row of a stencil along x: the flat index of its first node, the weights `S[i]` and the
/// gradients `G[axis][i]` of nodes `row + i` for `i < ROW` (zero for `i >= K`).
pub type Row<const D: usize> = (usize, [Real; ROW], [[Real; ROW]; D]);

/// The stencils of `W` particles at once, laid out lane-fastest so that computing them is a set
/// of loops over lanes the compiler vectorises.
#[derive(Clone, Copy, Debug)]
pub struct Stencils<const D: usize, const K: usize, const W: usize> {
    base: [usize; W],
    w: [[[Real; W]; ROW]; D],
    dw: [[[Real; W]; ROW]; D],
}

impl<const D: usize, const K: usize, const W: usize> Stencils<D, K, W> {
    /// Stencils of particles at `s[axis][lane]` (cell units); see [`Stencil::new`].
    #[inline(always)]
    pub fn new<S: Shape1D<K>>(
        shape: &S,
        s: &[[Real; W]; D],
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
    ) -> Self {
        let mut base = [0usize; W];
        let mut w = [[[0.0; W]; ROW]; D];
        let mut dw = [[[0.0; W]; ROW]; D];
        for a in 0..D {
            let hi = (nodes[a] - K) as i32;
            let mut f = [0.0; W];
            for ln in 0..W {
                let first = S::first_node(s[a][ln]).clamp(0, hi);
                base[ln] += first as usize * stride[a];
                f[ln] = s[a][ln] - first as Real;
            }
            for ln in 0..W {
                let (wa, dwa) = shape.stencil(f[ln]);
                for k in 0..K {
                    w[a][k][ln] = wa[k];
                    dw[a][k][ln] = dwa[k] * inv_h;
                }
            }
        }
        Stencils { base, w, dw }
    }

    /// The stencil of lane `ln`.
    #[inline(always)]
    pub fn lane(&self, ln: usize) -> Stencil<D, K> {
        Stencil {
            base: self.base[ln],
            w: core::array::from_fn(|a| core::array::from_fn(|k| self.w[a][k][ln])),
            dw: core::array::from_fn(|a| core::array::from_fn(|k| self.dw[a][k][ln])),
        }
    }
}

impl<const D: usize, const K: usize> Stencil<D, K> {
    /// Stencil of a particle at `s` (cell units per axis) on a grid with `nodes[a]` nodes per
    /// axis and flat strides `stride[a]`. The first node is clamped so that all `K` nodes exist:
    /// memory safety never depends on the position being valid. For positions inside the
    /// admissible region the clamp is exact (the dropped node's weight is zero).
    #[inline(always)]
    pub fn new<S: Shape1D<K>>(
        shape: &S,
        s: [Real; D],
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
    ) -> Self {
        let mut base = 0usize;
        let mut w = [[0.0; ROW]; D];
        let mut dw = [[0.0; ROW]; D];
        for a in 0..D {
            let hi = (nodes[a] - K) as i32;
            let first = S::first_node(s[a]).clamp(0, hi);
            base += first as usize * stride[a];
            let (wa, dwa) = shape.stencil(s[a] - first as Real);
            for k in 0..K {
                w[a][k] = wa[k];
                dw[a][k] = dwa[k] * inv_h;
            }
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
        let s: [Real; ROW] = core::array::from_fn(|i| w[0][i] * wt);
        let g: [[Real; ROW]; D] = core::array::from_fn(|a| {
            core::array::from_fn(|i| match a {
                0 => dw[0][i] * wt,
                1 => w[0][i] * dy,
                _ => w[0][i] * dz,
            })
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
        let check = |s: [Real; 2]| {
            let stencil = Stencil::<2, K>::new(&shape, s, nodes, stride, 1.0 / h);
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
