//! Steps scenes split over the ranks of `mpirun` and checks them against one world, bit for
//! bit: every rank builds the scene, the split steps it `--substeps` times (each at the
//! scene's stable step), gathers the particle columns on rank 0 in id order, and rank 0
//! compares them with the same scene stepped alone, with `to_bits`, column by column.
//! Exits nonzero on any difference (every rank).
//!
//! ```text
//! cargo build --release -p mpm-gimp-mpi --examples
//! mpirun --oversubscribe -np 3 target/release/examples/split_check
//! ```
//!
//! Options: `--case NAME` (every case unless given; `--list` names them), `--substeps M`
//! (40), `--halo H` (cell lines: thinner than the definition's must give a difference, so
//! `--halo 2 --expect-difference` checks that the comparison can fail), `--scale S` (the
//! block S times as long along the split axis), `--cost` (times the split step and prints
//! the halo's bytes and messages per substep; no comparison), `--threads N` (times the scene
//! as one world on N threads instead, on rank 0), `--workers N` (each rank steps on a pool of
//! N threads; the reference steps on one), `--rebalance L` (cut the slabs again past L times
//! the mean count, 1.25), `--no-rebalance` (keep the first slabs),
//! `--expect-rebalance` (fail unless some case cut its slabs again), `--check-errors`
//! (bad input: the same clear error on every rank), `--check-time-out` (a stalled rank: the
//! others abort the job within their time-out).

use mpi::traits::*;
use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Face, HeapBuffer, MaterialDef, MaterialModel, Real,
    ShapeFunction, Transfer, UpdateOrder, Vec3, World, WorldDef,
};
use mpm_gimp_mpi::{Split, SplitError};
use std::time::Instant;

/// A scene of the check: its definition and what fills it.
#[derive(Clone, Copy)]
struct Case {
    name: &'static str,
    three_d: bool,
    shape: ShapeFunction,
    transfer: Transfer,
    order: UpdateOrder,
    model: MaterialModel,
    /// The axis the slabs cut.
    axis: usize,
}

const CASES: &[Case] = &[
    Case {
        name: "2d-sand-quadratic-flip-usl",
        three_d: false,
        shape: ShapeFunction::QuadraticBspline,
        transfer: Transfer::Flip,
        order: UpdateOrder::Usl,
        model: MaterialModel::DruckerPrager,
        axis: 0,
    },
    Case {
        name: "2d-sand-gimp-apic-musl",
        three_d: false,
        shape: ShapeFunction::Gimp,
        transfer: Transfer::Apic,
        order: UpdateOrder::Musl,
        model: MaterialModel::DruckerPrager,
        axis: 0,
    },
    Case {
        name: "2d-elastic-cubic-mls-usl-y",
        three_d: false,
        shape: ShapeFunction::CubicBspline,
        transfer: Transfer::Mls,
        order: UpdateOrder::Usl,
        model: MaterialModel::NeoHookean,
        axis: 1,
    },
    Case {
        name: "2d-vonmises-gimp-flip-usf",
        three_d: false,
        shape: ShapeFunction::Gimp,
        transfer: Transfer::Flip,
        order: UpdateOrder::Usf,
        model: MaterialModel::VonMises,
        axis: 0,
    },
    Case {
        name: "3d-sand-quadratic-apic-musl",
        three_d: true,
        shape: ShapeFunction::QuadraticBspline,
        transfer: Transfer::Apic,
        order: UpdateOrder::Musl,
        model: MaterialModel::DruckerPrager,
        axis: 0,
    },
    Case {
        name: "3d-elastic-gimp-flip-usl-z",
        three_d: true,
        shape: ShapeFunction::Gimp,
        transfer: Transfer::Flip,
        order: UpdateOrder::Usl,
        model: MaterialModel::NeoHookean,
        axis: 2,
    },
];

/// The scene of `case`: a soft block on a floor, thrown along the split axis so that its
/// particles cross slab boundaries while it collapses under gravity; `scale` multiplies its
/// length along that axis. It is filled in strips two cells thick across the axis, one after
/// another, so that consecutive particles (the groups a rank holds whole) lie near each other
/// along it.
fn scene<'b>(case: &Case, scale: u32, storage: &'b mut HeapBuffer) -> World<'b> {
    scene_on(case, scale, 1, storage, |_| ())
}

/// [`scene`] for `workers` workers.
fn scene_on<'b>(
    case: &Case,
    scale: u32,
    workers: u32,
    storage: &'b mut HeapBuffer,
    tweak: impl Fn(&mut WorldDef),
) -> World<'b> {
    let mut def = WorldDef::DEFAULT;
    def.workers = workers;
    let h: Real = 0.01;
    def.cell_size = h;
    def.shape = case.shape;
    def.transfer = case.transfer;
    def.update_order = case.order;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.effects.plasticity = case.model != MaterialModel::NeoHookean;
    let dims = if case.three_d { 3 } else { 2 };
    // The block's cells: long along the split axis, short across it.
    let mut block = if case.three_d { [8, 6, 6] } else { [12, 10, 1] };
    block[case.axis] = if case.three_d { 32 } else { 48 } * scale;
    let room = [16, 6, 8];
    def.dimension = if case.three_d {
        Dimension::ThreeD
    } else {
        Dimension::Plane2D
    };
    def.cells = core::array::from_fn(|a| if a < dims { block[a] + room[a] } else { 1 });
    def.particle_capacity = (block.iter().product::<u32>() * 8 + 64).next_multiple_of(1024);
    tweak(&mut def);
    *storage = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = World::init(&def, storage.as_mut_bytes()).expect("buffer fits");
    let material = world
        .add_material(&MaterialDef {
            model: case.model,
            youngs_modulus: 2.0e5,
            density: 1600.0,
            friction_angle: 30.0,
            yield_stress: 2.0e3,
            ..MaterialDef::DEFAULT
        })
        .expect("material");
    let margin = def.shape.margin_cells() as Real * h;
    let lift = [2.0 * h, 0.0, 2.0 * h];
    let mut velocity = [0.3, -0.5, 0.3];
    velocity[case.axis] = 1.5;
    let velocity = Vec3::from_array(velocity.map(|v| v as Real));
    for strip in (0..block[case.axis]).step_by(2) {
        let lo: [Real; 3] = core::array::from_fn(|a| {
            let from = if a == case.axis {
                strip as Real * h
            } else {
                0.0
            };
            if a < dims {
                margin + lift[a] + from
            } else {
                0.0
            }
        });
        let hi: [Real; 3] = core::array::from_fn(|a| {
            let to = if a == case.axis {
                (strip + 2).min(block[a]) as Real * h
            } else {
                block[a] as Real * h
            };
            if a < dims {
                margin + lift[a] + to
            } else {
                0.0
            }
        });
        world
            .fill_box(
                Vec3::from_array(lo),
                Vec3::from_array(hi),
                material,
                velocity,
            )
            .expect("block");
    }
    world
}

fn main() {
    let universe = mpi::initialize().expect("MPI initialises");
    let comm = universe.world();
    let rank = comm.rank();
    let mut args = std::env::args().skip(1);
    let (mut only, mut substeps, mut halo, mut expect_difference, mut cost) =
        (None, 40u32, None, false, false);
    let (mut scale, mut threads, mut workers) = (1u32, 0u32, 1u32);
    let (mut rebalance, mut expect_rebalance) = (Some(mpm_gimp_mpi::DEFAULT_REBALANCE), false);
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| usage(&a));
        match a.as_str() {
            "--case" => only = Some(value()),
            "--substeps" => substeps = value().parse().unwrap_or_else(|_| usage(&a)),
            "--halo" => halo = Some(value().parse().unwrap_or_else(|_| usage(&a))),
            "--scale" => scale = value().parse().unwrap_or_else(|_| usage(&a)),
            "--threads" => threads = value().parse().unwrap_or_else(|_| usage(&a)),
            "--workers" => workers = value().parse().unwrap_or_else(|_| usage(&a)),
            "--expect-difference" => expect_difference = true,
            "--no-rebalance" => rebalance = None,
            "--rebalance" => rebalance = Some(value().parse().unwrap_or_else(|_| usage(&a))),
            "--expect-rebalance" => expect_rebalance = true,
            "--cost" => cost = true,
            "--check-errors" => {
                check_errors(&comm);
                return;
            }
            "--check-time-out" => {
                check_time_out(&comm);
                return;
            }
            "--list" => {
                if rank == 0 {
                    CASES.iter().for_each(|c| println!("{}", c.name));
                }
                return;
            }
            _ => usage(&a),
        }
    }
    let cases: Vec<&Case> = CASES
        .iter()
        .filter(|c| only.as_deref().is_none_or(|n| n == c.name))
        .collect();
    if cases.is_empty() {
        usage("--case");
    }
    let mut failed = false;
    // Cases whose slabs were cut again (a re-cut leaves slabs that cannot improve alone, so
    // not every case needs one).
    let mut recut_cases = 0u32;
    for case in cases {
        if threads > 0 {
            if rank == 0 {
                one_world_cost(case, scale, threads, substeps);
            }
            continue;
        }
        let mut storage = HeapBuffer::new(0);
        let scene_world = scene_on(case, scale, workers, &mut storage, |_| ());
        // Each rank's world on a pool of `workers` threads (the reference steps serially).
        let tasks = mpm_gimp_rayon::RayonTasks::new(workers as usize).expect("a rayon pool");
        let split = match halo {
            Some(h) => Split::with_halo(comm.duplicate(), &scene_world, case.axis, h),
            None => Split::new(comm.duplicate(), &scene_world, case.axis),
        };
        let mut split = match split {
            Ok(s) => s,
            Err(e) => {
                eprintln!("rank {rank}: {}: {e}", case.name);
                std::process::exit(2);
            }
        };
        // The scene alone, on rank 0: the reference.
        let mut reference = (rank == 0).then_some(scene_world);
        let (mut bytes, mut messages, mut rebuilt, mut seconds) = (0u64, 0u64, 0u64, 0.0f64);
        let mut recuts = 0u32;
        split.rebalance(rebalance);
        let mut report_differs = false;
        for _ in 0..substeps {
            let dt = split.stable_dt();
            comm.barrier();
            let start = Instant::now();
            let report = split.step_with_tasks(dt, &tasks).unwrap_or_else(|e| {
                eprintln!("rank {rank}: {}: {e}", case.name);
                std::process::exit(2);
            });
            comm.barrier();
            seconds += start.elapsed().as_secs_f64();
            bytes += report.bytes_sent;
            messages += report.messages_sent as u64;
            rebuilt += report.rebuilt as u64;
            recuts += report.rebalanced as u32;
            if let Some(world) = reference.as_mut().filter(|_| !cost) {
                report_differs |= world.stable_dt().to_bits() != dt.to_bits();
                let one = world.step(dt).expect("the scene steps");
                report_differs |= one.substeps != 1
                    || one.frozen != report.frozen
                    || one.escaped != report.escaped;
            }
        }
        let mut sums = [0u64; 3];
        comm.all_reduce_into(
            &[bytes, messages, rebuilt][..],
            &mut sums[..],
            mpi::collective::SystemOperation::sum(),
        );
        if cost {
            if rank == 0 {
                let n = split.total();
                let ranks = comm.size();
                println!(
                    "{}: {n} particles, {ranks} ranks, halo {} lines: {:.3} ms per substep, \
                     {:.0} halo bytes and {:.1} messages per substep (all ranks), {} of {} \
                     rank-substeps rebuilt",
                    case.name,
                    split.halo(),
                    seconds * 1e3 / substeps as f64,
                    sums[0] as f64 / substeps as f64,
                    sums[1] as f64 / substeps as f64,
                    sums[2],
                    substeps as usize * ranks as usize,
                );
            }
            continue;
        }
        let gathered = split.gather_to_root().unwrap_or_else(|e| {
            eprintln!("rank {rank}: {}: {e}", case.name);
            std::process::exit(2);
        });
        let mut differs = 0u8;
        if let (Some(got), Some(world)) = (gathered, reference.as_ref()) {
            let view = world.particles();
            let (want, have) = (view.state(), got.state());
            let (a, b) = (want.real_columns(), have.real_columns());
            let mut first = None;
            let mut count = 0usize;
            for (k, (x, y)) in a.iter().zip(b.iter()).enumerate() {
                if x.len() != y.len() {
                    first.get_or_insert((k, usize::MAX));
                    count += 1;
                    continue;
                }
                for (i, (p, q)) in x.iter().zip(y.iter()).enumerate() {
                    if p.to_bits() != q.to_bits() {
                        first.get_or_insert((k, i));
                        count += 1;
                    }
                }
            }
            let ids_differ =
                view.material != got.material.as_slice() || view.status != got.status.as_slice();
            let same = count == 0 && !ids_differ && !report_differs;
            let moved = (0..view.count)
                .filter(|&i| {
                    let owner = |x: Real| {
                        let c = ((x - world.def().origin[case.axis]) / world.def().cell_size)
                            .floor() as u32;
                        split.bounds()[1..].partition_point(|&b| b <= c)
                    };
                    owner(view.position[case.axis][i]) != owner(scene_at_start_x(case, scale, i))
                })
                .count();
            println!(
                "{}: {} ranks x {workers} workers, {} particles, {} substeps, halo {} lines, \
                 slabs {:?} (cut again {recuts} times), {} particles changed owner: {}",
                case.name,
                comm.size(),
                view.count,
                substeps,
                split.halo(),
                split.bounds(),
                moved,
                if same {
                    "bit-identical".to_string()
                } else {
                    format!(
                        "DIFFERENT ({count} values; first: column {:?}; materials or statuses \
                         {}; step report {})",
                        first,
                        if ids_differ { "differ" } else { "agree" },
                        if report_differs { "differs" } else { "agrees" }
                    )
                }
            );
            differs = (!same) as u8;
        }
        comm.process_at_rank(0).broadcast_into(&mut differs);
        failed |= (differs == 1) != expect_difference;
        recut_cases += (recuts > 0) as u32;
        if differs == 1 && expect_difference && rank == 0 {
            println!("{}: a difference, as expected with this halo", case.name);
        }
    }
    if expect_rebalance && recut_cases == 0 {
        if rank == 0 {
            eprintln!("split_check: no case cut its slabs again");
        }
        std::process::exit(1);
    }
    if failed {
        if rank == 0 {
            eprintln!(
                "split_check: {}",
                if expect_difference {
                    "a case agreed bit for bit where a difference was expected"
                } else {
                    "a split differs from one world"
                }
            );
        }
        std::process::exit(1);
    }
}

/// Particle `i`'s position along the case's axis in the scene before any step.
fn scene_at_start_x(case: &Case, scale: u32, i: usize) -> Real {
    thread_local! {
        static START: std::cell::RefCell<Option<(&'static str, Vec<Real>)>> =
            const { std::cell::RefCell::new(None) };
    }
    START.with(|s| {
        let mut s = s.borrow_mut();
        if s.as_ref().is_none_or(|(n, _)| *n != case.name) {
            let mut storage = HeapBuffer::new(0);
            let w = scene(case, scale, &mut storage);
            *s = Some((case.name, w.particles().position[case.axis].to_vec()));
        }
        s.as_ref().unwrap().1[i]
    })
}

/// Checks that bad input gives the same clear error on every rank: more ranks than cell
/// lines (a 2D scene split along z, which has none), a scene with colliders, a step above the
/// stable one. Exits nonzero on this rank where its error is not the one expected.
/// A rank that stalls (the last one sleeps 6 s before its first step): the others, with a
/// time-out of 1 s, abort the job with `TIME_OUT_EXIT_CODE` and say why, instead of waiting.
/// Returning from here is the failure.
fn check_time_out(comm: &mpi::topology::SimpleCommunicator) {
    let mut storage = HeapBuffer::new(0);
    let world = scene(&CASES[0], 1, &mut storage);
    let mut split = Split::new(comm.duplicate(), &world, 0).expect("the scene splits");
    split.time_out(std::time::Duration::from_secs(1));
    let dt = split.stable_dt();
    if comm.rank() == comm.size() - 1 {
        std::thread::sleep(std::time::Duration::from_secs(6));
    }
    let stepped = split.step(dt);
    eprintln!(
        "rank {}: the step returned ({stepped:?}) where the time-out should have aborted",
        comm.rank()
    );
    std::process::exit(1);
}

fn check_errors(comm: &mpi::topology::SimpleCommunicator) {
    let rank = comm.rank();
    let case = &CASES[0];
    let mut failed = false;
    let mut expect =
        |what: &str, got: Result<(), SplitError>, ok: fn(&SplitError) -> bool| match got {
            Err(e) if ok(&e) => {
                if rank == 0 {
                    println!("bad input, {what}: {e}");
                }
            }
            other => {
                eprintln!("rank {rank}: bad input, {what}: {other:?}");
                failed = true;
            }
        };
    let mut storage = HeapBuffer::new(0);
    let world = scene(case, 1, &mut storage);
    let too_many = Split::new(comm.duplicate(), &world, 2).map(drop);
    expect("ranks past the lines", too_many, |e| {
        matches!(e, SplitError::RanksDoNotFit { lines: 0, .. })
    });
    let mut storage = HeapBuffer::new(0);
    let world = scene_on(case, 1, 1, &mut storage, |d| {
        d.effects.collider_capacity = 1
    });
    let colliders = Split::new(comm.duplicate(), &world, 0).map(drop);
    expect("colliders", colliders, |e| {
        matches!(e, SplitError::Unsupported(_))
    });
    let mut storage = HeapBuffer::new(0);
    let world = scene(case, 1, &mut storage);
    let mut split = Split::new(comm.duplicate(), &world, 0).expect("the scene splits");
    let dt = split.stable_dt() * 2.0;
    expect(
        "a step above the stable one",
        split.step(dt).map(drop),
        |e| matches!(e, SplitError::TimeStepAboveStable { .. }),
    );
    if failed {
        std::process::exit(1);
    }
}

/// Times `substeps` substeps of `case`'s scene alone on `threads` workers (a rayon pool,
/// `World::step_with_tasks`), each at the stable step, and prints the mean.
fn one_world_cost(case: &Case, scale: u32, threads: u32, substeps: u32) {
    let mut storage = HeapBuffer::new(0);
    let mut world = scene_on(case, scale, threads, &mut storage, |_| ());
    let tasks = mpm_gimp_rayon::RayonTasks::new(threads as usize).expect("a rayon pool");
    let mut seconds = 0.0;
    for _ in 0..substeps {
        let dt = world.stable_dt();
        let start = Instant::now();
        tasks
            .install(|| world.step_with_tasks(dt, &tasks))
            .expect("the scene steps");
        seconds += start.elapsed().as_secs_f64();
    }
    println!(
        "{}: {} particles, one world on {threads} threads: {:.3} ms per substep",
        case.name,
        world.particle_count(),
        seconds * 1e3 / substeps as f64
    );
}

fn usage(flag: &str) -> ! {
    eprintln!(
        "split_check: bad or incomplete option {flag}\nusage: split_check [--case NAME] \
         [--substeps M] [--halo H] [--expect-difference] [--scale S] [--cost] [--threads N] \
         [--workers N] [--check-errors] [--list]"
    );
    std::process::exit(2);
}
