//! Two-way coupling with a host's rigid body: a heavy box falls into a bed of soft elastic
//! material, and the host moves it with the force the material puts on it.
//!
//! The pattern (docs/equations.md E93; ARCHITECTURE.md, "Colliders"): before each step the
//! host sets the collider to its body's pose and velocity; the step moves the collider with
//! that velocity through its substeps; after the step the host reads the impulse the material
//! put on the collider and gives it to its body, `v += J / M + g dt`, then moves the body.
//! The coupling is explicit: the body answers the material one step late. It is stable while
//! the body outweighs the material its contact nodes carry in a step (the added mass); a body
//! much lighter than that overshoots and rings.
//!
//! `cargo run --release --example coupling` prints the body's height, speed and the force on
//! it over 3 s: it bounces on the bed, lower each time as the foam's damping takes the energy.

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
    let g = def.gravity;
    let (mut position, mut velocity) = (Vec3::new(0.5, 0.6, 0.0), Vec3::ZERO);
    let body = |position: Vec3, velocity: Vec3| ColliderDef {
        shape: ColliderShape::Box { half_extents: half },
        position,
        velocity,
        contact: Contact::Separate,
        friction: 0.3,
        ..ColliderDef::DEFAULT
    };
    let id = world
        .add_collider(&body(position, velocity))
        .expect("collider");
    println!(
        "# t[s]  height[m]  speed[m/s]  force_y[N/m]  weight[N/m] = {:.1}",
        -mass * g.y
    );
    // One stable substep per host step: the body answers the material every substep (a
    // frame of many substeps with the body's velocity fixed through it drives it into the
    // material as a piston would, and the impulse it then gets back overshoots).
    let mut next_line = 0.0;
    while world.time() < 3.0 {
        let dt = world.stable_dt();
        // The host's step: the collider takes the body's state, the world steps, and the body
        // takes the impulse back.
        world
            .set_collider(id, &body(position, velocity))
            .expect("set");
        world.step(dt).expect("step");
        let state = world.collider(id).expect("collider");
        velocity += state.impulse / mass + g * dt;
        position += velocity * dt;
        if world.time() >= next_line {
            next_line += 0.1;
            println!(
                "{:.3}  {:.4}  {:+.4}  {:.1}",
                world.time(),
                position.y - half.y,
                velocity.y,
                state.force().y
            );
        }
    }
}
