//! The row-sum scatter engine: how a chunk's per-particle products ([`Products`]) reach the
//! grid. A chunk is scattered by [`scatter_chunk`], in one of two forms that add the same
//! values in the same order: group by group ([`scatter_lanes`], consecutive particles that
//! share their stencil's first node summed in registers) or, where every 4-lane block of the
//! chunk shares one, the groups of all the blocks of a vector at once ([`scatter_blocks`]).
//! Both run the one row code ([`for_each_row`]). The equations, what is scattered, are
//! `phases::p2g`'s (`Products::set`); here are the modes a scatter is compiled for and the
//! products it adds.

use super::lanes::{Lane, Lanes};
use super::rows::{self, Rows};
use crate::cut::Tile;
use crate::grid::{add_row, rows_fit, GridCols};
use crate::shape::{Row4, Shape1D, Stencil, Stencils, ROW};
use crate::Real;
use core::mem::MaybeUninit;
use core::ops::{Add, Mul};

/// What a particle-to-grid pass accumulates.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[repr(u8)]
pub(crate) enum Mode {
    /// Mass, momentum and internal force (USL, MUSL).
    All,
    /// Mass and momentum (first pass of USF).
    MassMomentum,
    /// Internal force only (second pass of USF, after the stress update).
    Force,
    /// Momentum of the updated particle velocities into the remap columns (MUSL).
    Remap,
}

/// The configuration the scatter's row code is compiled for, its const parameter `MODE`: the
/// [`Mode`] (which grid columns a row adds to, so which sums stay in registers) and, in
/// [`APIC_BIT`], the transfer (whether a row carries the affine momentum). Tested per row as
/// values, they made the default step 1.12 to 1.35 times as long (benches/PERFORMANCE.md); a
/// pass picks the instance once.
pub(crate) const fn rows(mode: Mode, apic: bool) -> u8 {
    mode as u8 | if apic { APIC_BIT } else { 0 }
}

/// The bit of [`rows`] that says APIC.
pub(crate) const APIC_BIT: u8 = 0x10;

/// Whether the row configuration `m` ([`rows`]) carries the affine momentum.
#[inline(always)]
pub(crate) const fn apic_rows(m: u8) -> bool {
    m & APIC_BIT != 0
}

impl Mode {
    /// The mode of the row configuration `m` ([`rows`]).
    #[inline(always)]
    pub(crate) const fn of(m: u8) -> Mode {
        match m & !APIC_BIT {
            0 => Mode::All,
            1 => Mode::MassMomentum,
            2 => Mode::Force,
            _ => Mode::Remap,
        }
    }

    /// Adds the nodal mass (and momentum).
    #[inline(always)]
    pub(crate) const fn mass(self) -> bool {
        matches!(self, Mode::All | Mode::MassMomentum)
    }

    /// Reads the particles' momenta (the momentum columns or the remap columns).
    #[inline(always)]
    pub(crate) const fn momentum(self) -> bool {
        !matches!(self, Mode::Force)
    }

    /// Adds the internal (and particle) force.
    #[inline(always)]
    pub(crate) const fn force(self) -> bool {
        matches!(self, Mode::All | Mode::Force)
    }
}

/// What a scatter adds: its [`Mode`], and whether the particle forces (`S_ip F_p`; only with
/// a mode that adds the force) and APIC's affine momentum (only with a mode that adds
/// momentum) enter. The scatter pass turns the mode and transfer into its row code's
/// configuration ([`rows`]) once; the particle forces stay a value.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Adds {
    pub mode: Mode,
    pub forces: bool,
    pub apic: bool,
}

/// What the particles of a chunk scatter, per lane (lane-fastest): the products of their
/// values that the row code scales the weights by, formed once per chunk. What a mode does not
/// read stays zero.
#[repr(C, align(64))]
pub(crate) struct Products<const D: usize, const W: usize> {
    /// m_p.
    pub(crate) m: Lane<W>,
    /// m_p v_p (modes with momentum).
    pub(crate) mv: [Lane<W>; D],
    /// m_p C_p (APIC, modes with momentum).
    pub(crate) mc: [[Lane<W>; D]; D],
    /// -m_p tau_p/rho0, symmetric (modes with force).
    pub(crate) mt: [[Lane<W>; D]; D],
    /// Axisymmetric: -m_p tau_thetatheta/rho0 (modes with force).
    pub(crate) mh: Lane<W>,
    /// The particle force F_p (`FORCE`, modes with force).
    pub(crate) f: [Lane<W>; D],
}

impl<const D: usize, const W: usize> Products<D, W> {
    /// All zero; a pass makes one and sets it per chunk.
    pub fn zero() -> Self {
        Products {
            m: [0.0; W],
            mv: [[0.0; W]; D],
            mc: [[[0.0; W]; D]; D],
            mt: [[[0.0; W]; D]; D],
            mh: [0.0; W],
            f: [[0.0; W]; D],
        }
    }
}

/// The grid columns a scatter adds to, numbered for [`YFactors::add_row`]: the mass, then the momentum,
/// force and remap columns of each axis (room for three axes each).
pub(crate) mod slot {
    pub const MASS: usize = 0;
    pub const MOMENTUM: usize = 1;
    pub const FORCE: usize = 4;
    pub const REMAP: usize = 7;
    /// Number of slots.
    pub const COUNT: usize = 10;
}

/// Grid column `c` (a [`slot`]).
#[inline(always)]
fn column<'g, const D: usize>(g: &'g mut GridCols<'_, D>, c: usize) -> &'g mut [Real] {
    if c == slot::MASS {
        g.mass
    } else if c < slot::FORCE {
        g.vel[c - slot::MOMENTUM]
    } else if c < slot::REMAP {
        g.acc[c - slot::FORCE]
    } else {
        g.remap[c - slot::REMAP]
    }
}

/// Whether a scatter in mode `MODE` adds to slot `c` of a `D`-dimensional grid.
#[inline(always)]
fn slot_used<const D: usize, const MODE: u8>(c: usize) -> bool {
    let axis_ok = |first: usize| c >= first && c < first + D;
    let mode = Mode::of(MODE);
    (mode.mass() && (c == slot::MASS || axis_ok(slot::MOMENTUM)))
        || (mode.force() && axis_ok(slot::FORCE))
        || (mode == Mode::Remap && axis_ok(slot::REMAP))
}

/// The grid rows of a stencil, checked against the grid when made.
pub(crate) struct Direct<'a, 'g, const D: usize> {
    g: &'a mut GridCols<'g, D>,
    base: usize,
    stride: [usize; D],
}

impl<'a, 'g, const D: usize> Direct<'a, 'g, D> {
    /// The rows of the `K`-node stencil at `base`, or `None` if they do not fit in the grid.
    #[inline(always)]
    pub fn new<const K: usize>(
        g: &'a mut GridCols<'g, D>,
        base: usize,
        stride: [usize; D],
    ) -> Option<Self> {
        let fits = g.tile != Tile::ALL || rows_fit(base, last_row::<D, K>(stride), g.len());
        fits.then_some(Direct { g, base, stride })
    }
}

impl<const D: usize> Direct<'_, '_, D> {
    /// Where stencil row `j` along y, layer `k` along z starts in the columns, if the row is
    /// theirs to add to ([`Tile::own`]).
    #[inline(always)]
    fn at(&self, j: usize, k: usize) -> Option<usize> {
        self.g
            .tile
            .own(crate::shape::row_start(self.base, j, k, self.stride))
    }
}

/// The offset of a `K`-node stencil's last row from its first node.
#[inline(always)]
fn last_row<const D: usize, const K: usize>(stride: [usize; D]) -> usize {
    Stencil::<D, K>::last_row_offset(stride)
}

/// Scatters the live lanes of a chunk: the groups of a vector's blocks at once
/// ([`scatter_blocks`]) where every lane is live, the lanes share their first node four by
/// four (what the fills' stencil-bin order gives) and the instance has vectors of 8 lanes or
/// more (in 3D, vectors of 8 lanes: [`Rows::Narrow`]); else in groups of consecutive live
/// lanes that share it ([`scatter_lanes`], for which the lanes' x factors are transposed
/// first, [`Stencils::fill_lanes`]). Both add the same values to the grid in the same order,
/// so the choice changes no result. The whole default step against the group scatter alone,
/// in the same runs (`benches/compare.sh`, 3 to 5 rounds): AVX-512 0.90 in 2D but 1.22 in 3D
/// with 16 lanes per vector (not pinned down; the four particles' x factors alone are 52
/// vectors there, for 32 registers), 0.97 with 8 (MUSL 0.956 and USL 0.989 of the kernel
/// before the block scatter, 5 rounds); AVX2 0.93 (2D) and 0.96 (3D); the baseline instance,
/// one block per vector, 1.03 and 1.02, so it scatters group by group (benches/PERFORMANCE.md,
/// "Decisions").
#[inline(always)]
pub(crate) fn scatter_chunk<
    I: Rows,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
    const MODE: u8,
>(
    st: &mut Stencils<D, K, W>,
    pr: &Products<D, W>,
    live: Lanes<W>,
    stride: [usize; D],
    g: &mut GridCols<'_, D>,
    adds: Adds,
) {
    let base = st.bases();
    let fits = g.tile != Tile::ALL || rows::fit(base, last_row::<D, K>(stride), g.len());
    let blocks = live == Lanes::ALL && rows::blocks_share(base) && fits;
    if blocks && D == 2 && I::N >= 8 {
        scatter_blocks::<I, D, K, S, W, MODE>(st, pr, stride, g, adds);
    } else if blocks && D == 3 && I::Narrow::N == 8 {
        scatter_blocks::<I::Narrow, D, K, S, W, MODE>(st, pr, stride, g, adds);
    } else {
        st.fill_lanes::<S>(apic_rows(MODE));
        scatter_lanes::<D, K, S, W, MODE>(st, pr, live, stride, g, adds);
    }
}

/// Scatters the live lanes of a chunk straight to the grid in groups of consecutive live lanes
/// that share a stencil base ([`scatter_group`]): four where four do, else two where two do,
/// else one (particles seeded in a lattice come in runs of a cell's worth: see
/// [`crate::World::fill_box`]). The grouping depends on the particle order alone, so the
/// result does not depend on the instruction set.
#[inline(always)]
fn scatter_lanes<const D: usize, const K: usize, S: Shape1D<K>, const W: usize, const MODE: u8>(
    st: &Stencils<D, K, W>,
    pr: &Products<D, W>,
    live: Lanes<W>,
    stride: [usize; D],
    g: &mut GridCols<'_, D>,
    adds: Adds,
) {
    let mut ln = 0;
    while ln < W {
        if !live.has(ln) {
            ln += 1;
            continue;
        }
        let base = st.lane(ln).base();
        let Some(mut sink) = Direct::new::<K>(g, base, stride) else {
            ln += 1;
            continue; // Unreachable by construction (first_node clamps).
        };
        let shares = |n: usize| ln + n < W && live.has(ln + n) && st.lane(ln + n).base() == base;
        let n = if shares(1) && shares(2) && shares(3) {
            scatter_group::<D, K, S, W, MODE, 4>(st, pr, ln, &mut sink, adds);
            4
        } else if shares(1) {
            scatter_group::<D, K, S, W, MODE, 2>(st, pr, ln, &mut sink, adds);
            2
        } else {
            scatter_group::<D, K, S, W, MODE, 1>(st, pr, ln, &mut sink, adds);
            1
        };
        ln += n;
    }
}

/// The arithmetic of the scatter's row values ([`XProducts`], [`YFactors`]), on one of two
/// kinds of row: one particle's row, a [`Row4`] over the row's nodes along x scaled by the
/// particle's own reals ([`scatter_group`]), or the rows of one particle of each four-lane
/// block of a vector of lanes, [`BlockRow`], scaled by each block's particle's reals
/// ([`scatter_blocks`]). The row code is written once, on this trait, so both compute every
/// value alike.
pub(crate) trait RowMath:
    Copy + Add<Output = Self> + Mul<<Self as RowMath>::S, Output = Self>
{
    /// What scales a row (`row * s`, every node times `s`): a particle's real, or each
    /// block's particle's real spread over the block.
    type S: Copy;

    /// All zero.
    ///
    /// # Safety
    /// The CPU supports the instance whose vectors `Self` holds.
    unsafe fn zero() -> Self;
}

impl RowMath for Row4 {
    type S = Real;

    #[inline(always)]
    unsafe fn zero() -> Self {
        Row4::ZERO
    }
}

/// One of instance `I`'s vectors holding a stencil row per 128-bit block: block `c` is the
/// row (its [`ROW`] nodes along x) of one particle of lanes `4 c .. 4 c + 4`.
pub(crate) struct BlockRow<I: Rows>(I::V);

impl<I: Rows> Clone for BlockRow<I> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<I: Rows> Copy for BlockRow<I> {}

impl<I: Rows> RowMath for BlockRow<I> {
    type S = I::V;

    #[inline(always)]
    unsafe fn zero() -> Self {
        // SAFETY: as required of the caller.
        BlockRow(unsafe { I::splat(0.0) })
    }
}

impl<I: Rows> Add for BlockRow<I> {
    type Output = Self;

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        BlockRow(I::add(self.0, o.0))
    }
}

impl<I: Rows> Mul<I::V> for BlockRow<I> {
    type Output = Self;

    #[inline(always)]
    fn mul(self, s: I::V) -> Self {
        BlockRow(I::mul(self.0, s))
    }
}

/// The x factors of a row ([`Stencil`]'s `w`, `dw`, `e` of the first axis and `t`), as a kind
/// of [`RowMath`] row.
#[derive(Clone, Copy)]
struct XRow<T> {
    w: T,
    dw: T,
    e: T,
    t: T,
}

/// The particles' products with their factors along x: the part of their row values that
/// does not depend on the row.
#[derive(Clone, Copy)]
struct XProducts<T, const D: usize> {
    /// m wx.
    mass: T,
    /// Momentum on a node: m S (v_a + sum_b C_ab (x_b,i - x_b,p)) (APIC); S (x_b,i - x_b,p)
    /// has the form of G_b with the moments e in place of dw: `mom[a][b]` = m C_ab times ex
    /// (b = 0) or wx (b >= 1), plus m v_a wx in b = 0.
    mom: [[T; D]; D],
    /// Force on a node: f_a = -m sum_b tau_ab G_b + S F_a; `force[a][b]` = -m tau_ab times
    /// dwx (b = 0) or wx (b >= 1), plus F_a wx in b = 0. Axisymmetric, the radial force also
    /// has the hoop term -m tau_thetatheta T_ip (E71), T_ip = t_i w_z: in b = 0 with t.
    force: [[T; D]; D],
}

impl<T: RowMath, const D: usize> XProducts<T, D> {
    /// From the x factors `x` and the products `pr` of particle `n` of `pick`.
    ///
    /// # Safety
    /// As for [`RowMath::zero`].
    #[inline(always)]
    unsafe fn new<const K: usize, S: Shape1D<K>, const W: usize, const MODE: u8>(
        x: &XRow<T>,
        pr: &Products<D, W>,
        pick: &impl Pick<T, W>,
        n: usize,
        adds: Adds,
    ) -> Self {
        // SAFETY: as required of the caller.
        let zero = unsafe { T::zero() };
        let at = |c: &Lane<W>| pick.at(n, c);
        // Loops, not `core::array::from_fn`, whose closures are not always inlined: one left
        // out of line runs the target's baseline code (benches/PERFORMANCE.md).
        let mut f = XProducts {
            mass: x.w * at(&pr.m),
            mom: [[zero; D]; D],
            force: [[zero; D]; D],
        };
        for a in 0..D {
            for b in 0..D {
                let plain = if b == 0 { x.w * at(&pr.mv[a]) } else { zero };
                f.mom[a][b] = if apic_rows(MODE) {
                    plain + (if b == 0 { x.e } else { x.w }) * at(&pr.mc[a][b])
                } else {
                    plain
                };
                let mut t = (if b == 0 { x.dw } else { x.w }) * at(&pr.mt[a][b]);
                if adds.forces && b == 0 {
                    t = t + x.w * at(&pr.f[a]);
                }
                if S::AXISYMMETRIC && a == 0 && b == 0 {
                    t = t + x.t * at(&pr.mh);
                }
                f.force[a][b] = t;
            }
        }
        f
    }
}

/// The particles' factors for the rows of y node `j`: mass times wy_j; the momentum's and
/// force's terms that carry wz_k (`_wz`: x and y factors) and the z factor dwz_k or ez_k
/// (`_dz`, 3D only).
#[derive(Clone, Copy)]
struct YFactors<T, const D: usize> {
    mass: T,
    mom_wz: [T; D],
    mom_dz: [T; D],
    f_wz: [T; D],
    f_dwz: [T; D],
}

/// The factors of a stencil node along one axis: weight, derivative and first moment.
type AxisFactors<S> = (S, S, S);

impl<T: RowMath, const D: usize> YFactors<T, D> {
    /// From the x factors and the y node's factors.
    ///
    /// # Safety
    /// As for [`RowMath::zero`].
    #[inline(always)]
    unsafe fn new<const MODE: u8>(x: &XProducts<T, D>, (wy, dwy, ey): AxisFactors<T::S>) -> Self {
        let apic = apic_rows(MODE);
        // SAFETY: as required of the caller.
        let zero = unsafe { T::zero() };
        let mut y = YFactors {
            mass: x.mass * wy,
            mom_wz: [zero; D],
            mom_dz: [zero; D],
            f_wz: [zero; D],
            f_dwz: [zero; D],
        };
        for a in 0..D {
            y.mom_wz[a] = if apic {
                x.mom[a][0] * wy + x.mom[a][1] * ey
            } else {
                x.mom[a][0] * wy
            };
            if apic && D == 3 {
                y.mom_dz[a] = x.mom[a][D - 1] * wy;
            }
            y.f_wz[a] = x.force[a][0] * wy + x.force[a][1] * dwy;
            if D == 3 {
                y.f_dwz[a] = x.force[a][D - 1] * wy;
            }
        }
        y
    }

    /// Adds these particles' values of the row of z node `k` (factors `z`; unread in 2D), per
    /// [`slot`], to `acc`, or with `FIRST` writes them there (the slots `MODE` fills; the
    /// others stay as they are). The first particle of a group writes: adding to zeros would
    /// cost an add per value (the compiler keeps `0 + x`, which is not `x` for `x = -0`).
    #[inline(always)]
    fn add_row<const MODE: u8, const FIRST: bool>(
        &self,
        (wz, dwz, ez): AxisFactors<T::S>,
        acc: &mut [T; slot::COUNT],
    ) {
        let mode = Mode::of(MODE);
        if mode.mass() {
            let m = if D == 3 { self.mass * wz } else { self.mass };
            put::<T, FIRST>(acc, slot::MASS, m);
        }
        for a in 0..D {
            let mom = if apic_rows(MODE) && D == 3 {
                self.mom_wz[a] * wz + self.mom_dz[a] * ez
            } else if D == 3 {
                self.mom_wz[a] * wz
            } else {
                self.mom_wz[a]
            };
            if mode.mass() {
                put::<T, FIRST>(acc, slot::MOMENTUM + a, mom);
            }
            if mode == Mode::Remap {
                put::<T, FIRST>(acc, slot::REMAP + a, mom);
            }
        }
        if mode.force() {
            for a in 0..D {
                let f = if D == 3 {
                    self.f_wz[a] * wz + self.f_dwz[a] * dwz
                } else {
                    self.f_wz[a]
                };
                put::<T, FIRST>(acc, slot::FORCE + a, f);
            }
        }
    }
}

/// Writes (`FIRST`) or adds `v` to slot `c` of `acc`.
#[inline(always)]
fn put<T: RowMath, const FIRST: bool>(acc: &mut [T; slot::COUNT], c: usize, v: T) {
    acc[c] = if FIRST { v } else { acc[c] + v };
}

/// Where the row code reads the particles' values ([`Products`]) and stencil factors from
/// the chunk's lane arrays: one lane's real per particle of a group ([`OneLane`]), or one
/// particle of each four-lane block of a vector of lanes ([`BlockAt`]).
trait Pick<T: RowMath, const W: usize> {
    /// Particle `n`'s value in `lanes`.
    fn at(&self, n: usize, lanes: &Lane<W>) -> T::S;

    /// Particle `n`'s factors of node `i` along axis `a`.
    #[inline(always)]
    fn axis<const D: usize, const K: usize>(
        &self,
        st: &Stencils<D, K, W>,
        a: usize,
        i: usize,
        n: usize,
    ) -> AxisFactors<T::S> {
        (
            self.at(n, &st.weights(a)[i]),
            self.at(n, &st.derivatives(a)[i]),
            self.at(n, &st.moments(a)[i]),
        )
    }
}

/// The particles of a group, from lane `.0` on, one lane each.
struct OneLane(usize);

impl<const W: usize> Pick<Row4, W> for OneLane {
    #[inline(always)]
    fn at(&self, n: usize, lanes: &Lane<W>) -> Real {
        lanes[self.0 + n]
    }
}

/// Particle `n` of each four-lane block of lanes `at..at + I::N` (lane `4 c + n` in block
/// `c`), for [`BlockRow`]s.
struct BlockAt<I> {
    at: usize,
    instance: core::marker::PhantomData<I>,
}

impl<I: Rows> BlockAt<I> {
    /// # Safety
    /// The CPU supports instance `I`.
    #[inline(always)]
    unsafe fn new(at: usize) -> Self {
        BlockAt {
            at,
            instance: core::marker::PhantomData,
        }
    }

    /// The rows of a stencil's lane arrays (`[node][lane]`): element `n` holds particle `n`'s
    /// row of each block.
    #[inline(always)]
    fn rows<const W: usize>(&self, c: &[Lane<W>; ROW]) -> [I::V; 4] {
        // SAFETY: `new` required the instance's CPU support.
        unsafe {
            I::transpose([
                I::load(&c[0], self.at),
                I::load(&c[1], self.at),
                I::load(&c[2], self.at),
                I::load(&c[3], self.at),
            ])
        }
    }
}

impl<I: Rows, const W: usize> Pick<BlockRow<I>, W> for BlockAt<I> {
    #[inline(always)]
    fn at(&self, n: usize, lanes: &Lane<W>) -> I::V {
        // SAFETY: `new` required the instance's CPU support.
        I::spread(unsafe { I::load(lanes, self.at) }, n)
    }
}

/// What takes each row's sums from [`for_each_row`].
trait RowSink<T> {
    /// Takes row `(j, k)`'s values `acc` (per [`slot`]; the slots `MODE` fills).
    fn row<const K: usize, const MODE: u8>(&mut self, j: usize, k: usize, acc: &[T; slot::COUNT]);
}

impl<const D: usize> RowSink<Row4> for Direct<'_, '_, D> {
    #[inline(always)]
    fn row<const K: usize, const MODE: u8>(
        &mut self,
        j: usize,
        k: usize,
        acc: &[Row4; slot::COUNT],
    ) {
        let Some(at) = self.at(j, k) else {
            return; // Another tile's row.
        };
        for (c, &v) in acc.iter().enumerate() {
            if slot_used::<D, MODE>(c) {
                // SAFETY: `new` checked the stencil's rows (j, k < K) against the whole grid,
                // or the columns are a tile's ([`Tile::own`]).
                unsafe { add_row(column(self.g, c), at, v) };
            }
        }
    }
}

/// The row sums of the four-lane blocks of one of instance `I`'s vectors ([`scatter_blocks`]):
/// per stencil row `(j, k)` (at `j K + k`) and [`slot`], block `c` holds the row summed over
/// lanes `4 c .. 4 c + 4`. Only what the scatter adds is written, and only that is
/// read.
struct BlockSums<I: Rows, const D: usize> {
    sums: [[MaybeUninit<I::V>; slot::COUNT]; ROW * ROW],
}

impl<I: Rows, const D: usize> RowSink<BlockRow<I>> for BlockSums<I, D> {
    #[inline(always)]
    fn row<const K: usize, const MODE: u8>(
        &mut self,
        j: usize,
        k: usize,
        acc: &[BlockRow<I>; slot::COUNT],
    ) {
        for (c, v) in acc.iter().enumerate() {
            if slot_used::<D, MODE>(c) {
                self.sums[j * K + k][c].write(v.0);
            }
        }
    }
}

/// Gives `sink` each stencil row `(j, k)` in turn with the row's values (per [`slot`])
/// summed over the `N` particles whose x factors are `x`, in their order, the first one's
/// written ([`YFactors::add_row`]); `pick` reads their factors along the other axes from the
/// stencils' lane arrays. Separable form (E6): node (i, j, k) has
/// S = wx_i wy_j wz_k and G = (dwx_i wy_j wz_k, wx_i dwy_j wz_k, wx_i wy_j dwz_k); the x
/// factors are multiplied by the y factors once per j, and each row (j, k) costs one multiply
/// by wz_k per quantity, plus one by dwz_k for the force (3D).
///
/// # Safety
/// As for [`RowMath::zero`].
#[inline(always)]
unsafe fn for_each_row<
    T: RowMath,
    const D: usize,
    const K: usize,
    const W: usize,
    const MODE: u8,
    const N: usize,
>(
    x: &[XProducts<T, D>; N],
    st: &Stencils<D, K, W>,
    pick: &impl Pick<T, W>,
    sink: &mut impl RowSink<T>,
) {
    const { assert!(N >= 1) };
    // SAFETY (every unsafe block below): as required of the caller.
    let zero = unsafe { T::zero() };
    for j in 0..K {
        // Loops over the particles, not `core::array::from_fn` (see `XProducts::new`).
        let mut y = [unsafe { YFactors::new::<MODE>(&x[0], pick.axis(st, 1, j, 0)) }; N];
        for n in 1..N {
            y[n] = unsafe { YFactors::new::<MODE>(&x[n], pick.axis(st, 1, j, n)) };
        }
        for k in 0..Stencil::<D, K>::layers() {
            let mut acc = [zero; slot::COUNT];
            y[0].add_row::<MODE, true>(pick.axis(st, D - 1, k, 0), &mut acc);
            for n in 1..N {
                y[n].add_row::<MODE, false>(pick.axis(st, D - 1, k, n), &mut acc);
            }
            sink.row::<K, MODE>(j, k, &acc);
        }
    }
}

/// Scatters the `N` live lanes from `ln` on, which share a stencil base, to `sink`, row by
/// row: each row's values are summed over the particles in registers, in the particles'
/// order ([`for_each_row`]), and then added to the sink once ([`slot_used`] names what
/// `MODE` adds), so a group of N costs one load, add and store per row and column where N single
/// particles cost N. The x factors are 4-wide vectors over a row's nodes (a quarter of each a
/// padding node when `K` is 3).
#[inline(always)]
fn scatter_group<
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
    const MODE: u8,
    const N: usize,
>(
    st: &Stencils<D, K, W>,
    pr: &Products<D, W>,
    ln: usize,
    sink: &mut Direct<'_, '_, D>,
    adds: Adds,
) {
    let pick = OneLane(ln);
    let xrow = |n: usize| {
        let s = st.lane(ln + n);
        XRow {
            w: s.wx(),
            dw: s.dwx(),
            e: s.ex(),
            t: s.t(),
        }
    };
    // SAFETY (every unsafe block): Row4 is the target's baseline, which every instance has.
    let mut x = [unsafe { XProducts::new::<K, S, W, MODE>(&xrow(0), pr, &pick, 0, adds) }; N];
    for n in 1..N {
        x[n] = unsafe { XProducts::new::<K, S, W, MODE>(&xrow(n), pr, &pick, n, adds) };
    }
    unsafe { for_each_row::<Row4, D, K, W, MODE, N>(&x, st, &pick, sink) };
}

/// Scatters a chunk whose lanes are all live and share their first node four by four
/// ([`rows::blocks_share`]): [`scatter_group`] for the groups of four of all the blocks of
/// one of the instance's vectors at once (the 2D default scene: 4 particles in 16 lanes per
/// operation with AVX-512, against one particle in 4). The x factors of the lanes, as lane
/// vectors, are transposed within their 128-bit blocks into rows ([`BlockAt::rows`]; block
/// `c` of row `n` is lane `4 c + n`'s), and the particles' reals are spread over their block
/// ([`Rows::spread`]); the row code ([`for_each_row`] on [`BlockRow`]) then sums the four
/// particles of each block as [`scatter_group`] sums a group's, and the blocks' sums are added
/// to the grid block after block, as it adds them: the same values, added in the same order.
///
/// The caller checked that every lane's rows fit the grid ([`rows::fit`]), or `g` is a tile's
/// columns ([`Tile::own`]).
#[inline(always)]
fn scatter_blocks<
    I: Rows,
    const D: usize,
    const K: usize,
    S: Shape1D<K>,
    const W: usize,
    const MODE: u8,
>(
    st: &Stencils<D, K, W>,
    pr: &Products<D, W>,
    stride: [usize; D],
    g: &mut GridCols<'_, D>,
    adds: Adds,
) {
    let base = st.bases();
    for at in (0..W).step_by(I::N) {
        // SAFETY: this instance runs only on a CPU that supports it.
        let pick = unsafe { BlockAt::<I>::new(at) };
        let (w, dw, e, t) = (
            pick.rows(st.weights(0)),
            pick.rows(st.derivatives(0)),
            pick.rows(st.moments(0)),
            pick.rows(st.hoop_factors()),
        );
        let xrow = |n: usize| XRow {
            w: BlockRow::<I>(w[n]),
            dw: BlockRow(dw[n]),
            e: BlockRow(e[n]),
            t: BlockRow(t[n]),
        };
        let mut sums = BlockSums::<I, D> {
            sums: [[MaybeUninit::uninit(); slot::COUNT]; ROW * ROW],
        };
        // SAFETY: as for `pick`.
        unsafe {
            let x = [
                XProducts::new::<K, S, W, MODE>(&xrow(0), pr, &pick, 0, adds),
                XProducts::new::<K, S, W, MODE>(&xrow(1), pr, &pick, 1, adds),
                XProducts::new::<K, S, W, MODE>(&xrow(2), pr, &pick, 2, adds),
                XProducts::new::<K, S, W, MODE>(&xrow(3), pr, &pick, 3, adds),
            ];
            for_each_row::<BlockRow<I>, D, K, W, MODE, 4>(&x, st, &pick, &mut sums);
        }
        // Block by block, each block's rows and columns in the order `scatter_group` adds
        // them. (Row by row, the blocks one after another, a block's row load overlapped the
        // store of the block before it at an offset of a node, which store forwarding does
        // not serve: the scatter took twice as long.) Each block is its own call, so that the
        // block taken out of the vectors is a constant (a loop over them was not unrolled in
        // 3D, and took the block by a jump table).
        let first = |b: usize| base[(at + 4 * b) % W] as usize;
        // SAFETY: `for_each_row` gave `sums` every row; the caller checked every lane's rows.
        unsafe {
            add_block::<I, D, K, MODE, 0>(&sums, first(0), stride, g);
            if I::N >= 8 {
                add_block::<I, D, K, MODE, 1>(&sums, first(1), stride, g);
            }
            if I::N >= 16 {
                add_block::<I, D, K, MODE, 2>(&sums, first(2), stride, g);
                add_block::<I, D, K, MODE, 3>(&sums, first(3), stride, g);
            }
        }
    }
}

/// Adds block `B` of every row sum of `sums` to the grid, at the stencil whose first node is
/// `first`, in the order [`scatter_group`] adds a group's rows and columns.
///
/// # Safety
/// Every lane's rows fit the grid, or `g` is a tile's columns ([`Tile::own`]); `sums` holds
/// every row (`j < K`, `k < layers`) with the slots `MODE` fills ([`for_each_row`] gave it
/// them).
#[inline(always)]
unsafe fn add_block<I: Rows, const D: usize, const K: usize, const MODE: u8, const B: usize>(
    sums: &BlockSums<I, D>,
    first: usize,
    stride: [usize; D],
    g: &mut GridCols<'_, D>,
) {
    for j in 0..K {
        for k in 0..Stencil::<D, K>::layers() {
            let Some(at) = g.tile.own(crate::shape::row_start(first, j, k, stride)) else {
                continue; // Another tile's row.
            };
            for c in 0..slot::COUNT {
                if slot_used::<D, MODE>(c) {
                    // SAFETY: as required of the caller ([`Tile::own`]).
                    unsafe {
                        let v = sums.sums[j * K + k][c].assume_init();
                        add_row(column(g, c), at, I::block(v, B));
                    }
                }
            }
        }
    }
}

/// The block scatter is taken only by instances with vectors of 8 or 16 lanes, which are f32.
#[cfg(all(
    test,
    target_arch = "x86_64",
    feature = "wide-simd",
    not(feature = "f64")
))]
mod tests {
    use super::*;
    use crate::shape::{first_node, Axisymmetric, CubicBspline, Gimp, Linear};

    /// Node entries per grid column in these tests (with room past the last row).
    const LEN: usize = NODES * NODES * NODES + 64;
    const NODES: usize = 16;

    /// A small deterministic generator (64-bit LCG, top bits).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> Real {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 40) as Real / (1u64 << 24) as Real
        }

        fn range(&mut self, lo: Real, hi: Real) -> Real {
            lo + (hi - lo) * self.next()
        }
    }

    fn grid<const D: usize>(cols: &mut [[Real; LEN]; 10]) -> GridCols<'_, D> {
        let [m, v0, v1, v2, a0, a1, a2, r0, r1, r2] = cols;
        let mut vel = [v0.as_mut_slice(), v1.as_mut_slice(), v2.as_mut_slice()].into_iter();
        let mut acc = [a0.as_mut_slice(), a1.as_mut_slice(), a2.as_mut_slice()].into_iter();
        let mut remap = [r0.as_mut_slice(), r1.as_mut_slice(), r2.as_mut_slice()].into_iter();
        GridCols {
            mass: m.as_mut_slice(),
            vel: core::array::from_fn(|_| vel.next().expect("three axes")),
            acc: core::array::from_fn(|_| acc.next().expect("three axes")),
            remap: core::array::from_fn(|_| remap.next().expect("three axes")),
            series: core::array::from_fn(|_| &mut [][..]),
            scalar: Default::default(),
            contact: Default::default(),
            len: LEN,
            tile: crate::cut::Tile::ALL,
            reach: &[],
            whole: &[],
        }
    }

    /// Scatters one chunk of random particles whose lanes share their first node four by four
    /// (blocks `step` nodes apart along x: 0 repeats a block's node, 1 overlaps their rows;
    /// with `step` 3 the third and fourth blocks start on the next line of nodes, where the
    /// rows of the blocks before reach) with instance `I`'s lane-major scatter and with the group
    /// scatter, onto grids holding the same random values (zeros of both signs among them),
    /// and checks that every entry of every column is bit-identical.
    fn check<
        I: Rows,
        const D: usize,
        const K: usize,
        S: Shape1D<K>,
        const W: usize,
        const MODE: u8,
    >(
        shape: &S,
        rng: &mut Rng,
        step: usize,
        adds: Adds,
    ) {
        let nodes = [NODES; D];
        let stride: [usize; D] = core::array::from_fn(|a| NODES.pow(a as u32));
        let inv_h = 2.0;
        // The first node of each block; the line's y (and z) node, and the first x node.
        let line: [usize; D] = core::array::from_fn(|_| 1 + (rng.next() * 2.0) as usize);
        let mut s = [[0.0; W]; D];
        for ln in 0..W {
            for a in 0..D {
                let b = ln / 4;
                let offset = match (a, step) {
                    (0, 3) => b % 2,
                    (0, _) => b * step,
                    (1, 3) => b / 2,
                    _ => 0,
                };
                let target = (line[a] + offset) as i32;
                // Rejection: a position in the cells around `target` whose stencil starts there.
                s[a][ln] = loop {
                    let x = rng.range(target as Real - 1.0, target as Real + 3.0);
                    if first_node::<K, S>(x, nodes[a]) == target {
                        break x;
                    }
                };
            }
        }
        let mut st = Stencils::<D, K, W>::default();
        st.compute::<S>(shape, &s, None, nodes, stride, inv_h, adds.apic);
        let base = st.bases();
        assert!(rows::blocks_share(base));
        assert!(rows::fit(
            base,
            Stencil::<D, K>::last_row_offset(stride),
            LEN
        ));
        let mut pr = Products::<D, W>::zero();
        for ln in 0..W {
            pr.m[ln] = rng.range(0.5, 2.0);
            pr.mh[ln] = rng.range(-2.0, 2.0);
            for a in 0..D {
                pr.mv[a][ln] = rng.range(-2.0, 2.0);
                pr.f[a][ln] = rng.range(-2.0, 2.0);
                for b in 0..D {
                    pr.mc[a][b][ln] = rng.range(-2.0, 2.0);
                    pr.mt[a][b][ln] = rng.range(-2.0, 2.0);
                }
            }
        }
        let mut before = [[0.0; LEN]; 10];
        for col in before.iter_mut() {
            for v in col.iter_mut() {
                let r = rng.next();
                *v = if r < 0.2 {
                    -0.0
                } else if r < 0.4 {
                    0.0
                } else {
                    rng.range(-1.0, 1.0)
                };
            }
        }
        let (mut by_blocks, mut by_groups) = (before, before);
        scatter_blocks::<I, D, K, S, W, MODE>(&st, &pr, stride, &mut grid(&mut by_blocks), adds);
        st.fill_lanes::<S>(adds.apic);
        scatter_lanes::<D, K, S, W, MODE>(
            &st,
            &pr,
            Lanes::ALL,
            stride,
            &mut grid(&mut by_groups),
            adds,
        );
        let mut changed = 0;
        for c in 0..10 {
            for i in 0..LEN {
                let (x, y) = (by_blocks[c][i], by_groups[c][i]);
                assert_eq!(
                    x.to_bits(),
                    y.to_bits(),
                    "column {c} node {i}: {x} against {y} (D {D}, K {K}, {adds:?}, step {step})"
                );
                changed += (x.to_bits() != before[c][i].to_bits()) as usize;
            }
        }
        assert!(changed > 0, "the scatter changed nothing");
    }

    /// [`check`] over every mode, with and without particle forces and APIC, and blocks
    /// placed apart, overlapping and on one node.
    fn check_modes<I: Rows, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        shape: &S,
    ) {
        let mut rng = Rng(0x5eed + D as u64 * 31 + K as u64);
        for step in [0, 1, 3] {
            let adds = |mode, forces, apic| Adds { mode, forces, apic };
            const ALL: u8 = Mode::All as u8;
            const REMAP: u8 = Mode::Remap as u8;
            check::<I, D, K, S, W, ALL>(shape, &mut rng, step, adds(Mode::All, false, false));
            check::<I, D, K, S, W, ALL>(shape, &mut rng, step, adds(Mode::All, true, true));
            let (mass, force) = (Mode::MassMomentum, Mode::Force);
            check::<I, D, K, S, W, { Mode::MassMomentum as u8 }>(
                shape,
                &mut rng,
                step,
                adds(mass, false, true),
            );
            check::<I, D, K, S, W, { Mode::Force as u8 }>(
                shape,
                &mut rng,
                step,
                adds(force, true, false),
            );
            check::<I, D, K, S, W, REMAP>(shape, &mut rng, step, adds(Mode::Remap, false, false));
            check::<I, D, K, S, W, REMAP>(shape, &mut rng, step, adds(Mode::Remap, false, true));
        }
    }

    /// The block scatter of every instance the CPU supports that takes it ([`scatter_chunk`]:
    /// AVX2 in 2D and 3D, AVX-512 in 2D; f32 only, where their vectors hold 8 and 16 lanes)
    /// adds to the grid what the group scatter adds, in the same order, to the bit: uGIMP in
    /// 2D and 3D, linear weights, the cubic B-spline in 3D and the axisymmetric form.
    #[test]
    fn every_instance_scatters_blocks_as_groups_do() {
        use crate::simd::lanes::width;
        use crate::simd::Avx2;
        use crate::simd::{Instance, Simd};
        let gimp = Gimp::new(2);
        let axisymmetric = Axisymmetric::new(gimp, 0.0, 0.5, 0.125);
        let widest = Simd::Detect.instance();
        if widest >= Instance::Avx2 {
            check_modes::<Avx2, 2, 3, _, { width(2) }>(&gimp);
            check_modes::<Avx2, 2, 2, _, { width(2) }>(&Linear);
            check_modes::<Avx2, 2, 3, _, { width(2) }>(&axisymmetric);
            check_modes::<Avx2, 3, 3, _, { width(3) }>(&gimp);
            check_modes::<Avx2, 3, 4, _, { width(3) }>(&CubicBspline);
        }
        #[cfg(all(target_arch = "x86_64", feature = "wide-simd"))]
        if widest == Instance::Avx512 {
            use crate::simd::Avx512;
            check_modes::<Avx512, 2, 3, _, { width(2) }>(&gimp);
            check_modes::<Avx512, 2, 2, _, { width(2) }>(&Linear);
            check_modes::<Avx512, 2, 3, _, { width(2) }>(&axisymmetric);
        }
    }
}
