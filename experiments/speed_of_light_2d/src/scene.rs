//! The step_cost 2D scene, replicated: 260 x 132 cells of 0.01 m, origin 0, slip walls, uGIMP
//! (l = 1/4 cell), a 256 x 128 cell block from cell (2, 2) at 2 x 2 particles per cell.

pub const CELLS: [usize; 2] = [260, 132];
pub const NX: usize = CELLS[0] + 1;
pub const NY: usize = CELLS[1] + 1;
pub const NODES: usize = NX * NY;
pub const PPC: usize = 2;
pub const FIRST: [usize; 2] = [2, 2];
pub const BLOCK: [usize; 2] = [256, 128];

/// Everything constant in a step (dt set per step).
#[derive(Clone, Copy, Debug)]
pub struct Params {
    pub h: f32,
    pub inv_h: f32,
    pub origin: [f32; 2],
    pub dt: f32,
    pub gravity: [f32; 2],
    /// 1 - beta.
    pub pic: f32,
    pub mu: f32,
    pub lambda: f32,
    pub inv_rho0: f32,
    pub density: f32,
    pub wave_speed: f32,
    pub mass_cutoff: f32,
    /// Admissible region in cells: [lo, hi[a]].
    pub lo: f32,
    pub hi: [f32; 2],
    /// uGIMP half-width (cells) and its inverses.
    pub l: f32,
    pub inv_l: f32,
    pub inv_2l: f32,
    pub inv_4l: f32,
    /// first_node clamp top per axis: nodes - 3 + 1 (LEAD).
    pub top: [f32; 2],
}

impl Params {
    pub fn new() -> Params {
        let h: f32 = 0.01;
        // MaterialDef::DEFAULT: E 1e6, nu 0.3, density 1000, in f32 as the kernel does.
        let (e, nu, density): (f32, f32, f32) = (1.0e6, 0.3, 1000.0);
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let wave_speed = ((lambda + 2.0 * mu) / density).sqrt();
        let spacing = h / PPC as f32;
        let min_mass = spacing * spacing * density;
        let l = 0.5 / PPC as f32;
        let inv_l = 1.0 / l;
        Params {
            h,
            inv_h: 1.0 / h,
            origin: [0.0, 0.0],
            dt: 0.0,
            gravity: [0.0, -9.81],
            pic: 1.0 - 0.99f32,
            mu,
            lambda,
            inv_rho0: 1.0 / density,
            density,
            wave_speed,
            mass_cutoff: ((f32::EPSILON * f32::EPSILON) as f64 * min_mass as f64) as f32,
            lo: 1.0,
            hi: [(CELLS[0] - 1) as f32, (CELLS[1] - 1) as f32],
            l,
            inv_l,
            inv_2l: 0.5 * inv_l,
            inv_4l: 0.25 * inv_l,
            top: [(NX - 3) as f32 + 1.0, (NY - 3) as f32 + 1.0],
        }
    }

    /// The kernel's stable_dt: cfl h / (c_max + |v|_max), in f64.
    pub fn stable_dt(&self, v2_max: f64) -> f32 {
        let speed = self.wave_speed as f64 + v2_max.sqrt();
        (0.5 * self.h as f64 / speed) as f32
    }
}

/// The block's particles in the kernel's fill order (x fastest): x, y, vx, vy, mass.
pub struct Initial {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub vx: Vec<f32>,
    pub vy: Vec<f32>,
    pub m: Vec<f32>,
}

pub fn initial(p: &Params) -> Initial {
    let spacing = p.h / PPC as f32;
    let volume = spacing * spacing;
    let mass = volume * p.density;
    let k0 = [FIRST[0] * PPC, FIRST[1] * PPC];
    let kn = [BLOCK[0] * PPC, BLOCK[1] * PPC];
    let n = kn[0] * kn[1];
    let mut s = Initial {
        x: Vec::with_capacity(n),
        y: Vec::with_capacity(n),
        vx: vec![0.0; n],
        vy: vec![-0.1; n],
        m: vec![mass; n],
    };
    for ky in k0[1]..k0[1] + kn[1] {
        for kx in k0[0]..k0[0] + kn[0] {
            s.x.push(p.origin[0] + (kx as f32 + 0.5) * spacing);
            s.y.push(p.origin[1] + (ky as f32 + 0.5) * spacing);
        }
    }
    s
}

/// uGIMP stencil along one axis, scalar (the kernel's `first_node` and `Gimp::stencil`): first
/// node and weights, derivatives per unit length.
#[inline(always)]
pub fn stencil1(p: &Params, s: f32, top: f32) -> (usize, [f32; 3], [f32; 3]) {
    let lo = 1.0f32;
    let y = s + 0.5;
    let y = if y > lo { y } else { lo };
    let y = if y < top { y } else { top };
    let first = (y as i32) - 1;
    let f = s - first as f32;
    let l = p.l;
    let xi = f - 1.0;
    let a1 = xi.abs();
    let inner = a1 < l;
    let s1 = if inner {
        1.0 - (xi * xi + l * l) * p.inv_2l
    } else {
        1.0 - a1
    };
    let d1 = if inner {
        -xi * p.inv_l
    } else if xi >= 0.0 {
        -1.0
    } else {
        1.0
    };
    let outer = |a: f32| -> (f32, f32) {
        let t = (1.0 + l - a).max(0.0);
        if a <= 1.0 - l {
            (1.0 - a, 1.0)
        } else {
            (t * t * p.inv_4l, t * p.inv_2l)
        }
    };
    let (s0, m0) = outer(f);
    let (s2, m2) = outer(2.0 - f);
    (
        first as usize,
        [s0, s1, s2],
        [-m0 * p.inv_h, d1 * p.inv_h, m2 * p.inv_h],
    )
}

/// ln(1 + x), the kernel's branch-free `ln_1p_fast` (f32).
#[inline(always)]
pub fn ln_1p_fast(x: f32) -> f32 {
    let u = 1.0 + x;
    let bits = u.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 127;
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let big = m > core::f32::consts::SQRT_2;
    m = if big { 0.5 * m } else { m };
    e += big as i32;
    let e = e as f32;
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let series = 1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0))));
    let ln_u = e * core::f64::consts::LN_2 as f32 + 2.0 * t * series;
    let exact = u == 1.0;
    let denom = if exact { 1.0 } else { u - 1.0 };
    if exact {
        x
    } else {
        ln_u * x / denom
    }
}
