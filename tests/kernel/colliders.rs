//! Colliders (E90-E93): the force read back, friction against the exact sliding law, one
//! worker's bits on many, snapshots and misuse.

use mpm_gimp::{
    memory_requirements, Boundary, ColliderDef, ColliderShape, Contact, Damping, Effects, Error,
    Face, HeapBuffer, MaterialDef, Real, Schedule, Vec3, World, WorldDef,
};

const G: Real = 9.81;

fn def(gravity: Vec3, damping: Real) -> WorldDef {
    WorldDef {
        cells: [32, 32, 1],
        cell_size: 1.0 / 32.0,
        particle_capacity: 4096,
        gravity,
        effects: Effects {
            collider_capacity: 2,
            damping: (damping > 0.0).then_some(Damping {
                grid: Schedule::constant(damping),
                ..Damping::NONE
            }),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    }
}

const BLOCK: MaterialDef = MaterialDef {
    youngs_modulus: 1.0e6,
    ..MaterialDef::DEFAULT
};

/// A floor at y = 0.25 and a block of `BLOCK` resting on it, x in [0.3, 0.7], y in
/// [0.25, 0.45]; returns its mass per unit thickness.
fn block_on_floor(world: &mut World<'_>, floor: ColliderDef) -> Real {
    let m = world.add_material(&BLOCK).expect("material");
    world.add_collider(&floor).expect("floor");
    world
        .fill_box(
            Vec3::new(0.3, 0.25, 0.0),
            Vec3::new(0.7, 0.45, 0.0),
            m,
            Vec3::ZERO,
        )
        .expect("block");
    world.particles().mass.iter().sum()
}

fn floor(contact: Contact, friction: Real) -> ColliderDef {
    ColliderDef {
        position: Vec3::new(0.0, 0.25, 0.0),
        contact,
        friction,
        ..ColliderDef::DEFAULT
    }
}

/// Steps `world` to 1 s at its stable step and returns the mean force of the last 0.1 s on
/// collider `id` (its impulses over their durations).
fn settled_force(world: &mut World<'_>, id: u32) -> Vec3 {
    let dt = world.stable_dt();
    let (mut impulse, mut time) = (Vec3::ZERO, 0.0);
    while world.time() < 1.0 {
        world.step(dt).expect("step");
        if world.time() > 0.9 {
            let c = world.collider(id).expect("collider");
            impulse += c.impulse;
            time += c.duration;
        }
    }
    impulse / time
}

/// The mass-weighted mean of `column` of the particles.
fn mean(world: &World<'_>, column: impl Fn(&mpm_gimp::ParticlesView<'_>) -> Vec<Real>) -> Real {
    let p = world.particles();
    let m: Real = p.mass.iter().sum();
    p.mass
        .iter()
        .zip(column(&p))
        .map(|(m, v)| m * v)
        .sum::<Real>()
        / m
}

fn mean_vx(world: &World<'_>) -> Real {
    mean(world, |p| p.velocity[0].to_vec())
}

fn mean_x(world: &World<'_>) -> Real {
    mean(world, |p| p.position[0].to_vec())
}

/// A block at rest on a floor collider puts its weight on it: once the drop onto it has
/// settled (grid damping), the mean force of the last 0.1 s read back from the collider is
/// `M g` downward within 1 % (at rest the grid's momentum balance makes the contact impulse
/// exactly the weight's; the 1 % leaves room for what motion is left).
#[test]
fn a_body_at_rest_on_a_collider_reports_its_weight() {
    let def = def(Vec3::new(0.0, -G, 0.0), 30.0);
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    let mass = block_on_floor(&mut world, floor(Contact::Separate, 0.0));
    let force = settled_force(&mut world, 0);
    let weight = mass * G;
    assert!(
        (force.y + weight).abs() < 0.01 * weight && force.x.abs() < 0.01 * weight,
        "force {force:?} against the weight {weight}"
    );
    // The torque about the floor's origin (x = 0) is the weight's: its arm is the block's
    // centre, x = 0.5.
    let c = world.collider(0).expect("floor");
    let torque = c.torque().z;
    assert!(
        (torque + 0.5 * weight).abs() < 0.02 * 0.5 * weight,
        "torque {torque} against {}",
        -0.5 * weight
    );
}

/// A block on a floor with Coulomb friction `mu` (a collider with separating contact, or the
/// box's floor as a slip face with `wall_friction`, E94), loaded as on a slope
/// of angle `theta` in the slope's frame: gravity `g cos theta` into the floor, and, once the
/// block has settled on it (grid damping until `T0`), a body force along it that ramps up to
/// `g sin theta` over `TAU` (a sudden one sets the elastic block rocking, and its normal force
/// with it). It slides with `a = g (r(t) sin theta - mu cos theta)` once that is positive, `r`
/// the ramp, when `tan theta > mu` (3 %, for the grid's stick and slip of the contact nodes),
/// and stays where `tan theta < mu` (its mean displacement under 3 % of the frictionless
/// slide's: the elastic block shears a little).
/// (Slip contact holds the material to the floor in tension too, so its contact nodes can
/// press harder than the weight: it is held to the frictionless law alone. An undamped block
/// dropped on the slope bounces, and its normal force with it: it creeps by stick and slip.)
#[test]
fn a_block_slides_down_a_slope_at_the_coulomb_rate_and_stays_below_it() {
    let theta: Real = 0.5;
    let (s, c) = (theta.sin(), theta.cos());
    const T0: Real = 0.3;
    const TAU: Real = 0.05;
    let t_end = T0 + 0.25;
    for (mu, contact, on_face) in [
        (0.0, Contact::Separate, false),
        (0.0, Contact::Slip, false),
        (0.3, Contact::Separate, false),
        (0.7, Contact::Separate, false),
        (0.3, Contact::Slip, true),
        (0.7, Contact::Slip, true),
    ] {
        let mut def = def(Vec3::new(0.0, -G * c, 0.0), 0.0);
        let fx = &mut def.effects;
        fx.damping = Some(Damping {
            grid: Schedule::from_points(&[(T0 - 0.01, 30.0), (T0, 0.0)]).expect("ramp"),
            ..Damping::NONE
        });
        fx.body_force = Vec3::new(G * s, 0.0, 0.0);
        fx.body_force_scale = Schedule::from_points(&[(T0, 0.0), (T0 + TAU, 1.0)]).expect("ramp");
        if on_face {
            // The box's floor: a slip face with friction, its wall plane at y = 0.25 (the
            // grid moved down so that it is).
            def.faces[Face::YMin as usize] = Boundary::Slip;
            def.wall_friction[Face::YMin as usize] = mu;
            def.origin.y = 0.25 - def.shape.margin_cells() as Real * def.cell_size;
            def.effects.collider_capacity = 0;
        }
        let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
        let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
        if on_face {
            let m = world.add_material(&BLOCK).expect("material");
            world
                .fill_box(
                    Vec3::new(0.3, 0.25, 0.0),
                    Vec3::new(0.7, 0.45, 0.0),
                    m,
                    Vec3::ZERO,
                )
                .expect("block");
        } else {
            block_on_floor(&mut world, floor(contact, mu));
        }
        let dt = world.stable_dt();
        while world.time() < T0 as f64 {
            world.step(dt).expect("step");
        }
        let (x0, v0, t0) = (mean_x(&world), mean_vx(&world), world.time());
        while world.time() < t_end as f64 {
            world.step(dt).expect("step");
        }
        let t = (world.time() - t0) as Real;
        let v = mean_vx(&world) - v0;
        if s > mu * c {
            // Sliding from when the ramp's load passes friction's, `t_s = TAU mu / tan theta`:
            // the integral of `g (r sin theta - mu cos theta)` from there.
            let t_s = TAU * mu * c / s;
            let exact =
                G * s * (t - 0.5 * TAU) - G * mu * c * (t - t_s) - G * s * t_s * t_s / (2.0 * TAU);
            assert!(
                (v - exact).abs() < 0.03 * exact,
                "mu {mu} {contact:?} (on the face: {on_face}): {v} m/s against {exact}"
            );
        } else {
            let moved = mean_x(&world) - x0;
            let slide = 0.5 * G * s * (t - 0.5 * TAU) * (t - 0.5 * TAU);
            assert!(
                moved.abs() < 0.03 * slide,
                "mu {mu}: moved {moved} m, should stay"
            );
        }
    }
}

/// The colliders' state and impulses are bit-identical for any number of workers, and a
/// snapshot carries them: a copy of the state steps on as the original does.
#[test]
fn colliders_give_one_workers_bits_and_travel_with_a_snapshot() {
    let mut def = def(Vec3::new(0.0, -G, 0.0), 0.0);
    def.workers = 4;
    let bytes = memory_requirements(&def).expect("valid").bytes;
    // Kinematic, and dynamic (E96): the step moves it by what the block puts on it.
    for mass in [0.0, 2.0] {
        let drum = ColliderDef {
            shape: ColliderShape::Sphere { radius: 0.1 },
            position: Vec3::new(0.5, 0.53, 0.0),
            velocity: Vec3::new(0.0, -0.5, 0.0),
            angular_velocity: Vec3::new(0.0, 0.0, 3.0),
            contact: Contact::Slip,
            friction: 0.4,
            mass,
            inertia: Vec3::new(0.0, 0.0, 0.01 * mass),
            ..ColliderDef::DEFAULT
        };
        let run = |workers: usize| {
            let mut buf = HeapBuffer::new(bytes);
            let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
            block_on_floor(&mut world, floor(Contact::Stick, 0.0));
            world.add_collider(&drum).expect("drum");
            let tasks = mpm_gimp_rayon::RayonTasks::new(workers).expect("pool");
            for _ in 0..40 {
                world.step_with_tasks(2.0e-4, &tasks).expect("step");
            }
            let state = world.state_bytes().to_vec();
            (
                state,
                world.as_bytes().to_vec(),
                world.collider(1).expect("drum"),
            )
        };
        let (state_one, one, drum_one) = run(1);
        for workers in [2, 3, 4] {
            let (state, _, drum) = run(workers);
            assert!(state_one == state, "{workers} workers: the state differs");
            assert_eq!(drum_one, drum);
        }
        assert!(drum_one.impulse.length() > 0.0, "the drum met the block");
        let mut copy = HeapBuffer::new(bytes);
        copy.as_mut_bytes()[..one.len()].copy_from_slice(&one);
        let mut world = World::open(copy.as_mut_bytes()).expect("a snapshot opens");
        assert_eq!(world.collider(1).expect("drum"), drum_one);
        world.step(2.0e-4).expect("step");
        if mass > 0.0 {
            assert!(
                drum_one.def.velocity.y != -0.5,
                "the block moved the dynamic drum"
            );
        }
    }
}

/// In 2D a collider's position z, its velocity's z and its turns about x and y are not read,
/// as no z of a 2D call is (`ColliderDef::position`): a sphere pressed into a block with its
/// centre at z = 0.5 (a plane-strain section of it would miss the plane), a z velocity and a
/// turn about x, and one with those values NaN or infinite, meet the block exactly as the
/// same sphere at z = 0: the state bytes are the same after 40 steps, a move by
/// `set_collider` half-way included, and the sphere met the block. Each reads back
/// with those components 0, and its distance at a point does not depend on the point's z.
#[test]
fn a_2d_collider_ignores_the_components_2d_does_not_read() {
    let def = def(Vec3::new(0.0, -G, 0.0), 0.0);
    let bytes = memory_requirements(&def).expect("valid").bytes;
    let sphere = |z: Real, vz: Real, wx: Real, y: Real| ColliderDef {
        shape: ColliderShape::Sphere { radius: 0.1 },
        position: Vec3::new(0.5, y, z),
        velocity: Vec3::new(0.0, -0.5, vz),
        angular_velocity: Vec3::new(wx, -wx, 3.0),
        contact: Contact::Slip,
        friction: 0.4,
        ..ColliderDef::DEFAULT
    };
    let run = |z: Real, vz: Real, wx: Real| {
        let mut buf = HeapBuffer::new(bytes);
        let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
        block_on_floor(&mut world, floor(Contact::Stick, 0.0));
        world
            .add_collider(&sphere(z, vz, wx, 0.53))
            .expect("sphere");
        let mut pushed = Vec3::ZERO;
        for k in 0..40 {
            if k == 20 {
                world
                    .set_collider(1, &sphere(z, vz, wx, 0.5))
                    .expect("moved");
            }
            world.step(2.0e-4).expect("step");
            pushed += world.collider(1).expect("sphere").impulse;
        }
        let c = world.collider(1).expect("sphere").def;
        let off_plane = [
            c.position.z,
            c.velocity.z,
            c.angular_velocity.x,
            c.angular_velocity.y,
        ];
        assert_eq!(off_plane, [0.0; 4], "z {z}: read back");
        let p = Vec3::new(0.45, 0.41, 0.0);
        let d = world.collider_distance(1, p).expect("distance");
        for pz in [0.7, -3.0, Real::NAN] {
            let q = Vec3::new(p.x, p.y, pz);
            assert_eq!(world.collider_distance(1, q), Ok(d), "point z {pz}");
        }
        (world.state_bytes().to_vec(), pushed)
    };
    let (in_plane, pushed) = run(0.0, 0.0, 0.0);
    assert!(pushed.length() > 0.0, "the sphere met the block");
    for (z, vz, wx) in [(0.5, 2.0, 1.0), (Real::NAN, Real::INFINITY, Real::NAN)] {
        let (state, _) = run(z, vz, wx);
        assert!(
            state == in_plane,
            "z {z}, vz {vz}, wx {wx}: the state differs"
        );
    }
}

/// Misuse: each call refused with its error and the world unchanged.
#[test]
fn collider_misuse_is_refused_and_changes_nothing() {
    let mut def = def(Vec3::new(0.0, -G, 0.0), 0.0);
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    let bad = [
        ColliderDef {
            shape: ColliderShape::Sphere { radius: 0.0 },
            ..ColliderDef::DEFAULT
        },
        ColliderDef {
            shape: ColliderShape::Box {
                half_extents: Vec3::new(1.0, Real::NAN, 1.0),
            },
            ..ColliderDef::DEFAULT
        },
        ColliderDef {
            rotation: [0.0; 4],
            ..ColliderDef::DEFAULT
        },
        ColliderDef {
            friction: -1.0,
            ..ColliderDef::DEFAULT
        },
        ColliderDef {
            velocity: Vec3::new(Real::INFINITY, 0.0, 0.0),
            ..ColliderDef::DEFAULT
        },
    ];
    let before = world.state_bytes().to_vec();
    for c in &bad {
        assert_eq!(world.add_collider(c), Err(Error::InvalidEffect), "{c:?}");
    }
    assert_eq!(world.collider(0).map(|_| ()), Err(Error::UnknownCollider));
    assert_eq!(
        world.set_collider(0, &ColliderDef::DEFAULT),
        Err(Error::UnknownCollider)
    );
    assert!(world.state_bytes() == before.as_slice());
    world.add_collider(&ColliderDef::DEFAULT).expect("one");
    world.add_collider(&ColliderDef::DEFAULT).expect("two");
    let full = world.state_bytes().to_vec();
    assert_eq!(
        world.add_collider(&ColliderDef::DEFAULT),
        Err(Error::ColliderCapacityExceeded)
    );
    assert_eq!(world.set_collider(1, &bad[0]), Err(Error::InvalidEffect));
    assert!(world.state_bytes() == full.as_slice());
    // None declared: nothing to add to.
    def.effects.collider_capacity = 0;
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    assert_eq!(
        world.add_collider(&ColliderDef::DEFAULT),
        Err(Error::EffectNotDeclared)
    );
}

/// A spinning axle drags an elastic load: the torque read back is the load's rate of change
/// of angular momentum. A stick cylinder of radius 0.05 m (a circle in 2D) at the centre of
/// a disk of load spins up to 8 rad/s over 0.05 s, without gravity or walls; APIC, whose
/// transfer conserves angular momentum (E85), with the quadratic B-spline. The angular
/// impulses read back over 0.1 s, moved to the origin (`L_c + c x J`), equal minus the
/// change of the load's angular momentum within 3 % (the grid's change is the impulse's sum
/// to round-off; the 3 % is what the particle update's transfer of it loses).
#[test]
fn a_spinning_axle_turns_its_load_by_the_torque_it_reads_back() {
    let mut def = def(Vec3::ZERO, 0.0);
    def.shape = mpm_gimp::ShapeFunction::QuadraticBspline;
    def.transfer = mpm_gimp::Transfer::Apic;
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    let m = world.add_material(&BLOCK).expect("material");
    let centre = Vec3::new(0.5, 0.5, 0.0);
    world.fill_disk(centre, 0.25, m, Vec3::ZERO).expect("load");
    let axle = |omega: Real| ColliderDef {
        shape: ColliderShape::Cylinder {
            half_length: 1.0,
            radius: 0.05,
            inner_radius: 0.0,
        },
        position: centre,
        angular_velocity: Vec3::new(0.0, 0.0, omega),
        contact: Contact::Stick,
        ..ColliderDef::DEFAULT
    };
    // The cylinder's axis along the frame's y: turned to z, its section in the plane is a
    // circle. (A quarter turn about x: (sin 45, 0, 0, cos 45).)
    let turn = [
        std::f64::consts::FRAC_1_SQRT_2 as Real,
        0.0,
        0.0,
        std::f64::consts::FRAC_1_SQRT_2 as Real,
    ];
    let id = world
        .add_collider(&ColliderDef {
            rotation: turn,
            ..axle(0.0)
        })
        .expect("axle");
    let l0 = world.diagnostics().angular_momentum[2];
    let mut angular = 0.0f64;
    let dt = world.stable_dt();
    while world.time() < 0.1 {
        let omega = 8.0 * (world.time() / 0.05).min(1.0) as Real;
        let now = world.collider(id).expect("axle").def;
        world
            .set_collider(
                id,
                &ColliderDef {
                    rotation: now.rotation,
                    ..axle(omega)
                },
            )
            .expect("spin");
        world.step(dt).expect("step");
        let c = world.collider(id).expect("axle");
        // About the origin: the angular impulse about the axle's centre plus c x J.
        let j = c.impulse;
        angular += c.angular_impulse.z as f64 + (centre.x * j.y - centre.y * j.x) as f64;
    }
    let change = world.diagnostics().angular_momentum[2] - l0;
    assert!(change > 0.0, "the load turned ({change})");
    assert!(
        (change + angular).abs() < 0.03 * change,
        "the load gained {change} kg m^2/s; the axle read back {angular}"
    );
}

/// A piston (a box collider, slip contact, its speed ramped to 0.1 m/s over 0.1 s so that it
/// sends no strong wave) compresses a column between frictionless walls on a frictionless
/// floor, without gravity, by 5 %: the work the piston does, from the impulses read back,
/// `sum J_y v`, equals the column's strain plus kinetic energy within 2 % (the continuum's
/// balance; the 2 % for the transfers' energy error), and the deformation is homogeneous
/// below the contact layer: every particle more than three cells below the piston has `H_yy`
/// within 10 % of their mean, which is at least 80 % of the piston's travel over the
/// column's height (the layer next to the piston takes the rest).
#[test]
fn a_piston_does_the_work_the_column_stores() {
    let mut def = def(Vec3::ZERO, 0.0);
    for face in [Face::XMin, Face::XMax, Face::YMin] {
        def.faces[face as usize] = Boundary::Slip;
    }
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    let m = world
        .add_material(&MaterialDef {
            youngs_modulus: 1.0e5,
            ..MaterialDef::DEFAULT
        })
        .expect("material");
    // The walls' planes are a margin inside the grid's faces.
    let margin = def.shape.margin_cells() as Real * def.cell_size;
    let (bottom, top) = (margin, 0.5);
    world
        .fill_box(
            Vec3::new(margin, bottom, 0.0),
            Vec3::new(1.0 - margin, top, 0.0),
            m,
            Vec3::ZERO,
        )
        .expect("column");
    let speed: Real = 0.1;
    world
        .add_collider(&ColliderDef {
            shape: ColliderShape::Box {
                half_extents: Vec3::new(1.0, 0.1, 1.0),
            },
            position: Vec3::new(0.5, top + 0.1, 0.0),
            velocity: Vec3::new(0.0, -speed, 0.0),
            contact: Contact::Slip,
            ..ColliderDef::DEFAULT
        })
        .expect("piston");
    let height = top - bottom;
    let ramp: Real = 0.1;
    let travel = |t: Real| {
        speed
            * if t < ramp {
                0.5 * t * t / ramp
            } else {
                t - 0.5 * ramp
            }
    };
    let mut work = 0.0f64;
    let dt = world.stable_dt();
    while travel(world.time() as Real) < 0.05 * height {
        let v = speed * (world.time() as Real / ramp).min(1.0);
        let mut piston = world.collider(0).expect("piston").def;
        piston.velocity = Vec3::new(0.0, -v, 0.0);
        world.set_collider(0, &piston).expect("move");
        world.step(dt).expect("step");
        work += world.collider(0).expect("piston").impulse.y as f64 * v as f64;
    }
    let d = world.diagnostics();
    let stored = d.strain + d.kinetic;
    assert!(
        (work - stored).abs() < 0.02 * stored,
        "the piston did {work} J/m, the column holds {stored} ({} strain, {} kinetic)",
        d.strain,
        d.kinetic
    );
    // Homogeneous below the contact layer: the piston acts on the nodes inside it, so the
    // particles near it (measured: the three cells below its face, `H_yy` from -0.024 to
    // -0.128 where the rest is at -0.043) take more of the compression than the rest (a known
    // limit of grid contact: README, "Known limits").
    let p = world.particles();
    let face = world.collider(0).expect("piston").def.position.y - 0.1;
    let below: Vec<Real> = (0..p.count)
        .filter(|&i| p.position[1][i] < face - 3.0 * def.cell_size)
        .map(|i| p.displacement_gradient[1][1][i])
        .collect();
    let mean = below.iter().sum::<Real>() / below.len() as Real;
    let worst = below.iter().map(|h| (h - mean).abs()).fold(0.0, Real::max);
    assert!(
        worst < 0.1 * mean.abs(),
        "H_yy off its mean {mean} by up to {worst} below the contact layer"
    );
    let travel = (top - face) / height;
    assert!(
        mean < -0.8 * travel,
        "the column compressed by {mean}, the piston {travel}"
    );
}

/// A moving wall (E94): a block resting on a stick floor that moves at 0.5 m/s along x (a
/// conveyor) is carried at the floor's speed: its mean velocity, averaged over the last 0.1 s
/// of 0.4 s (its elastic shear rings about it), within 3 % of 0.5 m/s.
#[test]
fn a_moving_stick_floor_carries_a_block_at_its_speed() {
    let mut def = def(Vec3::new(0.0, -G, 0.0), 0.0);
    def.effects.collider_capacity = 0;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.wall_velocity[Face::YMin as usize] = Vec3::new(0.5, 0.0, 0.0);
    def.origin.y = 0.25 - def.shape.margin_cells() as Real * def.cell_size;
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    let m = world.add_material(&BLOCK).expect("material");
    world
        .fill_box(
            Vec3::new(0.2, 0.25, 0.0),
            Vec3::new(0.4, 0.35, 0.0),
            m,
            Vec3::ZERO,
        )
        .expect("block");
    let dt = world.stable_dt();
    let (mut sum, mut time) = (0.0f64, 0.0f64);
    while world.time() < 0.4 {
        world.step(dt).expect("step");
        if world.time() > 0.3 {
            sum += mean_vx(&world) as f64 * dt as f64;
            time += dt as f64;
        }
    }
    let v = sum / time;
    assert!((v - 0.5).abs() < 0.03 * 0.5, "the block moves at {v} m/s");
}

/// A distance field collider (`ColliderShape::Sdf`): sampled from a circle of radius 0.2 m
/// every 0.01 m, it answers the circle's distance within the bilinear interpolation's error
/// bound, `h^2 / 8 (|f_xx| + |f_yy|)` = `h^2 / (8 r)` for `f = r - R`, at 1000 points from
/// r = 0.05 m out (2.9e-4 m in the cells there; 1e-6 m more for f32's rounding); a floor sampled from the half-space `y < 0` carries a resting
/// block's weight within 1 %, as the analytic floor does.
#[test]
fn a_distance_field_collider_is_the_solid_it_samples() {
    let mut def = def(Vec3::new(0.0, -G, 0.0), 30.0);
    def.effects.sdf_capacity = 4096;
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    // The circle, 61 x 61 samples 0.01 m apart about its centre.
    let (n, h, r) = (61usize, 0.01 as Real, 0.2 as Real);
    let half = 0.5 * (n - 1) as Real * h;
    let circle: Vec<Real> = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as Real * h - half, (k / n) as Real * h - half);
            (x * x + y * y).sqrt() - r
        })
        .collect();
    let first = world.add_distance_field(&circle).expect("samples");
    let centre = Vec3::new(0.5, 0.7, 0.0);
    let ball = world
        .add_collider(&ColliderDef {
            shape: ColliderShape::Sdf {
                first,
                dims: [n as u32, n as u32, 1],
                spacing: h,
            },
            position: centre,
            ..ColliderDef::DEFAULT
        })
        .expect("ball");
    let mut worst: Real = 0.0;
    for k in 0..1000 {
        let (a, d) = (k as Real * 2.399, 0.05 + 0.2 * (k % 10) as Real / 10.0);
        let p = centre + Vec3::new(d * a.cos(), d * a.sin(), 0.0);
        let got = world.collider_distance(ball, p).expect("distance");
        worst = worst.max((got - ((p - centre).length() - r)).abs());
    }
    // The nearest cells reach in to r = 0.05 - h / sqrt 2.
    let bound = h * h / (8.0 * (0.05 - h * std::f64::consts::FRAC_1_SQRT_2 as Real)) + 1.0e-6;
    assert!(
        worst < bound,
        "distance off the circle's by up to {worst} m (bound {bound})"
    );
    // A floor: the half-space below y = 0.25 sampled as `phi = y` on 41 x 9 points.
    let floor: Vec<Real> = (0..41 * 9)
        .map(|k| (k / 41) as Real * 0.025 - 0.1)
        .collect();
    let first = world.add_distance_field(&floor).expect("samples");
    world
        .add_collider(&ColliderDef {
            shape: ColliderShape::Sdf {
                first,
                dims: [41, 9, 1],
                spacing: 0.025,
            },
            position: Vec3::new(0.5, 0.25, 0.0),
            ..ColliderDef::DEFAULT
        })
        .expect("floor");
    let m = world.add_material(&BLOCK).expect("material");
    world
        .fill_box(
            Vec3::new(0.3, 0.25, 0.0),
            Vec3::new(0.7, 0.45, 0.0),
            m,
            Vec3::ZERO,
        )
        .expect("block");
    let mass: Real = world.particles().mass.iter().sum();
    let force = settled_force(&mut world, 1);
    assert!(
        (force.y + mass * G).abs() < 0.01 * mass * G,
        "force {force:?} against the weight {}",
        mass * G
    );
    // Misuse: a field past the samples added, samples not finite, past the capacity.
    let past = ColliderDef {
        shape: ColliderShape::Sdf {
            first: 4000,
            dims: [10, 10, 1],
            spacing: 0.01,
        },
        ..ColliderDef::DEFAULT
    };
    let before = world.state_bytes().to_vec();
    assert_eq!(world.set_collider(1, &past), Err(Error::InvalidEffect));
    assert_eq!(
        world.add_distance_field(&[0.0, Real::NAN]),
        Err(Error::NonFiniteInput)
    );
    assert_eq!(
        world.add_distance_field(&[0.0; 1000]),
        Err(Error::InvalidCapacity)
    );
    assert!(world.state_bytes() == before.as_slice());
}

/// Hertz: a rigid, frictionless sphere (radius `R` = 0.5 m, separating contact) pressed at
/// 0.2 m/s (0.5 % of the wave speed: quasi-static) into an elastic half-space (corotated
/// linear, E = 1 MPa, nu = 0.3), axisymmetric, carries the load `F = 4/3 E* sqrt(R) d^1.5`,
/// `E* = E / (1 - nu^2)`, at depth `d`. The force is read back per radian (times 2 pi), as
/// the mean over each 5 mm of travel against Hertz's mean over it; the depth is the sphere's
/// below the surface, where contact begins (the first impulse comes within 1e-4 m of it).
/// Within 10 % where the contact radius `sqrt(R d)` spans at least 7 cells (measured 6.6 %,
/// 3.2 % and 1.8 % from 7.5 to 8.8 cells, h = 1/64 m): shallower, the grid contact reads
/// stiffer (13 to 33 % at 1.5 to 6 cells; the nodes at the contact's edge, README "Known
/// limits"). The half-space is a block 2 m wide and deep, at least 15 contact radii, on a
/// stick floor with slip sides (a 1 m block reads 7 % stiffer at the deepest bin).
#[test]
fn a_sphere_pressed_into_an_elastic_half_space_follows_hertz() {
    use mpm_gimp::{Dimension, MaterialModel};
    let (n, size, radius, speed) = (64u32, 2.0 as Real, 0.5 as Real, 0.2 as Real);
    let h = 1.0 / n as Real;
    let cells = (size * n as Real) as u32;
    let mut def = WorldDef {
        dimension: Dimension::Axisymmetric2D,
        cells: [cells + 2, cells + 4, 1],
        cell_size: h,
        // The axis r = 0 and the floor on the wall planes, a margin in.
        origin: Vec3::new(-h, -h, 0.0),
        particle_capacity: 4 * cells * cells,
        gravity: Vec3::ZERO,
        effects: Effects {
            collider_capacity: 1,
            damping: Some(Damping {
                grid: Schedule::constant(5.0),
                ..Damping::NONE
            }),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    def.faces[Face::XMin as usize] = Boundary::Slip;
    def.faces[Face::XMax as usize] = Boundary::Slip;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.faces[Face::YMax as usize] = Boundary::Open;
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
    let material = MaterialDef {
        model: MaterialModel::LinearElastic,
        youngs_modulus: 1.0e6,
        poisson_ratio: 0.3,
        ..MaterialDef::DEFAULT
    };
    let m = world.add_material(&material).expect("material");
    world
        .fill_box(Vec3::ZERO, Vec3::new(size, size, 0.0), m, Vec3::ZERO)
        .expect("half-space");
    world
        .add_collider(&ColliderDef {
            shape: ColliderShape::Sphere { radius },
            position: Vec3::new(0.0, size + radius + 0.5 * h, 0.0),
            velocity: Vec3::new(0.0, -speed, 0.0),
            contact: Contact::Separate,
            ..ColliderDef::DEFAULT
        })
        .expect("sphere");
    let nu = material.poisson_ratio as f64;
    let e_star = material.youngs_modulus as f64 / (1.0 - nu * nu);
    let k = 4.0 / 3.0 * e_star * (radius as f64).sqrt();
    // Hertz's mean force over depths d0..d1 (the integral of `k d^1.5`).
    let hertz_mean = |d0: f64, d1: f64| 0.4 * k * (d1.powf(2.5) - d0.powf(2.5)) / (d1 - d0);
    let depth = |w: &World<'_>| {
        (size + radius) as f64 - w.collider(0).expect("sphere").def.position.y as f64
    };
    let dt = world.stable_dt();
    // Bins of 5 mm of travel from the surface (the force is zero above it).
    let (mut impulse, mut duration, mut from) = (0.0f64, 0.0f64, 0.0f64);
    let mut first_contact = None;
    let mut checked = 0;
    while depth(&world) < 0.041 {
        world.step(dt).expect("step");
        let c = world.collider(0).expect("sphere");
        let d = depth(&world);
        if first_contact.is_none() && c.impulse.y != 0.0 {
            first_contact = Some(d);
        }
        impulse += c.impulse.y as f64;
        duration += c.duration as f64;
        if d >= from + 0.005 {
            let (force, want) = (
                2.0 * std::f64::consts::PI * impulse / duration,
                hertz_mean(from.max(0.0), d),
            );
            let cells_wide = (radius as f64 * 0.5 * (from + d)).sqrt() / h as f64;
            if cells_wide >= 7.0 {
                assert!(
                    (force / want - 1.0).abs() < 0.1,
                    "depth {from:.4} to {d:.4} m: {force:.1} N, Hertz {want:.1} N"
                );
                checked += 1;
            }
            (impulse, duration, from) = (0.0, 0.0, d);
        }
    }
    assert!(
        checked >= 3,
        "only {checked} depths with a contact 7 cells wide"
    );
    let first = first_contact.expect("the sphere never touched");
    assert!(first.abs() < 1.0e-4, "contact began at depth {first} m");
}

/// XPIC(3) and FMPM(2) (E98-E101) keep a collider's contact: a block thrown at 0.5 m/s onto a
/// floor collider under gravity, its bottom layer of particles on the floor, in 2D, the
/// axisymmetric form and 3D, every update order each transfer takes, with a slip floor and
/// a separating one. The floor's plane lies half-way between two node lines, so a particle
/// within its half-width `l_p` of the plane reads only nodes inside the floor or within the
/// contact band above it (E91), which the contact leaves at no velocity into the floor (E92):
/// after every step a particle that was there when it began, whose new velocity is the
/// grid's at its place then (E100, E101), has
/// `v_y >= -64 eps |v|_max` (round-off of `v + a dt` summed over its stencil). The series mixes
/// the velocities of the nodes above into those in contact; before the colliders acted
/// again on its result, the bottom layer moved into the floor at 0.06 to 0.19 times the
/// largest particle speed (f32, by run).
#[test]
fn xpic_and_fmpm_keep_a_floor_colliders_contact() {
    use mpm_gimp::{Dimension, Transfer, UpdateOrder};
    let h: Real = 1.0 / 16.0;
    let floor_y = 4.5 * h;
    let lp = h / 4.0;
    let runs = [
        (Transfer::Xpic(3), UpdateOrder::Usl),
        (Transfer::Xpic(3), UpdateOrder::Usf),
        (Transfer::Xpic(3), UpdateOrder::Musl),
        (Transfer::Fmpm(2), UpdateOrder::Usf),
        (Transfer::Fmpm(2), UpdateOrder::Musl),
    ];
    for dim in [
        Dimension::Plane2D,
        Dimension::Axisymmetric2D,
        Dimension::ThreeD,
    ] {
        for (transfer, order) in runs {
            for contact in [Contact::Slip, Contact::Separate] {
                let mut def = WorldDef {
                    transfer,
                    update_order: order,
                    gravity: Vec3::new(0.0, -G, 0.0),
                    effects: Effects {
                        collider_capacity: 1,
                        ..Effects::NONE
                    },
                    ..crate::common::free_space(dim, 16, h)
                };
                if dim == Dimension::Axisymmetric2D {
                    // The axis r = 0 on the lower x face's wall plane.
                    def.origin.x = -h;
                    def.faces[Face::XMin as usize] = Boundary::Slip;
                }
                let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
                let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
                let m = world.add_material(&BLOCK).expect("material");
                world
                    .add_collider(&ColliderDef {
                        position: Vec3::new(0.0, floor_y, 0.0),
                        contact,
                        ..ColliderDef::DEFAULT
                    })
                    .expect("floor");
                let z = |z: Real| if dim == Dimension::ThreeD { z } else { 0.0 };
                world
                    .fill_box(
                        Vec3::new(0.3, floor_y, z(0.3)),
                        Vec3::new(0.7, floor_y + 0.2, z(0.7)),
                        m,
                        Vec3::new(0.0, -0.5, 0.0),
                    )
                    .expect("block");
                let mut checked = 0;
                for step in 0..40 {
                    // The stencils a particle reads are those of where the step starts.
                    let start = world.particles().position[1].to_vec();
                    world.step(world.stable_dt()).expect("step");
                    let p = world.particles();
                    let speed = (0..p.count)
                        .map(|i| p.velocity[1][i].abs().max(p.velocity[0][i].abs()))
                        .fold(0.0, Real::max);
                    let tol = 64.0 * Real::EPSILON * speed;
                    for (&y, &v) in start.iter().zip(p.velocity[1]) {
                        if y - floor_y > lp {
                            continue;
                        }
                        checked += 1;
                        assert!(
                            v >= -tol,
                            "{dim:?} {transfer:?} {order:?} {contact:?}, step {step}: a \
                             particle {} above the floor moves into it at {v} m/s (block's \
                             speed {speed})",
                            y - floor_y
                        );
                    }
                }
                assert!(
                    checked > 0,
                    "{dim:?} {transfer:?} {order:?} {contact:?}: no contact"
                );
            }
        }
    }
}

/// `Removal::Collider` takes the particles whose domains (squares, cubes in 3D, of half-width
/// `l = h / 4`) reach into a solid or touch it, in 2D and 3D:
/// - an axis-aligned box: exactly the particles whose domain overlaps the closed box (by
///   brute force over the domains, the box's faces put between domain edges so that no
///   particle lies within 1e-3 h of the choice), and, with its faces on domain edges, the
///   rows that only touch it as well;
/// - a tilted box and a sphere: at least every particle with one of 9^d points of its domain
///   inside the solid, and none whose centre lies farther than `l sqrt(d)` from it (a domain
///   reaches no farther);
/// - an unknown id: `UnknownCollider`, the world unchanged.
#[test]
fn a_collider_removes_the_material_it_displaces() {
    for three_d in [false, true] {
        let d = if three_d { 3 } else { 2 };
        let mut def = def(Vec3::ZERO, 0.0);
        if three_d {
            def.dimension = mpm_gimp::Dimension::ThreeD;
            def.cells = [16; 3];
            def.cell_size = 1.0 / 16.0;
            def.particle_capacity = 40_000;
        }
        let (h, l) = (def.cell_size, def.cell_size / 4.0);
        let bytes = memory_requirements(&def).expect("valid").bytes;
        let z = |v: Real| if three_d { v } else { 0.0 };
        let boxed = |centre: Vec3, half: Vec3, angle: Real| ColliderDef {
            shape: ColliderShape::Box { half_extents: half },
            position: centre,
            rotation: [0.0, 0.0, (angle / 2.0).sin(), (angle / 2.0).cos()],
            ..ColliderDef::DEFAULT
        };
        // Each case: the solid, and whether particle centre x must go (`Some`) or is left to
        // the bounds (`None`).
        type Decide = Box<dyn Fn([Real; 3]) -> Option<bool>>;
        let exact = |lo: [Real; 3], hi: [Real; 3]| -> Decide {
            Box::new(move |x| Some((0..d).all(|a| x[a] + l >= lo[a] && x[a] - l <= hi[a])))
        };
        let (lo, hi) = ([0.4137, 0.3311, z(0.3719)], [0.6291, 0.5573, z(0.6043)]);
        let mid = |a: usize| (lo[a] + hi[a]) / 2.0;
        let half = |a: usize| (hi[a] - lo[a]) / 2.0;
        // Domain edges of the lattice `fill_box` lays from 0.25: multiples of h / 2 from there.
        let (elo, ehi) = ([0.375, 0.3125, z(0.375)], [0.625, 0.5625, z(0.625)]);
        let cases: Vec<(ColliderDef, Decide)> = vec![
            (
                boxed(
                    Vec3::new(mid(0), mid(1), z(mid(2))),
                    Vec3::new(half(0), half(1), z(half(2)).max(0.1)),
                    0.0,
                ),
                exact(lo, hi),
            ),
            (
                boxed(
                    Vec3::new(0.5, (elo[1] + ehi[1]) / 2.0, z(0.5)),
                    Vec3::new(0.125, (ehi[1] - elo[1]) / 2.0, z(0.125).max(0.1)),
                    0.0,
                ),
                // Domains that touch a face only are taken too.
                exact(elo, ehi),
            ),
            (
                boxed(
                    Vec3::new(0.5, 0.45, z(0.5)),
                    Vec3::new(0.1, 0.07, 0.08),
                    0.3,
                ),
                Box::new(|_| None),
            ),
            (
                ColliderDef {
                    shape: ColliderShape::Sphere { radius: 0.13 },
                    position: Vec3::new(0.52, 0.47, z(0.49)),
                    ..ColliderDef::DEFAULT
                },
                Box::new(|_| None),
            ),
        ];
        for (k, (solid, decide)) in cases.into_iter().enumerate() {
            let case = format!("{d}D case {k}");
            let mut buf = HeapBuffer::new(bytes);
            let mut world = World::init(&def, buf.as_mut_bytes()).expect("init");
            let m = world.add_material(&BLOCK).expect("material");
            world
                .fill_box(
                    Vec3::new(0.25, 0.25, z(0.25)),
                    Vec3::new(0.75, 0.75, z(0.75)),
                    m,
                    Vec3::ZERO,
                )
                .expect("block");
            let id = world.add_collider(&solid).expect("solid");
            let before = world.state_bytes().to_vec();
            assert_eq!(
                world.remove_particles(mpm_gimp::Removal::Collider(id + 1)),
                Err(Error::UnknownCollider),
                "{case}"
            );
            assert!(
                world.state_bytes() == &before[..],
                "{case}: refused, yet changed"
            );
            let p = world.particles();
            let centres: Vec<[Real; 3]> = (0..p.count)
                .map(|i| core::array::from_fn(|a| if a < d { p.position[a][i] } else { 0.0 }))
                .collect();
            let distance = |x: [Real; 3]| {
                world
                    .collider_distance(id, Vec3::new(x[0], x[1], x[2]))
                    .expect("distance")
            };
            let mut must_go = Vec::new();
            let mut may_go = Vec::new();
            for x in &centres {
                match decide(*x) {
                    Some(go) => {
                        // No particle on the edge of the choice, but those meant to touch.
                        must_go.push(go);
                        may_go.push(go);
                    }
                    None => {
                        let n = 9usize;
                        let at = |j: usize| (j as Real / (n - 1) as Real * 2.0 - 1.0) * l;
                        let inside = (0..n.pow(d as u32)).any(|s| {
                            let q: [Real; 3] = core::array::from_fn(|a| {
                                if a < d {
                                    x[a] + at(s / n.pow(a as u32) % n)
                                } else {
                                    0.0
                                }
                            });
                            distance(q) <= 0.0
                        });
                        must_go.push(inside);
                        may_go.push(distance(*x) <= l * (d as Real).sqrt() + h / 1024.0);
                    }
                }
            }
            let taken = must_go.iter().filter(|&&g| g).count();
            assert!(
                taken > 0 && taken < centres.len(),
                "{case}: {taken} to take"
            );
            let removed = world
                .remove_particles(mpm_gimp::Removal::Collider(id))
                .expect("removed");
            // Which went: the survivors keep their order, so match them in turn.
            let p = world.particles();
            let mut next = 0;
            let mut went = vec![true; centres.len()];
            for i in 0..p.count {
                while (0..d).any(|a| centres[next][a] != p.position[a][i]) {
                    next += 1;
                }
                went[next] = false;
                next += 1;
            }
            assert_eq!(removed, went.iter().filter(|&&g| g).count(), "{case}");
            for (i, x) in centres.iter().enumerate() {
                assert!(
                    !must_go[i] || went[i],
                    "{case}: particle at {x:?} reaches the solid and stayed"
                );
                assert!(
                    !went[i] || may_go[i],
                    "{case}: particle at {x:?} cannot reach the solid and went"
                );
            }
        }
    }
}
