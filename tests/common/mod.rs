//! Helpers shared by the integration tests: buffers, scene builders and column hashes.
#![allow(dead_code)]

use core::ops::Range;
use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Face, HeapBuffer, MaterialDef, MaterialModel,
    ParticleBatch, ParticleStatus, Real, ShapeFunction, UpdateOrder, Vec3, World, WorldDef,
};

pub const SHAPES: [ShapeFunction; 5] = [
    ShapeFunction::Linear,
    ShapeFunction::Gimp,
    ShapeFunction::QuadraticBspline,
    ShapeFunction::CubicBspline,
    ShapeFunction::CpGimp,
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

/// A fixed-free bar along x of length `l`, `cells_per_l` cells per length, in 2D plane strain
/// with nu = 0 (so it is exactly one-dimensional: sigma_xx = E eps_xx, c = sqrt(E / rho)),
/// four cells high between slip walls, fixed (stick) at x = wall, free at the other end.
pub struct Bar {
    pub def: WorldDef,
    pub l: Real,
    pub wall: Real,
    pub c: Real,
    pub v0: Real,
    pub material: MaterialDef,
}

impl Bar {
    pub fn new(shape: ShapeFunction, cells_per_l: u32, v0: Real) -> Bar {
        let l: Real = 1.0;
        let h = l / cells_per_l as Real;
        let m = shape.margin_cells();
        let mut def = WorldDef {
            dimension: Dimension::Plane2D,
            cells: [cells_per_l + 2 * m + cells_per_l / 2, 4 + 2 * m, 1],
            cell_size: h,
            shape,
            gravity: Vec3::ZERO,
            faces: [Boundary::Slip; 6],
            flip_beta: 1.0,
            update_order: UpdateOrder::Musl,
            particle_capacity: 4 * cells_per_l * 4,
            ..WorldDef::DEFAULT
        };
        def.faces[Face::XMin as usize] = Boundary::Stick;
        def.faces[Face::XMax as usize] = Boundary::Open;
        let material = linear_elastic(0.0);
        Bar {
            def,
            l,
            wall: m as Real * h,
            c: (material.youngs_modulus / material.density).sqrt(),
            v0,
            material,
        }
    }

    pub fn omega(&self) -> Real {
        std::f64::consts::PI as Real * self.c / (2.0 * self.l)
    }

    pub fn period(&self) -> Real {
        4.0 * self.l / self.c
    }

    /// Exact displacement of the point at reference position x0 at time t:
    /// `u = (v0 / omega) sin(pi (x0 - wall) / 2L) sin(omega t)`.
    pub fn exact_u(&self, x0: Real, t: f64) -> f64 {
        let k = std::f64::consts::PI / (2.0 * self.l as f64);
        (self.v0 / self.omega()) as f64
            * (k * (x0 - self.wall) as f64).sin()
            * (self.omega() as f64 * t).sin()
    }

    /// Adds the bar's material and particles (2 x 2 per cell, at the sub-cell centres) moving
    /// in the first mode's velocity field `v = v0 sin(pi (x0 - wall) / 2L)`. Returns the
    /// reference x of every particle.
    pub fn populate(&self, world: &mut World) -> Vec<Real> {
        let mat = world.add_material(&self.material).unwrap();
        let h = self.def.cell_size;
        let d = h / 2.0;
        let nx = (self.l / d).round() as usize;
        let k = std::f64::consts::PI as Real / (2.0 * self.l);
        let (mut x, mut y, mut vx) = (vec![], vec![], vec![]);
        for j in 0..8 {
            for i in 0..nx {
                let x0 = self.wall + (i as Real + 0.5) * d;
                x.push(x0);
                y.push(self.wall + (j as Real + 0.5) * d);
                vx.push(self.v0 * (k * (x0 - self.wall)).sin());
            }
        }
        let n = x.len();
        let (vy, mass, vol, mats) = (
            vec![0.0; n],
            vec![self.material.density * d * d; n],
            vec![d * d; n],
            vec![mat; n],
        );
        world
            .add_particles(&ParticleBatch {
                position: [&x, &y, &[]],
                velocity: [&vx, &vy, &[]],
                mass: &mass,
                volume: &vol,
                material: &mats,
            })
            .unwrap();
        x
    }
}

/// A soft neo-Hookean solid: E = 100 kPa, nu = 0.3, rho = 1000 kg/m^3.
pub fn soft_neo_hookean() -> MaterialDef {
    MaterialDef {
        model: MaterialModel::NeoHookean,
        youngs_modulus: 1.0e5,
        poisson_ratio: 0.3,
        density: 1000.0,
        ..MaterialDef::DEFAULT
    }
}

/// Builds a square (2D) or cube (3D) block of side 0.3 m centred at 0.5 m with velocity
/// `v(x)` at 2 particles per cell per axis, in free space (no gravity, open faces).
pub fn moving_block(
    def: &WorldDef,
    world: &mut World,
    material: &MaterialDef,
    v: impl Fn([Real; 3]) -> [Real; 3],
) -> usize {
    let mat = world.add_material(material).unwrap();
    let d = def.axes();
    let spacing = def.cell_size / 2.0;
    let mut cols: [Vec<Real>; 6] = Default::default();
    block_lattice(&mut cols, d, [0.35; 3], 0.3, spacing, v);
    let count = cols[0].len();
    let vol = spacing.powi(d as i32);
    let mass = vec![material.density * vol; count];
    let volume = vec![vol; count];
    let mats = vec![mat; count];
    world
        .add_particles(&ParticleBatch {
            position: [&cols[0], &cols[1], &cols[2]],
            velocity: [&cols[3], &cols[4], &cols[5]],
            mass: &mass,
            volume: &volume,
            material: &mats,
        })
        .unwrap();
    count
}

/// Adds the block of [`moving_block`], of the default material with `model`, spinning rigidly
/// at 1 rad/s about (0.5, 0.5); returns the material.
pub fn spinning_block(def: &WorldDef, world: &mut World, model: MaterialModel) -> MaterialDef {
    let mat = MaterialDef {
        model,
        ..MaterialDef::DEFAULT
    };
    moving_block(def, world, &mat, |x| [-(x[1] - 0.5), x[0] - 0.5, 0.0]);
    mat
}

/// The number of equal steps of a quarter turn at 1 rad/s, each at most `world`'s stable
/// step, and their length.
pub fn quarter_turn(world: &World) -> (usize, Real) {
    let quarter = std::f64::consts::FRAC_PI_2;
    let steps = (quarter / world.stable_dt() as f64).ceil() as usize;
    (steps, (quarter / steps as f64) as Real)
}

/// Appends to `cols` (x, y, z, vx, vy, vz) the particles of a square (2D, `d` = 2) or cube of
/// side `side` m with lowest corner `at`, one per lattice site of spacing `spacing` (at the
/// sites' centres), moving at `v(x)`.
pub fn block_lattice(
    cols: &mut [Vec<Real>; 6],
    d: usize,
    at: [Real; 3],
    side: Real,
    spacing: Real,
    v: impl Fn([Real; 3]) -> [Real; 3],
) {
    let n = (side / spacing).round() as usize;
    box_lattice(cols, d, at, [n; 3], spacing, v);
}

/// [`block_lattice`] for a box of `sites[a]` sites along each axis `a < d`.
pub fn box_lattice(
    cols: &mut [Vec<Real>; 6],
    d: usize,
    at: [Real; 3],
    sites: [usize; 3],
    spacing: Real,
    v: impl Fn([Real; 3]) -> [Real; 3],
) {
    let nz = if d == 3 { sites[2] } else { 1 };
    for k in 0..nz {
        for j in 0..sites[1] {
            for i in 0..sites[0] {
                let ijk = [i, j, k];
                let x: [Real; 3] = core::array::from_fn(|a| {
                    if a < d {
                        at[a] + (ijk[a] as Real + 0.5) * spacing
                    } else {
                        0.0
                    }
                });
                let vel = v(x);
                for a in 0..3 {
                    cols[a].push(x[a]);
                    cols[3 + a].push(vel[a]);
                }
            }
        }
    }
}

/// Corotated linear elastic, E = 1 MPa, Poisson's ratio `nu`, rho = 1000 kg/m^3 (with `nu = 0`
/// uniaxial strain and stress are one, plane strain is plane stress, and c = 31.6 m/s).
pub fn linear_elastic(nu: Real) -> MaterialDef {
    MaterialDef {
        model: MaterialModel::LinearElastic,
        youngs_modulus: 1.0e6,
        poisson_ratio: nu,
        density: 1000.0,
        ..MaterialDef::DEFAULT
    }
}

/// Loads the particles of `ids` on the side of `face` (x-min or x-max: those with the least or
/// the greatest x) with a traction `traction` on that face each; returns them.
pub fn load_outer_column(
    world: &mut World,
    ids: Range<u32>,
    face: Face,
    traction: Vec3,
) -> Vec<u32> {
    let v = world.particles();
    let x = |i: &u32| v.position[0][*i as usize];
    let edge = match face {
        Face::XMin => ids.clone().map(|i| x(&i)).fold(Real::MAX, Real::min),
        Face::XMax => ids.clone().map(|i| x(&i)).fold(Real::MIN, Real::max),
        _ => panic!("x faces only"),
    };
    let column: Vec<u32> = ids.filter(|i| x(i) == edge).collect();
    for &i in &column {
        world.add_tractions(i..i + 1, face, traction).unwrap();
    }
    column
}

/// Lamé constants (lambda, mu) in f64 from Young's modulus and Poisson's ratio.
pub fn lame_of(youngs_modulus: Real, poisson_ratio: Real) -> (f64, f64) {
    let (e, nu) = (youngs_modulus as f64, poisson_ratio as f64);
    (
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        e / (2.0 * (1.0 + nu)),
    )
}

/// A conducting material: thermal diffusivity `k / (rho C_p)` = `kappa`, stiff enough that the
/// mechanics (at rest) takes no part, and diffusivity `kappa` for the concentration too.
pub fn conductor(kappa: Real) -> MaterialDef {
    MaterialDef {
        model: MaterialModel::LinearElastic,
        youngs_modulus: 1.0e4,
        poisson_ratio: 0.0,
        density: 1000.0,
        heat_capacity: 1000.0,
        conductivity: kappa * 1000.0 * 1000.0,
        diffusivity: kappa,
        ..MaterialDef::DEFAULT
    }
}
