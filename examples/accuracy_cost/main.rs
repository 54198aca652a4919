//! What accuracy costs in time: every scheme of `problems::SCHEMES` on every problem of
//! `problems::PROBLEMS` (each with an exact solution) over a grid-refinement series, next to
//! the scheme's nanoseconds per particle-step.
//!
//! `cargo run --release --example accuracy_cost` writes `results/accuracy_cost/`:
//! - `README.md`: per problem, metric, scheme, precision and resolution the error, the observed
//!   order of convergence and the ns per particle-step; the cost (single-core milliseconds) to
//!   reach each problem's stated error; the claims a correct kernel bears out;
//! - one SVG per problem and metric: error at the finest resolution against ns per
//!   particle-step, log-log, the Pareto front marked, each scheme labelled.
//!
//! Precision is a build feature of the kernel: the f32 run builds and runs itself with
//! `--features f64` for the f64 rows (`--precision this` skips that).
//!
//! Timing: the step_cost measurement (`benches/common/timing.rs`) on the step_cost 2D scene
//! (`benches/common/scene.rs`, 131072 particles) with the scheme and the problem's effect, 5
//! runs of 4 steps, median, on one worker (the calling thread) and on two (a world sized for
//! two workers on a rayon pool of two threads, as `step_cost --threads 2`). The accuracy runs
//! use both cores; the timings run alone.
//!
//! The report names the kernel source it measured (`source::kernel_source_hash`), which CI
//! checks against the source (`.ci/accuracy_source.py`).
//!
//! Options: `--quick` (the quick refinement series, no timing, checks the claims: exit code 1
//! if one fails; with `--out`, it writes its report there too, without costs), `--out DIR`,
//! `--precision both|this`, `--source-hash` (prints the kernel source's digest and exits).

mod claims;
mod problems;
mod report;
#[path = "../../benches/common/scene.rs"]
mod scene;
mod source;
// Only the median and the reference of a timing are reported here.
#[allow(dead_code)]
#[path = "../../benches/common/timing.rs"]
mod timing;

use mpm_gimp::MaterialModel;
use mpm_gimp_rayon::RayonTasks;
use problems::{Declares, PROBLEMS, SCHEMES};
use scene::{Effect, Scene, SceneDef};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::process::{exit, Command};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

const USAGE: &str =
    "usage: accuracy_cost [--quick] [--out DIR] [--precision both|this] [--source-hash]";

/// Timed runs and steps per run of each scheme's cost.
const COST_RUNS: u32 = 5;
const COST_STEPS: u32 = 4;

fn precision() -> &'static str {
    if core::mem::size_of::<mpm_gimp::Real>() == 8 {
        "f64"
    } else {
        "f32"
    }
}

/// One accuracy run's result.
#[derive(Clone, Debug)]
struct Row {
    problem: String,
    scheme: String,
    precision: String,
    cells: u32,
    errors: Vec<f64>,
    particles: usize,
    steps: usize,
}

/// One cost measurement: ns per particle-step of a scheme with a problem's effect, on one
/// worker and on two.
#[derive(Clone, Debug)]
struct Cost {
    scheme: String,
    precision: String,
    declares: String,
    ns: f64,
    ns_two: f64,
    reference: f64,
}

fn declares_name(d: Declares) -> &'static str {
    match d {
        Declares::Nothing => "none",
        Declares::ParticleForces => "particle_forces",
        Declares::Heat => "heat",
        Declares::Fluid => "fluid",
    }
}

/// Runs every (problem, scheme, level) on two threads, the largest runs first.
fn accuracy(quick: bool) -> Vec<Row> {
    let mut tasks = vec![];
    for (p, problem) in PROBLEMS.iter().enumerate() {
        let levels = if quick {
            problem.quick_levels
        } else {
            problem.levels
        };
        for s in 0..SCHEMES.len() {
            for &n in levels {
                tasks.push((p, s, n));
            }
        }
    }
    tasks.sort_by_key(|&(_, _, n)| std::cmp::Reverse(n));
    let next = AtomicUsize::new(0);
    let rows = Mutex::new(vec![]);
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(&(p, s, n)) = tasks.get(k) else {
                    break;
                };
                let (problem, scheme) = (&PROBLEMS[p], &SCHEMES[s]);
                let o = (problem.run)(scheme, n);
                eprintln!(
                    "accuracy_cost: {} {} {} n={n}: {:?} ({} particles, {} steps)",
                    problem.key,
                    scheme.label,
                    precision(),
                    o.errors,
                    o.particles,
                    o.steps
                );
                rows.lock().unwrap().push(Row {
                    problem: problem.key.into(),
                    scheme: scheme.label.into(),
                    precision: precision().into(),
                    cells: n,
                    errors: o.errors,
                    particles: o.particles,
                    steps: o.steps,
                });
            });
        }
    });
    rows.into_inner().unwrap()
}

/// Times every scheme with every effect the problems declare, one at a time: on the calling
/// thread, then a world sized for two workers on a pool of two threads.
fn costs() -> Vec<Cost> {
    let pool = RayonTasks::new(2).expect("a pool of two threads");
    let mut declared: Vec<Declares> = PROBLEMS.iter().map(|p| p.declares).collect();
    declared.sort_by_key(|d| *d as u32);
    declared.dedup();
    let mut out = vec![];
    for scheme in SCHEMES {
        for &d in &declared {
            let def = SceneDef {
                shape: scheme.shape,
                order: scheme.order,
                transfer: scheme.transfer,
                flip_beta: scheme.flip_beta,
                exp_terms: scheme.exp_terms,
                effect: match d {
                    Declares::Nothing | Declares::Fluid => Effect::None,
                    Declares::ParticleForces => Effect::ParticleForces,
                    Declares::Heat => Effect::Heat,
                },
                material: if d == Declares::Fluid {
                    MaterialModel::Fluid
                } else {
                    SceneDef::PLANE_2D.material
                },
                ..SceneDef::PLANE_2D
            };
            let mut s = Scene::new(&def).unwrap_or_else(|e| panic!("{}: {e}", scheme.label));
            let particles = s.particles;
            let t = timing::time_steps(
                &mut s.world(),
                particles,
                COST_RUNS,
                COST_STEPS,
                mpm_gimp::simd::Simd::Detect,
                &mpm_gimp::Serial,
            );
            let def_two = SceneDef { workers: 2, ..def };
            let mut s = Scene::new(&def_two).unwrap_or_else(|e| panic!("{}: {e}", scheme.label));
            let mut world = s.world();
            let w = &mut world;
            let two = pool.install(|| {
                timing::time_steps(
                    w,
                    particles,
                    COST_RUNS,
                    COST_STEPS,
                    mpm_gimp::simd::Simd::Detect,
                    &pool,
                )
            });
            eprintln!(
                "accuracy_cost: cost {} {} {}: {:.2} ns per particle-step, {:.2} on two \
workers (reference {:.3})",
                scheme.label,
                precision(),
                declares_name(d),
                t.median,
                two.median,
                t.reference
            );
            out.push(Cost {
                scheme: scheme.label.into(),
                precision: precision().into(),
                declares: declares_name(d).into(),
                ns: t.median,
                ns_two: two.median,
                reference: t.reference,
            });
        }
    }
    out
}

/// Tab-separated lines: how the f64 build hands its rows to the f32 run.
fn to_lines(rows: &[Row], costs: &[Cost]) -> String {
    let mut s = String::new();
    for r in rows {
        let errors: Vec<String> = r.errors.iter().map(|e| format!("{e:e}")).collect();
        let _ = writeln!(
            s,
            "row\t{}\t{}\t{}\t{}\t{}\t{}\t{}",
            r.problem,
            r.scheme,
            r.precision,
            r.cells,
            r.particles,
            r.steps,
            errors.join(",")
        );
    }
    for c in costs {
        let _ = writeln!(
            s,
            "cost\t{}\t{}\t{}\t{:e}\t{:e}\t{:e}",
            c.scheme, c.precision, c.declares, c.ns, c.ns_two, c.reference
        );
    }
    s
}

fn from_lines(text: &str) -> (Vec<Row>, Vec<Cost>) {
    let (mut rows, mut costs) = (vec![], vec![]);
    for line in text.lines() {
        let f: Vec<&str> = line.split('\t').collect();
        match f.as_slice() {
            ["row", problem, scheme, precision, cells, particles, steps, errors] => {
                rows.push(Row {
                    problem: problem.to_string(),
                    scheme: scheme.to_string(),
                    precision: precision.to_string(),
                    cells: cells.parse().expect("cells"),
                    particles: particles.parse().expect("particles"),
                    steps: steps.parse().expect("steps"),
                    errors: errors
                        .split(',')
                        .map(|e| e.parse().expect("error"))
                        .collect(),
                })
            }
            ["cost", scheme, precision, declares, ns, ns_two, reference] => costs.push(Cost {
                scheme: scheme.to_string(),
                precision: precision.to_string(),
                declares: declares.to_string(),
                ns: ns.parse().expect("ns"),
                ns_two: ns_two.parse().expect("ns on two workers"),
                reference: reference.parse().expect("reference"),
            }),
            _ => panic!("unexpected line from the f64 run: {line}"),
        }
    }
    (rows, costs)
}

/// The f64 rows: this example built with `--features f64`, run as a child.
fn f64_rows(quick: bool) -> (Vec<Row>, Vec<Cost>) {
    let file = std::env::temp_dir().join(format!("accuracy_cost_f64_{}.tsv", std::process::id()));
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(env!("CARGO_MANIFEST_DIR")).args([
        "run",
        "--release",
        "--features",
        "f64",
        "--example",
        "accuracy_cost",
        "--",
        "--rows-only",
    ]);
    cmd.arg(&file);
    if quick {
        cmd.arg("--quick");
    }
    eprintln!("accuracy_cost: building and running the f64 rows");
    let status = cmd.status().expect("running cargo for the f64 rows");
    if !status.success() {
        eprintln!("accuracy_cost: the f64 run failed ({status})");
        exit(1);
    }
    let text = std::fs::read_to_string(&file).expect("the f64 run's rows");
    let _ = std::fs::remove_file(&file);
    from_lines(&text)
}

struct Options {
    quick: bool,
    out: String,
    out_given: bool,
    both: bool,
    rows_only: Option<String>,
}

fn options() -> Options {
    let mut o = Options {
        quick: false,
        out: "results/accuracy_cost".into(),
        out_given: false,
        both: true,
        rows_only: None,
    };
    let mut args = std::env::args().skip(1);
    let bad = |msg: String| -> ! {
        eprintln!("accuracy_cost: {msg}\n{USAGE}");
        exit(2)
    };
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quick" => o.quick = true,
            "--out" => {
                o.out = args
                    .next()
                    .unwrap_or_else(|| bad("--out needs a folder".into()));
                o.out_given = true;
            }
            "--source-hash" => {
                println!("{}", source_hash());
                exit(0)
            }
            "--precision" => match args.next().as_deref() {
                Some("both") => o.both = true,
                Some("this") => o.both = false,
                _ => bad("--precision takes both or this".into()),
            },
            "--rows-only" => o.rows_only = args.next(),
            "-h" | "--help" => {
                eprintln!("{USAGE}");
                exit(0)
            }
            _ => bad(format!("unknown option `{a}`")),
        }
    }
    o
}

fn main() {
    let o = options();
    let wall = std::time::Instant::now();
    // The source cargo built this run from, before the hours anyone may edit it in.
    let source = source_hash();
    let mut rows = accuracy(o.quick);
    let mut costs = if o.quick { vec![] } else { costs() };
    if let Some(file) = &o.rows_only {
        std::fs::write(file, to_lines(&rows, &costs)).expect("writing the rows");
        return;
    }
    if o.both && precision() == "f32" {
        let (r, c) = f64_rows(o.quick);
        rows.extend(r);
        costs.extend(c);
    }
    // The claims read the f64 rows when there are some: at the finest levels f32 round-off
    // (1e-7 of positions near 1, over 25600 steps) reaches the errors measured.
    let claim_precision = if rows.iter().any(|r| r.precision == "f64") {
        "f64"
    } else {
        precision()
    };
    let claims = claims::check(&|problem: &str, metric: usize, scheme: &str| {
        series(&rows, problem, metric, scheme, claim_precision)
    });
    let mut failed = false;
    for c in &claims {
        eprintln!(
            "accuracy_cost: claim {}: {} ({})",
            if c.holds { "holds" } else { "FAILS" },
            c.text,
            c.detail
        );
        failed |= !c.holds;
    }
    if !o.quick || o.out_given {
        let seconds = wall.elapsed().as_secs_f64();
        report::write(&o.out, &rows, &costs, &claims, seconds, &source)
            .expect("writing the report");
        eprintln!("accuracy_cost: report written to {}/", o.out);
    }
    if failed {
        exit(1);
    }
}

/// The digest of the kernel source this example was run from (its repository: where cargo
/// builds it).
fn source_hash() -> String {
    source::kernel_source_hash(std::path::Path::new(env!("CARGO_MANIFEST_DIR")))
        .expect("reading the kernel source")
}

/// Errors of one (problem, metric, scheme, precision) by level, coarsest first.
fn series(rows: &[Row], problem: &str, metric: usize, scheme: &str, prec: &str) -> Vec<(u32, f64)> {
    let mut s: Vec<(u32, f64)> = rows
        .iter()
        .filter(|r| r.problem == problem && r.scheme == scheme && r.precision == prec)
        .map(|r| (r.cells, r.errors[metric]))
        .collect();
    s.sort_by_key(|e| e.0);
    s
}

/// Cost (ns per particle-step on one worker) of a scheme, precision and effect.
fn cost_of(costs: &[Cost], scheme: &str, prec: &str, declares: Declares) -> Option<f64> {
    find_cost(costs, scheme, prec, declares).map(|c| c.ns)
}

/// The cost measurement of a scheme, precision and effect.
fn find_cost<'a>(
    costs: &'a [Cost],
    scheme: &str,
    prec: &str,
    declares: Declares,
) -> Option<&'a Cost> {
    costs.iter().find(|c| {
        c.scheme == scheme && c.precision == prec && c.declares == declares_name(declares)
    })
}

/// The precisions present in the rows, f32 first.
fn precisions(rows: &[Row]) -> Vec<String> {
    let p: BTreeSet<String> = rows.iter().map(|r| r.precision.clone()).collect();
    p.into_iter().collect()
}
