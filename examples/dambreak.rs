//! A dam break against Martin and Moyce (1952): a water column `a` = 0.2 m wide and `2a` high
//! collapses along the floor; prints the surge front `Z = x / a` (the farthest particle)
//! against `T = t sqrt(2 g / a)` beside their data, the front's speed, and the shift of the
//! time origin (the experiment's release, see `tests/kernel/materials.rs`) that fits best;
//! and the sound speed over the fastest flow, the substeps a 60 Hz frame and the least volume
//! ratio, what `--bulk` trades (`mpm_gimp_output::stiffness::bulk_modulus_for_speed_ratio`
//! tabulates it).
//!
//! `cargo run --release --example dambreak` (20 cells across the column, APIC, slip floor).
//! Options: `--cells N`, `--flip`, `--stick` (a no-slip floor), `--friction MU` (the floor's
//! Coulomb friction), `--gate SPEED` (m/s: the column starts behind a gate, a box collider
//! lifted at this speed, as the experiment's was), `--bulk K` (Pa, 1e6).

use mpm_gimp::{
    memory_requirements, Boundary, ColliderDef, ColliderShape, Contact, Face, HeapBuffer,
    MaterialDef, MaterialModel, Real, Transfer, Vec3, World, WorldDef,
};

#[path = "common/args.rs"]
mod args;

const USAGE: &str =
    "usage: dambreak [--cells N] [--flip] [--stick] [--friction MU] [--gate SPEED] [--bulk K]";

/// Martin and Moyce 1952, Fig. 3 (n^2 = 2, a = 2.25 in): (T, Z).
const DATA: [(f64, f64); 5] = [
    (0.832, 1.217),
    (1.219, 1.474),
    (1.997, 2.292),
    (2.547, 2.995),
    (3.345, 4.134),
];

fn main() {
    let (mut cells, mut gate, mut bulk) = (20u32, 0.0f64, 1.0e6f64);
    let mut def = WorldDef {
        transfer: Transfer::Apic,
        ..WorldDef::DEFAULT
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args::number(&mut args, &a, false, USAGE);
        match a.as_str() {
            "--flip" => def.transfer = Transfer::Flip,
            "--stick" => def.faces[Face::YMin as usize] = Boundary::Stick,
            "--cells" => cells = value().round().max(4.0) as u32,
            "--friction" => def.wall_friction[Face::YMin as usize] = value() as Real,
            "--gate" => gate = value(),
            "--bulk" => bulk = value(),
            _ => args::unknown(&a, USAGE),
        }
    }
    let a: f64 = 0.2;
    let h = a / cells as f64;
    def.cells = [5 * cells + 2, 2 * cells + 4, 1];
    def.cell_size = h as Real;
    def.particle_capacity = 4 * 2 * cells * cells + 100;
    def.faces[Face::YMax as usize] = Boundary::Open;
    def.effects.collider_capacity = 1;
    let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let water = world
        .add_material(&MaterialDef {
            model: MaterialModel::Fluid,
            bulk_modulus: bulk as Real,
            ..MaterialDef::DEFAULT
        })
        .expect("water");
    let wall = def.shape.margin_cells() as f64 * h;
    world
        .fill_box(
            Vec3::new(wall as Real, wall as Real, 0.0),
            Vec3::new((wall + a) as Real, (wall + 2.0 * a) as Real, 0.0),
            water,
            Vec3::ZERO,
        )
        .expect("column");
    // The gate: a plate 2 cells thick at the column's face, lifted at `gate` m/s.
    let plate = ColliderDef {
        shape: ColliderShape::Box {
            half_extents: Vec3::new(h as Real, a as Real * 1.5, 1.0),
        },
        position: Vec3::new((wall + a + h) as Real, (wall + 1.5 * a) as Real, 0.0),
        velocity: Vec3::new(0.0, gate as Real, 0.0),
        contact: Contact::Slip,
        ..ColliderDef::DEFAULT
    };
    if gate > 0.0 {
        world.add_collider(&plate).expect("gate");
    }
    let scale = (2.0 * 9.81 / a).sqrt();
    // The front (farthest particle, in a) every 1/240 s up to T = 3.5.
    let mut fronts = vec![(0.0f64, 0.0f64)];
    let frame = 1.0 / 240.0;
    let (mut substeps, mut j_min) = (0u64, 1.0f64);
    while world.time() < 3.5 / scale {
        if gate > 0.0 {
            let mut c = world.collider(0).expect("gate").def;
            c.position.y = (wall + 1.5 * a + gate * (world.time() + frame)) as Real;
            world.set_collider(0, &c).expect("gate moves");
        }
        substeps += world.step(frame as Real).expect("step").substeps as u64;
        let v = world.particles();
        j_min = (0..v.count).fold(j_min, |j, i| j.min(v.jacobian(i) as f64));
        let front = (0..v.count)
            .map(|i| v.position[0][i] as f64 - wall)
            .fold(0.0, f64::max)
            / a;
        fronts.push((world.time() * scale, front));
    }
    let at = |t: f64| {
        let k = fronts
            .partition_point(|&(tt, _)| tt < t)
            .clamp(1, fronts.len() - 1);
        let ((t0, z0), (t1, z1)) = (fronts[k - 1], fronts[k]);
        z0 + (z1 - z0) * (t - t0) / (t1 - t0)
    };
    let c = (bulk / 1000.0).sqrt();
    println!(
        "sound speed {c:.1} m/s, {:.2} times Ritter's front speed 2 sqrt(2 g a); substeps a \
         60 Hz frame {:.1}; least volume ratio J {j_min:.3}",
        c / (2.0 * (2.0 * 9.81 * a).sqrt()),
        substeps as f64 * 4.0 / (fronts.len() - 1) as f64
    );
    let ((t0, z0), (t1, z1)) = (DATA[2], DATA[4]);
    println!(
        "front speed dZ/dT over T {t0}-{t1}: {:.3} (Martin and Moyce {:.3}, Ritter 2)",
        (at(t1) - at(t0)) / (t1 - t0),
        (z1 - z0) / (t1 - t0)
    );
    // The release: the experiment's T = 0 against the simulation's, the shift that best fits.
    let worst = |shift: f64| {
        DATA.iter()
            .map(|&(t, z)| (at(t - shift) / z - 1.0).abs())
            .fold(0.0, f64::max)
    };
    let shift = (0..=60)
        .map(|k| k as f64 * 0.01)
        .min_by(|&p, &q| worst(p).total_cmp(&worst(q)))
        .unwrap_or(0.0);
    println!("     T   Z (sim)   Z (shifted {shift:.2})   Z (Martin & Moyce)");
    for (t, z) in DATA {
        println!(
            "{t:6.3}   {:7.3} ({:+5.1} %)   {:7.3} ({:+5.1} %)   {z:7.3}",
            at(t),
            100.0 * (at(t) / z - 1.0),
            at(t - shift),
            100.0 * (at(t - shift) / z - 1.0)
        );
    }
}
