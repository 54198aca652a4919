//! What the example scenes (the samples viewer's, `mpm_gimp_output::scenes`) cost a frame:
//! their substeps per frame and nanoseconds per particle-substep, the figure `step_cost` gives
//! for its large block, for scenes of a few thousand particles stepped a frame at a time.
//!
//! `cargo run --release --example scene_cost` (every scene), or `-- water sand` (those), with
//! `--frames N` (timed frames per run, default 10), `--runs N` (default 5, at least 3) and
//! `--particle-forces` (declare the effect, as the samples viewer does for its mouse drag).
//! Each scene runs 3 untimed frames, then its runs; one JSON line per scene on stdout: the
//! particles, the substeps of a frame, the median ns per particle-substep, the median ms of
//! simulation per frame and `reference_ns`, the machine's speed at the time (as in
//! `step_cost`). Unknown options: a message on stderr and exit code 2.

use mpm_gimp::simd::Simd;
use mpm_gimp::World;
use mpm_gimp_output::scenes::{self, Scene};
use std::process::exit;
use std::time::Instant;

#[path = "../benches/common/timing.rs"]
#[allow(dead_code)]
mod timing;
use timing::{median, reference_ns_per_particle};

const USAGE: &str =
    "usage: scene_cost [--frames N] [--runs N (>= 3)] [--particle-forces] [SCENE ...]";

fn main() {
    let (mut frames, mut runs, mut names, mut forces) = (10u32, 5u32, Vec::new(), false);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut number = |min: u32| -> u32 {
            match args.next().and_then(|v| v.parse().ok()) {
                Some(n) if n >= min => n,
                _ => {
                    eprintln!("{USAGE}");
                    exit(2)
                }
            }
        };
        match a.as_str() {
            "--frames" => frames = number(1),
            "--runs" => runs = number(3),
            "--particle-forces" => forces = true,
            "--help" | "-h" => {
                println!("{USAGE}");
                return;
            }
            name => match scenes::find(name) {
                Some(s) => names.push(s),
                None => {
                    eprintln!("no scene named {name}; {USAGE}");
                    exit(2)
                }
            },
        }
    }
    let list: Vec<&Scene> = if names.is_empty() {
        scenes::ALL.iter().collect()
    } else {
        names
    };
    for scene in list {
        measure(scene, frames, runs, forces);
    }
}

/// Times `runs` runs of `frames` frames of `scene` after 3 untimed ones, with particle forces
/// declared if `forces`; prints its line.
fn measure(scene: &Scene, frames: u32, runs: u32, forces: bool) {
    let mut def = (scene.def)();
    def.effects.particle_forces |= forces;
    let mut storage = Scene::storage(&def).expect("a scene's definition is valid");
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("the buffer fits");
    let particles = (scene.fill)(&mut world).expect("a scene fills its world") as f64;
    let frame = |world: &mut World<'_>| {
        // The host's work (the tap's particles) is not timed; the particles it leaves are
        // the ones the frame steps.
        (scene.host)(world, scene.frame_dt).expect("the scene's host fits its world");
        let n = world.particle_count() as f64;
        let t0 = Instant::now();
        let report = world
            .step_with_simd(scene.frame_dt, Simd::Detect)
            .expect("a scene's frame is within its substep limit");
        (t0.elapsed().as_nanos() as f64, report.substeps as f64, n)
    };
    for _ in 0..3 {
        frame(&mut world);
    }
    let (mut per_step, mut per_frame, mut substeps, mut refs) = (vec![], vec![], vec![], vec![]);
    for _ in 0..runs {
        refs.push(reference_ns_per_particle(particles as usize));
        let (mut ns, mut steps, mut particle_steps) = (0.0, 0.0, 0.0);
        for _ in 0..frames {
            let (t, s, n) = frame(&mut world);
            ns += t;
            steps += s;
            particle_steps += s * n;
        }
        per_step.push(ns / particle_steps);
        per_frame.push(ns / frames as f64 * 1e-6);
        substeps.push(steps / frames as f64);
    }
    let (ns, ms, sub, r) = (
        median(&per_step),
        median(&per_frame),
        median(&substeps),
        median(&refs),
    );
    eprintln!(
        "{}: {} particles, {sub:.1} substeps a frame, {ns:.1} ns per particle-substep, \
         {ms:.2} ms a frame",
        scene.name, particles
    );
    println!(
        "{{\"scene\":\"{}\",\"particles\":{},\"substeps_per_frame\":{sub:.1},\
         \"ns_per_particle_step\":{ns:.2},\"ms_per_frame\":{ms:.3},\"simd\":\"{}\",\
         \"reference_ns\":{r:.3}}}",
        scene.name,
        particles,
        Simd::Detect.instance_for(&world.def()).name()
    );
}
