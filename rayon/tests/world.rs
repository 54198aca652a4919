//! Worlds stepped on `RayonTasks` end in the state `World::step` gives, bit for bit, for any
//! number of threads; a world sized for fewer workers than the pool has is refused.

use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Effects, Error, Face, HeapBuffer, MaterialDef,
    MaterialModel, Real, TaskSystem, Transfer, Vec3, World, WorldDef,
};
use mpm_gimp_rayon::RayonTasks;

/// The thread counts the worlds step on; the worlds are sized for [`WORKERS`].
const THREADS: [usize; 6] = [1, 2, 3, 4, 7, 8];
const WORKERS: u32 = 8;
/// Steps of [`DT`] each world takes.
const STEPS: usize = 12;
const DT: Real = 1.0 / 240.0;

/// Adds a scene's material and particles to its world.
type Fill = fn(&mut World);

/// A rubber block falling on a stick floor (2D, FLIP and uGIMP: the kernel's defaults).
fn drop_2d() -> (WorldDef, Fill) {
    let mut def = WorldDef {
        cells: [24, 24, 1],
        cell_size: 0.05,
        particle_capacity: 4096,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    let fill = |world: &mut World| {
        let rubber = world
            .add_material(&MaterialDef {
                youngs_modulus: 2.0e5,
                ..MaterialDef::DEFAULT
            })
            .expect("material");
        world
            .fill_box(
                Vec3::new(0.3, 0.1, 0.0),
                Vec3::new(0.8, 0.5, 0.0),
                rubber,
                Vec3::new(0.5, -2.0, 0.0),
            )
            .expect("block");
    };
    (def, fill)
}

/// Snow thrown at a slip wall in 3D, APIC with quadratic B-splines: plasticity with hardening
/// (the step replans its substeps) and the affine transfer.
fn snow_3d() -> (WorldDef, Fill) {
    let def = WorldDef {
        dimension: Dimension::ThreeD,
        cells: [12, 12, 12],
        cell_size: 0.05,
        particle_capacity: 8192,
        shape: mpm_gimp::ShapeFunction::QuadraticBspline,
        transfer: Transfer::Apic,
        effects: Effects {
            plasticity: true,
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    let fill = |world: &mut World| {
        let snow = world
            .add_material(&MaterialDef {
                model: MaterialModel::Snow,
                youngs_modulus: 1.0e5,
                density: 400.0,
                ..MaterialDef::DEFAULT
            })
            .expect("material");
        world
            .fill_box(
                Vec3::new(0.15, 0.1, 0.15),
                Vec3::new(0.4, 0.35, 0.4),
                snow,
                Vec3::new(3.0, -1.0, 0.5),
            )
            .expect("block");
    };
    (def, fill)
}

/// The state after [`STEPS`] steps, each by `step`.
fn run(
    def: &WorldDef,
    fill: &dyn Fn(&mut World),
    step: &dyn Fn(&mut World) -> Result<(), Error>,
) -> Vec<u8> {
    let mut storage = HeapBuffer::new(memory_requirements(def).expect("valid def").bytes);
    let mut world = World::init(def, storage.as_mut_bytes()).expect("world");
    fill(&mut world);
    assert!(world.particle_count() > 100);
    for _ in 0..STEPS {
        step(&mut world).expect("step");
    }
    world.state_bytes().to_vec()
}

fn serial(def: &WorldDef, fill: &dyn Fn(&mut World)) -> Vec<u8> {
    run(def, fill, &|w| w.step(DT).map(|_| ()))
}

fn on(def: &WorldDef, fill: &dyn Fn(&mut World), tasks: &RayonTasks) -> Vec<u8> {
    run(def, fill, &|w| w.step_with_tasks(DT, tasks).map(|_| ()))
}

#[test]
fn any_thread_count_steps_as_the_serial_step() {
    for (name, scene) in [
        ("drop_2d", drop_2d as fn() -> (WorldDef, Fill)),
        ("snow_3d", snow_3d),
    ] {
        let (mut def, fill) = scene();
        def.workers = WORKERS;
        let reference = serial(&def, &fill);
        for threads in THREADS {
            let tasks = RayonTasks::new(threads).expect("a pool");
            let state = on(&def, &fill, &tasks);
            assert!(
                state == reference,
                "{name}: {threads} threads differ from World::step"
            );
        }
    }
}

/// Inside `install` the pool's other threads take the passes spinning between them: the
/// same bits.
#[test]
fn steps_inside_install_step_as_the_serial_step() {
    let (mut def, fill) = snow_3d();
    def.workers = WORKERS;
    let reference = serial(&def, &fill);
    for threads in THREADS {
        let tasks = RayonTasks::new(threads).expect("a pool");
        let state = tasks.install(|| on(&def, &fill, &tasks));
        assert!(state == reference, "{threads} threads in install differ");
    }
}

#[test]
fn the_global_pool_steps_as_the_serial_step() {
    let tasks = RayonTasks::global();
    let workers = tasks.worker_count() as u32;
    if workers > mpm_gimp::MAX_WORKERS {
        eprintln!("skipped: {workers} threads in rayon's global pool, more than a world takes");
        return;
    }
    let (mut def, fill) = drop_2d();
    def.workers = workers;
    assert!(on(&def, &fill, &tasks) == serial(&def, &fill));
}

#[test]
fn more_threads_than_the_world_has_workers_is_refused() {
    let (mut def, fill) = drop_2d();
    def.workers = 2;
    let mut storage = HeapBuffer::new(memory_requirements(&def).expect("valid def").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("world");
    fill(&mut world);
    let before = world.state_bytes().to_vec();
    let three = RayonTasks::new(3).expect("a pool");
    assert_eq!(
        world.step_with_tasks(DT, &three).map(|_| ()),
        Err(Error::InvalidLimit)
    );
    assert!(
        world.state_bytes() == before,
        "a refused step changed the world"
    );
    let two = RayonTasks::new(2).expect("a pool");
    world.step_with_tasks(DT, &two).expect("two workers");
}
