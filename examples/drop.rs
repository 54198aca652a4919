//! An elastic block dropped on a stick floor: prints its centre-of-mass height, its kinetic,
//! strain and gravitational energy over time, the substeps of each frame, and the particles
//! frozen since the last line (the step report's flag that a step went bad).
//!
//! `cargo run --release --example drop` (add `-- --3d` for the 3D version, `-- --classic` for
//! classic MPM: linear shape functions with USL, which is unstable, to see particles whose
//! volume runs away frozen and reported).

use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Face, HeapBuffer, MaterialDef, ShapeFunction,
    UpdateOrder, Vec3, World, WorldDef,
};

fn main() {
    let three_d = std::env::args().any(|a| a == "--3d");
    let classic = std::env::args().any(|a| a == "--classic");
    let mut def = WorldDef {
        cells: [40, 40, 40],
        cell_size: 0.025,
        particle_capacity: 100_000,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    if classic {
        def.shape = ShapeFunction::Linear;
        def.update_order = UpdateOrder::Usl;
    }
    if three_d {
        def.dimension = Dimension::ThreeD;
    } else {
        def.cells[2] = 1;
    }
    let req = memory_requirements(&def).expect("valid definition");
    let mut storage = HeapBuffer::new(req.bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let rubber = world
        .add_material(&MaterialDef {
            youngs_modulus: 2.0e5,
            ..MaterialDef::DEFAULT
        })
        .expect("valid material");
    let (lo, hi) = if three_d {
        (Vec3::new(0.35, 0.4, 0.35), Vec3::new(0.65, 0.7, 0.65))
    } else {
        (Vec3::new(0.3, 0.4, 0.0), Vec3::new(0.7, 0.7, 0.0))
    };
    let ids = world
        .fill_box(lo, hi, rubber, Vec3::ZERO)
        .expect("block fits");
    println!(
        "# {} particles, {}D, {:?}, stable dt {:.3e} s",
        ids.len(),
        def.axes(),
        def.shape,
        world.stable_dt()
    );
    println!(
        "# t[s]  com_height[m]  kinetic[J]  strain[J]  gravity[J]  total[J]  substeps  frozen"
    );
    let frame = 1.0 / 60.0;
    let (mut frozen, mut runaway) = (0, 0);
    for f in 0..=90 {
        let mut substeps = 0;
        if f > 0 {
            let report = world.step(frame).expect("valid dt");
            substeps = report.substeps;
            // `went_bad`: some particle froze in this frame (non-finite state, inverted F or a
            // runaway volume); the count says how many.
            if report.went_bad() {
                frozen += report.frozen;
                runaway += report.runaway;
            }
        }
        if f % 5 == 0 {
            let d = world.diagnostics();
            println!(
                "{:6.3}  {:8.5}  {:10.4e}  {:10.4e}  {:10.4e}  {:10.4e}  {:8}  {}",
                world.time(),
                d.center_of_mass[1],
                d.kinetic,
                d.strain,
                d.potential,
                d.total_energy(),
                substeps,
                frozen
            );
            frozen = 0;
        }
    }
    if runaway > 0 {
        println!("# {runaway} particles frozen because their volume ran away (J out of bounds)");
    }
}
