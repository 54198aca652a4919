//! Cost of one `World::step`, in nanoseconds per particle per step, on a fixed large scene.
//!
//! `cargo run --release --example step_cost -- --dim 2` (or `--dim 3`) prints exactly one JSON
//! line on stdout and a human-readable line with the same numbers on stderr.
//!
//! Scene: a block of elastic material fully filled at 2 particles per cell per axis, at rest but
//! for a uniform downward velocity of 0.1 m/s, under gravity, with slip walls on every face.
//! - 2D: 131072 particles, a block of 256 x 128 cells inside a 260 x 132 grid (one margin cell
//!   per side plus one cell of room).
//! - 3D: 262144 particles, a block of 32^3 cells in the middle of a 64^3 grid.
//!
//! Timing (`benches/common/timing.rs`, shared with the accuracy report): 3 warm-up steps, then `--runs` runs (default 7, at least 5) of `--steps` steps each
//! (default 10). Every step uses `dt = world.stable_dt()`, so it is exactly one substep; only the
//! `step` call is timed (the `stable_dt` evaluation that picks `dt` is not). Reported:
//! `elapsed_ns / (steps * particles)` for each run and their median, and `state_hash`, the
//! FNV-1a hash of the world's state bytes after every step taken (the same for the same
//! options and binary on every instruction set: a refactor that keeps it keeps the results).
//!
//! Options: `--dim 2|3`, `--shape linear|gimp|quadratic|cubic`,
//! `--material neo_hookean|linear_elastic|fixed_corotated|fluid|von_mises|drucker_prager|snow`, `--order usf|usl|musl`, `--runs N`, `--steps S`,
//! `--simd auto|avx2|baseline` (`auto`, the default, is what `World::step` does: the widest
//! instance the CPU has, AVX-512 or AVX2; `avx2` caps it at AVX2; `baseline` forces the SSE2
//! instance, e.g. under valgrind, which cannot decode every AVX instruction). The JSON line
//! says which instance ran (`"simd"`).
//! `--effect none|damping|feedback|local_damping|damping_zones|particle_forces|tractions|body_force|apic|mls|heat|diffusion|thermal_expansion|axisymmetric|colliders|sdf_colliders`
//! declares one effect (see `benches/common/scene.rs`; default none) to price it; the JSON line
//! names it and gives the world's bytes per particle (`benches/effect_cost.sh` tabulates every
//! effect's marginal cost). `thermal_expansion` declares heat conduction too (its cost includes
//! heat's); `axisymmetric` makes the 2D scene axisymmetric (same grid and block, the origin
//! moved so that the block sits at r >= 0) and is 2D only: with `--dim 3` step_cost says so on
//! stderr and exits with code 1. `--grid-scale N` (default 1) puts the same block in the
//! middle of a grid N times larger per axis: what empty grid costs (the grid passes work on
//! the nodes the particles reach). `--shrink N` (default 1; 1, 2, 4 or 8) divides the block's
//! cells per axis by N, the grid shrinking with it (the room around the block stays): N^D
//! times fewer particles, to see what the step costs once its data fits in the caches (3D
//! `--shrink 4`: 4096 particles). `--particle-order fill|rows|shuffled` (default fill) sets the
//! order of the particles in their columns: as `fill_box` writes them (the sites of each
//! stencil bin together, which the scatter sums in runs), lattice rows x fastest (a host that
//! adds its particles row by row), or a fixed random permutation (no runs, no locality).
//! `--threads N` (default 1, at most `mpm_gimp::MAX_WORKERS`) steps on N workers: N > 1 steps
//! with `World::step_with_tasks` on a rayon pool of N threads of its own
//! (`mpm_gimp_rayon::RayonTasks`), the world sized for N workers (`WorldDef::workers`); 1 steps
//! on the calling thread, as `World::step` does. The times are wall time, so with N threads the
//! ns per particle-step fall by up to N. The world's header records the workers it is sized
//! for (and its size, which the parallel step's scratch adds to), so `state_hash` is taken over
//! the state as a world sized for one worker holds it: the same for every N (the parallel
//! step's results are bit-identical), and for N = 1 the plain state bytes' hash as before. The
//! JSON line gives `"threads"`.
//! `--remove none|half|half_rebuilt` (default none; one thread): `half` removes the particles
//! in the block's upper half (`World::remove_particles` with a box) before the timing, and
//! the JSON line gives that call's cost per particle of the world before it
//! (`"removal_ns_per_particle"`); `half_rebuilt` then builds a new world from the remaining
//! particles alone, as a host would add them, and times that one: the same state (the
//! `state_hash` agrees with `half`'s), so the same step cost (`benches/compare.sh` of the two).
//! `--transfer flip|xpicK|fmpmK` (default flip) steps with XPIC(K) or FMPM(K) (their extra
//! projections: `benches/PERFORMANCE.md`, "What an effect costs").
//! `--sort off|on` (default off; one thread): `on` reorders the particles by cell
//! (`World::sort_particles`) once before the timing, as a host does between frames, and the
//! JSON line gives that call's cost per particle (`"sort_ns_per_particle"`); with
//! `--particle-order shuffled`, the mixed scene after a reorder (`benches/sort.sh` tabulates
//! fill, shuffled and shuffled then sorted).
//! Unknown options or values: a message on stderr and exit code 2.

use mpm_gimp::simd::Simd;
use mpm_gimp::{
    memory_requirements, Dimension, HeapBuffer, MaterialModel, ParticleBatch, Real, Removal,
    Serial, ShapeFunction, Transfer, UpdateOrder, Vec3, World, WorldDef, MAX_WORKERS,
};
use mpm_gimp_rayon::RayonTasks;
use std::process::exit;

const USAGE: &str = "usage: step_cost [--dim 2|3] [--shape linear|gimp|quadratic|cubic] \
[--material neo_hookean|linear_elastic|fixed_corotated|fluid|von_mises|drucker_prager|snow] [--order usf|usl|musl] [--runs N (>= 5)] [--steps S (>= 1)] \
[--simd auto|avx2|baseline] [--grid-scale N (1..=16)] [--shrink 1|2|4|8] \
[--particle-order fill|rows|shuffled] [--sort off|on] [--transfer flip|xpicK|fmpmK] [--threads N (1..=256)] [--remove none|half|half_rebuilt] [--effect none|damping|feedback|local_damping|damping_zones|particle_forces|tractions|\
body_force|apic|mls (B-splines)|momentum|heat|diffusion|thermal_expansion|axisymmetric (2D only)|colliders|sdf_colliders]";

#[path = "../benches/common/scene.rs"]
mod scene;
use scene::{Effect, ParticleOrder, Scene, SceneDef};
#[path = "../benches/common/timing.rs"]
mod timing;
use timing::time_steps;

struct Options {
    dim: u32,
    shape: ShapeFunction,
    material: MaterialModel,
    order: UpdateOrder,
    runs: u32,
    steps: u32,
    simd: Simd,
    effect: Effect,
    grid_scale: u32,
    shrink: u32,
    particle_order: ParticleOrder,
    threads: u32,
    remove: Remove,
    sort: bool,
    transfer: Transfer,
}

/// What `--remove` does before the timing.
#[derive(Clone, Copy, PartialEq)]
enum Remove {
    None,
    Half,
    HalfRebuilt,
}

fn usage_error(msg: &str) -> ! {
    eprintln!("step_cost: {msg}");
    eprintln!("{USAGE}");
    exit(2);
}

fn parse_options() -> Options {
    let mut o = Options {
        dim: 2,
        shape: ShapeFunction::Gimp,
        material: MaterialModel::NeoHookean,
        order: UpdateOrder::Musl,
        runs: 7,
        steps: 10,
        simd: Simd::Detect,
        effect: Effect::None,
        grid_scale: 1,
        shrink: 1,
        particle_order: ParticleOrder::Fill,
        threads: 1,
        remove: Remove::None,
        sort: false,
        transfer: WorldDef::DEFAULT.transfer,
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        if arg == "-h" || arg == "--help" {
            eprintln!("{USAGE}");
            exit(0);
        }
        // Accept both `--key value` and `--key=value`.
        let (key, inline) = match arg.split_once('=') {
            Some((k, v)) if k.starts_with("--") => (k.to_string(), Some(v.to_string())),
            _ => (arg.clone(), None),
        };
        let known = [
            "--dim",
            "--shape",
            "--material",
            "--order",
            "--runs",
            "--steps",
            "--simd",
            "--effect",
            "--grid-scale",
            "--shrink",
            "--particle-order",
            "--threads",
            "--remove",
            "--sort",
            "--transfer",
        ];
        if !known.contains(&key.as_str()) {
            usage_error(&format!("unknown option `{arg}`"));
        }
        let value = match inline.or_else(|| args.next()) {
            Some(v) => v,
            None => usage_error(&format!("option `{key}` needs a value")),
        };
        let bad = || -> ! { usage_error(&format!("invalid value `{value}` for `{key}`")) };
        match key.as_str() {
            "--dim" => {
                o.dim = match value.as_str() {
                    "2" => 2,
                    "3" => 3,
                    _ => bad(),
                }
            }
            "--shape" => {
                o.shape = match value.as_str() {
                    "linear" => ShapeFunction::Linear,
                    "gimp" => ShapeFunction::Gimp,
                    "quadratic" => ShapeFunction::QuadraticBspline,
                    "cubic" => ShapeFunction::CubicBspline,
                    "cpgimp" => ShapeFunction::CpGimp,
                    _ => bad(),
                }
            }
            "--material" => {
                o.material = match value.as_str() {
                    "neo_hookean" => MaterialModel::NeoHookean,
                    "linear_elastic" => MaterialModel::LinearElastic,
                    "fixed_corotated" => MaterialModel::FixedCorotated,
                    "fluid" => MaterialModel::Fluid,
                    "von_mises" => MaterialModel::VonMises,
                    "drucker_prager" => MaterialModel::DruckerPrager,
                    "snow" => MaterialModel::Snow,
                    _ => bad(),
                }
            }
            "--order" => {
                o.order = match value.as_str() {
                    "usf" => UpdateOrder::Usf,
                    "usl" => UpdateOrder::Usl,
                    "musl" => UpdateOrder::Musl,
                    _ => bad(),
                }
            }
            "--runs" => {
                o.runs = match value.parse::<u32>() {
                    Ok(n) if n >= 5 => n,
                    _ => bad(),
                }
            }
            "--steps" => {
                o.steps = match value.parse::<u32>() {
                    Ok(n) if n >= 1 => n,
                    _ => bad(),
                }
            }
            "--simd" => {
                o.simd = match value.as_str() {
                    "auto" => Simd::Detect,
                    "avx2" => Simd::Avx2,
                    "baseline" => Simd::Baseline,
                    _ => bad(),
                }
            }
            "--effect" => {
                o.effect = match Effect::ALL.iter().find(|(_, n)| *n == value) {
                    Some((e, _)) => *e,
                    None => bad(),
                }
            }
            "--grid-scale" => {
                o.grid_scale = match value.parse::<u32>() {
                    Ok(n) if (1..=16).contains(&n) => n,
                    _ => bad(),
                }
            }
            "--shrink" => {
                o.shrink = match value.parse::<u32>() {
                    Ok(n) if [1, 2, 4, 8].contains(&n) => n,
                    _ => bad(),
                }
            }
            "--particle-order" => {
                o.particle_order = match ParticleOrder::ALL.iter().find(|(_, n)| *n == value) {
                    Some((p, _)) => *p,
                    None => bad(),
                }
            }
            "--threads" => {
                o.threads = match value.parse::<u32>() {
                    Ok(n) if (1..=MAX_WORKERS).contains(&n) => n,
                    _ => bad(),
                }
            }
            "--remove" => {
                o.remove = match value.as_str() {
                    "none" => Remove::None,
                    "half" => Remove::Half,
                    "half_rebuilt" => Remove::HalfRebuilt,
                    _ => bad(),
                }
            }
            "--sort" => {
                o.sort = match value.as_str() {
                    "off" => false,
                    "on" => true,
                    _ => bad(),
                }
            }
            "--transfer" => {
                let order = |prefix: &str| value.strip_prefix(prefix)?.parse::<u32>().ok();
                o.transfer = if value == "flip" {
                    Transfer::Flip
                } else if let Some(k) = order("xpic") {
                    Transfer::Xpic(k)
                } else if let Some(k) = order("fmpm") {
                    Transfer::Fmpm(k)
                } else {
                    bad()
                }
            }
            _ => unreachable!("checked against the known options"),
        }
    }
    o
}

fn shape_name(s: ShapeFunction) -> &'static str {
    match s {
        ShapeFunction::Linear => "linear",
        ShapeFunction::Gimp => "gimp",
        ShapeFunction::QuadraticBspline => "quadratic",
        ShapeFunction::CubicBspline => "cubic",
        ShapeFunction::CpGimp => "cpgimp",
    }
}

fn material_name(m: MaterialModel) -> &'static str {
    match m {
        MaterialModel::NeoHookean => "neo_hookean",
        MaterialModel::LinearElastic => "linear_elastic",
        MaterialModel::FixedCorotated => "fixed_corotated",
        MaterialModel::Fluid => "fluid",
        MaterialModel::VonMises => "von_mises",
        MaterialModel::DruckerPrager => "drucker_prager",
        MaterialModel::Snow => "snow",
    }
}

fn order_name(u: UpdateOrder) -> &'static str {
    match u {
        UpdateOrder::Usf => "usf",
        UpdateOrder::Usl => "usl",
        UpdateOrder::Musl => "musl",
    }
}

fn precision_name() -> &'static str {
    match core::mem::size_of::<Real>() {
        4 => "f32",
        8 => "f64",
        _ => "unknown",
    }
}

/// Grid cells, and the block of filled cells as (first cell, cell count) per axis.
fn scene(dim: u32) -> ([u32; 3], [u32; 3], [u32; 3]) {
    if dim == 2 {
        // One margin cell per side (uGIMP and B-splines) plus one cell of room per side.
        let s = SceneDef::PLANE_2D;
        (s.grid, s.first, s.block)
    } else {
        ([64, 64, 64], [16, 16, 16], [32, 32, 32])
    }
}

/// The world's state bytes as a world of the same definition sized for one worker holds them:
/// the header bytes that depend on `WorldDef::workers` (the count itself and the world's size)
/// are those of a world of one worker, found where the headers of two new worlds, of one
/// worker and of the world's workers, differ. A world of one worker: its state bytes as they
/// are.
fn state_for_one_worker(world: &World<'_>) -> Vec<u8> {
    let mut state = world.state_bytes().to_vec();
    let def = world.def();
    if def.workers > 1 {
        let header = |workers: u32| -> Vec<u8> {
            let def = WorldDef { workers, ..def };
            let bytes = memory_requirements(&def)
                .expect("the world's definition")
                .bytes;
            let mut storage = HeapBuffer::new(bytes);
            let world = World::init(&def, storage.as_mut_bytes()).expect("a new world");
            world.as_bytes()[..World::HEADER_BYTES].to_vec()
        };
        let (one, many) = (header(1), header(def.workers));
        for (k, byte) in state[..World::HEADER_BYTES].iter_mut().enumerate() {
            if one[k] != many[k] {
                *byte = one[k];
            }
        }
    }
    state
}

pub fn main() {
    let o = parse_options();
    let axes = o.dim as usize;
    let (grid, first, block) = scene(o.dim);
    // --shrink: the block's cells per axis divided by N (every block dimension is a multiple
    // of 8), the grid smaller by as many cells.
    let shrunk = |b: u32, a: usize| if a < axes { b / o.shrink } else { b };
    let grid: [u32; 3] = core::array::from_fn(|a| grid[a] - (block[a] - shrunk(block[a], a)));
    let block: [u32; 3] = core::array::from_fn(|a| shrunk(block[a], a));
    // --grid-scale: the same block in the middle of a grid N times larger per axis.
    let axes_scaled = |v: [u32; 3], f: &dyn Fn(u32, usize) -> u32| -> [u32; 3] {
        core::array::from_fn(|a| if a < axes { f(v[a], a) } else { v[a] })
    };
    let n = o.grid_scale;
    let first = axes_scaled(first, &|f, a| f + grid[a] * (n - 1) / 2);
    let grid = axes_scaled(grid, &|g, _| g * n);
    let mut rebuilt: HeapBuffer;
    let mut scene = match Scene::new(&SceneDef {
        dimension: if o.dim == 3 {
            Dimension::ThreeD
        } else {
            Dimension::Plane2D
        },
        shape: o.shape,
        material: o.material,
        order: o.order,
        grid,
        first,
        block,
        effect: o.effect,
        particle_order: o.particle_order,
        workers: o.threads,
        transfer: o.transfer,
        ..SceneDef::PLANE_2D
    }) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("step_cost: {e}");
            exit(1);
        }
    };
    let bytes_per_particle = scene.bytes as f64 / scene.particles as f64;
    let mut world = scene.world();
    let mut removal_ns = 0.0;
    if o.remove != Remove::None {
        if o.threads != 1 || o.effect != Effect::None {
            usage_error("--remove takes one thread and no effect");
        }
        // The block's upper half: every particle above its middle height.
        let def = world.def();
        let v = world.particles();
        let (lo, hi) = v.position[1]
            .iter()
            .fold((Real::MAX, Real::MIN), |(l, h), &y| (l.min(y), h.max(y)));
        let top: Vec3 = Vec3::new(1.0e6, 1.0e6, 1.0e6);
        let min = Vec3::new(-1.0e6, 0.5 * (lo + hi), -1.0e6);
        let n = world.particle_count();
        let start = std::time::Instant::now();
        world
            .remove_particles(Removal::Box { min, max: top })
            .expect("a box of finite corners");
        removal_ns = start.elapsed().as_nanos() as f64 / n as f64;
        if o.remove == Remove::HalfRebuilt {
            rebuilt = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
            let mut fresh = World::init(&def, rebuilt.as_mut_bytes()).expect("the buffer fits");
            for id in 0..world.material_count() as u32 {
                let m = world.material(id).expect("a material the world has");
                fresh.add_material(&m).expect("the same material");
            }
            let v = world.particles();
            fresh
                .add_particles(&ParticleBatch {
                    position: v.position,
                    velocity: v.velocity,
                    mass: v.mass,
                    volume: v.volume0,
                    material: v.material,
                })
                .expect("the same particles");
            world = fresh;
        }
    }
    let mut sort_ns = 0.0;
    if o.sort {
        if o.threads != 1 {
            usage_error("--sort takes one thread");
        }
        let mut order = vec![0u32; world.particle_count()];
        let start = std::time::Instant::now();
        world
            .sort_particles(&mut order)
            .expect("room for the order");
        sort_ns = start.elapsed().as_nanos() as f64 / order.len() as f64;
    }
    let particles = world.particle_count() as u32;
    // One thread: the calling thread, as `World::step`; more: a rayon pool of that many, the
    // steps run on one of its threads (`RayonTasks::install`), as a host with a job system
    // steps from a job.
    let timing = if o.threads == 1 {
        time_steps(&mut world, particles, o.runs, o.steps, o.simd, &Serial)
    } else {
        let tasks = match RayonTasks::new(o.threads as usize) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("step_cost: a pool of {} threads: {e}", o.threads);
                exit(1);
            }
        };
        let w = &mut world;
        tasks.install(|| time_steps(w, particles, o.runs, o.steps, o.simd, &tasks))
    };
    let (runs, med, med_ref, wall) = (timing.runs, timing.median, timing.reference, timing.wall);
    let mut sorted = runs.clone();
    sorted.sort_by(f64::total_cmp);
    // FNV-1a over the world's state after every step taken (warm-up and timed): the same
    // options give the same hash on every instruction set, run and thread count.
    let state_hash = state_for_one_worker(&world)
        .iter()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
        });

    let cells = block[..axes]
        .iter()
        .map(|c| c.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let runs_json = runs
        .iter()
        .map(|r| format!("{r:.3}"))
        .collect::<Vec<_>>()
        .join(",");
    println!(
        "{{\"dim\":{},\"particles\":{},\"cells\":[{}],\"shape\":\"{}\",\"material\":\"{}\",\
\"order\":\"{}\",\"precision\":\"{}\",\"simd\":\"{}\",\"threads\":{},\"ns_per_particle_step\":{:.3},\"runs\":[{}],\
\"reference_ns\":{:.3},\"relative_to_reference\":{:.3},\"effect\":\"{}\",\"bytes_per_particle\":{:.1},\"particle_order\":\"{}\",\"removal_ns_per_particle\":{:.3},\"sort_ns_per_particle\":{:.3},\"state_hash\":\"{:016x}\"}}",
        o.dim,
        particles,
        cells,
        shape_name(o.shape),
        material_name(o.material),
        order_name(o.order),
        precision_name(),
        o.simd.instance_for(&world.def()).name(),
        o.threads,
        med,
        runs_json,
        med_ref,
        med / med_ref,
        o.effect.name(),
        bytes_per_particle,
        o.particle_order.name(),
        removal_ns,
        sort_ns,
        state_hash
    );
    eprintln!(
        "step_cost: {}D, {} particles in a {} cell block (grid {}), {}, {}, {}, {}, {} thread{}: \
median {:.3} ns per particle-step ({:.3} ms per step) over {} runs of {} steps; \
runs [{}] ns; min {:.3}, max {:.3}; wall {:.2} s",
        o.dim,
        particles,
        block[..axes]
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join("x"),
        grid[..axes]
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join("x"),
        shape_name(o.shape),
        material_name(o.material),
        order_name(o.order),
        precision_name(),
        o.threads,
        if o.threads == 1 { "" } else { "s" },
        med,
        med * particles as f64 * 1e-6,
        o.runs,
        o.steps,
        runs_json.replace(',', ", "),
        sorted[0],
        sorted[sorted.len() - 1],
        wall.as_secs_f64()
    );
}
