//! A column of sand collapsing against a wall onto a rough floor, plane strain: the run-out
//! and final height that Lube et al. (2005) and Lajeunesse et al. (2005) measured, and what
//! the transfer, the stiffness, the resolution and the PIC share do to them.
//!
//! `cargo run --release --example collapse` releases a column 0.2 m wide and twice as high
//! (Drucker-Prager, friction angle 30 degrees, 20 cells across, FLIP) and prints the run-out
//! `(L - L0) / L0`, the final height over `L0`, when it came to rest (specific kinetic
//! energy below 1e-6 J/kg for good) and the substeps a 60 Hz frame took.
//! Options: `--aspect A` (2), `--cells N` (cells across the column, 20), `--phi DEG` (30),
//! `--youngs E` (Pa, 1e6), `--apic`, `--flip-beta B` (the world's default), `--pic-rate R`
//! (1/s, the world's default), `--seconds S` (3).
//!
//! Measured run-outs at a = 2 (f32; Lube et al. 1.2 a = 2.4 for a < 1.8, Lajeunesse et al.
//! the upper edge near 3.6):
//!
//! | cells across | E, Pa | FLIP 0.99 | `--flip-beta 1 --pic-rate 30` | APIC |
//! |---|---|---|---|---|
//! | 10 | 1e6 / 1e7 | 2.53 / 2.18 | 2.53 / 2.54 | |
//! | 20 | 1e6 / 1e7 | 2.91 / 2.51 | 3.08 / 3.19 | 4.39 / 4.06 |
//! | 40 | 1e6 / 1e7 | 3.13 / 2.85 | 3.53 / 3.51 | 4.64 / 4.63 |
//! | 80 | 1e6 | 3.22 | 3.69 | 4.23 |
//!
//! A share per substep damps a stiffer or finer column harder; a rate does not. What is left
//! grows with resolution and is larger with APIC: the flow stops by the transfer's own
//! dissipation as much as by friction. Taller columns run out farther than measured (a = 4:
//! 6.0 to 6.7 with FLIP at 40 cells, Lube's `1.9 a^(2/3)` = 4.8; a = 8: 10.2 to 11.0, 7.6).

use mpm_gimp::{
    memory_requirements, Boundary, Face, HeapBuffer, MaterialDef, MaterialModel, Real, Transfer,
    Vec3, World, WorldDef,
};

#[path = "common/args.rs"]
mod args;

const USAGE: &str = "usage: collapse [--aspect A] [--cells N] [--phi DEG] [--youngs E] [--apic] \
                     [--flip-beta B] [--pic-rate R] [--seconds S]";

fn main() {
    let mut def = WorldDef::DEFAULT;
    let (mut aspect, mut cells, mut phi, mut youngs, mut seconds) = (2.0, 20.0, 30.0, 1.0e6, 3.0);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args::number(&mut args, &a, false, USAGE);
        match a.as_str() {
            "--apic" => def.transfer = Transfer::Apic,
            "--aspect" => aspect = value(),
            "--cells" => cells = value().round().max(4.0),
            "--phi" => phi = value(),
            "--youngs" => youngs = value(),
            "--flip-beta" => def.flip_beta = value() as Real,
            "--pic-rate" => def.pic_rate = value() as Real,
            "--seconds" => seconds = value(),
            _ => args::unknown(&a, USAGE),
        }
    }
    let l0 = 0.2f64;
    let h = l0 / cells;
    // Room for a run-out of 3 a^(2/3) + 3 column widths, and the column's height.
    let width = l0 * (4.0 + 3.0 * aspect.powf(2.0 / 3.0).max(aspect.min(2.0)));
    def.cells = [
        (width / h).ceil() as u32 + 4,
        (aspect * l0 / h).ceil() as u32 + 5,
        1,
    ];
    def.cell_size = h as Real;
    def.particle_capacity = (cells * cells * aspect * 4.0) as u32 + 1000;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.effects.plasticity = true;
    let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let sand = world
        .add_material(&MaterialDef {
            model: MaterialModel::DruckerPrager,
            youngs_modulus: youngs as Real,
            density: 1600.0,
            friction_angle: phi as Real,
            ..MaterialDef::DEFAULT
        })
        .expect("sand");
    let wall = def.shape.margin_cells() as f64 * h;
    world
        .fill_box(
            Vec3::new(wall as Real, wall as Real, 0.0),
            Vec3::new((wall + l0) as Real, (wall + aspect * l0) as Real, 0.0),
            sand,
            Vec3::ZERO,
        )
        .expect("column");
    let mut substeps = 0u64;
    let frames = (seconds * 60.0).round() as u64;
    let mut rest = None;
    for frame in 0..frames {
        substeps += world.step(1.0 / 60.0).expect("step").substeps as u64;
        let d = world.diagnostics();
        let (ke, mass) = (d.kinetic, d.mass);
        if ke / mass < 1e-6 && frame > 30 && rest.is_none() {
            rest = Some(frame as f64 / 60.0);
        } else if ke / mass >= 1e-6 {
            rest = None;
        }
    }
    let v = world.particles();
    let mut xs: Vec<f64> = (0..v.count)
        .map(|i| v.position[0][i] as f64 - wall)
        .collect();
    xs.sort_by(f64::total_cmp);
    // The front: the 99.5th percentile of x (a stray grain does not count).
    let front = xs[(xs.len() as f64 * 0.995) as usize];
    let top = (0..v.count)
        .filter(|&i| (v.position[0][i] as f64 - wall) < 2.0 * h)
        .map(|i| v.position[1][i] as f64 - wall)
        .fold(0.0, f64::max);
    println!(
        "aspect {aspect} cells {cells} phi {phi} E {youngs:e} {:?} beta {} pic_rate {}: \
         runout {:.3} height {:.3} rest {} substeps/frame {:.1}",
        def.transfer,
        def.flip_beta,
        def.pic_rate,
        (front - l0) / l0,
        top / l0,
        rest.map_or("no".into(), |t| format!("{t:.2} s")),
        substeps as f64 / frames as f64
    );
}
