//! Cross-check against the kernel (the only place the kernel is used).

use crate::scene::*;
use mpm_gimp::{
    memory_requirements, Dimension, HeapBuffer, MaterialDef, MaterialModel, UpdateOrder, Vec3,
    World, WorldDef,
};

/// The state a prototype exposes for the check, in the kernel's particle order.
pub struct State {
    pub x: [Vec<f32>; 2],
    pub v: [Vec<f32>; 2],
    pub tau: [Vec<f32>; 4],
}

pub struct Kernel {
    storage: HeapBuffer,
    /// The lattice index (x fastest, the prototypes' order) of each kernel particle: the
    /// kernel's fill writes them in stencil-bin order.
    lattice: Vec<usize>,
}

impl Kernel {
    pub fn new(usl: bool) -> Kernel {
        let def = WorldDef {
            dimension: Dimension::Plane2D,
            cell_size: 0.01,
            cells: [CELLS[0] as u32, CELLS[1] as u32, 1],
            particle_capacity: (BLOCK[0] * BLOCK[1] * PPC * PPC) as u32,
            material_capacity: 1,
            particles_per_cell: PPC as u32,
            update_order: if usl {
                UpdateOrder::Usl
            } else {
                UpdateOrder::Musl
            },
            ..WorldDef::DEFAULT
        };
        let req = memory_requirements(&def).unwrap();
        let mut storage = HeapBuffer::new(req.bytes);
        let mut world = World::init(&def, storage.as_mut_bytes()).unwrap();
        let mat = world
            .add_material(&MaterialDef {
                model: MaterialModel::NeoHookean,
                ..MaterialDef::DEFAULT
            })
            .unwrap();
        let spacing = 0.01 / PPC as f32;
        let lo = Vec3::new(
            FIRST[0] as f32 * 0.01 + 0.25 * spacing,
            FIRST[1] as f32 * 0.01 + 0.25 * spacing,
            0.0,
        );
        let hi = Vec3::new(
            (FIRST[0] + BLOCK[0]) as f32 * 0.01 - 0.25 * spacing,
            (FIRST[1] + BLOCK[1]) as f32 * 0.01 - 0.25 * spacing,
            0.0,
        );
        world
            .fill_box(lo, hi, mat, Vec3::new(0.0, -0.1, 0.0))
            .unwrap();
        // Each particle's lattice site from its position (sites at (k + 1/2) spacing).
        let p = world.particles();
        let site = |x: f32, first: usize| ((x / spacing - 0.5).round() as usize) - first * PPC;
        let lattice = (0..p.count)
            .map(|i| {
                let kx = site(p.position[0][i], FIRST[0]);
                let ky = site(p.position[1][i], FIRST[1]);
                ky * BLOCK[0] * PPC + kx
            })
            .collect();
        Kernel { storage, lattice }
    }

    pub fn world(&mut self) -> World<'_> {
        World::open(self.storage.as_mut_bytes()).unwrap()
    }

    /// The kernel's state in the prototypes' particle order.
    pub fn state(&mut self) -> State {
        let lattice = self.lattice.clone();
        let w = self.world();
        let p = w.particles();
        let order = |c: &[f32]| {
            let mut o = vec![0.0f32; c.len()];
            for (i, &v) in c.iter().enumerate() {
                o[lattice[i]] = v;
            }
            o
        };
        State {
            x: [order(p.position[0]), order(p.position[1])],
            v: [order(p.velocity[0]), order(p.velocity[1])],
            tau: [
                order(p.stress[0]),
                order(p.stress[1]),
                order(p.stress[2]),
                order(p.stress[3]),
            ],
        }
    }
}

/// Max |x_a - x_b| in cells, max |v_a - v_b| relative to max |v|, max |tau_a - tau_b| relative to
/// max |tau| (per component set).
pub fn compare(a: &State, b: &State, inv_h: f32) -> (f64, f64, f64, f64) {
    let mut dx = 0.0f64;
    let mut dv = 0.0f64;
    let mut vmax = 0.0f64;
    let mut dt = 0.0f64;
    let mut tmax = 0.0f64;
    for c in 0..2 {
        for i in 0..a.x[c].len() {
            dx = dx.max(((a.x[c][i] - b.x[c][i]) * inv_h).abs() as f64);
            dv = dv.max((a.v[c][i] - b.v[c][i]).abs() as f64);
            vmax = vmax.max(b.v[c][i].abs() as f64);
        }
    }
    for c in 0..4 {
        for i in 0..a.tau[c].len() {
            dt = dt.max((a.tau[c][i] - b.tau[c][i]).abs() as f64);
            tmax = tmax.max(b.tau[c][i].abs() as f64);
        }
    }
    (dx, dv / vmax, dt / tmax, tmax)
}
