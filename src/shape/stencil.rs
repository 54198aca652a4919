//! Stencils: the nodes a particle touches and their weights and derivatives, by tensor
//! product of a family's per-axis values (E4-E6), for one particle ([`Stencil`]) or a chunk
//! of them lane-fastest ([`Stencils`]), and the first node of a stencil ([`first_node`]).

use super::family::{radial_stencil, Row4, Shape1D, Visit, ROW};
use crate::Real;

#[cfg(not(feature = "f64"))]
type Mat4 = glam::Mat4;
#[cfg(feature = "f64")]
type Mat4 = glam::DMat4;

/// First node of the stencil of a particle at `s` (cell units) on an axis with `nodes` nodes,
/// clamped to `[0, nodes - K]` (to 0 if `nodes < K`; at most 2^30, the grid's limit) so that
/// every node of the stencil exists, for any `s` (NaN and infinities included). Inside the
/// admissible region the clamp changes nothing.
///
/// The clamp is done on the float, before the conversion (`floor` commutes with clamping to
/// integers), so the conversion is a plain truncation the compiler vectorises.
#[inline(always)]
pub fn first_node<const K: usize, S: Shape1D<K>>(s: Real, nodes: usize) -> i32 {
    const { assert!(S::LEAD >= 0 && S::LEAD <= 4) };
    let lo = S::LEAD as Real;
    let top = nodes.saturating_sub(K).min(1 << 30) as Real + lo;
    let y = s + S::SHIFT;
    let y = if y > lo { y } else { lo }; // also NaN -> lo
    let y = if y < top { y } else { top };
    // SAFETY: y is finite and in [LEAD, 2^30 + LEAD] with 0 <= LEAD <= 4, exactly representable
    // bounds that fit in i32, and y >= 0, so truncation is the floor.
    unsafe { y.to_int_unchecked::<i32>() - S::LEAD }
}

/// The nodes a particle touches and their per-axis weights and derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Stencil<const D: usize, const K: usize> {
    /// Flat index of the stencil's first node.
    pub base: usize,
    /// Per-axis weights, `w[axis][k]` for node `k` along the axis, zero for `k >= K`.
    pub w: [Row4; D],
    /// Per-axis derivatives `dw[axis][k]`, per unit length (already divided by h), zero for
    /// `k >= K`.
    pub dw: [Row4; D],
    /// APIC only (else zero): per-axis first moments `e[axis][k] = w[axis][k] (x_k - x_p)`, m.
    /// With them, `S_ip (x_i - x_p)` has the tensor-product form of `G_ip` with `dw` replaced
    /// by `e`, so the affine transfer reuses the gradient's row code.
    pub e: [Row4; D],
    /// APIC only (else zero): `1 / D_p[axis][axis]`, 1/m^2, where
    /// `D_p = sum_i S_ip (x_i - x_p)(x_i - x_p)^T` (E78) is diagonal for tensor-product
    /// weights (its off-diagonal entries are products of first moments, which vanish). Zero
    /// where `D_p` vanishes (a linear-shape particle exactly on a node, where the first
    /// moments vanish too).
    pub inv_d: [Real; D],
    /// Axisymmetric only (else zero): the hoop factors `T_ip` along the radius, `t[k]` for node
    /// `k` of the first axis, 1/m (E68): `T_ip = t[i] w[1][j]`.
    pub t: Row4,
}

/// The stencils of `W` particles. They are computed lane-fastest (loops over lanes the compiler
/// vectorises); the x factors, which the hot loops multiply whole rows by, are then transposed
/// four lanes at a time into one [`XFactors`] per particle, while the factors along the other
/// axes, which they read one at a time, stay where they were computed ([`LaneStencil`];
/// transposing those too cost about 6 % of a 2D step). A pass makes one `Stencils` and refills
/// it for every chunk ([`Stencils::compute`]): building a new one per chunk zeroed and copied
/// over a kilobyte each time.
#[derive(Clone, Copy, Debug)]
pub struct Stencils<const D: usize, const K: usize, const W: usize> {
    lanes: [XFactors; W],
    /// Lane-fastest first nodes (flat indices, below 2^30).
    base: [u32; W],
    /// Lane-fastest weights and derivatives, `w[axis][k][lane]`; rows `k >= K` stay zero.
    w: [[[Real; W]; ROW]; D],
    dw: [[[Real; W]; ROW]; D],
    e: [[[Real; W]; ROW]; D],
    t: [[Real; W]; ROW],
    /// Lane-fastest `1 / D_p` per axis (APIC, else zero).
    inv_d: [[Real; W]; D],
    /// Lane-fastest domain stretch per axis, read by cpGIMP alone: 1 until a
    /// [`Stencils::compute`] gives stretches, which then stay until the next that does (a
    /// family that does not stretch never reads them, and a chunk of it stores none).
    stretch: [[Real; W]; D],
}

/// One particle's x factors in a [`Stencils`], with the fields of [`Stencil`]
/// of the same names (`w`, `dw`, `e` of the first axis).
#[derive(Clone, Copy, Debug)]
pub struct XFactors {
    w: Row4,
    dw: Row4,
    e: Row4,
    t: Row4,
}

/// One particle's stencil in a [`Stencils`] ([`Stencils::lane`]): what [`Stencil`] holds, read
/// through accessors: the x factors as vectors, the factors along axis `a >= 1` as scalars.
#[derive(Clone, Copy, Debug)]
pub struct LaneStencil<'a, const D: usize, const K: usize, const W: usize> {
    x: &'a XFactors,
    all: &'a Stencils<D, K, W>,
    ln: usize,
}

impl<const D: usize, const K: usize, const W: usize> LaneStencil<'_, D, K, W> {
    /// [`Stencil::base`].
    #[inline(always)]
    pub fn base(&self) -> usize {
        self.all.base[self.ln] as usize
    }

    /// The x weights, `w[0]` of [`Stencil::w`].
    #[inline(always)]
    pub fn wx(&self) -> Row4 {
        self.x.w
    }

    /// The x derivatives, `dw[0]` of [`Stencil::dw`].
    #[inline(always)]
    pub fn dwx(&self) -> Row4 {
        self.x.dw
    }

    /// The x first moments, `e[0]` of [`Stencil::e`].
    #[inline(always)]
    pub fn ex(&self) -> Row4 {
        self.x.e
    }

    /// [`Stencil::t`].
    #[inline(always)]
    pub fn t(&self) -> Row4 {
        self.x.t
    }

    /// Weight `w[a][k]` of [`Stencil::w`], for an axis `a >= 1`.
    #[inline(always)]
    pub fn w(&self, a: usize, k: usize) -> Real {
        self.all.w[a][k][self.ln]
    }

    /// Derivative `dw[a][k]` of [`Stencil::dw`], for an axis `a >= 1`.
    #[inline(always)]
    pub fn dw(&self, a: usize, k: usize) -> Real {
        self.all.dw[a][k][self.ln]
    }

    /// First moment `e[a][k]` of [`Stencil::e`], for an axis `a >= 1`.
    #[inline(always)]
    pub fn e(&self, a: usize, k: usize) -> Real {
        self.all.e[a][k][self.ln]
    }

    /// [`Stencil::row`].
    #[inline(always)]
    pub fn row(&self, j: usize, k: usize, stride: [usize; D]) -> (usize, [Real; D]) {
        let (wz, dwz) = if D == 3 {
            (self.w(D - 1, k), self.dw(D - 1, k))
        } else {
            (0.0, 0.0)
        };
        (
            row_start(self.base(), j, k, stride),
            row_factors(self.w(1, j), self.dw(1, j), wz, dwz),
        )
    }

    /// Flat index of the first node of row `j` along y, layer `k` along z.
    #[inline(always)]
    pub fn row_start(&self, j: usize, k: usize, stride: [usize; D]) -> usize {
        row_start(self.base(), j, k, stride)
    }
}

/// Flat index of the first node of row `j` along y, layer `k` along z, of a stencil whose
/// first node is `base`.
#[inline(always)]
pub(crate) fn row_start<const D: usize>(
    base: usize,
    j: usize,
    k: usize,
    stride: [usize; D],
) -> usize {
    base + j * stride[1] + if D == 3 { k * stride[D - 1] } else { 0 }
}

/// The factors `r` of a row ([`Stencil::row`]) from its y weight and derivative and, in 3D,
/// its z weight and derivative.
#[inline(always)]
fn row_factors<const D: usize>(wy: Real, dwy: Real, wz: Real, dwz: Real) -> [Real; D] {
    if D == 3 {
        core::array::from_fn(|b| match b {
            0 => wy * wz,
            1 => dwy * wz,
            _ => wy * dwz,
        })
    } else {
        core::array::from_fn(|b| if b == 0 { wy } else { dwy })
    }
}

impl<const D: usize, const K: usize, const W: usize> Default for Stencils<D, K, W> {
    fn default() -> Self {
        const { assert!(W.is_multiple_of(4) && K <= ROW) };
        Stencils {
            lanes: [XFactors {
                w: Row4::ZERO,
                dw: Row4::ZERO,
                e: Row4::ZERO,
                t: Row4::ZERO,
            }; W],
            base: [0; W],
            w: [[[0.0; W]; ROW]; D],
            dw: [[[0.0; W]; ROW]; D],
            e: [[[0.0; W]; ROW]; D],
            t: [[0.0; W]; ROW],
            inv_d: [[0.0; W]; D],
            stretch: [[1.0; W]; D],
        }
    }
}

impl<const D: usize, const K: usize, const W: usize> Stencils<D, K, W> {
    /// Replaces the stencils by those of particles at `s[axis][lane]` (cell units) whose
    /// domains are stretched by `stretch[axis][lane]` (read only by cpGIMP); with `affine`, also their first moments and `D_p^-1` (APIC).
    /// Only the lane-fastest arrays, which the lane-major passes read: the row code's per-lane
    /// x factors ([`Stencils::lane`]) follow from [`Stencils::fill_lanes`].
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn compute<S: Shape1D<K>>(
        &mut self,
        shape: &S,
        s: &[[Real; W]; D],
        stretch: Option<&[[Real; W]; D]>,
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
        affine: bool,
    ) {
        if let Some(stretch) = stretch {
            self.stretch = *stretch;
        }
        shape.visit(ComputeStencils {
            st: self,
            s,
            grid: (nodes, stride, inv_h),
            affine,
        })
    }

    /// [`Stencils::compute`] for a concrete family.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn compute_family<S: Shape1D<K>>(
        &mut self,
        shape: &S,
        s: &[[Real; W]; D],
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
        affine: bool,
    ) {
        // Flat indices stay below 2^30 (the grid's limit), so u32 lanes hold them.
        let (base, w, dw, e, t, inv_d, stretch) = (
            &mut self.base,
            &mut self.w,
            &mut self.dw,
            &mut self.e,
            &mut self.t,
            &mut self.inv_d,
            &self.stretch,
        );
        base.fill(0);
        let h = 1.0 / inv_h;
        for a in 0..D {
            let mut f = [0.0; W];
            for ln in 0..W {
                let first = first_node::<K, S>(s[a][ln], nodes[a]);
                base[ln] = base[ln].wrapping_add((first as u32).wrapping_mul(stride[a] as u32));
                f[ln] = s[a][ln] - first as Real;
            }
            // One lane loop per kind of axis, with no branch inside, so that each vectorises.
            if S::AXISYMMETRIC && a == 0 {
                for ln in 0..W {
                    let (wa, dwa, ta) =
                        radial_stencil::<K, S>(shape, f[ln], s[a][ln], stretch[a][ln], h);
                    for k in 0..K {
                        w[a][k][ln] = wa[k];
                        dw[a][k][ln] = dwa[k];
                        t[k][ln] = ta[k];
                    }
                }
            } else {
                for ln in 0..W {
                    let (wa, dwa) = cartesian_weights::<K, S>(shape, f[ln], stretch[a][ln], inv_h);
                    for k in 0..K {
                        w[a][k][ln] = wa[k];
                        dw[a][k][ln] = dwa[k];
                    }
                }
            }
            if affine {
                for ln in 0..W {
                    // The weights' centroid: the particle, f, except for the r-weighted weights
                    // of a finite domain (then the moments are taken about the centroid, so that
                    // they still sum to zero and the affine transfer adds no momentum).
                    let c = if S::AXISYMMETRIC && S::FINITE_DOMAIN && a == 0 {
                        (0..K).map(|k| w[a][k][ln] * k as Real).sum()
                    } else {
                        f[ln]
                    };
                    let mut d2 = 0.0;
                    for k in 0..K {
                        // x_k - x_p = (k - f) h.
                        let dx = (k as Real - c) * h;
                        e[a][k][ln] = w[a][k][ln] * dx;
                        d2 += e[a][k][ln] * dx;
                    }
                    inv_d[a][ln] = moment_inverse(d2, h);
                }
            }
        }
    }

    /// MLS-MPM (E82): every derivative factor becomes the moment factor times `D_p^-1`,
    /// so that the gradient the passes form, node (i, j, k)'s `dwx_i wy_j wz_k` and the others,
    /// is the MLS gradient `D_p^-1 S_ip (x_i - x_p)`. Needs the moments (`affine`) of the
    /// last [`Stencils::compute`].
    #[inline(always)]
    pub fn use_mls_gradient(&mut self) {
        for a in 0..D {
            for k in 0..K {
                for ln in 0..W {
                    self.dw[a][k][ln] = self.e[a][k][ln] * self.inv_d[a][ln];
                }
            }
        }
    }

    /// Each lane's x factors for the row code ([`Stencils::lane`]), transposed four lanes at a
    /// time from the lane-fastest arrays of the last [`Stencils::compute`] (with its `affine`
    /// and family `S`).
    #[inline(always)]
    pub fn fill_lanes<S: Shape1D<K>>(&mut self, affine: bool) {
        for l0 in (0..W).step_by(4) {
            let tw = transpose4(&self.w[0], l0);
            let tdw = transpose4(&self.dw[0], l0);
            for i in 0..4 {
                self.lanes[l0 + i].w = tw[i];
                self.lanes[l0 + i].dw = tdw[i];
            }
            if affine {
                let te = transpose4(&self.e[0], l0);
                for i in 0..4 {
                    self.lanes[l0 + i].e = te[i];
                }
            }
            if S::AXISYMMETRIC {
                let tt = transpose4(&self.t, l0);
                for i in 0..4 {
                    self.lanes[l0 + i].t = tt[i];
                }
            }
        }
    }

    /// The first node of every lane's stencil (flat indices, lane-fastest).
    #[inline(always)]
    pub fn bases(&self) -> &[u32; W] {
        &self.base
    }

    /// The weights along `axis` of every lane, `[node][lane]` (nodes `k >= K` zero).
    #[inline(always)]
    pub fn weights(&self, axis: usize) -> &[[Real; W]; ROW] {
        &self.w[axis]
    }

    /// The derivatives along `axis` (per unit length) of every lane, `[node][lane]`.
    #[inline(always)]
    pub fn derivatives(&self, axis: usize) -> &[[Real; W]; ROW] {
        &self.dw[axis]
    }

    /// APIC only (else zero): the first moments along `axis` of every lane, `[node][lane]`
    /// ([`Stencil::e`]).
    #[inline(always)]
    pub fn moments(&self, axis: usize) -> &[[Real; W]; ROW] {
        &self.e[axis]
    }

    /// Axisymmetric only (else zero): the hoop factors of every lane, `[node][lane]`
    /// ([`Stencil::t`]).
    #[inline(always)]
    pub fn hoop_factors(&self) -> &[[Real; W]; ROW] {
        &self.t
    }

    /// APIC only (else zero): `1 / D_p` along `axis` of every lane ([`Stencil::inv_d`]).
    #[inline(always)]
    pub fn inverse_moments(&self, axis: usize) -> &[Real; W] {
        &self.inv_d[axis]
    }

    /// The stencil of lane `ln`.
    #[inline(always)]
    pub fn lane(&self, ln: usize) -> LaneStencil<'_, D, K, W> {
        LaneStencil {
            x: &self.lanes[ln],
            all: self,
            ln,
        }
    }
}

/// [`Stencils::compute`] as a [`Visit`].
struct ComputeStencils<'a, const D: usize, const K: usize, const W: usize> {
    st: &'a mut Stencils<D, K, W>,
    s: &'a [[Real; W]; D],
    grid: ([usize; D], [usize; D], Real),
    affine: bool,
}

impl<const D: usize, const K: usize, const W: usize> Visit<K> for ComputeStencils<'_, D, K, W> {
    type Out = ();

    #[inline(always)]
    fn visit<S: Shape1D<K>>(self, shape: &S) {
        let (nodes, stride, inv_h) = self.grid;
        (self.st).compute_family(shape, self.s, nodes, stride, inv_h, self.affine)
    }
}

/// [`Stencil::new`] as a [`Visit`].
struct NewStencil<const D: usize> {
    s: [Real; D],
    stretch: [Real; D],
    grid: ([usize; D], [usize; D], Real),
}

impl<const D: usize, const K: usize> Visit<K> for NewStencil<D> {
    type Out = Stencil<D, K>;

    #[inline(always)]
    fn visit<S: Shape1D<K>>(self, shape: &S) -> Stencil<D, K> {
        let (nodes, stride, inv_h) = self.grid;
        Stencil::of_family(shape, self.s, self.stretch, nodes, stride, inv_h)
    }
}

/// Weights, derivatives (per unit length) and hoop factors along axis `a` of a particle at
/// offset `f` from its first node and `s` (cell units), its domain stretched by `stretch`
/// (read only by cpGIMP): the radial axis of the axisymmetric
/// form through [`radial_stencil`], every other axis with no hoop factors (zeros).
#[inline(always)]
fn axis_weights<const K: usize, S: Shape1D<K>>(
    shape: &S,
    a: usize,
    f: Real,
    s: Real,
    stretch: Real,
    (h, inv_h): (Real, Real),
) -> ([Real; K], [Real; K], [Real; K]) {
    if S::AXISYMMETRIC && a == 0 {
        return radial_stencil::<K, S>(shape, f, s, stretch, h);
    }
    let (w, dw) = cartesian_weights::<K, S>(shape, f, stretch, inv_h);
    (w, dw, [0.0; K])
}

/// Weights and derivatives (per unit length) along a Cartesian axis of a particle at offset
/// `f` from its first node, its domain stretched by `stretch`.
#[inline(always)]
fn cartesian_weights<const K: usize, S: Shape1D<K>>(
    shape: &S,
    f: Real,
    stretch: Real,
    inv_h: Real,
) -> ([Real; K], [Real; K]) {
    let (w, mut dw) = shape.stencil_stretched(f, stretch);
    for d in dw.iter_mut() {
        *d *= inv_h;
    }
    (w, dw)
}

/// The stretch of a particle domain along each axis for cpGIMP: the extent of the deformed
/// domain `F [-1, 1]^D` along the axis, `sum_b |F_ab|`, from `H = F - I` (`h(a, b)` is
/// `H_ab`). Under a stretch along the axes it is `F_aa`, as cpGIMP has it; a rotation changes
/// the box's extent but not the domain's size.
#[inline(always)]
pub(crate) fn domain_stretch<const D: usize>(h: impl Fn(usize, usize) -> Real) -> [Real; D] {
    core::array::from_fn(|a| {
        (0..D)
            .map(|b| (h(a, b) + if a == b { 1.0 } else { 0.0 }).abs())
            .sum()
    })
}

/// `1 / d` for a diagonal entry `d` of the APIC moment matrix `D_p` on a grid of spacing `h`;
/// 0 when `d` is below `h^2` times a round-off floor (then the first moments, which it
/// divides, vanish as well: only linear weights on a node get there).
#[inline(always)]
pub(crate) fn moment_inverse(d: Real, h: Real) -> Real {
    if d > h * h * Real::EPSILON {
        1.0 / d
    } else {
        0.0
    }
}

/// Lanes `l0..l0 + 4` of `rows[k][lane]` as one [`Row4`] over `k` per lane.
#[inline(always)]
fn transpose4<const W: usize>(rows: &[[Real; W]; ROW], l0: usize) -> [Row4; 4] {
    let row = |k: usize| Row4::from_array(core::array::from_fn(|i| rows[k][l0 + i]));
    transpose4_rows([row(0), row(1), row(2), row(3)])
}

/// The 4 x 4 transpose of four [`Row4`]s, in registers: element `i` of result `k` is element
/// `k` of `rows[i]`.
#[inline(always)]
pub(crate) fn transpose4_rows(rows: [Row4; 4]) -> [Row4; 4] {
    let t = Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose();
    [t.x_axis, t.y_axis, t.z_axis, t.w_axis]
}

impl<const D: usize, const K: usize> Stencil<D, K> {
    /// Stencil of a particle at `s` (cell units per axis) on a grid with `nodes[a]` nodes per
    /// axis and flat strides `stride[a]`. The first node is clamped so that all `K` nodes exist
    /// ([`first_node`]): memory safety never depends on the position being valid. For positions
    /// inside the admissible region the clamp is exact (the dropped node's weight is zero).
    #[inline(always)]
    pub fn new<S: Shape1D<K>>(
        shape: &S,
        s: [Real; D],
        stretch: [Real; D],
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
    ) -> Self {
        shape.visit(NewStencil {
            s,
            stretch,
            grid: (nodes, stride, inv_h),
        })
    }

    /// [`Stencil::new`] for a concrete family.
    #[inline(always)]
    fn of_family<S: Shape1D<K>>(
        shape: &S,
        s: [Real; D],
        stretch: [Real; D],
        nodes: [usize; D],
        stride: [usize; D],
        inv_h: Real,
    ) -> Self {
        let mut base = 0usize;
        let mut w = [Row4::ZERO; D];
        let mut dw = [Row4::ZERO; D];
        let mut t = Row4::ZERO;
        for a in 0..D {
            let first = first_node::<K, S>(s[a], nodes[a]);
            base += first as usize * stride[a];
            let f = s[a] - first as Real;
            let (wa, dwa, ta) =
                axis_weights::<K, S>(shape, a, f, s[a], stretch[a], (1.0 / inv_h, inv_h));
            for k in 0..K {
                (w[a][k], dw[a][k]) = (wa[k], dwa[k]);
                if S::AXISYMMETRIC && a == 0 {
                    t[k] = ta[k];
                }
            }
        }
        Stencil {
            base,
            w,
            dw,
            e: [Row4::ZERO; D],
            inv_d: [0.0; D],
            t,
        }
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

    /// Row `j` along y of layer `k` along z: the flat index of its first node, and the factors
    /// that turn the x weights into the row's weights and gradients. With `r = row(..).1`,
    /// node `row + i` has `S = w[0][i] r[0]`, `G_x = dw[0][i] r[0]` and `G_b = w[0][i] r[b]`
    /// for `b >= 1` (E6: `r[0]` is the y (and z) weight, `r[b]` the same
    /// product with axis b's factor differentiated). `row + ROW` is at most two past the last
    /// node, which the node columns' padding covers.
    #[inline(always)]
    pub fn row(&self, j: usize, k: usize, stride: [usize; D]) -> (usize, [Real; D]) {
        let (w, dw) = (&self.w, &self.dw);
        let (wz, dwz) = if D == 3 {
            (w[D - 1][k], dw[D - 1][k])
        } else {
            (0.0, 0.0)
        };
        (
            row_start(self.base, j, k, stride),
            row_factors(w[1][j], dw[1][j], wz, dwz),
        )
    }

    /// Calls `f(node, S_ip, G_ip)` for every node of the stencil (K^D of them), x fastest.
    /// Every `node` is below the product of the `nodes` the stencil was made with (the first
    /// node was clamped so that the last one exists).
    #[inline(always)]
    pub fn for_each_node(&self, stride: [usize; D], mut f: impl FnMut(usize, Real, [Real; D])) {
        let (wx, dwx) = (self.w[0], self.dw[0]);
        for k in 0..Self::layers() {
            for j in 0..K {
                let (row, r) = self.row(j, k, stride);
                for i in 0..K {
                    let g: [Real; D] =
                        core::array::from_fn(|b| if b == 0 { dwx[i] * r[0] } else { wx[i] * r[b] });
                    f(row + i, wx[i] * r[0], g);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::{
        Axisymmetric, CpGimp, CubicBspline, Gimp, Linear, QuadraticBspline, ThreeNode,
    };

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
        // A stretching family (cpGIMP) gets a different domain stretch per check, from 0.05 to
        // 3 (both clamps of its half-width included).
        let mut stretch_state = 3u64;
        let mut check = |s: [Real; 2]| {
            let stretch = [
                0.05 + 2.95 * lcg(&mut stretch_state),
                0.05 + 2.95 * lcg(&mut stretch_state),
            ];
            let stencil = Stencil::<2, K>::new(&shape, s, stretch, nodes, stride, 1.0 / h);
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

    /// The clamped first node stays in `[0, nodes - K]` for every input, and equals
    /// `floor(s + SHIFT) - LEAD` inside that range.
    #[test]
    fn first_node_is_clamped_for_any_position() {
        fn check<const K: usize, S: Shape1D<K>>() {
            for nodes in [0usize, 1, K, K + 1, 12, 1 << 20, usize::MAX] {
                let hi = nodes.saturating_sub(K).min(1 << 30) as i32;
                for s in [
                    Real::NAN,
                    Real::INFINITY,
                    Real::NEG_INFINITY,
                    Real::MAX,
                    -Real::MAX,
                    -1.0,
                    0.0,
                    0.49,
                    0.5,
                    3.99,
                    4.0,
                    7.5,
                    1.0e9,
                ] {
                    let f = first_node::<K, S>(s, nodes);
                    assert!(
                        (0..=hi).contains(&f),
                        "{f} outside [0, {hi}] (s {s}, nodes {nodes})"
                    );
                    let exact =
                        (libm::floor((s + S::SHIFT) as f64) as i64).saturating_sub(S::LEAD as i64);
                    if s.is_finite() && (0..=hi as i64).contains(&exact) {
                        assert_eq!(f as i64, exact, "s {s}, nodes {nodes}");
                    }
                }
            }
        }
        check::<2, Linear>();
        check::<3, Gimp>();
        check::<3, QuadraticBspline>();
        check::<4, CubicBspline>();
        check::<3, CpGimp>();
    }

    /// `1/(2 l) int_{-l}^{l} g(u) du` by Simpson's rule on each piece between the `kinks`
    /// (where g or its slope jumps): exact for the piecewise quadratics here.
    fn mean_over(l: f64, kinks: &[f64], g: impl Fn(f64) -> f64) -> f64 {
        let mut cuts: std::vec::Vec<f64> = kinks.iter().copied().filter(|k| k.abs() < l).collect();
        cuts.push(-l);
        cuts.push(l);
        cuts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut sum = 0.0;
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            // Inside a piece, away from its ends (a jump sits exactly on an end).
            let e = (b - a) * 1e-12;
            sum += (b - a) / 6.0 * (g(a + e) + 4.0 * g(0.5 * (a + b)) + g(b - e));
        }
        sum / (2.0 * l)
    }

    /// The axisymmetric form of one family at many radii, from one particle half-width off the
    /// axis outward: the r-weighted weights sum to 1 and their gradients to 0; a linear nodal
    /// field `v_r = k r`, `v_z = k' z` gives exactly `dv_r/dr = k`, `v_r / r = k` (the hoop
    /// rate, `sum r_i T_ip = 1`), `dv_z/dz = k'` and no cross terms, which is the patch test of
    /// a uniform radial expansion at any distance from the axis; and for uGIMP the weights
    /// equal the r-weighted integrals of E66-E68 by quadrature.
    fn check_axisymmetric<const K: usize, S: Shape1D<K>>(inner: S, finite: Option<f64>) {
        const N: usize = 14;
        let h: Real = 0.25;
        let margin = 2.0; // cells between the grid's first node and the axis
        let origin = -margin * h;
        let half_width = h / 4.0; // 2 particles per cell
        let shape = Axisymmetric::new(inner, origin, h, half_width);
        let (nodes, stride) = ([N, N], [1, N]);
        let mut st = 11u64;
        let check = |r: Real, z: Real| {
            let s = [(r - origin) / h, z / h];
            let stencil = Stencil::<2, K>::new(&shape, s, [1.0; 2], nodes, stride, 1.0 / h);
            let (mut sum_w, mut sum_g) = (0.0f64, [0.0f64; 2]);
            let mut grad = [[0.0f64; 2]; 2]; // sum x_a,i G_b,i
            let mut hoop = 0.0f64; // sum r_i T_ip
            let (wx, dwx, t) = (stencil.w[0], stencil.dw[0], stencil.t);
            stencil.for_each_node(stride, |idx, w, g| {
                let node = [
                    origin as f64 + (idx % N) as f64 * h as f64,
                    (idx / N) as f64 * h as f64,
                ];
                let (i, j) = (idx % N, idx / N);
                let tij = t[i - stencil.base % N] * stencil.w[1][j - stencil.base / N];
                sum_w += w as f64;
                hoop += node[0] * tij as f64;
                for a in 0..2 {
                    sum_g[a] += g[a] as f64;
                    for b in 0..2 {
                        grad[a][b] += node[a] * g[b] as f64;
                    }
                }
            });
            let tol = 64.0 * Real::EPSILON as f64;
            let at = std::format!("r {r}, z {z}");
            assert!((sum_w - 1.0).abs() < tol, "sum S = {sum_w} at {at}");
            for a in 0..2 {
                assert!(
                    sum_g[a].abs() < tol / h as f64 * 8.0,
                    "sum G {sum_g:?} at {at}"
                );
                for b in 0..2 {
                    let expect = if a == b { 1.0 } else { 0.0 };
                    assert!(
                        (grad[a][b] - expect).abs() < tol * 8.0,
                        "sum x G {grad:?} at {at}"
                    );
                }
            }
            assert!((hoop - 1.0).abs() < tol * 8.0, "sum r T = {hoop} at {at}");
            // The radial factors against the integrals, node by node.
            if let Some(l) = finite {
                let (rp, l) = (r as f64, l * h as f64);
                let first = (stencil.base % N) as f64;
                for k in 0..K {
                    let ri = origin as f64 + (first + k as f64) * h as f64;
                    let hat = |x: f64| (1.0 - ((x - ri) / h as f64).abs()).max(0.0);
                    let slope = |x: f64| {
                        let xi = (x - ri) / h as f64;
                        if xi.abs() < 1.0 {
                            -xi.signum() / h as f64
                        } else {
                            0.0
                        }
                    };
                    let hw = h as f64;
                    let kinks = [ri - hw - rp, ri - rp, ri + hw - rp];
                    let s_r = mean_over(l, &kinks, |u| hat(rp + u) * (rp + u)) / rp;
                    let g_r = mean_over(l, &kinks, |u| slope(rp + u) * (rp + u)) / rp;
                    let t_r = mean_over(l, &kinks, |u| hat(rp + u)) / rp;
                    let q = 1.0e-12 + 64.0 * Real::EPSILON as f64;
                    assert!(
                        (wx[k] as f64 - s_r).abs() < q,
                        "S_r {} vs {s_r} at {at}",
                        wx[k]
                    );
                    assert!(
                        (dwx[k] as f64 - g_r).abs() < q / h as f64,
                        "G_r {} vs {g_r} at {at}",
                        dwx[k]
                    );
                    assert!(
                        (t[k] as f64 - t_r).abs() < q / h as f64,
                        "T {} vs {t_r}",
                        t[k]
                    );
                }
            }
        };
        // From one half-width off the axis to well inside the grid, cell edges and nodes
        // included, then at random.
        let (lo, hi) = (half_width, (N as Real - 2.0 * margin - 1.0) * h);
        let mut r = lo;
        while r <= hi {
            check(r, 5.3 * h);
            r += 0.125 * h;
        }
        for _ in 0..2000 {
            check(
                lo + (hi - lo) * lcg(&mut st),
                (3.0 + 5.0 * lcg(&mut st)) * h,
            );
        }
    }

    #[test]
    fn axisymmetric_weights_reproduce_a_uniform_radial_expansion() {
        check_axisymmetric(Linear, None);
        check_axisymmetric(QuadraticBspline, None);
        check_axisymmetric(CubicBspline, None);
        check_axisymmetric(Gimp::new(2), Some(0.25));
        check_axisymmetric(CpGimp::new(2), Some(0.25));
    }

    /// A [`ThreeNode`] gives the bits of the family it holds, one particle at a time and a
    /// chunk at a time (with the first moments), at random positions and stretches, in 2D and
    /// in the axisymmetric form.
    #[test]
    fn three_node_families_give_the_bits_of_the_family_they_hold() {
        const W: usize = 16;
        let (nodes, stride, inv_h) = ([12, 12], [1, 12], 4.0);
        let mut state = 99u64;
        let members = [
            ThreeNode::Gimp(Gimp::new(2)),
            ThreeNode::CpGimp(CpGimp::new(3)),
            ThreeNode::QuadraticBspline(QuadraticBspline),
        ];
        fn same<const W: usize>(a: &Stencils<2, 3, W>, b: &Stencils<2, 3, W>) -> bool {
            let bits = |x: &[[[Real; W]; ROW]; 2]| x.map(|a| a.map(|r| r.map(Real::to_bits)));
            a.bases() == b.bases()
                && bits(&a.w) == bits(&b.w)
                && bits(&a.dw) == bits(&b.dw)
                && bits(&a.e) == bits(&b.e)
                && a.t.map(|r| r.map(Real::to_bits)) == b.t.map(|r| r.map(Real::to_bits))
                && a.inv_d.map(|r| r.map(Real::to_bits)) == b.inv_d.map(|r| r.map(Real::to_bits))
        }
        fn check<const W: usize, S: Shape1D<3>, T: Shape1D<3>>(
            held: &S,
            three: &T,
            s: &[[Real; W]; 2],
            stretch: &[[Real; W]; 2],
            grid: ([usize; 2], [usize; 2], Real),
        ) {
            let (nodes, stride, inv_h) = grid;
            let (mut a, mut b) = (Stencils::<2, 3, W>::default(), Stencils::default());
            a.compute(held, s, Some(stretch), nodes, stride, inv_h, true);
            b.compute(three, s, Some(stretch), nodes, stride, inv_h, true);
            assert!(same(&a, &b));
            for ln in 0..W {
                let at = [s[0][ln], s[1][ln]];
                let st = [stretch[0][ln], stretch[1][ln]];
                let one = Stencil::<2, 3>::new(held, at, st, nodes, stride, inv_h);
                let other = Stencil::<2, 3>::new(three, at, st, nodes, stride, inv_h);
                assert_eq!(one.base, other.base);
                assert_eq!(
                    (one.w, one.dw, one.t).map_bits(),
                    (other.w, other.dw, other.t).map_bits()
                );
            }
        }
        for _ in 0..200 {
            let s: [[Real; W]; 2] =
                core::array::from_fn(|_| core::array::from_fn(|_| 1.0 + 9.0 * lcg(&mut state)));
            let stretch: [[Real; W]; 2] =
                core::array::from_fn(|_| core::array::from_fn(|_| 0.2 + 2.0 * lcg(&mut state)));
            for three in members {
                let grid = (nodes, stride, inv_h);
                match three {
                    ThreeNode::Gimp(g) => check(&g, &three, &s, &stretch, grid),
                    ThreeNode::CpGimp(g) => check(&g, &three, &s, &stretch, grid),
                    ThreeNode::QuadraticBspline(g) => check(&g, &three, &s, &stretch, grid),
                }
                fn axi<S>(inner: S) -> Axisymmetric<S> {
                    Axisymmetric::new(inner, -0.5, 0.25, 0.0625)
                }
                match three {
                    ThreeNode::Gimp(g) => check(&axi(g), &axi(three), &s, &stretch, grid),
                    ThreeNode::CpGimp(g) => check(&axi(g), &axi(three), &s, &stretch, grid),
                    ThreeNode::QuadraticBspline(g) => {
                        check(&axi(g), &axi(three), &s, &stretch, grid)
                    }
                }
            }
        }
    }

    /// The bits of a stencil's per-axis rows, for exact comparisons.
    trait MapBits {
        type Out: PartialEq + core::fmt::Debug;
        fn map_bits(self) -> Self::Out;
    }

    impl MapBits for ([Row4; 2], [Row4; 2], Row4) {
        type Out = [[u64; 4]; 5];
        fn map_bits(self) -> Self::Out {
            let b = |r: Row4| r.to_array().map(|x| x.to_bits() as u64);
            [
                b(self.0[0]),
                b(self.0[1]),
                b(self.1[0]),
                b(self.1[1]),
                b(self.2),
            ]
        }
    }

    #[test]
    fn cpgimp_partition_of_unity_gradient_sum_and_linear_reproduction_at_any_stretch() {
        for ppc in 1..=4 {
            check_family(CpGimp::new(ppc), 1.0, 10.0);
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
