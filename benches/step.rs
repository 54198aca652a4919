//! Criterion benches of a whole `World::step` (one substep), reported per particle
//! (`Throughput::Elements`), so criterion prints particle-steps per second.
//!
//! - `step_shape_2d/<shape>` and `step_shape_3d/<shape>`: 32768 particles, default update order
//!   (MUSL), for each shape function.
//! - `step_order_gimp_2d/<order>`: 32768 particles, uGIMP, for each update order.
//! - `phase_gimp_2d/<phase>` and `phase_gimp_3d/<phase>`: each phase of a USL step alone
//!   (reset, particle to grid, grid update, grid to particle), through the hidden
//!   `World::run_phase` hook, so the phases' costs add up to a USL step.
//! - `step_effect_gimp_2d/<effect>`: 32768 particles, uGIMP, MUSL, with no effect and with each
//!   effect declared alone (`benches/common/scene.rs`), to price each one (`thermal_expansion`
//!   declares heat conduction too; `axisymmetric` makes the scene axisymmetric).
//!
//! Only `step` (or the phase) is timed (`iter_custom`): the `stable_dt` call that picks each
//! step's `dt` is outside the measurement.
//!
//! `cargo bench --bench step` (add `-- <filter>` to run a subset).

use criterion::measurement::WallTime;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, Throughput,
};
use mpm_gimp::{Dimension, MaterialModel, Phase, ShapeFunction, UpdateOrder, World, WorldDef};
use std::hint::black_box;
use std::time::{Duration, Instant};

#[path = "common/scene.rs"]
mod scene;
use scene::{Effect, Scene, SceneDef};

const SHAPES: [(ShapeFunction, &str); 5] = [
    (ShapeFunction::Linear, "linear"),
    (ShapeFunction::Gimp, "gimp"),
    (ShapeFunction::QuadraticBspline, "quadratic"),
    (ShapeFunction::CubicBspline, "cubic"),
    (ShapeFunction::CpGimp, "cpgimp"),
];

const ORDERS: [(UpdateOrder, &str); 3] = [
    (UpdateOrder::Usf, "usf"),
    (UpdateOrder::Usl, "usl"),
    (UpdateOrder::Musl, "musl"),
];

/// 2D: 32768 particles, a 128 x 64 cell block in a 132 x 68 grid.
fn plane(shape: ShapeFunction, order: UpdateOrder) -> Scene {
    plane_with(shape, order, Effect::None)
}

/// [`plane`] with `effect` declared.
fn plane_with(shape: ShapeFunction, order: UpdateOrder, effect: Effect) -> Scene {
    Scene::new(&SceneDef {
        dimension: Dimension::Plane2D,
        shape,
        material: MaterialModel::NeoHookean,
        order,
        grid: [132, 68, 1],
        first: [2, 2, 0],
        block: [128, 64, 1],
        effect,
        ..SceneDef::PLANE_2D
    })
    .expect("the 2D bench scene")
}

/// 3D: 32768 particles, a 16^3 cell block in the middle of a 32^3 grid.
fn solid(shape: ShapeFunction, order: UpdateOrder) -> Scene {
    Scene::new(&SceneDef {
        dimension: Dimension::ThreeD,
        shape,
        material: MaterialModel::NeoHookean,
        order,
        grid: [32, 32, 32],
        first: [8, 8, 8],
        block: [16, 16, 16],
        effect: Effect::None,
        ..SceneDef::PLANE_2D
    })
    .expect("the 3D bench scene")
}

/// Times `iters` steps of `dt = stable_dt()` each (one substep), counting only `step`.
fn timed_steps(world: &mut World<'_>, iters: u64) -> Duration {
    let mut total = Duration::ZERO;
    for _ in 0..iters {
        let dt = world.stable_dt();
        let t0 = Instant::now();
        let report = world.step(black_box(dt));
        total += t0.elapsed();
        let report = black_box(report).expect("valid dt");
        assert_eq!(report.substeps, 1);
    }
    total
}

fn configure<'c>(c: &'c mut Criterion, name: &str) -> BenchmarkGroup<'c, WallTime> {
    let mut group = c.benchmark_group(name);
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(10);
    group
}

fn bench_shapes(c: &mut Criterion) {
    for (group_name, three_d) in [("step_shape_2d", false), ("step_shape_3d", true)] {
        let mut group = configure(c, group_name);
        for (shape, name) in SHAPES {
            let order = WorldDef::DEFAULT.update_order;
            let mut scene = if three_d {
                solid(shape, order)
            } else {
                plane(shape, order)
            };
            group.throughput(Throughput::Elements(scene.particles as u64));
            let mut world = scene.world();
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter_custom(|iters| timed_steps(&mut world, iters))
            });
        }
        group.finish();
    }
}

fn bench_orders(c: &mut Criterion) {
    let mut group = configure(c, "step_order_gimp_2d");
    for (order, name) in ORDERS {
        let mut scene = plane(ShapeFunction::Gimp, order);
        group.throughput(Throughput::Elements(scene.particles as u64));
        let mut world = scene.world();
        group.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter_custom(|iters| timed_steps(&mut world, iters))
        });
    }
    group.finish();
}

fn bench_effects(c: &mut Criterion) {
    let mut group = configure(c, "step_effect_gimp_2d");
    for (effect, name) in Effect::ALL {
        let mut scene = plane_with(ShapeFunction::Gimp, UpdateOrder::Musl, effect);
        group.throughput(Throughput::Elements(scene.particles as u64));
        let mut world = scene.world();
        group.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter_custom(|iters| timed_steps(&mut world, iters))
        });
    }
    group.finish();
}

const PHASES: [(Phase, &str); 4] = [
    (Phase::ResetGrid, "reset_grid"),
    (Phase::ParticleToGrid, "particle_to_grid"),
    (Phase::GridUpdate, "grid_update"),
    (Phase::GridToParticle, "grid_to_particle"),
];

/// Each phase of a USL step on its own. The grid is filled once (scatter and grid update) so
/// that the grid update and grid-to-particle phases read a real grid; particles then move on
/// that grid, which is fine for timing and keeps the state finite (slip walls hold them).
fn bench_phases(c: &mut Criterion) {
    for (group_name, three_d) in [("phase_gimp_2d", false), ("phase_gimp_3d", true)] {
        let mut group = configure(c, group_name);
        let order = UpdateOrder::Usl;
        let mut scene = if three_d {
            solid(ShapeFunction::Gimp, order)
        } else {
            plane(ShapeFunction::Gimp, order)
        };
        group.throughput(Throughput::Elements(scene.particles as u64));
        let mut world = scene.world();
        let dt = world.stable_dt();
        world
            .run_phase(Phase::ParticleToGrid, dt)
            .expect("valid dt");
        world.run_phase(Phase::GridUpdate, dt).expect("valid dt");
        for (phase, name) in PHASES {
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| black_box(world.run_phase(black_box(phase), dt)))
            });
        }
        group.finish();
    }
}

criterion_group!(
    benches,
    bench_shapes,
    bench_orders,
    bench_phases,
    bench_effects
);
criterion_main!(benches);
