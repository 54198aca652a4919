//! An elastic block dropped on a stick floor: prints its centre-of-mass height, its kinetic,
//! strain and gravitational energy over time, the substeps of each frame, and the particles
//! frozen since the last line (the step report's flag that a step went bad); and writes the
//! fall as an animated GIF, `target/drop.gif` (particles coloured by speed).
//!
//! `cargo run --release --example drop` (add `-- --3d` for the 3D version, `-- --classic` for
//! classic MPM: linear shape functions with USL, which is unstable, to see particles whose
//! volume runs away frozen and reported; `-- --flip-beta B` for another FLIP share; `-- --gif
//! PATH` to write the picture elsewhere).
//!
//! Units: SI (s, m, J; energies per metre of thickness in 2D). What to expect in 2D: the block
//! lands at 0.29 s and twice more by 1.5 s, and its total energy falls by 30 %. The
//! default transfer (FLIP with `flip_beta` 0.99) takes 1 % of each substep's particle velocity
//! from the grid, which damps the block's ringing after each landing: with `--flip-beta 1` the
//! total falls by 7 %, what the stick floor takes at each impact.

use mpm_gimp::{memory_requirements, HeapBuffer, World};
use mpm_gimp_output::picture::{render, write_gif, Colour};
use mpm_gimp_output::scenes::{drop_def, drop_fill};

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let three_d = args.iter().any(|a| a == "--3d");
    let classic = args.iter().any(|a| a == "--classic");
    let gif = args
        .iter()
        .position(|a| a == "--gif")
        .and_then(|k| args.get(k + 1).cloned())
        .unwrap_or_else(|| "target/drop.gif".into());
    let mut def = drop_def(three_d, classic);
    if let Some(beta) = args.iter().position(|a| a == "--flip-beta") {
        def.flip_beta = args
            .get(beta + 1)
            .and_then(|b| b.parse().ok())
            .expect("--flip-beta takes a number in [0, 1]");
    }
    let req = memory_requirements(&def).expect("valid definition");
    let mut storage = HeapBuffer::new(req.bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let particles = drop_fill(&mut world).expect("block fits");
    println!(
        "# {} particles, {}D, {:?}, stable dt {:.3e} s",
        particles,
        def.axes(),
        def.shape,
        world.stable_dt()
    );
    if def.axes() == 2 {
        println!("# 2D: energies in J per metre of thickness");
    }
    println!(
        "# t[s]  com_height[m]  kinetic[J]  strain[J]  gravity[J]  total[J]  substeps  frozen"
    );
    let frame = 1.0 / 60.0;
    let (mut frozen, mut runaway) = (0, 0);
    let start = world.diagnostics().total_energy();
    let mut pictures = vec![];
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
        // Speeds from rest to the fall's 2.7 m/s at the floor, one colour scale throughout.
        pictures.push(render(&world, Colour::Speed, (0.0, 2.5), 200));
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
    let end = world.diagnostics().total_energy();
    println!(
        "# total energy {start:.1} J at rest, {end:.1} J at {:.2} s ({:+.0} %): what the stick \
         floor takes at each landing and FLIP's PIC share (flip_beta {}) takes from the ringing",
        world.time(),
        100.0 * (end / start - 1.0),
        def.flip_beta
    );
    if runaway > 0 {
        println!("# {runaway} particles frozen because their volume ran away (J out of bounds)");
    }
    if let Some(dir) = std::path::Path::new(&gif).parent() {
        std::fs::create_dir_all(dir)?;
    }
    write_gif(std::fs::File::create(&gif)?, &pictures, 2)?;
    println!("# the fall, coloured by speed: {gif}");
    Ok(())
}
