//! What a per-item query of a world costs, in nanoseconds per call: the queries a host calls
//! once per item or per pixel (a viewer that draws a collider asks for its distance at every
//! pixel).
//!
//! `cargo run --release --example query_cost` prints one line per query on stdout: its name,
//! the median and the minimum over `--runs` runs (default 9, at least 3) of the mean cost of
//! `--calls` calls (default 200000), ns per call. The world is the samples viewer's paddle
//! scene (`mpm_gimp_output::scenes`, a turning box in a water tank, 2D), stepped one frame;
//! the distance is asked at points spread over the grid's box, as a picture asks it.
//!
//! Queries: `collider_distance` ([`mpm_gimp::World::collider_distance`]), `collider`
//! ([`mpm_gimp::World::collider`]), `material` ([`mpm_gimp::World::material`]), and, for
//! comparison, `def_distance` ([`mpm_gimp::ColliderDef::distance`] of the collider's
//! definition, which needs no world) and `reopen` ([`mpm_gimp::WorldRef::reopen`]: the check
//! of the header that every call of the C interface makes before its query). Unknown
//! options: a message on stderr and exit code 2.

use mpm_gimp::{Real, Vec3, World};
use mpm_gimp_output::scenes;
use std::hint::black_box;
use std::process::exit;
use std::time::Instant;

const USAGE: &str = "usage: query_cost [--runs N (>= 3)] [--calls N (>= 1)]";

/// The median and the minimum of `runs` runs of `f` called `calls` times, ns per call.
fn time(runs: u32, calls: u32, mut f: impl FnMut(u32)) -> (f64, f64) {
    let mut per_call: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            for k in 0..calls {
                f(k);
            }
            start.elapsed().as_nanos() as f64 / calls as f64
        })
        .collect();
    per_call.sort_by(f64::total_cmp);
    (per_call[per_call.len() / 2], per_call[0])
}

fn main() {
    let (mut runs, mut calls) = (9u32, 200_000u32);
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
            "--runs" => runs = number(3),
            "--calls" => calls = number(1),
            _ => {
                eprintln!("{USAGE}");
                exit(2)
            }
        }
    }
    let scene = scenes::find("paddle").expect("the paddle scene");
    let def = (scene.def)();
    let mut storage = scenes::Scene::storage(&def).expect("a valid definition");
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("a world");
    (scene.fill)(&mut world).expect("the scene fills");
    scene.frame(&mut world, scene.frame_dt).expect("a frame");
    // Points over the grid's box, 256 by 256, as a picture's pixels.
    let side = 256u32;
    let extent = def.cells[0] as Real * def.cell_size;
    let point = |k: u32| {
        let (i, j) = (k % side, (k / side) % side);
        Vec3::new(
            def.origin.x + (i as Real + 0.5) * extent / side as Real,
            def.origin.y + (j as Real + 0.5) * extent / side as Real,
            0.0,
        )
    };
    let collider = world.collider(0).expect("a collider").def;
    let results = [
        (
            "collider_distance",
            time(runs, calls, |k| {
                black_box(world.collider_distance(0, black_box(point(k))).ok());
            }),
        ),
        (
            "collider",
            time(runs, calls, |_| {
                black_box(world.collider(black_box(0)).ok());
            }),
        ),
        (
            "material",
            time(runs, calls, |_| {
                black_box(world.material(black_box(0)));
            }),
        ),
        (
            "reopen",
            time(runs, calls, |_| {
                black_box(mpm_gimp::WorldRef::reopen(black_box(world.as_bytes())).is_ok());
            }),
        ),
        (
            "def_distance",
            time(runs, calls, |k| {
                black_box(black_box(&collider).distance(black_box(point(k))));
            }),
        ),
    ];
    for (name, (median, min)) in results {
        println!("{name}: median {median:.1} ns per call, min {min:.1} ({runs} runs of {calls})");
    }
}
