//! How a step is timed, shared by the cost example (`examples/step_cost.rs`) and the accuracy
//! report (`examples/accuracy_cost`), which include this file with `#[path]`: the same warm-up,
//! the same runs, the same reference workload, so their nanoseconds per particle-step compare.

use mpm_gimp::simd::Simd;
use mpm_gimp::{TaskSystem, World};
use std::time::{Duration, Instant};

/// Warm-up steps before the timed runs.
pub const WARMUP_STEPS: u32 = 3;

/// The figures of one timing.
pub struct Timing {
    /// Nanoseconds per particle-step of each run, in run order.
    pub runs: Vec<f64>,
    /// Median of `runs`.
    pub median: f64,
    /// Median of the reference workload's ns per particle, timed right before each run.
    pub reference: f64,
    /// Wall time of the whole timing, warm-up included.
    pub wall: Duration,
}

/// Times `world.step(world.stable_dt())` on the instance `simd` and the task system `tasks`
/// (`&mpm_gimp::Serial`: the calling thread, as `World::step`): `WARMUP_STEPS` untimed steps,
/// then `runs` runs of `steps` steps; only the `step` call is timed, in wall time (on several
/// workers too). Each step must take exactly one substep and freeze no particle (the scene is
/// at rest but for a gentle motion).
pub fn time_steps(
    world: &mut World<'_>,
    particles: u32,
    runs: u32,
    steps: u32,
    simd: Simd,
    tasks: &dyn TaskSystem,
) -> Timing {
    let step = |world: &mut World<'_>| -> Duration {
        let dt = world.stable_dt();
        let t0 = Instant::now();
        let report = world.step_on(dt, simd, tasks);
        let elapsed = t0.elapsed();
        let report = report.expect("stable dt is a valid time step");
        assert_eq!(report.substeps, 1, "dt = stable_dt() must take one substep");
        assert_eq!(report.frozen, 0, "no particle may freeze in this scene");
        elapsed
    };
    let wall = Instant::now();
    for _ in 0..WARMUP_STEPS {
        step(world);
    }
    // The machine is shared: each run is paired with a fixed reference workload timed right
    // before it, so that figures from different runs can be compared through their ratio.
    let mut times = Vec::with_capacity(runs as usize);
    let mut refs = Vec::with_capacity(runs as usize);
    for _ in 0..runs {
        refs.push(reference_ns_per_particle(particles as usize));
        let mut elapsed = Duration::ZERO;
        for _ in 0..steps {
            elapsed += step(world);
        }
        times.push(elapsed.as_nanos() as f64 / (steps as f64 * particles as f64));
    }
    Timing {
        median: median(&times),
        reference: median(&refs),
        runs: times,
        wall: wall.elapsed(),
    }
}

/// Median of `values` (any order; not empty).
pub fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    }
}

/// The reference workload: a fixed scalar computation per particle (a 32-term polynomial by
/// Horner's rule, a dependent chain of 32 multiply-adds, over 4 interleaved streams), in ns per
/// particle. It does not depend on the kernel, so its time tracks only the machine's speed at
/// that moment.
pub fn reference_ns_per_particle(particles: usize) -> f64 {
    let xs: Vec<f64> = (0..particles).map(|i| (i % 1024) as f64 * 1.0e-3).collect();
    let t0 = Instant::now();
    let mut acc = [0.0f64; 4];
    for chunk in xs.chunks_exact(4) {
        for (a, &x) in acc.iter_mut().zip(chunk) {
            let mut p = 1.0f64;
            for k in 0..32 {
                p = p * x + (k as f64) * 1.0e-3;
            }
            *a += p;
        }
    }
    std::hint::black_box(acc);
    t0.elapsed().as_nanos() as f64 / particles as f64
}
