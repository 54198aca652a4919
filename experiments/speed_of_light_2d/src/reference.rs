//! v0: a plain scalar MUSL/USL step (one particle at a time, SoA node columns), written to
//! follow the kernel's formulas term by term. The correctness baseline.

use crate::scene::*;

pub struct Reference {
    pub n: usize,
    pub x: [Vec<f32>; 2],
    pub v: [Vec<f32>; 2],
    pub xn: [Vec<f32>; 2],
    pub m: Vec<f32>,
    /// H = F - I, h[r][c].
    pub h: [[Vec<f32>; 2]; 2],
    /// tau/rho0: xx, yy, xy, zz.
    pub tau: [Vec<f32>; 4],
    // Grid columns.
    gm: Vec<f32>,
    gv: [Vec<f32>; 2],
    ga: [Vec<f32>; 2],
    gr: [Vec<f32>; 2],
}

impl Reference {
    pub fn new(init: &Initial) -> Reference {
        let n = init.x.len();
        let z = || vec![0.0f32; n];
        let zg = || vec![0.0f32; NODES];
        Reference {
            n,
            x: [init.x.clone(), init.y.clone()],
            v: [init.vx.clone(), init.vy.clone()],
            xn: [z(), z()],
            m: init.m.clone(),
            h: [[z(), z()], [z(), z()]],
            tau: [z(), z(), z(), z()],
            gm: zg(),
            gv: [zg(), zg()],
            ga: [zg(), zg()],
            gr: [zg(), zg()],
        }
    }

    fn stencil(&self, p: &Params, i: usize) -> (usize, [[f32; 3]; 2], [[f32; 3]; 2]) {
        let sx = (self.x[0][i] - p.origin[0]) * p.inv_h;
        let sy = (self.x[1][i] - p.origin[1]) * p.inv_h;
        let (fx, wx, dwx) = stencil1(p, sx, p.top[0]);
        let (fy, wy, dwy) = stencil1(p, sy, p.top[1]);
        (fx + NX * fy, [wx, wy], [dwx, dwy])
    }

    fn is_wall(i: usize, j: usize) -> [bool; 2] {
        [i <= 1 || i >= NX - 2, j <= 1 || j >= NY - 2]
    }

    pub fn step(&mut self, p: &Params, usl: bool) {
        let dt = p.dt;
        // 1. reset and scatter.
        self.gm.fill(0.0);
        for a in 0..2 {
            self.gv[a].fill(0.0);
            self.ga[a].fill(0.0);
            self.gr[a].fill(0.0);
        }
        for i in 0..self.n {
            let (base, w, dw) = self.stencil(p, i);
            let m = self.m[i];
            let t = [
                [self.tau[0][i], self.tau[2][i]],
                [self.tau[2][i], self.tau[1][i]],
            ];
            for j in 0..3 {
                for k in 0..3 {
                    let node = base + k + NX * j;
                    let s = w[0][k] * w[1][j];
                    let g = [dw[0][k] * w[1][j], w[0][k] * dw[1][j]];
                    self.gm[node] += s * m;
                    for a in 0..2 {
                        self.gv[a][node] += s * m * self.v[a][i];
                        self.ga[a][node] -= m * (t[a][0] * g[0] + t[a][1] * g[1]);
                    }
                }
            }
        }
        // 2. grid: velocity, acceleration, walls.
        let inv_dt = 1.0 / dt;
        for j in 0..NY {
            for i in 0..NX {
                let node = i + NX * j;
                let m = self.gm[node];
                let wall = Self::is_wall(i, j);
                for a in 0..2 {
                    if m > p.mass_cutoff {
                        self.gv[a][node] /= m;
                        self.ga[a][node] = self.ga[a][node] / m + p.gravity[a];
                    } else {
                        self.gv[a][node] = 0.0;
                        self.ga[a][node] = 0.0;
                    }
                    if wall[a] {
                        self.ga[a][node] = -self.gv[a][node] * inv_dt;
                    }
                }
            }
        }
        // 3. particle pass (+ the re-map scatter, MUSL; + the stress, USL).
        for i in 0..self.n {
            let (base, w, dw) = self.stencil(p, i);
            let mut vg = [0.0f32; 2];
            let mut ag = [0.0f32; 2];
            let mut l = [[0.0f32; 2]; 2];
            for j in 0..3 {
                for k in 0..3 {
                    let node = base + k + NX * j;
                    let s = w[0][k] * w[1][j];
                    let g = [dw[0][k] * w[1][j], w[0][k] * dw[1][j]];
                    for a in 0..2 {
                        vg[a] += s * self.gv[a][node];
                        ag[a] += s * self.ga[a][node];
                        if usl {
                            let u = self.gv[a][node] + self.ga[a][node] * dt;
                            l[a][0] += u * g[0];
                            l[a][1] += u * g[1];
                        }
                    }
                }
            }
            let mut vn = [0.0f32; 2];
            let mut xn = [0.0f32; 2];
            for a in 0..2 {
                let vp = self.v[a][i];
                let inversion = (vp - vg[a]) * p.pic;
                vn[a] = vp + ag[a] * dt - inversion;
                xn[a] = self.x[a][i] + (vg[a] + ag[a] * 0.5 * dt - inversion * 0.5) * dt;
                let s = (xn[a] - p.origin[a]) * p.inv_h;
                if s < p.lo {
                    xn[a] = p.origin[a] + p.lo * p.h;
                    if vn[a] < 0.0 {
                        vn[a] = 0.0;
                    }
                } else if s > p.hi[a] {
                    xn[a] = p.origin[a] + p.hi[a] * p.h;
                    if vn[a] > 0.0 {
                        vn[a] = 0.0;
                    }
                }
            }
            if usl {
                self.update_stress(p, i, l);
            }
            let m = self.m[i];
            for a in 0..2 {
                self.v[a][i] = vn[a];
                if usl {
                    self.x[a][i] = xn[a];
                } else {
                    self.xn[a][i] = xn[a];
                }
            }
            if !usl {
                for j in 0..3 {
                    for k in 0..3 {
                        let node = base + k + NX * j;
                        let s = w[0][k] * w[1][j];
                        for a in 0..2 {
                            self.gr[a][node] += s * m * vn[a];
                        }
                    }
                }
            }
        }
        if usl {
            return;
        }
        // 4. re-mapped velocity with the walls.
        for j in 0..NY {
            for i in 0..NX {
                let node = i + NX * j;
                let m = self.gm[node];
                let wall = Self::is_wall(i, j);
                for a in 0..2 {
                    self.gr[a][node] = if m > p.mass_cutoff {
                        self.gr[a][node] / m
                    } else {
                        0.0
                    };
                    if wall[a] {
                        self.gr[a][node] = 0.0;
                    }
                }
            }
        }
        // 5. stress at the old positions, then x = x_next.
        for i in 0..self.n {
            let (base, w, dw) = self.stencil(p, i);
            let mut l = [[0.0f32; 2]; 2];
            for j in 0..3 {
                for k in 0..3 {
                    let node = base + k + NX * j;
                    let g = [dw[0][k] * w[1][j], w[0][k] * dw[1][j]];
                    for a in 0..2 {
                        l[a][0] += self.gr[a][node] * g[0];
                        l[a][1] += self.gr[a][node] * g[1];
                    }
                }
            }
            self.update_stress(p, i, l);
            for a in 0..2 {
                self.x[a][i] = self.xn[a][i];
            }
        }
    }

    fn update_stress(&mut self, p: &Params, i: usize, l: [[f32; 2]; 2]) {
        let dt = p.dt;
        let mut a = l;
        for r in a.iter_mut() {
            for v in r.iter_mut() {
                *v *= dt;
            }
        }
        // Q = A + A (A / 2).
        let mut q2 = a;
        for r in q2.iter_mut() {
            for v in r.iter_mut() {
                *v *= 0.5;
            }
        }
        let mut q = a;
        for r in 0..2 {
            for c in 0..2 {
                for m in 0..2 {
                    q[r][c] += a[r][m] * q2[m][c];
                }
            }
        }
        let ho = [
            [self.h[0][0][i], self.h[0][1][i]],
            [self.h[1][0][i], self.h[1][1][i]],
        ];
        let mut h = [[0.0f32; 2]; 2];
        for r in 0..2 {
            for c in 0..2 {
                let mut v = ho[r][c];
                for m in 0..2 {
                    v += q[r][m] * ho[m][c];
                }
                h[r][c] = v + q[r][c];
            }
        }
        let jm1 = (h[0][0] + h[1][1]) + (h[0][0] * h[1][1] - h[0][1] * h[1][0]);
        let lnj = ln_1p_fast(jm1.max(-1.0 + f32::EPSILON));
        let pairs = [(0, 0), (1, 1), (0, 1)];
        for (k, &(r, c)) in pairs.iter().enumerate() {
            let mut hh = 0.0;
            for m in 0..2 {
                hh += h[r][m] * h[c][m];
            }
            let diag = if r == c { p.lambda * lnj } else { 0.0 };
            self.tau[k][i] = (p.mu * (h[r][c] + h[c][r] + hh) + diag) * p.inv_rho0;
        }
        self.tau[3][i] = (p.mu * 0.0 * 2.0 + p.lambda * lnj) * p.inv_rho0;
        for r in 0..2 {
            for c in 0..2 {
                self.h[r][c][i] = h[r][c];
            }
        }
    }
}
