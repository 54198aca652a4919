//! Helpers shared by the integration tests: buffers, scene builders and column hashes.
#![allow(dead_code)]

use mpm_gimp::{
    memory_requirements, Boundary, Dimension, HeapBuffer, ParticleStatus, Real, ShapeFunction,
    UpdateOrder, World, WorldDef,
};

pub const SHAPES: [ShapeFunction; 4] = [
    ShapeFunction::Linear,
    ShapeFunction::Gimp,
    ShapeFunction::QuadraticBspline,
    ShapeFunction::CubicBspline,
];

pub const ORDERS: [UpdateOrder; 3] = [UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl];

/// A zeroed buffer big enough for `def`.
pub fn buffer_for(def: &WorldDef) -> HeapBuffer {
    HeapBuffer::new(memory_requirements(def).expect("valid definition").bytes)
}

/// A definition with `cells` per axis in `dim`, no gravity and open faces.
pub fn free_space(dim: Dimension, cells: u32, h: Real) -> WorldDef {
    WorldDef {
        dimension: dim,
        cells: if dim == Dimension::ThreeD {
            [cells; 3]
        } else {
            [cells, cells, 1]
        },
        cell_size: h,
        gravity: mpm_gimp::Vec3::ZERO,
        faces: [Boundary::Open; 6],
        particle_capacity: 200_000,
        ..WorldDef::DEFAULT
    }
}

/// True if every particle value is finite and every active particle lies in the grid.
pub fn all_finite(world: &World) -> bool {
    let v = world.particles();
    let d = world.def().axes();
    (0..v.count).all(|i| {
        (0..d).all(|a| v.position[a][i].is_finite() && v.velocity[a][i].is_finite())
            && v.stress.iter().all(|s| s.is_empty() || s[i].is_finite())
            && v.jacobian(i).is_finite()
    })
}

/// Number of particles with the given status.
pub fn count_status(world: &World, status: ParticleStatus) -> usize {
    let v = world.particles();
    v.status.iter().filter(|&&s| s == status as u32).count()
}

/// Sum of all particle masses (every status), in f64.
pub fn total_mass(world: &World) -> f64 {
    world.particles().mass.iter().map(|&m| m as f64).sum()
}

/// Largest von Mises-like stress magnitude `sqrt(sum of squared components)` over active
/// particles, as Cauchy stress in Pa given the material density `rho0`.
pub fn max_stress(world: &World, rho0: Real) -> f64 {
    let v = world.particles();
    (0..v.count)
        .filter(|&i| v.status[i] == ParticleStatus::Active as u32)
        .map(|i| {
            let j = v.jacobian(i) as f64;
            let s2: f64 = v
                .stress
                .iter()
                .filter(|c| !c.is_empty())
                .map(|c| (c[i] as f64 * rho0 as f64 / j).powi(2))
                .sum();
            s2.sqrt()
        })
        .fold(0.0, f64::max)
}
