//! How deep a floating box sits against Archimedes' depth: a box of wood in a tank of water at
//! a game's frame rate, moved by the step as a dynamic collider (E96).
//!
//! `cargo run --release --example float` prints, every tenth of the run, the time, the box's
//! depth below the far surface over Archimedes' (1 is exact), its tilt and how many water
//! particles are inside it; then the largest error after the first 2 s. Options: `--width`
//! (m, default 0.2) and `--height` (0.1) of the box, `--density` (kg/m^3, 500), `--cells` a
//! metre (50, the viewer's), `--seconds` (20), `--turn` (the box may turn; it starts tilted
//! `--tilt` rad, 0.05, or level with `--level`), `--apic` (APIC in place of the default
//! FLIP blend), `--cut-centres` (cut only the water whose particle centres lie inside the box,
//! in place of every particle whose domain reaches it).
//! The tank is 1 m wide, the water 0.35 m deep (bulk modulus 90 kPa, grid damping 20/s);
//! 60 Hz frames.
//!
//! The box shares its velocities with the water its contact holds each substep (E96), a water
//! particle carried into it is put back out (E91), and water packed against it relaxes its
//! volume (E97). What remains is where the box's edges fall between nodes: about a cell's
//! width of support either way, so the error scales as `h / width`.

use mpm_gimp::{
    memory_requirements, Boundary, Damping, Effects, HeapBuffer, Real, Schedule, Transfer, Vec3,
    World, WorldDef,
};
use mpm_gimp_output::scenes;

#[path = "common/args.rs"]
mod args;

const USAGE: &str = "usage: float [--width M] [--height M] [--density KG_M3] [--cells N] \
                     [--seconds S] [--turn [--level | --tilt RAD]] [--apic] [--cut-centres]";

fn main() {
    let (mut width, mut height, mut density, mut cells, mut seconds) =
        (0.2 as Real, 0.1 as Real, 500.0 as Real, 50u32, 20.0f64);
    let (mut turn, mut apic, mut tilt) = (false, false, 0.05 as Real);
    let mut cut = scenes::Cut::Domains;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args::number(&mut args, &a, true, USAGE);
        match a.as_str() {
            "--width" => width = value() as Real,
            "--height" => height = value() as Real,
            "--density" => density = value() as Real,
            "--cells" => cells = value() as u32,
            "--seconds" => seconds = value(),
            "--turn" => turn = true,
            "--level" => tilt = 0.0,
            "--tilt" => tilt = value() as Real,
            "--apic" => apic = true,
            "--cut-centres" => cut = scenes::Cut::Centres,
            _ => args::unknown(&a, USAGE),
        }
    }
    let n = cells.max(8);
    let h = 1.0 / n as Real;
    let def = WorldDef {
        cells: [n, n, 1],
        cell_size: h,
        particle_capacity: (8 * n * n).max(20_000),
        transfer: if apic { Transfer::Apic } else { Transfer::Flip },
        faces: [Boundary::Slip; 6],
        effects: Effects {
            collider_capacity: 1,
            damping: Some(Damping {
                grid: Schedule::constant(20.0),
                ..Damping::NONE
            }),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let (_, surface) = scenes::still_water(&mut world, 90.0e3, 0.35).expect("tank");
    let tilt = if turn { tilt } else { 0.0 };
    let (id, archimedes) = scenes::floating_box(
        &mut world,
        surface,
        [width, height],
        density,
        tilt,
        turn,
        cut,
    )
    .expect("box");
    let frame: Real = 1.0 / 60.0;
    let (mut next, mut worst) = (0.0f64, 0.0f64);
    while world.time() < seconds {
        world.step(frame).expect("step");
        let body = world.collider(id).expect("box").def;
        // The surface away from the box, 15 cm past its edges (the water next to it stands a
        // few mm higher and settles slowly); the box's depth below it at its centre line.
        let far = |x: Real| (x - body.position.x).abs() > width / 2.0 + 0.15;
        let top = scenes::surface_height(&world, far).expect("water away from the box");
        let angle = 2.0 * body.rotation[2].atan2(body.rotation[3]);
        let depth = top - (body.position.y - height / 2.0 * angle.cos());
        let error = (depth / archimedes - 1.0) as f64;
        if world.time() > 2.0 {
            worst = worst.max(error.abs());
        }
        if world.time() >= next {
            let p = world.particles();
            let inside = (0..p.count)
                .filter(|&i| {
                    let x = Vec3::new(p.position[0][i], p.position[1][i], 0.0);
                    world.collider_distance(id, x).is_ok_and(|d| d < 0.0)
                })
                .count();
            println!(
                "t {:6.2} s  depth/Archimedes {:.4}  tilt {:+.3} rad  inside {inside}",
                world.time(),
                depth / archimedes,
                angle
            );
            next += seconds / 10.0;
        }
    }
    println!("largest |depth/Archimedes - 1| after 2 s: {worst:.4}");
}
