//! Two-way coupling with a host's rigid body at a game's frame rate: a box falls into a bed
//! of soft elastic material, and the step moves it by the force the material puts on it.
//!
//! The pattern (docs/equations.md E93, E96; README, "Colliders and rigid bodies"): give the
//! collider the body's mass and moments of inertia (2D: per metre of thickness, as the
//! impulse). The world then owns the pose through each `step`: it moves the body every
//! substep by the impulse of that substep and by gravity, so the body answers the material
//! within the stable step, at any frame rate. After the step the host reads the pose and
//! velocities back (`collider(id).def`) and the frame's impulse and force; to push the body
//! itself (a player's hand, a joint), it sets a new pose or velocity between steps with
//! `set_collider`. A host that integrates the body itself from the impulse read back once a
//! frame holds the body's velocity through the frame's substeps: stable only while the body
//! outweighs the material its contact carries in a frame (a lighter one rings).
//!
//! `cargo run --release --example coupling` prints the body's height, speed and the force on
//! it over 3 s of 60 Hz frames: it bounces on the bed, lower each time as the foam's damping
//! takes the energy.

use mpm_gimp::{
    memory_requirements, Boundary, ColliderDef, ColliderShape, Contact, Damping, Effects, Face,
    HeapBuffer, MaterialDef, Real, Schedule, Vec3, World, WorldDef,
};

fn main() {
    let mut def = WorldDef {
        cells: [48, 48, 1],
        cell_size: 1.0 / 48.0,
        particle_capacity: 20_000,
        effects: Effects {
            collider_capacity: 1,
            // The foam's own losses, so that the body comes to rest.
            damping: Some(Damping {
                grid: Schedule::constant(60.0),
                ..Damping::NONE
            }),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let foam = world
        .add_material(&MaterialDef {
            youngs_modulus: 2.0e5,
            density: 300.0,
            ..MaterialDef::DEFAULT
        })
        .expect("material");
    let lo = def.cell_size * 2.0;
    world
        .fill_box(
            Vec3::new(lo, lo, 0.0),
            Vec3::new(1.0 - lo, 0.35, 0.0),
            foam,
            Vec3::ZERO,
        )
        .expect("bed");
    // The host's rigid body: a box 0.2 m wide, 0.1 m tall, 60 kg per metre of thickness,
    // dropped from 0.6 m.
    let half = Vec3::new(0.1, 0.05, 0.5);
    let mass: Real = 60.0;
    let id = world
        .add_collider(&ColliderDef {
            shape: ColliderShape::Box { half_extents: half },
            position: Vec3::new(0.5, 0.6, 0.0),
            contact: Contact::Separate,
            friction: 0.3,
            mass,
            // The moment about its centre, per metre of thickness: M (w^2 + h^2) / 12.
            inertia: Vec3::new(0.0, 0.0, mass * (half.x * half.x + half.y * half.y) / 3.0),
            ..ColliderDef::DEFAULT
        })
        .expect("collider");
    println!(
        "# t[s]  height[m]  speed[m/s]  force_y[N/m]  weight[N/m] = {:.1}",
        -mass * def.gravity.y
    );
    let frame: Real = 1.0 / 60.0;
    let mut next_line = 0.0;
    while world.time() < 3.0 {
        world.step(frame).expect("step");
        let body = world.collider(id).expect("collider");
        if world.time() >= next_line {
            next_line += 0.1;
            println!(
                "{:.3}  {:.4}  {:+.4}  {:.1}",
                world.time(),
                body.def.position.y - half.y,
                body.def.velocity.y,
                body.force().y
            );
        }
    }
}
