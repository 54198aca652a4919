//! Material that comes and goes: a tap pours water into a basin whose drain takes it out, for
//! a minute of simulated time, with the particle count bounded.
//!
//! The pattern (the host's, between steps; `mpm_gimp_output::tap::Tap` is the code): before
//! each frame the host removes whatever its sink region holds (`World::remove_particles` with
//! `Removal::Box`), which frees room, then adds the rows of particles its source delivers in
//! the frame (`World::add_particles`), as many as the rate and the frame's length give. The
//! others keep their order and state, and a particle's id moves down by the number removed
//! before it. The count settles where the sink takes what the source gives.
//!
//! `cargo run --release --example tap` prints, every 5 s, the particle count and the most
//! it has been. The scene is the viewer's `tap` (and `results/pictures/tap.gif`).

use mpm_gimp::World;
use mpm_gimp_output::scenes::{find, Scene};

fn main() {
    let scene = find("tap").expect("the registry has the tap scene");
    let def = (scene.def)();
    let mut storage = Scene::storage(&def).expect("a valid definition");
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("the buffer fits");
    (scene.fill)(&mut world).expect("the basin fits");
    let frames_per_report = (5.0 / scene.frame_dt).round() as usize;
    let mut most = 0;
    println!("time (s)  particles  at most");
    for report in 1..=12 {
        for _ in 0..frames_per_report {
            scene
                .frame(&mut world, scene.frame_dt)
                .expect("a frame within its substep limit");
            most = most.max(world.particle_count());
        }
        println!(
            "{:8.1}  {:9}  {:7}",
            5.0 * report as f64,
            world.particle_count(),
            most
        );
    }
}
