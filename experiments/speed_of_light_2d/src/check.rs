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
        Kernel { storage }
    }

    pub fn world(&mut self) -> World<'_> {
        World::open(self.storage.as_mut_bytes()).unwrap()
    }

    pub fn state(&mut self) -> State {
        let w = self.world();
        let p = w.particles();
        State {
            x: [p.position[0].to_vec(), p.position[1].to_vec()],
            v: [p.velocity[0].to_vec(), p.velocity[1].to_vec()],
            tau: [
                p.stress[0].to_vec(),
                p.stress[1].to_vec(),
                p.stress[2].to_vec(),
                p.stress[3].to_vec(),
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
