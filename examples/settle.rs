//! A tank of water settling from rest: what a bulk viscosity (E46) and grid damping each do to
//! the sound that rings in a weakly compressible fluid, and what they cost in substeps.
//!
//! `cargo run --release --example settle` fills a 1 m tank (50 cells a metre, slip walls,
//! FLIP) with water 0.35 m deep, released without its hydrostatic compression (bulk modulus
//! 90 kPa, viscosity 1 Pa s), and prints each second the kinetic energy over `m g H`, then
//! from when it stayed below 1e-6 and the substeps a 60 Hz frame took. Options: `--xi X`, the
//! bulk viscosity as `zeta = X rho c h` (c the sound speed, h the cell: a damping ratio of
//! `X k h / 2` for a sound of wavenumber k, so that the grid's shortest waves go first; up to
//! `1 / (2 d)` it costs no substep at the default cfl, past it the viscous bound of E88 sets
//! the substep);
//! `--grid-damping RATE` (1/s, every node's velocity, which damps any motion);
//! `--seconds S` (10).
//!
//! Without either, the tank rings for good (the shear viscosity does not touch a change of
//! volume, and FLIP's PIC share reaches only the shortest waves).

use mpm_gimp::{
    memory_requirements, Boundary, Damping, HeapBuffer, MaterialDef, MaterialModel, Real, Schedule,
    Transfer, Vec3, World, WorldDef,
};

#[path = "common/args.rs"]
mod args;

const USAGE: &str = "usage: settle [--xi X] [--grid-damping RATE] [--seconds S]";

fn main() {
    let (mut xi, mut damping, mut seconds) = (0.0 as Real, 0.0 as Real, 10.0f64);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let value = args::number(&mut args, &a, false, USAGE);
        match a.as_str() {
            "--xi" => xi = value as Real,
            "--grid-damping" => damping = value as Real,
            "--seconds" => seconds = value,
            _ => args::unknown(&a, USAGE),
        }
    }
    let n = 50;
    let h = 1.0 / n as Real;
    let mut def = WorldDef {
        cells: [n, n, 1],
        cell_size: h,
        particle_capacity: 20_000,
        transfer: Transfer::Flip,
        faces: [Boundary::Slip; 6],
        ..WorldDef::DEFAULT
    };
    if damping > 0.0 {
        def.effects.damping = Some(Damping {
            grid: Schedule::constant(damping),
            ..Damping::NONE
        });
    }
    let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let (k, rho, depth) = (90.0e3 as Real, 1000.0 as Real, 0.35 as Real);
    let zeta = xi * rho * (k / rho).sqrt() * h;
    let water = world
        .add_material(&MaterialDef {
            model: MaterialModel::Fluid,
            density: rho,
            bulk_modulus: k,
            viscosity: 1.0,
            bulk_viscosity: zeta,
            ..MaterialDef::DEFAULT
        })
        .expect("water");
    // The tank's floor and walls: the slip walls' planes, the shape's margin in.
    let wall = def.shape.margin_cells() as Real * h;
    world
        .fill_box(
            Vec3::new(wall, wall, 0.0),
            Vec3::new(1.0 - wall, wall + depth, 0.0),
            water,
            Vec3::ZERO,
        )
        .expect("tank");
    let mgh = world.diagnostics().mass * def.gravity.length() as f64 * depth as f64;
    println!("bulk viscosity {zeta:.1} Pa s, grid damping {damping} /s");
    let (mut next, mut quiet, mut substeps, mut frames) = (1.0, None, 0u64, 0u64);
    while world.time() < seconds {
        substeps += world.step(1.0 / 60.0).expect("step").substeps as u64;
        frames += 1;
        let ke = world.diagnostics().kinetic / mgh;
        // Settled from the last frame that was still above.
        if ke >= 1e-6 {
            quiet = None;
        } else if quiet.is_none() {
            quiet = Some(world.time());
        }
        if world.time() >= next {
            println!("t {:5.1} s  kinetic / (m g H) {ke:.1e}", world.time());
            next += 1.0;
        }
    }
    match quiet {
        Some(t) => println!("below 1e-6 of m g H from {t:.2} s"),
        None => println!("still above 1e-6 of m g H"),
    }
    println!("substeps a frame: {:.1}", substeps as f64 / frames as f64);
}
