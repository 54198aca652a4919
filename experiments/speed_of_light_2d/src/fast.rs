//! The hand-tuned step: AVX2 intrinsics, 8 particle lanes, AoS node records of 8 floats,
//! particles sorted by stencil base ("bin": the 3 x 3 nodes a particle touches), and the
//! scatter and gathers accumulating or holding a bin's 9 node records in registers.
//!
//! Node record lanes: 0 m | 1 unused (0) | 2,3 p' then v' (MUSL re-map) | 4,5 p then v |
//! 6,7 f then a.

use crate::scene::*;
use std::arch::x86_64::*;
use std::time::Instant;

#[repr(C, align(32))]
#[derive(Clone, Copy)]
pub struct Rec(pub [f32; 8]);

/// Floats per chunk of 8 in a stencil block: base[8] (u32 bits), wx[3][8], dwx[3][8], wy[3][8],
/// dwy[3][8].
const SW: usize = 13 * 8;
const OWX: usize = 8;
const ODWX: usize = 32;
const OWY: usize = 56;
const ODWY: usize = 80;

#[derive(Clone, Copy, Debug)]
pub struct Opts {
    pub fma: bool,
    pub stored: bool,
    pub binned: bool,
    pub checks: bool,
    pub breakdown: bool,
    /// Attribution only (wrong physics): bit 0 skips the stress gather, 1 the stress math, 2 the
    /// scatter's node loop, 3 the particle gather, 4 the p' scatter.
    pub skip: u32,
    /// Loop fission: each pass runs its gathers, its lane math and its scatter as separate
    /// loops over blocks of BLK particles (needs stored stencils).
    pub fission: bool,
    /// Stress gather from the compact v' array (rows of 4 nodes per 256-bit load).
    pub compact: bool,
    /// Scatter with one FMA per node: the force's two terms in separate record lanes (summed
    /// by the grid update), lane-varying x and y weight vectors.
    pub split: bool,
    /// The particle pass's gather keeps a bin's 9 records in registers (else reloads them).
    pub gcache: bool,
}

#[repr(C, align(32))]
struct Block([f32; SW]);

pub struct Fast {
    pub n: usize,
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub vx: Vec<f32>,
    pub vy: Vec<f32>,
    pub m: Vec<f32>,
    pub h00: Vec<f32>,
    pub h01: Vec<f32>,
    pub h10: Vec<f32>,
    pub h11: Vec<f32>,
    pub txx: Vec<f32>,
    pub tyy: Vec<f32>,
    pub txy: Vec<f32>,
    pub tzz: Vec<f32>,
    pub xn: Vec<f32>,
    pub yn: Vec<f32>,
    pub status: Vec<u32>,
    /// Index of each particle in the kernel's fill order.
    pub id: Vec<u32>,
    grid: Vec<Rec>,
    /// Compact re-mapped velocities (v'x, v'y) per node, for the stress gather.
    vr: Vec<f32>,
    st: Vec<Block>,
    /// Particles whose stencil base changed in the last step (they may be out of bin order).
    pub moved: usize,
    /// Largest |v|^2 after the last particle pass (for the next stable dt).
    pub v2max: f32,
    pub bad: usize,
    pub opts: Opts,
    /// Seconds: reset, scatter, grid update 1, particle pass, grid update 2, stress pass.
    pub times: [f64; 6],
}

// ---------------------------------------------------------------- small helpers

#[inline(always)]
unsafe fn s1(v: f32) -> __m256 {
    _mm256_set1_ps(v)
}
#[inline(always)]
unsafe fn add(a: __m256, b: __m256) -> __m256 {
    _mm256_add_ps(a, b)
}
#[inline(always)]
unsafe fn sub(a: __m256, b: __m256) -> __m256 {
    _mm256_sub_ps(a, b)
}
#[inline(always)]
unsafe fn mul(a: __m256, b: __m256) -> __m256 {
    _mm256_mul_ps(a, b)
}
/// a * b + c, fused when F.
#[inline(always)]
unsafe fn fma<const F: bool>(a: __m256, b: __m256, c: __m256) -> __m256 {
    if F {
        _mm256_fmadd_ps(a, b, c)
    } else {
        _mm256_add_ps(_mm256_mul_ps(a, b), c)
    }
}
#[inline(always)]
unsafe fn ld(p: *const f32) -> __m256 {
    _mm256_loadu_ps(p)
}
#[inline(always)]
unsafe fn st(p: *mut f32, v: __m256) {
    _mm256_storeu_ps(p, v)
}
#[inline(always)]
unsafe fn bc(p: *const f32) -> __m256 {
    _mm256_broadcast_ss(&*p)
}
#[inline(always)]
unsafe fn sel(mask: __m256, yes: __m256, no: __m256) -> __m256 {
    _mm256_blendv_ps(no, yes, mask)
}

/// 8 x 8 transpose: out[t][q] = r[q][t].
#[inline(always)]
unsafe fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    let t4 = _mm256_unpacklo_ps(r[4], r[5]);
    let t5 = _mm256_unpackhi_ps(r[4], r[5]);
    let t6 = _mm256_unpacklo_ps(r[6], r[7]);
    let t7 = _mm256_unpackhi_ps(r[6], r[7]);
    let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
    let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
    let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
    let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
    let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
    let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
    let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
    let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
    [
        _mm256_permute2f128_ps::<0x20>(u0, u4),
        _mm256_permute2f128_ps::<0x20>(u1, u5),
        _mm256_permute2f128_ps::<0x20>(u2, u6),
        _mm256_permute2f128_ps::<0x20>(u3, u7),
        _mm256_permute2f128_ps::<0x31>(u0, u4),
        _mm256_permute2f128_ps::<0x31>(u1, u5),
        _mm256_permute2f128_ps::<0x31>(u2, u6),
        _mm256_permute2f128_ps::<0x31>(u3, u7),
    ]
}

/// In-lane 4 x 4 transpose: out[k] lane (h, i) = r[i] lane (h, k) for each 128-bit half h.
#[inline(always)]
unsafe fn transpose4(r: [__m256; 4]) -> [__m256; 4] {
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xEE>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
        _mm256_shuffle_ps::<0xEE>(t1, t3),
    ]
}

/// The upper (HI) or lower halves of 8 per-particle vectors as 4 lane vectors of the 8
/// particles (particle order): out[k] lane t = v[t] lane (4 HI + k).
#[inline(always)]
unsafe fn halves_to_lanes<const HI: bool>(v: &[__m256; 8]) -> [__m256; 4] {
    let mut u = [_mm256_setzero_ps(); 4];
    for k in 0..4 {
        u[k] = if HI {
            _mm256_permute2f128_ps::<0x31>(v[k], v[k + 4])
        } else {
            _mm256_permute2f128_ps::<0x20>(v[k], v[k + 4])
        };
    }
    transpose4(u)
}

#[inline(always)]
unsafe fn mask(lanes: [bool; 8]) -> __m256 {
    let m: [i32; 8] = core::array::from_fn(|i| if lanes[i] { -1 } else { 0 });
    _mm256_castsi256_ps(_mm256_loadu_si256(m.as_ptr() as *const __m256i))
}

// ---------------------------------------------------------------- stencils

/// uGIMP along one axis for 8 lanes of `s` (cells): first node, weights, derivatives / h.
#[inline(always)]
unsafe fn stencil_axis(p: &Params, s: __m256, top: f32) -> (__m256i, [__m256; 3], [__m256; 3]) {
    let one = s1(1.0);
    let zero = _mm256_setzero_ps();
    let y = add(s, s1(0.5));
    let y = _mm256_max_ps(y, one); // NaN -> 1
    let y = _mm256_min_ps(y, s1(top));
    let fi = _mm256_sub_epi32(_mm256_cvttps_epi32(y), _mm256_set1_epi32(1));
    let f = sub(s, _mm256_cvtepi32_ps(fi));
    let l = p.l;
    let xi = sub(f, one);
    let a1 = _mm256_andnot_ps(s1(-0.0), xi);
    let inner = _mm256_cmp_ps::<_CMP_LT_OQ>(a1, s1(l));
    let s_in = sub(one, mul(add(mul(xi, xi), s1(l * l)), s1(p.inv_2l)));
    let s1v = sel(inner, s_in, sub(one, a1));
    let d_in = mul(_mm256_xor_ps(xi, s1(-0.0)), s1(p.inv_l));
    let d_mid = sel(_mm256_cmp_ps::<_CMP_GE_OQ>(xi, zero), s1(-1.0), one);
    let d1 = sel(inner, d_in, d_mid);
    let outer = |a: __m256| -> (__m256, __m256) {
        let t = _mm256_max_ps(sub(s1(1.0 + l), a), zero);
        let cond = _mm256_cmp_ps::<_CMP_LE_OQ>(a, s1(1.0 - l));
        (
            sel(cond, sub(one, a), mul(mul(t, t), s1(p.inv_4l))),
            sel(cond, one, mul(t, s1(p.inv_2l))),
        )
    };
    let (s0, m0) = outer(f);
    let (s2, m2) = outer(sub(s1(2.0), f));
    let ih = s1(p.inv_h);
    (
        fi,
        [s0, s1v, s2],
        [
            mul(_mm256_xor_ps(m0, s1(-0.0)), ih),
            mul(d1, ih),
            mul(m2, ih),
        ],
    )
}

/// Stencils of the 8 particles at (x, y) into a block.
#[inline(always)]
unsafe fn stencil_chunk(p: &Params, x: *const f32, y: *const f32, blk: *mut f32) {
    let sx = mul(sub(ld(x), s1(p.origin[0])), s1(p.inv_h));
    let sy = mul(sub(ld(y), s1(p.origin[1])), s1(p.inv_h));
    let (fx, wx, dwx) = stencil_axis(p, sx, p.top[0]);
    let (fy, wy, dwy) = stencil_axis(p, sy, p.top[1]);
    let base = _mm256_add_epi32(fx, _mm256_mullo_epi32(fy, _mm256_set1_epi32(NX as i32)));
    _mm256_store_si256(blk as *mut __m256i, base);
    for k in 0..3 {
        _mm256_store_ps(blk.add(OWX + 8 * k), wx[k]);
        _mm256_store_ps(blk.add(ODWX + 8 * k), dwx[k]);
        _mm256_store_ps(blk.add(OWY + 8 * k), wy[k]);
        _mm256_store_ps(blk.add(ODWY + 8 * k), dwy[k]);
    }
}

/// The stencil bases of 8 positions (bin check).
#[inline(always)]
unsafe fn bin_bases(p: &Params, x: __m256, y: __m256) -> __m256i {
    let f = |v: __m256, o: f32, top: f32| {
        let s = mul(sub(v, s1(o)), s1(p.inv_h));
        let y = _mm256_min_ps(_mm256_max_ps(add(s, s1(0.5)), s1(1.0)), s1(top));
        _mm256_cvttps_epi32(y)
    };
    let fx = f(x, p.origin[0], p.top[0]);
    let fy = f(y, p.origin[1], p.top[1]);
    _mm256_sub_epi32(
        _mm256_add_epi32(fx, _mm256_mullo_epi32(fy, _mm256_set1_epi32(NX as i32))),
        _mm256_set1_epi32(1 + NX as i32),
    )
}

// ---------------------------------------------------------------- node records

#[inline(always)]
unsafe fn load9(g: *const f32, base: u32) -> [__m256; 9] {
    let mut r = [_mm256_setzero_ps(); 9];
    for j in 0..3 {
        for i in 0..3 {
            r[3 * j + i] = _mm256_load_ps(g.add((base as usize + i + NX * j) * 8));
        }
    }
    r
}

#[inline(always)]
unsafe fn flush9(g: *mut f32, base: u32, acc: &[__m256; 9]) {
    for j in 0..3 {
        for i in 0..3 {
            let q = g.add((base as usize + i + NX * j) * 8);
            _mm256_store_ps(q, add(_mm256_load_ps(q), acc[3 * j + i]));
        }
    }
}

// ---------------------------------------------------------------- the step

impl Fast {
    pub fn new(init: &Initial, p: &Params, opts: Opts) -> Fast {
        let n0 = init.x.len();
        assert!(n0 % 8 == 0);
        // Sort by stencil base (stable): the particles of a bin become consecutive.
        let mut order: Vec<u32> = (0..n0 as u32).collect();
        let base = |i: usize| {
            let (fx, _, _) = stencil1(p, (init.x[i] - p.origin[0]) * p.inv_h, p.top[0]);
            let (fy, _, _) = stencil1(p, (init.y[i] - p.origin[1]) * p.inv_h, p.top[1]);
            fx + NX * fy
        };
        if opts.binned {
            order.sort_by_key(|&i| base(i as usize));
        }
        let pick = |c: &Vec<f32>| order.iter().map(|&i| c[i as usize]).collect::<Vec<f32>>();
        let z = vec![0.0f32; n0];
        Fast {
            n: n0,
            x: pick(&init.x),
            y: pick(&init.y),
            vx: pick(&init.vx),
            vy: pick(&init.vy),
            m: pick(&init.m),
            h00: z.clone(),
            h01: z.clone(),
            h10: z.clone(),
            h11: z.clone(),
            txx: z.clone(),
            tyy: z.clone(),
            txy: z.clone(),
            tzz: z.clone(),
            xn: z.clone(),
            yn: z,
            status: vec![0; n0],
            id: order,
            grid: vec![Rec([0.0; 8]); NODES],
            vr: vec![0.0; 2 * (NODES + 8)],
            st: (0..n0 / 8).map(|_| Block([0.0; SW])).collect(),
            moved: 0,
            v2max: 0.0,
            bad: 0,
            opts,
            times: [0.0; 6],
        }
    }

    /// Re-sorts the particles by stencil base (what a general kernel would do when `moved`
    /// grows); returns nothing, permutes every column.
    pub fn resort(&mut self, p: &Params) {
        let n = self.n;
        let key: Vec<usize> = (0..n)
            .map(|i| {
                let (fx, _, _) = stencil1(p, (self.x[i] - p.origin[0]) * p.inv_h, p.top[0]);
                let (fy, _, _) = stencil1(p, (self.y[i] - p.origin[1]) * p.inv_h, p.top[1]);
                fx + NX * fy
            })
            .collect();
        // Counting sort over the nodes.
        let mut count = vec![0u32; NODES + 1];
        for &k in &key {
            count[k + 1] += 1;
        }
        for k in 0..NODES {
            count[k + 1] += count[k];
        }
        let mut perm = vec![0u32; n];
        for i in 0..n {
            let k = key[i];
            perm[count[k] as usize] = i as u32;
            count[k] += 1;
        }
        let cols: [&mut Vec<f32>; 15] = [
            &mut self.x,
            &mut self.y,
            &mut self.vx,
            &mut self.vy,
            &mut self.m,
            &mut self.h00,
            &mut self.h01,
            &mut self.h10,
            &mut self.h11,
            &mut self.txx,
            &mut self.tyy,
            &mut self.txy,
            &mut self.tzz,
            &mut self.xn,
            &mut self.yn,
        ];
        let mut tmp = vec![0.0f32; n];
        for c in cols {
            for i in 0..n {
                tmp[i] = c[perm[i] as usize];
            }
            std::mem::swap(c, &mut tmp);
        }
        let ids: Vec<u32> = perm.iter().map(|&i| self.id[i as usize]).collect();
        self.id = ids;
        let sts: Vec<u32> = perm.iter().map(|&i| self.status[i as usize]).collect();
        self.status = sts;
    }

    pub fn step(&mut self, p: &Params, usl: bool) {
        let o = self.opts;
        macro_rules! go {
            ($f:literal, $s:literal, $b:literal) => {
                unsafe {
                    if usl {
                        self.step_impl::<$f, $s, $b, true>(p)
                    } else {
                        self.step_impl::<$f, $s, $b, false>(p)
                    }
                }
            };
        }
        match (o.fma, o.stored, o.binned) {
            (true, true, true) => go!(true, true, true),
            (true, false, true) => go!(true, false, true),
            (true, true, false) => go!(true, true, false),
            (true, false, false) => go!(true, false, false),
            (false, true, true) => go!(false, true, true),
            (false, false, true) => go!(false, false, true),
            (false, true, false) => go!(false, true, false),
            (false, false, false) => go!(false, false, false),
        }
    }

    #[inline(never)]
    unsafe fn step_impl<const F: bool, const S: bool, const B: bool, const USL: bool>(
        &mut self,
        p: &Params,
    ) {
        let bd = self.opts.breakdown;
        let mut t = if bd { Some(Instant::now()) } else { None };
        let mut lap = |k: usize, times: &mut [f64; 6]| {
            if let Some(t0) = t.as_mut() {
                let now = Instant::now();
                times[k] += (now - *t0).as_secs_f64();
                *t0 = now;
            }
        };
        // Reset: the whole grid (the node box is 97 % of it here).
        std::ptr::write_bytes(self.grid.as_mut_ptr(), 0, NODES);
        lap(0, &mut self.times);
        let fis = S && self.opts.fission;
        if fis {
            self.scatter2::<F, B>(p);
        } else {
            self.scatter::<F, S, B>(p);
        }
        lap(1, &mut self.times);
        self.grid_update(p);
        lap(2, &mut self.times);
        if USL {
            if fis {
                self.particles_usl2::<F, B>(p);
            } else {
                self.particles_usl::<F, S, B>(p);
            }
            lap(3, &mut self.times);
            return;
        }
        if fis {
            self.particles2::<F, B>(p);
        } else {
            self.particles::<F, S, B>(p);
        }
        lap(3, &mut self.times);
        self.remap_update(p);
        lap(4, &mut self.times);
        if fis {
            self.stress2::<F, B>(p);
        } else {
            self.stress::<F, S, B>(p);
        }
        lap(5, &mut self.times);
    }

    /// Block of chunk c: the stored one, or `local` after computing it.
    #[inline(always)]
    unsafe fn block<const S: bool>(
        &mut self,
        p: &Params,
        c: usize,
        compute: bool,
        local: &mut Block,
    ) -> *mut f32 {
        let blk = if S {
            self.st.as_mut_ptr().add(c).cast::<f32>()
        } else {
            local.0.as_mut_ptr()
        };
        if compute || !S {
            stencil_chunk(
                p,
                self.x.as_ptr().add(8 * c),
                self.y.as_ptr().add(8 * c),
                blk,
            );
        }
        blk
    }

    #[inline(never)]
    unsafe fn scatter<const F: bool, const S: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_mut_ptr().cast::<f32>();
        let mut local = Block([0.0; SW]);
        let m0 = mask([true, false, false, false, true, true, false, false]);
        let m1 = mask([false, false, false, false, false, false, true, true]);
        let idx = _mm256_setr_epi32(2, 2, 2, 2, 2, 2, 7, 1);
        let neg = s1(-0.0);
        for c in 0..self.n / 8 {
            let i0 = 8 * c;
            let blk = self.block::<S>(p, c, true, &mut local);
            let m = ld(self.m.as_ptr().add(i0));
            let nm = _mm256_xor_ps(m, neg);
            let zero = _mm256_setzero_ps();
            let q = transpose8([
                m,
                mul(nm, ld(self.tyy.as_ptr().add(i0))),
                zero,
                zero,
                mul(m, ld(self.vx.as_ptr().add(i0))),
                mul(m, ld(self.vy.as_ptr().add(i0))),
                mul(nm, ld(self.txx.as_ptr().add(i0))),
                mul(nm, ld(self.txy.as_ptr().add(i0))),
            ]);
            let bases = blk as *const u32;
            let mut acc = [zero; 9];
            let mut cur = *bases;
            if self.opts.skip & 4 != 0 {
                st(self.xn.as_mut_ptr(), q[0]);
                continue;
            }
            for t in 0..8 {
                let b = *bases.add(t);
                if B {
                    if b != cur {
                        flush9(g, cur, &acc);
                        acc = [zero; 9];
                        cur = b;
                    }
                } else {
                    acc = [zero; 9];
                }
                let p0 = _mm256_and_ps(q[t], m0);
                let p1 = _mm256_and_ps(q[t], m1);
                let p2 = _mm256_permutevar8x32_ps(q[t], idx);
                let wx = [
                    bc(blk.add(OWX + t)),
                    bc(blk.add(OWX + 8 + t)),
                    bc(blk.add(OWX + 16 + t)),
                ];
                let dwx = [
                    bc(blk.add(ODWX + t)),
                    bc(blk.add(ODWX + 8 + t)),
                    bc(blk.add(ODWX + 16 + t)),
                ];
                for j in 0..3 {
                    let wy = bc(blk.add(OWY + 8 * j + t));
                    let dwy = bc(blk.add(ODWY + 8 * j + t));
                    let d = fma::<F>(dwy, p2, mul(wy, p0));
                    let e = mul(wy, p1);
                    for i in 0..3 {
                        let a = fma::<F>(wx[i], d, acc[3 * j + i]);
                        acc[3 * j + i] = fma::<F>(dwx[i], e, a);
                    }
                }
                if !B {
                    flush9(g, b, &acc);
                }
            }
            if B {
                flush9(g, cur, &acc);
            }
        }
    }

    /// v = p / m, a = f / m + g (zero on empty nodes), then the slip walls on a; zeroes the
    /// re-map lanes.
    #[inline(never)]
    unsafe fn grid_update(&mut self, p: &Params) {
        let g = self.grid.as_mut_ptr().cast::<f32>();
        let keep0 = mask([true, false, false, false, false, false, false, false]);
        let upper = mask([false, false, false, false, true, true, true, true]);
        let grav = _mm256_setr_ps(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, p.gravity[0], p.gravity[1]);
        let cut = s1(p.mass_cutoff);
        let split = self.opts.split && self.opts.fission && self.opts.stored;
        let i1 = _mm256_setr_epi32(0, 7, 7, 7, 1, 2, 3, 4);
        let i2 = _mm256_setr_epi32(7, 7, 7, 7, 7, 7, 5, 6);
        for k in 0..NODES {
            let q = g.add(8 * k);
            let r = _mm256_load_ps(q);
            // Split records [m, px, py, fxa, fya, fxb, fyb, 0] -> [m, 0, 0, 0, px, py, fx, fy].
            let r = if split {
                add(
                    _mm256_permutevar8x32_ps(r, i1),
                    _mm256_permutevar8x32_ps(r, i2),
                )
            } else {
                r
            };
            let m = bc(q);
            let d = add(_mm256_div_ps(r, m), grav);
            let ok = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(m, cut), upper);
            _mm256_store_ps(
                q,
                _mm256_or_ps(_mm256_and_ps(d, ok), _mm256_and_ps(r, keep0)),
            );
        }
        let inv_dt = 1.0 / p.dt;
        let grid = &mut self.grid;
        for j in 0..NY {
            for i in [0, 1, NX - 2, NX - 1] {
                let r = &mut grid[i + NX * j].0;
                r[6] = -r[4] * inv_dt;
            }
        }
        for j in [0, 1, NY - 2, NY - 1] {
            for i in 0..NX {
                let r = &mut grid[i + NX * j].0;
                r[7] = -r[5] * inv_dt;
            }
        }
    }

    /// v' = p' / m (zero on empty nodes), then the slip walls.
    #[inline(never)]
    unsafe fn remap_update(&mut self, p: &Params) {
        let g = self.grid.as_mut_ptr().cast::<f32>();
        let lanes23 = mask([false, false, true, true, false, false, false, false]);
        let cut = s1(p.mass_cutoff);
        for k in 0..NODES {
            let q = g.add(8 * k);
            let r = _mm256_load_ps(q);
            let m = bc(q);
            let d = _mm256_div_ps(r, m);
            let ok = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(m, cut), lanes23);
            _mm256_store_ps(
                q,
                _mm256_or_ps(_mm256_and_ps(d, ok), _mm256_andnot_ps(lanes23, r)),
            );
        }
        let grid = &mut self.grid;
        for j in 0..NY {
            for i in [0, 1, NX - 2, NX - 1] {
                grid[i + NX * j].0[2] = 0.0;
            }
        }
        for j in [0, 1, NY - 2, NY - 1] {
            for i in 0..NX {
                grid[i + NX * j].0[3] = 0.0;
            }
        }
        if self.opts.compact {
            let vr = self.vr.as_mut_ptr();
            for k in 0..NODES {
                let r = _mm_load_ps(g.add(8 * k));
                _mm_storeh_pd(vr.add(2 * k) as *mut f64, _mm_castps_pd(r));
            }
        }
    }

    /// Gathers v_gp, a_gp of a chunk (per-particle vectors; lanes 4..7 = v, a).
    #[inline(always)]
    unsafe fn gather_va<const F: bool, const B: bool, const GC: bool>(
        g: *const f32,
        blk: *const f32,
    ) -> [__m256; 8] {
        let bases = blk as *const u32;
        let mut out = [_mm256_setzero_ps(); 8];
        let mut cur = *bases;
        let mut r = load9(g, cur);
        for t in 0..8 {
            let b = *bases.add(t);
            if !B || !GC || b != cur {
                r = load9(g, b);
                cur = b;
            }
            let wx = [
                bc(blk.add(OWX + t)),
                bc(blk.add(OWX + 8 + t)),
                bc(blk.add(OWX + 16 + t)),
            ];
            let mut rows = [_mm256_setzero_ps(); 3];
            for j in 0..3 {
                rows[j] = fma::<F>(
                    wx[2],
                    r[3 * j + 2],
                    fma::<F>(wx[1], r[3 * j + 1], mul(wx[0], r[3 * j])),
                );
            }
            let wy = [
                bc(blk.add(OWY + t)),
                bc(blk.add(OWY + 8 + t)),
                bc(blk.add(OWY + 16 + t)),
            ];
            out[t] = fma::<F>(
                wy[2],
                rows[2],
                fma::<F>(wy[1], rows[1], mul(wy[0], rows[0])),
            );
        }
        out
    }

    /// The FLIP update of a chunk from v_gp, a_gp (lane vectors); returns v_new, x_new.
    #[inline(always)]
    unsafe fn flip<const F: bool>(
        p: &Params,
        vg: [__m256; 2],
        ag: [__m256; 2],
        v: [__m256; 2],
        x: [__m256; 2],
    ) -> ([__m256; 2], [__m256; 2]) {
        let dt = s1(p.dt);
        let half = s1(0.5);
        let pic = s1(p.pic);
        let zero = _mm256_setzero_ps();
        let mut vn = [zero; 2];
        let mut xn = [zero; 2];
        for a in 0..2 {
            let inv = mul(sub(v[a], vg[a]), pic);
            let vv = sub(fma::<F>(ag[a], dt, v[a]), inv);
            let xx = fma::<F>(
                sub(fma::<F>(mul(ag[a], half), dt, vg[a]), mul(inv, half)),
                dt,
                x[a],
            );
            let s = mul(sub(xx, s1(p.origin[a])), s1(p.inv_h));
            let below = _mm256_cmp_ps::<_CMP_LT_OQ>(s, s1(p.lo));
            let above = _mm256_cmp_ps::<_CMP_GT_OQ>(s, s1(p.hi[a]));
            let lo_x = p.origin[a] + p.lo * p.h;
            let hi_x = p.origin[a] + p.hi[a] * p.h;
            xn[a] = sel(below, s1(lo_x), sel(above, s1(hi_x), xx));
            let out = _mm256_or_ps(
                _mm256_and_ps(below, _mm256_cmp_ps::<_CMP_LT_OQ>(vv, zero)),
                _mm256_and_ps(above, _mm256_cmp_ps::<_CMP_GT_OQ>(vv, zero)),
            );
            vn[a] = _mm256_andnot_ps(out, vv);
        }
        (vn, xn)
    }

    #[inline(never)]
    unsafe fn particles<const F: bool, const S: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_mut_ptr().cast::<f32>();
        let mut local = Block([0.0; SW]);
        let lanes23 = mask([false, false, true, true, false, false, false, false]);
        let mut v2max = _mm256_setzero_ps();
        let mut bad = 0u32;
        for c in 0..self.n / 8 {
            let i0 = 8 * c;
            let blk = self.block::<S>(p, c, false, &mut local);
            let out = if self.opts.skip & 8 == 0 {
                Self::gather_va::<F, B, true>(g, blk)
            } else {
                [ld(self.xn.as_ptr().add(i0)); 8]
            };
            let [vgx, vgy, agx, agy] = halves_to_lanes::<true>(&out);
            let v = [ld(self.vx.as_ptr().add(i0)), ld(self.vy.as_ptr().add(i0))];
            let x = [ld(self.x.as_ptr().add(i0)), ld(self.y.as_ptr().add(i0))];
            let (vn, xn) = Self::flip::<F>(p, [vgx, vgy], [agx, agy], v, x);
            if self.opts.checks {
                let sum = add(add(vn[0], xn[0]), add(vn[1], xn[1]));
                let fin = _mm256_cmp_ps::<_CMP_EQ_OQ>(sub(sum, sum), _mm256_setzero_ps());
                bad |= (_mm256_movemask_ps(fin) ^ 0xff) as u32;
                let stat = _mm256_loadu_si256(self.status.as_ptr().add(i0) as *const __m256i);
                bad |= (_mm256_testz_si256(stat, stat) == 0) as u32;
            }
            st(self.vx.as_mut_ptr().add(i0), vn[0]);
            st(self.vy.as_mut_ptr().add(i0), vn[1]);
            st(self.xn.as_mut_ptr().add(i0), xn[0]);
            st(self.yn.as_mut_ptr().add(i0), xn[1]);
            v2max = _mm256_max_ps(v2max, fma::<F>(vn[0], vn[0], mul(vn[1], vn[1])));
            let m = ld(self.m.as_ptr().add(i0));
            let pmx = mul(m, vn[0]);
            let pmy = mul(m, vn[1]);
            // (pmx, pmy) pairs: lo = particles 0,1 | 4,5; hi = 2,3 | 6,7.
            let mut pairs = [0.0f32; 16];
            st(pairs.as_mut_ptr(), _mm256_unpacklo_ps(pmx, pmy));
            st(pairs.as_mut_ptr().add(8), _mm256_unpackhi_ps(pmx, pmy));
            const OFF: [usize; 8] = [0, 2, 8, 10, 4, 6, 12, 14];
            let bases = blk as *const u32;
            let zero = _mm256_setzero_ps();
            let mut acc = [zero; 9];
            let mut cur = *bases;
            if self.opts.skip & 16 != 0 {
                continue;
            }
            for t in 0..8 {
                let b = *bases.add(t);
                if B {
                    if b != cur {
                        flush9(g, cur, &acc);
                        acc = [zero; 9];
                        cur = b;
                    }
                } else {
                    acc = [zero; 9];
                }
                let pv = _mm256_castpd_ps(_mm256_broadcast_sd(
                    &*(pairs.as_ptr().add(OFF[t]) as *const f64),
                ));
                let pv = _mm256_and_ps(pv, lanes23);
                for j in 0..3 {
                    let e = mul(bc(blk.add(OWY + 8 * j + t)), pv);
                    for i in 0..3 {
                        acc[3 * j + i] = fma::<F>(bc(blk.add(OWX + 8 * i + t)), e, acc[3 * j + i]);
                    }
                }
                if !B {
                    flush9(g, b, &acc);
                }
            }
            if B {
                flush9(g, cur, &acc);
            }
        }
        let mut v = [0.0f32; 8];
        st(v.as_mut_ptr(), v2max);
        self.v2max = v.iter().fold(0.0, |a, &b| a.max(b));
        self.bad += bad as usize;
    }

    /// H, J and tau/rho0 of a chunk from its velocity gradient; stores them.
    #[inline(always)]
    unsafe fn update_stress<const F: bool>(
        &mut self,
        p: &Params,
        i0: usize,
        l: [[__m256; 2]; 2],
    ) -> u32 {
        let dt = s1(p.dt);
        let half = s1(0.5);
        let a = [
            [mul(l[0][0], dt), mul(l[0][1], dt)],
            [mul(l[1][0], dt), mul(l[1][1], dt)],
        ];
        let q2 = [
            [mul(a[0][0], half), mul(a[0][1], half)],
            [mul(a[1][0], half), mul(a[1][1], half)],
        ];
        let mut q = a;
        for r in 0..2 {
            for c in 0..2 {
                q[r][c] = fma::<F>(a[r][1], q2[1][c], fma::<F>(a[r][0], q2[0][c], a[r][c]));
            }
        }
        let ho = [
            [ld(self.h00.as_ptr().add(i0)), ld(self.h01.as_ptr().add(i0))],
            [ld(self.h10.as_ptr().add(i0)), ld(self.h11.as_ptr().add(i0))],
        ];
        let mut h = ho;
        for r in 0..2 {
            for c in 0..2 {
                h[r][c] = add(
                    fma::<F>(q[r][1], ho[1][c], fma::<F>(q[r][0], ho[0][c], ho[r][c])),
                    q[r][c],
                );
            }
        }
        let det = if F {
            _mm256_fmsub_ps(h[0][0], h[1][1], mul(h[0][1], h[1][0]))
        } else {
            sub(mul(h[0][0], h[1][1]), mul(h[0][1], h[1][0]))
        };
        let jm1 = add(add(h[0][0], h[1][1]), det);
        let lnj = ln_1p_lanes::<F>(_mm256_max_ps(jm1, s1(-1.0 + f32::EPSILON)));
        let mu = s1(p.mu);
        let lam = s1(p.lambda);
        let ir = s1(p.inv_rho0);
        let hh = |r: usize, c: usize| fma::<F>(h[r][1], h[c][1], mul(h[r][0], h[c][0]));
        let txx = mul(
            fma::<F>(mu, add(add(h[0][0], h[0][0]), hh(0, 0)), mul(lam, lnj)),
            ir,
        );
        let tyy = mul(
            fma::<F>(mu, add(add(h[1][1], h[1][1]), hh(1, 1)), mul(lam, lnj)),
            ir,
        );
        let txy = mul(mul(mu, add(add(h[0][1], h[1][0]), hh(0, 1))), ir);
        let tzz = mul(mul(lam, lnj), ir);
        let mut bad = 0u32;
        if self.opts.checks {
            let mut sum = add(add(jm1, txx), add(tyy, txy));
            sum = add(sum, add(add(h[0][0], h[0][1]), add(h[1][0], h[1][1])));
            sum = add(sum, tzz);
            let fin = _mm256_cmp_ps::<_CMP_EQ_OQ>(sub(sum, sum), _mm256_setzero_ps());
            let inv = _mm256_cmp_ps::<_CMP_GT_OQ>(jm1, s1(-1.0));
            bad = (_mm256_movemask_ps(_mm256_and_ps(fin, inv)) ^ 0xff) as u32;
        }
        st(self.h00.as_mut_ptr().add(i0), h[0][0]);
        st(self.h01.as_mut_ptr().add(i0), h[0][1]);
        st(self.h10.as_mut_ptr().add(i0), h[1][0]);
        st(self.h11.as_mut_ptr().add(i0), h[1][1]);
        st(self.txx.as_mut_ptr().add(i0), txx);
        st(self.tyy.as_mut_ptr().add(i0), tyy);
        st(self.txy.as_mut_ptr().add(i0), txy);
        st(self.tzz.as_mut_ptr().add(i0), tzz);
        bad
    }

    #[inline(never)]
    unsafe fn stress<const F: bool, const S: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_ptr().cast::<f32>();
        let mut local = Block([0.0; SW]);
        let mut moved = 0u32;
        let mut bad = 0u32;
        let skip = self.opts.skip;
        for c in 0..self.n / 8 {
            let i0 = 8 * c;
            let blk = self.block::<S>(p, c, false, &mut local);
            let bases = blk as *const u32;
            let mut o = [_mm256_setzero_ps(); 8];
            let mut cur = *bases;
            let mut r = load9(g, cur);
            if skip & 1 == 0 {
                for t in 0..8 {
                    let b = *bases.add(t);
                    if !B || b != cur {
                        r = load9(g, b);
                        cur = b;
                    }
                    let wx = [
                        bc(blk.add(OWX + t)),
                        bc(blk.add(OWX + 8 + t)),
                        bc(blk.add(OWX + 16 + t)),
                    ];
                    let dwx = [
                        bc(blk.add(ODWX + t)),
                        bc(blk.add(ODWX + 8 + t)),
                        bc(blk.add(ODWX + 16 + t)),
                    ];
                    let mut rw = [_mm256_setzero_ps(); 3];
                    let mut rd = [_mm256_setzero_ps(); 3];
                    for j in 0..3 {
                        rw[j] = fma::<F>(
                            wx[2],
                            r[3 * j + 2],
                            fma::<F>(wx[1], r[3 * j + 1], mul(wx[0], r[3 * j])),
                        );
                        rd[j] = fma::<F>(
                            dwx[2],
                            r[3 * j + 2],
                            fma::<F>(dwx[1], r[3 * j + 1], mul(dwx[0], r[3 * j])),
                        );
                    }
                    let wy = [
                        bc(blk.add(OWY + t)),
                        bc(blk.add(OWY + 8 + t)),
                        bc(blk.add(OWY + 16 + t)),
                    ];
                    let dwy = [
                        bc(blk.add(ODWY + t)),
                        bc(blk.add(ODWY + 8 + t)),
                        bc(blk.add(ODWY + 16 + t)),
                    ];
                    let gx = fma::<F>(wy[2], rd[2], fma::<F>(wy[1], rd[1], mul(wy[0], rd[0])));
                    let gy = fma::<F>(dwy[2], rw[2], fma::<F>(dwy[1], rw[1], mul(dwy[0], rw[0])));
                    // lanes 0,1 <- gy lanes 2,3 (l01, l11); lanes 2,3 = gx (l00, l10).
                    o[t] = _mm256_blend_ps::<0b0000_0011>(gx, _mm256_permute_ps::<0x4E>(gy));
                }
            }
            let [l01, l11, l00, l10] = halves_to_lanes::<false>(&o);
            if skip & 2 == 0 {
                bad |= self.update_stress::<F>(p, i0, [[l00, l01], [l10, l11]]);
            }
            // x = x_next, and the bin check.
            let xn = ld(self.xn.as_ptr().add(i0));
            let yn = ld(self.yn.as_ptr().add(i0));
            st(self.x.as_mut_ptr().add(i0), xn);
            st(self.y.as_mut_ptr().add(i0), yn);
            let nb = bin_bases(p, xn, yn);
            let ob = _mm256_loadu_si256(blk as *const __m256i);
            let same = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nb, ob)));
            moved += (same ^ 0xff).count_ones();
        }
        self.moved = moved as usize;
        self.bad += bad as usize;
    }

    /// USL particle pass: v_gp, a_gp and the gradient of v + a dt in one gather, FLIP, stress,
    /// x update.
    #[inline(always)]
    unsafe fn particles_usl<const F: bool, const S: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_ptr().cast::<f32>();
        let mut local = Block([0.0; SW]);
        let mut v2max = _mm256_setzero_ps();
        let mut moved = 0u32;
        let mut bad = 0u32;
        let dt = s1(p.dt);
        for c in 0..self.n / 8 {
            let i0 = 8 * c;
            let blk = self.block::<S>(p, c, false, &mut local);
            let bases = blk as *const u32;
            let mut ov = [_mm256_setzero_ps(); 8];
            let mut ogx = [_mm256_setzero_ps(); 8];
            let mut ogy = [_mm256_setzero_ps(); 8];
            let mut cur = *bases;
            let mut r = load9(g, cur);
            for t in 0..8 {
                let b = *bases.add(t);
                if !B || b != cur {
                    r = load9(g, b);
                    cur = b;
                }
                let wx = [
                    bc(blk.add(OWX + t)),
                    bc(blk.add(OWX + 8 + t)),
                    bc(blk.add(OWX + 16 + t)),
                ];
                let dwx = [
                    bc(blk.add(ODWX + t)),
                    bc(blk.add(ODWX + 8 + t)),
                    bc(blk.add(ODWX + 16 + t)),
                ];
                let mut rw = [_mm256_setzero_ps(); 3];
                let mut rd = [_mm256_setzero_ps(); 3];
                for j in 0..3 {
                    rw[j] = fma::<F>(
                        wx[2],
                        r[3 * j + 2],
                        fma::<F>(wx[1], r[3 * j + 1], mul(wx[0], r[3 * j])),
                    );
                    rd[j] = fma::<F>(
                        dwx[2],
                        r[3 * j + 2],
                        fma::<F>(dwx[1], r[3 * j + 1], mul(dwx[0], r[3 * j])),
                    );
                }
                let wy = [
                    bc(blk.add(OWY + t)),
                    bc(blk.add(OWY + 8 + t)),
                    bc(blk.add(OWY + 16 + t)),
                ];
                let dwy = [
                    bc(blk.add(ODWY + t)),
                    bc(blk.add(ODWY + 8 + t)),
                    bc(blk.add(ODWY + 16 + t)),
                ];
                ov[t] = fma::<F>(wy[2], rw[2], fma::<F>(wy[1], rw[1], mul(wy[0], rw[0])));
                ogx[t] = fma::<F>(wy[2], rd[2], fma::<F>(wy[1], rd[1], mul(wy[0], rd[0])));
                ogy[t] = fma::<F>(dwy[2], rw[2], fma::<F>(dwy[1], rw[1], mul(dwy[0], rw[0])));
            }
            let [vgx, vgy, agx, agy] = halves_to_lanes::<true>(&ov);
            let [xvx, xvy, xax, xay] = halves_to_lanes::<true>(&ogx);
            let [yvx, yvy, yax, yay] = halves_to_lanes::<true>(&ogy);
            // grad (v + a dt).
            let l = [
                [fma::<F>(xax, dt, xvx), fma::<F>(yax, dt, yvx)],
                [fma::<F>(xay, dt, xvy), fma::<F>(yay, dt, yvy)],
            ];
            let v = [ld(self.vx.as_ptr().add(i0)), ld(self.vy.as_ptr().add(i0))];
            let x = [ld(self.x.as_ptr().add(i0)), ld(self.y.as_ptr().add(i0))];
            let (vn, xn) = Self::flip::<F>(p, [vgx, vgy], [agx, agy], v, x);
            bad |= self.update_stress::<F>(p, i0, l);
            if self.opts.checks {
                let sum = add(add(vn[0], xn[0]), add(vn[1], xn[1]));
                let fin = _mm256_cmp_ps::<_CMP_EQ_OQ>(sub(sum, sum), _mm256_setzero_ps());
                bad |= (_mm256_movemask_ps(fin) ^ 0xff) as u32;
            }
            st(self.vx.as_mut_ptr().add(i0), vn[0]);
            st(self.vy.as_mut_ptr().add(i0), vn[1]);
            st(self.x.as_mut_ptr().add(i0), xn[0]);
            st(self.y.as_mut_ptr().add(i0), xn[1]);
            v2max = _mm256_max_ps(v2max, fma::<F>(vn[0], vn[0], mul(vn[1], vn[1])));
            let nb = bin_bases(p, xn[0], xn[1]);
            let ob = _mm256_loadu_si256(blk as *const __m256i);
            let same = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nb, ob)));
            moved += (same ^ 0xff).count_ones();
        }
        let mut v = [0.0f32; 8];
        st(v.as_mut_ptr(), v2max);
        self.v2max = v.iter().fold(0.0, |a, &b| a.max(b));
        self.moved = moved as usize;
        self.bad += bad as usize;
    }
}

/// The kernel's ln_1p_fast on 8 lanes.
#[inline(always)]
unsafe fn ln_1p_lanes<const F: bool>(x: __m256) -> __m256 {
    let one = s1(1.0);
    let u = add(one, x);
    let bits = _mm256_castps_si256(u);
    let e = _mm256_sub_epi32(
        _mm256_and_si256(_mm256_srli_epi32::<23>(bits), _mm256_set1_epi32(0xff)),
        _mm256_set1_epi32(127),
    );
    let mb = _mm256_or_si256(
        _mm256_and_si256(bits, _mm256_set1_epi32(0x007f_ffff)),
        _mm256_set1_epi32(0x3f80_0000),
    );
    let m = _mm256_castsi256_ps(mb);
    let big = _mm256_cmp_ps::<_CMP_GT_OQ>(m, s1(core::f32::consts::SQRT_2));
    let m = sel(big, mul(m, s1(0.5)), m);
    let e = _mm256_sub_epi32(e, _mm256_castps_si256(big));
    let ef = _mm256_cvtepi32_ps(e);
    let t = _mm256_div_ps(sub(m, one), add(m, one));
    let t2 = mul(t, t);
    let series = fma::<F>(
        t2,
        fma::<F>(
            t2,
            fma::<F>(
                t2,
                fma::<F>(t2, s1(1.0 / 9.0), s1(1.0 / 7.0)),
                s1(1.0 / 5.0),
            ),
            s1(1.0 / 3.0),
        ),
        one,
    );
    let ln_u = fma::<F>(
        ef,
        s1(core::f64::consts::LN_2 as f32),
        mul(add(t, t), series),
    );
    let exact = _mm256_cmp_ps::<_CMP_EQ_OQ>(u, one);
    let denom = sel(exact, one, sub(u, one));
    sel(exact, x, _mm256_div_ps(mul(ln_u, x), denom))
}

const BLK: usize = 64;

#[repr(C, align(32))]
struct Buf<const N: usize>([f32; N]);

impl Fast {
    #[inline(never)]
    unsafe fn scatter2<const F: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_mut_ptr().cast::<f32>();
        let stp = self.st.as_mut_ptr().cast::<f32>();
        let m0 = mask([true, false, false, false, true, true, false, false]);
        let m1 = mask([false, false, false, false, false, false, true, true]);
        let idx = _mm256_setr_epi32(2, 2, 2, 2, 2, 2, 7, 1);
        let neg = s1(-0.0);
        let zero = _mm256_setzero_ps();
        let mut qbuf = Buf::<{ 8 * BLK }>([0.0; 8 * BLK]);
        let n = self.n;
        let skip_nodes = self.opts.skip & 4 != 0;
        let split = self.opts.split;
        for b0 in (0..n).step_by(BLK) {
            let nb = BLK.min(n - b0);
            for c in 0..nb / 8 {
                let i0 = b0 + 8 * c;
                let blk = stp.add((i0 / 8) * SW);
                stencil_chunk(p, self.x.as_ptr().add(i0), self.y.as_ptr().add(i0), blk);
                let m = ld(self.m.as_ptr().add(i0));
                let nm = _mm256_xor_ps(m, neg);
                let q = if split {
                    let mtxy = mul(nm, ld(self.txy.as_ptr().add(i0)));
                    transpose8([
                        m,
                        mul(m, ld(self.vx.as_ptr().add(i0))),
                        mul(m, ld(self.vy.as_ptr().add(i0))),
                        mul(nm, ld(self.txx.as_ptr().add(i0))),
                        mtxy,
                        mtxy,
                        mul(nm, ld(self.tyy.as_ptr().add(i0))),
                        zero,
                    ])
                } else {
                    transpose8([
                        m,
                        mul(nm, ld(self.tyy.as_ptr().add(i0))),
                        zero,
                        zero,
                        mul(m, ld(self.vx.as_ptr().add(i0))),
                        mul(m, ld(self.vy.as_ptr().add(i0))),
                        mul(nm, ld(self.txx.as_ptr().add(i0))),
                        mul(nm, ld(self.txy.as_ptr().add(i0))),
                    ])
                };
                for t in 0..8 {
                    _mm256_store_ps(qbuf.0.as_mut_ptr().add(8 * (8 * c + t)), q[t]);
                }
            }
            if skip_nodes {
                continue;
            }
            let mut acc = [zero; 9];
            let mut cur = *(stp.add((b0 / 8) * SW) as *const u32);
            for t in 0..nb {
                let blk = stp.add(((b0 + t) / 8) * SW) as *const f32;
                let l = t % 8;
                let b = *(blk as *const u32).add(l);
                if B {
                    if b != cur {
                        flush9(g, cur, &acc);
                        acc = [zero; 9];
                        cur = b;
                    }
                } else {
                    acc = [zero; 9];
                }
                let q = _mm256_load_ps(qbuf.0.as_ptr().add(8 * t));
                if split {
                    let xw: [__m256; 3] = core::array::from_fn(|i| {
                        _mm256_blend_ps::<0b0001_1000>(
                            bc(blk.add(OWX + 8 * i + l)),
                            bc(blk.add(ODWX + 8 * i + l)),
                        )
                    });
                    for j in 0..3 {
                        let yw = _mm256_blend_ps::<0b0110_0000>(
                            bc(blk.add(OWY + 8 * j + l)),
                            bc(blk.add(ODWY + 8 * j + l)),
                        );
                        let u = mul(yw, q);
                        for i in 0..3 {
                            acc[3 * j + i] = fma::<F>(xw[i], u, acc[3 * j + i]);
                        }
                    }
                    if !B {
                        flush9(g, b, &acc);
                    }
                    continue;
                }
                let p0 = _mm256_and_ps(q, m0);
                let p1 = _mm256_and_ps(q, m1);
                let p2 = _mm256_permutevar8x32_ps(q, idx);
                let wx = [
                    bc(blk.add(OWX + l)),
                    bc(blk.add(OWX + 8 + l)),
                    bc(blk.add(OWX + 16 + l)),
                ];
                let dwx = [
                    bc(blk.add(ODWX + l)),
                    bc(blk.add(ODWX + 8 + l)),
                    bc(blk.add(ODWX + 16 + l)),
                ];
                for j in 0..3 {
                    let wy = bc(blk.add(OWY + 8 * j + l));
                    let dwy = bc(blk.add(ODWY + 8 * j + l));
                    let d = fma::<F>(dwy, p2, mul(wy, p0));
                    let e = mul(wy, p1);
                    for i in 0..3 {
                        let a = fma::<F>(wx[i], d, acc[3 * j + i]);
                        acc[3 * j + i] = fma::<F>(dwx[i], e, a);
                    }
                }
                if !B {
                    flush9(g, b, &acc);
                }
            }
            if B {
                flush9(g, cur, &acc);
            }
        }
    }

    #[inline(never)]
    unsafe fn particles2<const F: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_mut_ptr().cast::<f32>();
        let stp = self.st.as_mut_ptr().cast::<f32>();
        let lanes23 = mask([false, false, true, true, false, false, false, false]);
        let zero = _mm256_setzero_ps();
        let mut v2max = zero;
        let mut bad = 0u32;
        let mut gbuf = Buf::<{ 4 * BLK }>([0.0; 4 * BLK]);
        let mut pbuf = Buf::<{ 2 * BLK }>([0.0; 2 * BLK]);
        let n = self.n;
        let skip = self.opts.skip;
        for b0 in (0..n).step_by(BLK) {
            let nb = BLK.min(n - b0);
            // Gathers.
            for c in 0..nb / 8 {
                let blk = stp.add(((b0 + 8 * c) / 8) * SW);
                let out = if skip & 8 == 0 {
                    if self.opts.gcache {
                        Self::gather_va::<F, B, true>(g, blk)
                    } else {
                        Self::gather_va::<F, B, false>(g, blk)
                    }
                } else {
                    [ld(self.xn.as_ptr().add(b0)); 8]
                };
                let r = halves_to_lanes::<true>(&out);
                for k in 0..4 {
                    _mm256_store_ps(gbuf.0.as_mut_ptr().add(k * BLK + 8 * c), r[k]);
                }
            }
            // FLIP.
            for c in 0..nb / 8 {
                let i0 = b0 + 8 * c;
                let gl = |k: usize| _mm256_load_ps(gbuf.0.as_ptr().add(k * BLK + 8 * c));
                let v = [ld(self.vx.as_ptr().add(i0)), ld(self.vy.as_ptr().add(i0))];
                let x = [ld(self.x.as_ptr().add(i0)), ld(self.y.as_ptr().add(i0))];
                let (vn, xn) = Self::flip::<F>(p, [gl(0), gl(1)], [gl(2), gl(3)], v, x);
                if self.opts.checks {
                    let sum = add(add(vn[0], xn[0]), add(vn[1], xn[1]));
                    let fin = _mm256_cmp_ps::<_CMP_EQ_OQ>(sub(sum, sum), zero);
                    bad |= (_mm256_movemask_ps(fin) ^ 0xff) as u32;
                    let stat = _mm256_loadu_si256(self.status.as_ptr().add(i0) as *const __m256i);
                    bad |= (_mm256_testz_si256(stat, stat) == 0) as u32;
                }
                st(self.vx.as_mut_ptr().add(i0), vn[0]);
                st(self.vy.as_mut_ptr().add(i0), vn[1]);
                st(self.xn.as_mut_ptr().add(i0), xn[0]);
                st(self.yn.as_mut_ptr().add(i0), xn[1]);
                v2max = _mm256_max_ps(v2max, fma::<F>(vn[0], vn[0], mul(vn[1], vn[1])));
                let m = ld(self.m.as_ptr().add(i0));
                let pmx = mul(m, vn[0]);
                let pmy = mul(m, vn[1]);
                let lo = _mm256_unpacklo_ps(pmx, pmy);
                let hi = _mm256_unpackhi_ps(pmx, pmy);
                _mm256_store_ps(
                    pbuf.0.as_mut_ptr().add(16 * c),
                    _mm256_permute2f128_ps::<0x20>(lo, hi),
                );
                _mm256_store_ps(
                    pbuf.0.as_mut_ptr().add(16 * c + 8),
                    _mm256_permute2f128_ps::<0x31>(lo, hi),
                );
            }
            if skip & 16 != 0 {
                continue;
            }
            // Re-map scatter.
            let mut acc = [zero; 9];
            let mut cur = *(stp.add((b0 / 8) * SW) as *const u32);
            for t in 0..nb {
                let blk = stp.add(((b0 + t) / 8) * SW) as *const f32;
                let l = t % 8;
                let b = *(blk as *const u32).add(l);
                if B {
                    if b != cur {
                        flush9(g, cur, &acc);
                        acc = [zero; 9];
                        cur = b;
                    }
                } else {
                    acc = [zero; 9];
                }
                let pv = _mm256_castpd_ps(_mm256_broadcast_sd(
                    &*(pbuf.0.as_ptr().add(2 * t) as *const f64),
                ));
                let pv = _mm256_and_ps(pv, lanes23);
                for j in 0..3 {
                    let e = mul(bc(blk.add(OWY + 8 * j + l)), pv);
                    for i in 0..3 {
                        acc[3 * j + i] = fma::<F>(bc(blk.add(OWX + 8 * i + l)), e, acc[3 * j + i]);
                    }
                }
                if !B {
                    flush9(g, b, &acc);
                }
            }
            if B {
                flush9(g, cur, &acc);
            }
        }
        let mut v = [0.0f32; 8];
        st(v.as_mut_ptr(), v2max);
        self.v2max = v.iter().fold(0.0, |a, &b| a.max(b));
        self.bad += bad as usize;
    }

    #[inline(never)]
    unsafe fn stress2<const F: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_ptr().cast::<f32>();
        let stp = self.st.as_mut_ptr().cast::<f32>();
        let mut moved = 0u32;
        let mut bad = 0u32;
        let mut lbuf = Buf::<{ 4 * BLK }>([0.0; 4 * BLK]);
        let n = self.n;
        let skip = self.opts.skip;
        for b0 in (0..n).step_by(BLK) {
            let nb = BLK.min(n - b0);
            for c in 0..nb / 8 {
                let blk = stp.add(((b0 + 8 * c) / 8) * SW) as *const f32;
                let bases = blk as *const u32;
                let mut o = [_mm256_setzero_ps(); 8];
                let mut cur = *bases;
                let mut r = load9(g, cur);
                if skip & 1 == 0 && !self.opts.compact {
                    for t in 0..8 {
                        let b = *bases.add(t);
                        if !B || b != cur {
                            r = load9(g, b);
                            cur = b;
                        }
                        let wx = [
                            bc(blk.add(OWX + t)),
                            bc(blk.add(OWX + 8 + t)),
                            bc(blk.add(OWX + 16 + t)),
                        ];
                        let dwx = [
                            bc(blk.add(ODWX + t)),
                            bc(blk.add(ODWX + 8 + t)),
                            bc(blk.add(ODWX + 16 + t)),
                        ];
                        let mut rw = [_mm256_setzero_ps(); 3];
                        let mut rd = [_mm256_setzero_ps(); 3];
                        for j in 0..3 {
                            rw[j] = fma::<F>(
                                wx[2],
                                r[3 * j + 2],
                                fma::<F>(wx[1], r[3 * j + 1], mul(wx[0], r[3 * j])),
                            );
                            rd[j] = fma::<F>(
                                dwx[2],
                                r[3 * j + 2],
                                fma::<F>(dwx[1], r[3 * j + 1], mul(dwx[0], r[3 * j])),
                            );
                        }
                        let wy = [
                            bc(blk.add(OWY + t)),
                            bc(blk.add(OWY + 8 + t)),
                            bc(blk.add(OWY + 16 + t)),
                        ];
                        let dwy = [
                            bc(blk.add(ODWY + t)),
                            bc(blk.add(ODWY + 8 + t)),
                            bc(blk.add(ODWY + 16 + t)),
                        ];
                        let gx = fma::<F>(wy[2], rd[2], fma::<F>(wy[1], rd[1], mul(wy[0], rd[0])));
                        let gy =
                            fma::<F>(dwy[2], rw[2], fma::<F>(dwy[1], rw[1], mul(dwy[0], rw[0])));
                        o[t] = _mm256_blend_ps::<0b0000_0011>(gx, _mm256_permute_ps::<0x4E>(gy));
                    }
                }
                let r = if self.opts.compact {
                    let [l00, l01, l10, l11] = Self::gather_compact::<F>(self.vr.as_ptr(), blk);
                    [l01, l11, l00, l10]
                } else {
                    halves_to_lanes::<false>(&o)
                };
                for k in 0..4 {
                    _mm256_store_ps(lbuf.0.as_mut_ptr().add(k * BLK + 8 * c), r[k]);
                }
            }
            for c in 0..nb / 8 {
                let i0 = b0 + 8 * c;
                let blk = stp.add((i0 / 8) * SW) as *const f32;
                let gl = |k: usize| _mm256_load_ps(lbuf.0.as_ptr().add(k * BLK + 8 * c));
                // lbuf rows: l01, l11, l00, l10.
                if skip & 2 == 0 {
                    bad |= self.update_stress::<F>(p, i0, [[gl(2), gl(0)], [gl(3), gl(1)]]);
                }
                let xn = ld(self.xn.as_ptr().add(i0));
                let yn = ld(self.yn.as_ptr().add(i0));
                st(self.x.as_mut_ptr().add(i0), xn);
                st(self.y.as_mut_ptr().add(i0), yn);
                let nbs = bin_bases(p, xn, yn);
                let ob = _mm256_loadu_si256(blk as *const __m256i);
                let same = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nbs, ob)));
                moved += (same ^ 0xff).count_ones();
            }
        }
        self.moved = moved as usize;
        self.bad += bad as usize;
    }
}

impl Fast {
    /// Velocity gradient of a chunk from the compact v' array: per particle, 3 rows of 4 nodes
    /// (one 256-bit load each) weighted by lane vectors of the x weights. Returns l00, l01, l10,
    /// l11 as lane vectors.
    #[inline(always)]
    unsafe fn gather_compact<const F: bool>(vr: *const f32, blk: *const f32) -> [__m256; 4] {
        let z = _mm256_setzero_ps();
        let wp = transpose8([
            _mm256_load_ps(blk.add(OWX)),
            _mm256_load_ps(blk.add(OWX + 8)),
            _mm256_load_ps(blk.add(OWX + 16)),
            z,
            _mm256_load_ps(blk.add(ODWX)),
            _mm256_load_ps(blk.add(ODWX + 8)),
            _mm256_load_ps(blk.add(ODWX + 16)),
            z,
        ]);
        let iw = _mm256_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3);
        let idw = _mm256_setr_epi32(4, 4, 5, 5, 6, 6, 7, 7);
        let bases = blk as *const u32;
        let mut d = [z; 8];
        for t in 0..8 {
            let b = *bases.add(t) as usize;
            let wx = _mm256_permutevar8x32_ps(wp[t], iw);
            let dwx = _mm256_permutevar8x32_ps(wp[t], idw);
            let row = |j: usize| _mm256_loadu_ps(vr.add(2 * (b + NX * j)));
            let (t0, t1, t2) = (row(0), row(1), row(2));
            let wy = [
                bc(blk.add(OWY + t)),
                bc(blk.add(OWY + 8 + t)),
                bc(blk.add(OWY + 16 + t)),
            ];
            let dwy = [
                bc(blk.add(ODWY + t)),
                bc(blk.add(ODWY + 8 + t)),
                bc(blk.add(ODWY + 16 + t)),
            ];
            let rw = fma::<F>(wy[2], t2, fma::<F>(wy[1], t1, mul(wy[0], t0)));
            let rd = fma::<F>(dwy[2], t2, fma::<F>(dwy[1], t1, mul(dwy[0], t0)));
            let a = mul(dwx, rw);
            let bv = mul(wx, rd);
            let c = add(
                _mm256_permute2f128_ps::<0x20>(a, bv),
                _mm256_permute2f128_ps::<0x31>(a, bv),
            );
            d[t] = add(c, _mm256_permute_ps::<0x4E>(c));
        }
        let e: [__m256; 4] = core::array::from_fn(|k| {
            _mm256_castpd_ps(_mm256_unpacklo_pd(
                _mm256_castps_pd(d[2 * k]),
                _mm256_castps_pd(d[2 * k + 1]),
            ))
        });
        let x0 = _mm256_shuffle_ps::<0x88>(e[0], e[1]);
        let y0 = _mm256_shuffle_ps::<0xDD>(e[0], e[1]);
        let x1 = _mm256_shuffle_ps::<0x88>(e[2], e[3]);
        let y1 = _mm256_shuffle_ps::<0xDD>(e[2], e[3]);
        [
            _mm256_permute2f128_ps::<0x20>(x0, x1),
            _mm256_permute2f128_ps::<0x31>(x0, x1),
            _mm256_permute2f128_ps::<0x20>(y0, y1),
            _mm256_permute2f128_ps::<0x31>(y0, y1),
        ]
    }
}

impl Fast {
    /// USL particle pass with loop fission: the gathers (v_gp, a_gp and the gradient of
    /// v + a dt) of a block, then FLIP and the stress update as lane loops.
    #[inline(always)]
    unsafe fn particles_usl2<const F: bool, const B: bool>(&mut self, p: &Params) {
        let g = self.grid.as_ptr().cast::<f32>();
        let stp = self.st.as_mut_ptr().cast::<f32>();
        let zero = _mm256_setzero_ps();
        let mut v2max = zero;
        let mut moved = 0u32;
        let mut bad = 0u32;
        let dt = s1(p.dt);
        let mut gbuf = Buf::<{ 8 * BLK }>([0.0; 8 * BLK]);
        let n = self.n;
        for b0 in (0..n).step_by(BLK) {
            let nb = BLK.min(n - b0);
            for c in 0..nb / 8 {
                let blk = stp.add(((b0 + 8 * c) / 8) * SW) as *const f32;
                let bases = blk as *const u32;
                let mut ov = [zero; 8];
                let mut ogx = [zero; 8];
                let mut ogy = [zero; 8];
                let mut cur = *bases;
                let mut r = load9(g, cur);
                for t in 0..8 {
                    let b = *bases.add(t);
                    if !B || b != cur {
                        r = load9(g, b);
                        cur = b;
                    }
                    let wx = [
                        bc(blk.add(OWX + t)),
                        bc(blk.add(OWX + 8 + t)),
                        bc(blk.add(OWX + 16 + t)),
                    ];
                    let dwx = [
                        bc(blk.add(ODWX + t)),
                        bc(blk.add(ODWX + 8 + t)),
                        bc(blk.add(ODWX + 16 + t)),
                    ];
                    let mut rw = [zero; 3];
                    let mut rd = [zero; 3];
                    for j in 0..3 {
                        rw[j] = fma::<F>(
                            wx[2],
                            r[3 * j + 2],
                            fma::<F>(wx[1], r[3 * j + 1], mul(wx[0], r[3 * j])),
                        );
                        rd[j] = fma::<F>(
                            dwx[2],
                            r[3 * j + 2],
                            fma::<F>(dwx[1], r[3 * j + 1], mul(dwx[0], r[3 * j])),
                        );
                    }
                    let wy = [
                        bc(blk.add(OWY + t)),
                        bc(blk.add(OWY + 8 + t)),
                        bc(blk.add(OWY + 16 + t)),
                    ];
                    let dwy = [
                        bc(blk.add(ODWY + t)),
                        bc(blk.add(ODWY + 8 + t)),
                        bc(blk.add(ODWY + 16 + t)),
                    ];
                    ov[t] = fma::<F>(wy[2], rw[2], fma::<F>(wy[1], rw[1], mul(wy[0], rw[0])));
                    ogx[t] = fma::<F>(wy[2], rd[2], fma::<F>(wy[1], rd[1], mul(wy[0], rd[0])));
                    ogy[t] = fma::<F>(dwy[2], rw[2], fma::<F>(dwy[1], rw[1], mul(dwy[0], rw[0])));
                }
                let [vgx, vgy, agx, agy] = halves_to_lanes::<true>(&ov);
                let [xvx, xvy, xax, xay] = halves_to_lanes::<true>(&ogx);
                let [yvx, yvy, yax, yay] = halves_to_lanes::<true>(&ogy);
                let vals = [
                    vgx,
                    vgy,
                    agx,
                    agy,
                    fma::<F>(xax, dt, xvx),
                    fma::<F>(yax, dt, yvx),
                    fma::<F>(xay, dt, xvy),
                    fma::<F>(yay, dt, yvy),
                ];
                for k in 0..8 {
                    _mm256_store_ps(gbuf.0.as_mut_ptr().add(k * BLK + 8 * c), vals[k]);
                }
            }
            for c in 0..nb / 8 {
                let i0 = b0 + 8 * c;
                let blk = stp.add((i0 / 8) * SW) as *const f32;
                let gl = |k: usize| _mm256_load_ps(gbuf.0.as_ptr().add(k * BLK + 8 * c));
                let v = [ld(self.vx.as_ptr().add(i0)), ld(self.vy.as_ptr().add(i0))];
                let x = [ld(self.x.as_ptr().add(i0)), ld(self.y.as_ptr().add(i0))];
                let (vn, xn) = Self::flip::<F>(p, [gl(0), gl(1)], [gl(2), gl(3)], v, x);
                bad |= self.update_stress::<F>(p, i0, [[gl(4), gl(5)], [gl(6), gl(7)]]);
                if self.opts.checks {
                    let sum = add(add(vn[0], xn[0]), add(vn[1], xn[1]));
                    let fin = _mm256_cmp_ps::<_CMP_EQ_OQ>(sub(sum, sum), zero);
                    bad |= (_mm256_movemask_ps(fin) ^ 0xff) as u32;
                }
                st(self.vx.as_mut_ptr().add(i0), vn[0]);
                st(self.vy.as_mut_ptr().add(i0), vn[1]);
                st(self.x.as_mut_ptr().add(i0), xn[0]);
                st(self.y.as_mut_ptr().add(i0), xn[1]);
                v2max = _mm256_max_ps(v2max, fma::<F>(vn[0], vn[0], mul(vn[1], vn[1])));
                let nbs = bin_bases(p, xn[0], xn[1]);
                let ob = _mm256_loadu_si256(blk as *const __m256i);
                let same = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nbs, ob)));
                moved += (same ^ 0xff).count_ones();
            }
        }
        let mut v = [0.0f32; 8];
        st(v.as_mut_ptr(), v2max);
        self.v2max = v.iter().fold(0.0, |a, &b| a.max(b));
        self.moved = moved as usize;
        self.bad += bad as usize;
    }
}
