//! The public API contract of the kernel, exercised through the public API only:
//! no heap use, determinism, snapshots, definition validation, "a call that fails changes
//! nothing", capacity, error strings and the fill helpers.
//!
//! Runs in both precisions (`cargo test --release --test kernel -- api_contract::`, and with
//! `--features f64`).

use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Error, Face, HeapBuffer, MaterialDef, ParticleBatch,
    ParticleDef, ParticleStatus, Real, ShapeFunction, Transfer, UpdateOrder, Vec3, World, WorldDef,
    WorldRef,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::collections::HashSet;
use std::sync::atomic::{AtomicUsize, Ordering};

// ---------------------------------------------------------------------------------------------
// Counting allocator
// ---------------------------------------------------------------------------------------------

/// Heap allocations (alloc, alloc_zeroed, realloc) made by threads whose `COUNTING` flag is set.
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set only around a measured region, on the measuring thread: the test harness runs the
    /// other tests on other threads, and their allocations must not be counted. Const
    /// initialised and without a destructor, so reading it never allocates.
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

struct CountingAllocator;

fn counting_here() -> bool {
    COUNTING.try_with(Cell::get).unwrap_or(false)
}

fn note_allocation() {
    if counting_here() {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

// SAFETY: every call is forwarded unchanged to `System`; the counter has no effect on memory.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_allocation();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Runs `f` and returns its result with the number of heap allocations this thread made in it.
fn allocations_during<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    (r, after - before)
}

// ---------------------------------------------------------------------------------------------
// Hashing
// ---------------------------------------------------------------------------------------------

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

fn fnv_bytes(h: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(FNV_PRIME);
    }
}

fn hash_bytes(bytes: &[u8]) -> u64 {
    let mut h = FNV_OFFSET;
    fnv_bytes(&mut h, bytes);
    h
}

/// FNV-1a over the raw bits of every value (so -0.0 and 0.0, or two NaNs, differ).
fn hash_reals(col: &[Real]) -> u64 {
    let mut h = FNV_OFFSET;
    for x in col {
        fnv_bytes(&mut h, &x.to_bits().to_le_bytes());
    }
    h
}

fn hash_u32s(col: &[u32]) -> u64 {
    let mut h = FNV_OFFSET;
    for x in col {
        fnv_bytes(&mut h, &x.to_le_bytes());
    }
    h
}

/// A named hash of every particle column (and the count).
fn column_hashes(world: &World<'_>) -> Vec<(String, u64)> {
    let p = world.particles();
    let mut out = vec![("count".to_string(), p.count as u64)];
    for a in 0..3 {
        out.push((format!("position[{a}]"), hash_reals(p.position[a])));
        out.push((format!("velocity[{a}]"), hash_reals(p.velocity[a])));
    }
    out.push(("mass".to_string(), hash_reals(p.mass)));
    out.push(("volume0".to_string(), hash_reals(p.volume0)));
    for a in 0..3 {
        for b in 0..3 {
            out.push((
                format!("displacement_gradient[{a}][{b}]"),
                hash_reals(p.displacement_gradient[a][b]),
            ));
        }
    }
    for k in 0..6 {
        out.push((format!("stress[{k}]"), hash_reals(p.stress[k])));
    }
    out.push(("material".to_string(), hash_u32s(p.material)));
    out.push(("status".to_string(), hash_u32s(p.status)));
    out
}

// ---------------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------------

/// A small 2D world: 20 x 20 cells of 5 cm, room for 1024 particles and 4 materials.
fn def_2d() -> WorldDef {
    WorldDef {
        cells: [20, 20, 1],
        cell_size: 0.05,
        particle_capacity: 1024,
        material_capacity: 4,
        ..WorldDef::DEFAULT
    }
}

/// The 3D counterpart of [`def_2d`] (20^3 cells).
fn def_3d() -> WorldDef {
    WorldDef {
        dimension: Dimension::ThreeD,
        cells: [20, 20, 20],
        ..def_2d()
    }
}

/// A soft rubber: few substeps per 1/240 s frame on a 5 cm grid.
const RUBBER: MaterialDef = MaterialDef {
    youngs_modulus: 2.0e5,
    ..MaterialDef::DEFAULT
};

fn buffer_for(def: &WorldDef) -> HeapBuffer {
    HeapBuffer::new(memory_requirements(def).expect("valid definition").bytes)
}

/// A block thrown down onto a stick floor (it hits it within 50 frames of 1/240 s).
fn drop_scene<'a>(def: &WorldDef, buf: &'a mut [u8]) -> World<'a> {
    let mut def = *def;
    def.faces[Face::YMin as usize] = Boundary::Stick;
    let mut world = World::init(&def, buf).expect("init");
    let rubber = world.add_material(&RUBBER).expect("material");
    let v = Vec3::new(0.3, -1.0, 0.2);
    let ids = if def.axes() == 3 {
        world.fill_box(
            Vec3::new(0.425, 0.3, 0.425),
            Vec3::new(0.575, 0.45, 0.575),
            rubber,
            v,
        )
    } else {
        world.fill_box(
            Vec3::new(0.35, 0.3, 0.0),
            Vec3::new(0.65, 0.6, 0.0),
            rubber,
            v,
        )
    }
    .expect("block fits");
    assert!(ids.len() >= 100, "scene too small: {} particles", ids.len());
    world
}

fn valid_particle() -> ParticleDef {
    ParticleDef {
        position: Vec3::new(0.0, 0.7, 0.0),
        velocity: Vec3::new(0.1, -0.2, 0.0),
        mass: 0.625,
        volume: 6.25e-4,
        material: 0,
    }
}

/// Asserts that `call` fails with `expected` and leaves every byte of the world unchanged.
fn assert_rejected<'a, T>(
    world: &mut World<'a>,
    what: &str,
    expected: Error,
    call: impl FnOnce(&mut World<'a>) -> Result<T, Error>,
) {
    let before = hash_bytes(world.as_bytes());
    let count = world.particle_count();
    let materials = world.material_count();
    let got = call(world).err();
    assert_eq!(got, Some(expected), "{what}: wrong result");
    assert_eq!(
        world.particle_count(),
        count,
        "{what}: particle count changed"
    );
    assert_eq!(
        world.material_count(),
        materials,
        "{what}: material count changed"
    );
    assert_eq!(
        hash_bytes(world.as_bytes()),
        before,
        "{what}: the world's bytes changed"
    );
}

/// A Real widened to f64 (a no-op with the `f64` feature).
#[allow(clippy::unnecessary_cast)]
fn wide(x: Real) -> f64 {
    x as f64
}

fn rel_close(a: Real, b: Real, rel: Real) -> bool {
    (a - b).abs() <= rel * b.abs().max(Real::MIN_POSITIVE)
}

// ---------------------------------------------------------------------------------------------
// 1. No heap use
// ---------------------------------------------------------------------------------------------

#[derive(Debug)]
struct AllocRun {
    particles: usize,
    substeps: [u32; 3],
    mass: f64,
    reopened_count: usize,
    checksum: u64,
}

/// Builds, fills, steps (with substeps), reads back, snapshots and reopens one small world,
/// with both buffers allocated beforehand.
/// A task system of 4 workers that runs the ranges one after another on the calling thread,
/// one item each: the parallel step's code paths, counted by the allocator of this thread.
struct InOrder;

// SAFETY: every item once, one at a time, before returning.
unsafe impl mpm_gimp::TaskSystem for InOrder {
    fn worker_count(&self) -> usize {
        4
    }

    fn parallel_for(&self, items: usize, _min_range: usize, task: &mpm_gimp::tasks::Task<'_>) {
        for i in 0..items {
            task(i, i + 1, i % 4);
        }
    }
}

fn allocation_free_run(def: &WorldDef, buf: &mut HeapBuffer, copy: &mut HeapBuffer) -> AllocRun {
    let d3 = def.axes() == 3;
    // Batch columns on the stack.
    let xs: [Real; 3] = [0.22, 0.25, 0.28];
    let ys: [Real; 3] = [0.55, 0.55, 0.55];
    let zs: [Real; 3] = [0.3, 0.31, 0.32];
    let vs: [Real; 3] = [0.0, 0.1, -0.1];
    let ms: [Real; 3] = [0.1, 0.1, 0.1];
    let vols: [Real; 3] = [1.0e-4, 1.0e-4, 1.0e-4];
    let mats: [u32; 3] = [1, 1, 0];

    let mut world = World::init(def, buf.as_mut_bytes()).expect("init");
    let soft = world.add_material(&RUBBER).expect("material");
    let stiff = world
        .add_material(&MaterialDef {
            model: mpm_gimp::MaterialModel::LinearElastic,
            youngs_modulus: 4.0e5,
            ..MaterialDef::DEFAULT
        })
        .expect("material");
    world
        .add_particle(&ParticleDef {
            position: Vec3::new(0.5, 0.5, 0.3),
            velocity: Vec3::new(0.0, -0.5, 0.0),
            mass: 0.1,
            volume: 1.0e-4,
            material: stiff,
        })
        .expect("particle");
    world
        .add_particles(&ParticleBatch {
            position: [&xs, &ys, &zs],
            velocity: [&vs, &vs, &vs],
            mass: &ms,
            volume: &vols,
            material: &mats,
        })
        .expect("batch");
    world
        .fill_box(
            Vec3::new(0.3, 0.2, 0.3),
            Vec3::new(0.5, 0.4, 0.5),
            soft,
            Vec3::new(0.0, -0.3, 0.0),
        )
        .expect("box");
    if d3 {
        world
            .fill_sphere(Vec3::new(0.6, 0.6, 0.4), 0.1, stiff, Vec3::ZERO)
            .expect("sphere");
    } else {
        world
            .fill_disk(Vec3::new(0.6, 0.6, 0.0), 0.1, stiff, Vec3::ZERO)
            .expect("disk");
    }
    // Rejected calls must not allocate either (e.g. to format an error).
    assert_eq!(world.step(Real::NAN).err(), Some(Error::InvalidTimeStep));
    assert_eq!(
        world
            .fill_box(Vec3::ONE, Vec3::ZERO, soft, Vec3::ZERO)
            .err(),
        Some(Error::InvalidRegion)
    );
    let mut substeps = [0; 3];
    for (k, s) in substeps.iter_mut().enumerate() {
        let dt = 3.5 * world.stable_dt();
        // The last step on a task system: the parallel passes' scratch is the world's.
        *s = if k == 2 {
            world.step_with_tasks(dt, &InOrder)
        } else {
            world.step(dt)
        }
        .expect("step")
        .substeps;
    }
    let view = world.particles();
    let mut checksum = FNV_OFFSET;
    for a in 0..3 {
        checksum ^= hash_reals(view.position[a]) ^ hash_reals(view.velocity[a]);
    }
    checksum ^= hash_reals(view.stress[0]) ^ hash_u32s(view.status);
    let diag = world.diagnostics();
    let n = world.as_bytes().len();
    copy.as_mut_bytes()[..n].copy_from_slice(world.as_bytes());
    let reopened = World::open(copy.as_mut_bytes()).expect("open");
    AllocRun {
        particles: view.count,
        substeps,
        mass: diag.mass,
        reopened_count: reopened.particle_count(),
        checksum,
    }
}

#[test]
fn counting_allocator_sees_allocations_on_this_thread() {
    let (v, n) = allocations_during(|| {
        let v: Vec<u64> = Vec::with_capacity(32);
        std::hint::black_box(v)
    });
    assert_eq!(v.capacity(), 32);
    assert!(n >= 1, "the counter missed a Vec allocation");
    let (_, none) = allocations_during(|| std::hint::black_box(3 + 4));
    assert_eq!(
        none, 0,
        "the counter counted an allocation that did not happen"
    );
}

#[test]
fn init_add_fill_step_read_snapshot_make_no_heap_allocation() {
    let shapes = [
        ShapeFunction::Linear,
        ShapeFunction::Gimp,
        ShapeFunction::QuadraticBspline,
        ShapeFunction::CubicBspline,
    ];
    let orders = [UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl];
    for dimension in [Dimension::Plane2D, Dimension::ThreeD] {
        for shape in shapes {
            for update_order in orders {
                let mut def = WorldDef {
                    dimension,
                    shape,
                    update_order,
                    cells: [10, 10, 10],
                    cell_size: 0.1,
                    particle_capacity: 512,
                    material_capacity: 2,
                    workers: 4,
                    ..WorldDef::DEFAULT
                };
                def.faces[Face::YMin as usize] = Boundary::Stick;
                def.faces[Face::XMax as usize] = Boundary::Open;
                let mut buf = buffer_for(&def);
                let mut copy = buffer_for(&def);
                let (run, allocations) =
                    allocations_during(|| allocation_free_run(&def, &mut buf, &mut copy));
                let what = format!("{dimension:?} {shape:?} {update_order:?}");
                assert_eq!(allocations, 0, "{what}: heap allocations in {run:?}");
                assert!(run.particles > 10, "{what}: too few particles: {run:?}");
                assert!(
                    run.substeps.iter().all(|&s| s >= 2),
                    "{what}: no substeps taken: {run:?}"
                );
                assert!(run.mass > 0.0, "{what}: {run:?}");
                assert_eq!(run.reopened_count, run.particles, "{what}");
                // The checksum only makes sure the columns were really read.
                std::hint::black_box(run.checksum);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Determinism
// ---------------------------------------------------------------------------------------------

fn assert_hashes_equal(a: &[(String, u64)], b: &[(String, u64)], what: &str) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x, y, "{what}: column {} differs", x.0);
    }
}

#[test]
fn identical_worlds_stepped_identically_are_bit_identical() {
    let configs = [
        (def_2d(), "2D uGIMP MUSL"),
        (def_3d(), "3D uGIMP MUSL"),
        (
            WorldDef {
                shape: ShapeFunction::Linear,
                update_order: UpdateOrder::Usf,
                ..def_2d()
            },
            "2D linear USF",
        ),
        (
            WorldDef {
                shape: ShapeFunction::QuadraticBspline,
                update_order: UpdateOrder::Usl,
                ..def_2d()
            },
            "2D quadratic USL",
        ),
        (
            WorldDef {
                shape: ShapeFunction::CubicBspline,
                update_order: UpdateOrder::Usf,
                ..def_2d()
            },
            "2D cubic USF",
        ),
    ];
    for (def, what) in configs {
        let mut buf_a = buffer_for(&def);
        let mut buf_b = buffer_for(&def);
        let mut a = drop_scene(&def, buf_a.as_mut_bytes());
        let mut b = drop_scene(&def, buf_b.as_mut_bytes());
        let initial = column_hashes(&a);
        let com0 = a.diagnostics().center_of_mass[1];
        let mut com_min = com0;
        let mut frozen = 0;
        for frame in 0..50 {
            let ra = a.step(1.0 / 240.0).expect("step a");
            let rb = b.step(1.0 / 240.0).expect("step b");
            assert_eq!(ra, rb, "{what}: step reports differ at frame {frame}");
            frozen += ra.frozen;
            com_min = com_min.min(a.diagnostics().center_of_mass[1]);
        }
        let ha = column_hashes(&a);
        let hb = column_hashes(&b);
        assert_hashes_equal(&ha, &hb, what);
        assert_eq!(
            hash_bytes(a.as_bytes()),
            hash_bytes(b.as_bytes()),
            "{what}: buffers differ"
        );
        assert_ne!(ha, initial, "{what}: nothing changed in 50 steps");
        // Not vacuous: the block fell onto the floor, deformed and stayed sane.
        assert!(
            com_min < com0 - 0.15,
            "{what}: block did not fall ({com0} -> {com_min})"
        );
        assert!(a.diagnostics().strain > 0.0, "{what}: block never deformed");
        assert_eq!(frozen, 0, "{what}: particles froze");
    }
}

/// The step has a baseline instance and, on x86-64, instances compiled for AVX2 and for
/// AVX-512 (`mpm_gimp::simd`). All round every operation identically, so a result must not
/// depend on which one ran: every shape, order, transfer and dimension form, 30 frames of a
/// block dropped on the floor, stepped by the widest instance, by the widest up to AVX2 and
/// by the baseline, compared bit for bit. (Where the CPU lacks AVX-512 or AVX2, two or all
/// three runs take the same path and the test checks only determinism for them.) The
/// baseline scatters every mode but USF's force scatter on the full row code, with zeros for
/// what a mode does not add, so this also checks that those zeros change no bit.
#[test]
fn every_instruction_set_instance_gives_bit_identical_state() {
    use mpm_gimp::simd::Simd;
    let choices = [Simd::Detect, Simd::Avx2, Simd::Baseline];
    eprintln!(
        "instances compared: {:?}",
        choices.map(|c| c.instance().name())
    );
    let axisymmetric = WorldDef {
        dimension: Dimension::Axisymmetric2D,
        ..def_2d()
    };
    let transfers: &[Transfer] = if cfg!(feature = "effects") {
        &[Transfer::Flip, Transfer::Apic]
    } else {
        &[Transfer::Flip]
    };
    let dims = if cfg!(feature = "effects") {
        vec![def_2d(), axisymmetric, def_3d()]
    } else {
        vec![def_2d(), def_3d()]
    };
    for base in dims {
        for shape in [
            ShapeFunction::Linear,
            ShapeFunction::Gimp,
            ShapeFunction::QuadraticBspline,
            ShapeFunction::CubicBspline,
        ] {
            for (order, &transfer) in [UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl]
                .into_iter()
                .flat_map(|o| transfers.iter().map(move |t| (o, t)))
            {
                let mut def = WorldDef {
                    shape,
                    update_order: order,
                    transfer,
                    ..base
                };
                if def.dimension == Dimension::Axisymmetric2D {
                    // The axis r = 0 on the lower x face's wall plane.
                    def.origin.x = -(shape.margin_cells() as Real) * def.cell_size;
                    def.faces[Face::XMin as usize] = Boundary::Slip;
                }
                let what = format!("{:?} {shape:?} {order:?} {transfer:?}", def.dimension);
                let mut bufs = choices.map(|_| buffer_for(&def));
                let mut worlds = bufs.each_mut().map(|b| drop_scene(&def, b.as_mut_bytes()));
                let initial = column_hashes(&worlds[0]);
                for frame in 0..30 {
                    let reports = choices
                        .iter()
                        .zip(worlds.iter_mut())
                        .map(|(&simd, w)| w.step_with_simd(1.0 / 240.0, simd).expect("step"))
                        .collect::<Vec<_>>();
                    for (r, simd) in reports.iter().zip(choices).skip(1) {
                        assert_eq!(
                            &reports[0], r,
                            "{what}: step reports of {:?} and {simd:?} differ at frame {frame}",
                            choices[0]
                        );
                    }
                }
                let hashes = worlds.each_ref().map(column_hashes);
                assert_ne!(hashes[0], initial, "{what}: nothing changed");
                for (h, simd) in hashes.iter().zip(choices).skip(1) {
                    assert_hashes_equal(&hashes[0], h, &format!("{what}, {simd:?}"));
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Snapshots
// ---------------------------------------------------------------------------------------------

#[test]
fn snapshot_reopened_from_bytes_steps_bit_identically_to_its_original() {
    for def in [def_2d(), def_3d()] {
        let mut buf = buffer_for(&def);
        let mut world = drop_scene(&def, buf.as_mut_bytes());
        for _ in 0..10 {
            world.step(1.0 / 240.0).expect("step");
        }
        let n = world.as_bytes().len();
        assert_eq!(n, memory_requirements(&def).unwrap().bytes);
        let mut copy = HeapBuffer::new(n);
        copy.as_mut_bytes()[..n].copy_from_slice(world.as_bytes());
        let mut twin = World::open(copy.as_mut_bytes()).expect("open snapshot");
        assert_eq!(twin.def(), world.def());
        assert_eq!(twin.particle_count(), world.particle_count());
        assert_eq!(twin.material_count(), world.material_count());
        assert_eq!(twin.step_count(), 10);
        assert_eq!(twin.time().to_bits(), world.time().to_bits());
        assert_eq!(twin.material(0), Some(RUBBER));
        assert_hashes_equal(&column_hashes(&world), &column_hashes(&twin), "at open");
        let before = column_hashes(&world);
        for frame in 0..15 {
            let r = world.step(1.0 / 240.0).expect("step original");
            let t = twin.step(1.0 / 240.0).expect("step twin");
            assert_eq!(r, t, "{:?}: reports differ at frame {frame}", def.dimension);
        }
        let after = column_hashes(&world);
        assert_ne!(before, after, "nothing moved after the snapshot");
        assert_hashes_equal(&after, &column_hashes(&twin), "after stepping");
        assert_eq!(hash_bytes(world.as_bytes()), hash_bytes(twin.as_bytes()));
        assert_eq!(twin.step_count(), 25);
        assert_eq!(twin.time().to_bits(), world.time().to_bits());
    }
}

/// A snapshot read through a shared borrow (`WorldRef`, what concurrent readers and the C
/// interface's const calls use) answers every query exactly as the world it was copied from,
/// and refuses what `World::open` refuses.
#[test]
fn read_only_view_of_a_snapshot_answers_like_the_world() {
    for def in [def_2d(), def_3d()] {
        let mut buf = buffer_for(&def);
        let mut world = drop_scene(&def, buf.as_mut_bytes());
        for _ in 0..5 {
            world.step(1.0 / 240.0).expect("step");
        }
        let n = world.as_bytes().len();
        let mut copy = HeapBuffer::new(n);
        copy.as_mut_bytes()[..n].copy_from_slice(world.as_bytes());
        let read = WorldRef::open(copy.as_bytes()).expect("read snapshot");
        assert_eq!(read.def(), world.def());
        assert_eq!(read.particle_count(), world.particle_count());
        assert_eq!(read.material(0), world.material(0));
        assert_eq!(read.stable_dt().to_bits(), world.stable_dt().to_bits());
        assert_eq!(read.diagnostics(), world.diagnostics());
        assert_eq!(hash_bytes(read.as_bytes()), hash_bytes(world.as_bytes()));
        let (a, b) = (read.particles(), world.particles());
        for axis in 0..3 {
            assert_eq!(hash_reals(a.position[axis]), hash_reals(b.position[axis]));
            assert_eq!(hash_reals(a.velocity[axis]), hash_reals(b.velocity[axis]));
        }
        let zeroed = HeapBuffer::new(n);
        assert_eq!(
            WorldRef::open(zeroed.as_bytes()).err(),
            Some(Error::NotAWorld)
        );
        assert_eq!(
            WorldRef::open(&copy.as_bytes()[..n - 1]).err(),
            Some(Error::BufferTooSmall)
        );
    }
}

#[test]
fn open_rejects_zeroed_corrupted_short_and_misaligned_buffers() {
    let def = def_2d();
    let req = memory_requirements(&def).unwrap();
    let mut zeroed = HeapBuffer::new(req.bytes);
    assert_eq!(
        World::open(zeroed.as_mut_bytes()).err(),
        Some(Error::NotAWorld)
    );

    let mut buf = buffer_for(&def);
    let mut world = drop_scene(&def, buf.as_mut_bytes());
    world.step(1.0 / 240.0).unwrap();
    let snapshot = world.as_bytes().to_vec();
    let n = snapshot.len();

    // The intact copy opens: the rejections below are due to the damage alone.
    let mut copy = HeapBuffer::new(n + 64);
    copy.as_mut_bytes()[..n].copy_from_slice(&snapshot);
    assert!(World::open(copy.as_mut_bytes()).is_ok());

    for byte in 0..8 {
        let mut copy = HeapBuffer::new(n);
        copy.as_mut_bytes()[..n].copy_from_slice(&snapshot);
        copy.as_mut_bytes()[byte] ^= 0x5a;
        assert_eq!(
            World::open(copy.as_mut_bytes()).err(),
            Some(Error::NotAWorld),
            "magic byte {byte} corrupted"
        );
    }

    let mut copy = HeapBuffer::new(n);
    copy.as_mut_bytes()[..n].copy_from_slice(&snapshot);
    assert_eq!(
        World::open(&mut copy.as_mut_bytes()[..n - 1]).err(),
        Some(Error::BufferTooSmall)
    );

    let mut shifted = HeapBuffer::new(n + 64);
    shifted.as_mut_bytes()[1..n + 1].copy_from_slice(&snapshot);
    assert_eq!(
        World::open(&mut shifted.as_mut_bytes()[1..n + 1]).err(),
        Some(Error::BufferMisaligned)
    );
}

// ---------------------------------------------------------------------------------------------
// 4. Definition validation
// ---------------------------------------------------------------------------------------------

/// Definitions that differ from a valid one in exactly one field, with the error they must get.
fn bad_definitions() -> Vec<(&'static str, WorldDef, Error)> {
    let base = def_2d();
    let base3 = def_3d();
    let with = |f: &dyn Fn(&mut WorldDef)| {
        let mut d = base;
        f(&mut d);
        d
    };
    let mut v: Vec<(&'static str, WorldDef, Error)> = vec![
        (
            "axisymmetric, wall plane off the axis",
            with(&|d| d.dimension = Dimension::Axisymmetric2D),
            Error::InvalidAxis,
        ),
        (
            "axisymmetric, open axis face",
            with(&|d| {
                d.dimension = Dimension::Axisymmetric2D;
                d.origin.x = -(d.shape.margin_cells() as Real) * d.cell_size;
                d.faces[0] = Boundary::Open;
            }),
            Error::InvalidAxis,
        ),
        (
            "cell_size 0",
            with(&|d| d.cell_size = 0.0),
            Error::InvalidCellSize,
        ),
        (
            "cell_size NaN",
            with(&|d| d.cell_size = Real::NAN),
            Error::InvalidCellSize,
        ),
        (
            "cell_size -0.01",
            with(&|d| d.cell_size = -0.01),
            Error::InvalidCellSize,
        ),
        (
            "cell_size inf",
            with(&|d| d.cell_size = Real::INFINITY),
            Error::InvalidCellSize,
        ),
        (
            "linear, 1 cell in x",
            with(&|d| {
                d.shape = ShapeFunction::Linear;
                d.cells[0] = 1;
            }),
            Error::InvalidCellCount,
        ),
        (
            "linear, 1 cell in y",
            with(&|d| {
                d.shape = ShapeFunction::Linear;
                d.cells[1] = 1;
            }),
            Error::InvalidCellCount,
        ),
        (
            "particle_capacity 0",
            with(&|d| d.particle_capacity = 0),
            Error::InvalidCapacity,
        ),
        (
            "material_capacity 0",
            with(&|d| d.material_capacity = 0),
            Error::InvalidCapacity,
        ),
        (
            "flip_beta -0.1",
            with(&|d| d.flip_beta = -0.1),
            Error::InvalidFlipBeta,
        ),
        (
            "flip_beta 1.1",
            with(&|d| d.flip_beta = 1.1),
            Error::InvalidFlipBeta,
        ),
        (
            "flip_beta NaN",
            with(&|d| d.flip_beta = Real::NAN),
            Error::InvalidFlipBeta,
        ),
        (
            "pic_rate -1",
            with(&|d| d.pic_rate = -1.0),
            Error::InvalidFlipBeta,
        ),
        (
            "pic_rate NaN",
            with(&|d| d.pic_rate = Real::NAN),
            Error::InvalidFlipBeta,
        ),
        (
            "pic_rate inf",
            with(&|d| d.pic_rate = Real::INFINITY),
            Error::InvalidFlipBeta,
        ),
        ("cfl 0", with(&|d| d.cfl = 0.0), Error::InvalidCfl),
        ("cfl 1.5", with(&|d| d.cfl = 1.5), Error::InvalidCfl),
        ("cfl NaN", with(&|d| d.cfl = Real::NAN), Error::InvalidCfl),
        (
            "exp_terms 0",
            with(&|d| d.exp_terms = 0),
            Error::InvalidExpTerms,
        ),
        (
            "exp_terms 9",
            with(&|d| d.exp_terms = 9),
            Error::InvalidExpTerms,
        ),
        (
            "particles_per_cell 0",
            with(&|d| d.particles_per_cell = 0),
            Error::InvalidParticlesPerCell,
        ),
        (
            "particles_per_cell 9",
            with(&|d| d.particles_per_cell = 9),
            Error::InvalidParticlesPerCell,
        ),
        (
            "origin.x NaN",
            with(&|d| d.origin.x = Real::NAN),
            Error::NonFiniteDefinition,
        ),
        (
            "origin.y inf",
            with(&|d| d.origin.y = Real::INFINITY),
            Error::NonFiniteDefinition,
        ),
        (
            "gravity.y NaN",
            with(&|d| d.gravity.y = Real::NAN),
            Error::NonFiniteDefinition,
        ),
        (
            "gravity.x -inf",
            with(&|d| d.gravity.x = Real::NEG_INFINITY),
            Error::NonFiniteDefinition,
        ),
    ];
    // Shapes with a one-cell margin need 4 cells per axis.
    for shape in [
        ShapeFunction::Gimp,
        ShapeFunction::QuadraticBspline,
        ShapeFunction::CubicBspline,
    ] {
        for axis in 0..2 {
            let mut d = base;
            d.shape = shape;
            d.cells[axis] = 3;
            v.push(("3 cells, margin 1", d, Error::InvalidCellCount));
        }
        let mut d = base3;
        d.shape = shape;
        d.cells[2] = 3;
        v.push(("3D, 3 cells in z, margin 1", d, Error::InvalidCellCount));
    }
    let mut d = base3;
    d.shape = ShapeFunction::Linear;
    d.cells[2] = 1;
    v.push(("3D linear, 1 cell in z", d, Error::InvalidCellCount));
    let mut d = base3;
    d.gravity.z = Real::NAN;
    v.push(("3D gravity.z NaN", d, Error::NonFiniteDefinition));
    v
}

/// Definitions at the edge of each accepted range.
fn edge_definitions() -> Vec<(&'static str, WorldDef)> {
    let base = def_2d();
    let with = |f: &dyn Fn(&mut WorldDef)| {
        let mut d = base;
        f(&mut d);
        d
    };
    vec![
        (
            "linear, 2 cells",
            with(&|d| {
                d.shape = ShapeFunction::Linear;
                d.cells = [2, 2, 1];
            }),
        ),
        ("uGIMP, 4 cells", with(&|d| d.cells = [4, 4, 1])),
        (
            "cubic, 4 cells",
            with(&|d| {
                d.shape = ShapeFunction::CubicBspline;
                d.cells = [4, 4, 1];
            }),
        ),
        ("2D ignores cells[2]", with(&|d| d.cells[2] = 0)),
        ("particle_capacity 1", with(&|d| d.particle_capacity = 1)),
        ("material_capacity 1", with(&|d| d.material_capacity = 1)),
        ("flip_beta 0", with(&|d| d.flip_beta = 0.0)),
        ("flip_beta 1", with(&|d| d.flip_beta = 1.0)),
        ("cfl 1", with(&|d| d.cfl = 1.0)),
        ("exp_terms 1", with(&|d| d.exp_terms = 1)),
        ("exp_terms 8", with(&|d| d.exp_terms = 8)),
        ("particles_per_cell 1", with(&|d| d.particles_per_cell = 1)),
        ("particles_per_cell 8", with(&|d| d.particles_per_cell = 8)),
        (
            "origin and gravity finite, nonzero",
            with(&|d| {
                d.origin = Vec3::new(-3.0, 2.0, 1.0);
                d.gravity = Vec3::new(1.0, -20.0, 0.5);
            }),
        ),
        (
            "axisymmetric, axis on the wall plane",
            with(&|d| {
                d.dimension = Dimension::Axisymmetric2D;
                d.origin.x = -(d.shape.margin_cells() as Real) * d.cell_size;
            }),
        ),
        (
            "3D cubic, 4 cells",
            WorldDef {
                shape: ShapeFunction::CubicBspline,
                cells: [4, 4, 4],
                ..def_3d()
            },
        ),
    ]
}

#[test]
fn memory_requirements_and_init_reject_each_bad_field_with_its_error() {
    // Large enough for any definition here, so only the definition can be at fault.
    let mut big = HeapBuffer::new(1 << 24);
    for (what, def, expected) in bad_definitions() {
        assert_eq!(
            memory_requirements(&def).err(),
            Some(expected),
            "memory_requirements, {what}"
        );
        let bytes = big.as_mut_bytes();
        bytes.fill(0xa5);
        assert_eq!(
            World::init(&def, bytes).err(),
            Some(expected),
            "World::init, {what}"
        );
        assert!(
            big.as_bytes().iter().all(|&b| b == 0xa5),
            "World::init wrote to the buffer although it failed ({what})"
        );
    }
    for (what, def) in edge_definitions() {
        let req = memory_requirements(&def).unwrap_or_else(|e| panic!("{what}: {e:?}"));
        assert!(req.bytes <= big.as_bytes().len(), "{what}");
        let world =
            World::init(&def, big.as_mut_bytes()).unwrap_or_else(|e| panic!("{what}: {e:?}"));
        assert_eq!(world.def(), def, "{what}: definition not kept");
        assert_eq!(world.as_bytes().len(), req.bytes, "{what}");
    }
}

#[test]
fn init_rejects_a_buffer_one_byte_short_or_misaligned() {
    for def in [def_2d(), def_3d()] {
        let req = memory_requirements(&def).unwrap();
        assert_eq!(req.align, mpm_gimp::ALIGN);
        let mut buf = HeapBuffer::new(req.bytes + 2 * req.align);
        let bytes = buf.as_mut_bytes();
        assert_eq!(bytes.as_ptr() as usize % req.align, 0);
        assert_eq!(
            World::init(&def, &mut bytes[..req.bytes - 1]).err(),
            Some(Error::BufferTooSmall)
        );
        assert_eq!(
            World::init(&def, &mut bytes[1..req.bytes + 1]).err(),
            Some(Error::BufferMisaligned)
        );
        assert_eq!(
            World::init(&def, &mut bytes[8..req.bytes + 8]).err(),
            Some(Error::BufferMisaligned)
        );
        // Exactly the requirement, at an aligned start, works.
        assert!(World::init(&def, &mut bytes[..req.bytes]).is_ok());
        assert!(World::init(&def, &mut bytes[req.align..req.align + req.bytes]).is_ok());
    }
}

#[test]
fn memory_requirements_is_pure_and_grows_with_capacity_and_dimension() {
    let d2 = def_2d();
    let a = memory_requirements(&d2).unwrap();
    let b = memory_requirements(&d2).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.align, mpm_gimp::ALIGN);
    assert_eq!(a.align, 64);
    let bigger = memory_requirements(&WorldDef {
        particle_capacity: 2 * d2.particle_capacity,
        ..d2
    })
    .unwrap();
    assert!(bigger.bytes > a.bytes, "{bigger:?} vs {a:?}");
    let more_materials = memory_requirements(&WorldDef {
        material_capacity: 64,
        ..d2
    })
    .unwrap();
    assert!(more_materials.bytes > a.bytes);
    let more_cells = memory_requirements(&WorldDef {
        cells: [40, 20, 1],
        ..d2
    })
    .unwrap();
    assert!(more_cells.bytes > a.bytes);
    // Same cell counts on every axis: 3D needs more than 2D.
    let three = memory_requirements(&def_3d()).unwrap();
    let two = memory_requirements(&WorldDef {
        cells: [20, 20, 20],
        ..d2
    })
    .unwrap();
    assert!(three.bytes > two.bytes, "3D {three:?} vs 2D {two:?}");
    // Fields that do not size anything do not change the requirement.
    let same = memory_requirements(&WorldDef {
        cfl: 0.3,
        flip_beta: 0.5,
        gravity: Vec3::ZERO,
        origin: Vec3::new(1.0, 2.0, 3.0),
        ..d2
    })
    .unwrap();
    assert_eq!(same, a);
}

// ---------------------------------------------------------------------------------------------
// 5. Bad input changes nothing
// ---------------------------------------------------------------------------------------------

#[test]
fn every_rejected_call_returns_its_error_and_changes_no_byte() {
    // Dyadic origin and cell size: the margin planes are exact, so a position on one is
    // unambiguously admissible and half a cell from it unambiguously not.
    let h: Real = 0.0625;
    let def = WorldDef {
        origin: Vec3::new(-0.5, 0.25, 0.0),
        cell_size: h,
        cells: [16, 16, 1],
        particle_capacity: 64,
        material_capacity: 2,
        shape: ShapeFunction::Gimp,
        ..WorldDef::DEFAULT
    };
    let o = def.origin;
    let mut buf = buffer_for(&def);
    let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m0 = world.add_material(&RUBBER).unwrap();
    assert_eq!(m0, 0);
    // 16 particles, stepped so that velocities and stresses are not trivial.
    let ids = world
        .fill_box(
            Vec3::new(-0.125, 0.5, 0.0),
            Vec3::new(0.0, 0.625, 0.0),
            m0,
            Vec3::new(0.2, -0.3, 0.0),
        )
        .unwrap();
    assert_eq!(ids, 0..16);
    world.step(1.0 / 240.0).unwrap();

    // add_material
    let mat = |f: &dyn Fn(&mut MaterialDef)| {
        let mut m = RUBBER;
        f(&mut m);
        m
    };
    let bad_materials = [
        ("E = 0", mat(&|m| m.youngs_modulus = 0.0)),
        ("E = -1", mat(&|m| m.youngs_modulus = -1.0)),
        ("E NaN", mat(&|m| m.youngs_modulus = Real::NAN)),
        ("E inf", mat(&|m| m.youngs_modulus = Real::INFINITY)),
        ("nu = 0.5", mat(&|m| m.poisson_ratio = 0.5)),
        ("nu = -1", mat(&|m| m.poisson_ratio = -1.0)),
        ("nu NaN", mat(&|m| m.poisson_ratio = Real::NAN)),
        ("density 0", mat(&|m| m.density = 0.0)),
        ("density -1", mat(&|m| m.density = -1.0)),
        ("density NaN", mat(&|m| m.density = Real::NAN)),
    ];
    for (what, m) in bad_materials {
        assert_rejected(&mut world, what, Error::InvalidMaterial, |w| {
            w.add_material(&m)
        });
    }
    let m1 = world.add_material(&MaterialDef::DEFAULT).unwrap();
    assert_eq!(m1, 1);
    assert_rejected(
        &mut world,
        "material table full",
        Error::MaterialCapacityExceeded,
        |w| w.add_material(&MaterialDef::DEFAULT),
    );

    // add_particle
    let part = |f: &dyn Fn(&mut ParticleDef)| {
        let mut p = valid_particle();
        f(&mut p);
        p
    };
    let bad_particles = [
        (
            "position NaN",
            part(&|p| p.position.x = Real::NAN),
            Error::NonFiniteInput,
        ),
        (
            "position inf",
            part(&|p| p.position.y = Real::INFINITY),
            Error::NonFiniteInput,
        ),
        (
            "velocity inf",
            part(&|p| p.velocity.x = Real::INFINITY),
            Error::NonFiniteInput,
        ),
        (
            "velocity NaN",
            part(&|p| p.velocity.y = Real::NAN),
            Error::NonFiniteInput,
        ),
        (
            "mass NaN",
            part(&|p| p.mass = Real::NAN),
            Error::NonFiniteInput,
        ),
        (
            "volume inf",
            part(&|p| p.volume = Real::INFINITY),
            Error::NonFiniteInput,
        ),
        (
            "mass 0",
            part(&|p| p.mass = 0.0),
            Error::NonPositiveMassOrVolume,
        ),
        (
            "mass -1",
            part(&|p| p.mass = -1.0),
            Error::NonPositiveMassOrVolume,
        ),
        (
            "volume 0",
            part(&|p| p.volume = 0.0),
            Error::NonPositiveMassOrVolume,
        ),
        (
            "volume -1e-4",
            part(&|p| p.volume = -1.0e-4),
            Error::NonPositiveMassOrVolume,
        ),
        (
            "material 2 (of 2)",
            part(&|p| p.material = 2),
            Error::UnknownMaterial,
        ),
        (
            "material u32::MAX",
            part(&|p| p.material = u32::MAX),
            Error::UnknownMaterial,
        ),
        (
            "x beyond the grid",
            part(&|p| p.position.x = 2.0),
            Error::PositionOutsideDomain,
        ),
        (
            "x below the grid",
            part(&|p| p.position.x = -0.6),
            Error::PositionOutsideDomain,
        ),
        (
            "y below the grid",
            part(&|p| p.position.y = 0.0),
            Error::PositionOutsideDomain,
        ),
        (
            "x in the lower margin",
            part(&|p| p.position.x = o.x + 0.5 * h),
            Error::PositionOutsideDomain,
        ),
        (
            "y in the lower margin",
            part(&|p| p.position.y = o.y + 0.5 * h),
            Error::PositionOutsideDomain,
        ),
        (
            "x in the upper margin",
            part(&|p| p.position.x = o.x + 15.5 * h),
            Error::PositionOutsideDomain,
        ),
        (
            "y in the upper margin",
            part(&|p| p.position.y = o.y + 15.5 * h),
            Error::PositionOutsideDomain,
        ),
    ];
    for (what, p, expected) in bad_particles {
        assert_rejected(&mut world, what, expected, |w| w.add_particle(&p));
    }

    // add_particles: a batch whose last element alone is bad adds nothing.
    let xs: [Real; 5] = [-0.3, -0.2, -0.1, 0.1, 0.2];
    let ys: [Real; 5] = [0.8; 5];
    let zs: [Real; 5] = [0.0; 5];
    let vs: [Real; 5] = [0.5; 5];
    let ms: [Real; 5] = [0.5; 5];
    let vols: [Real; 5] = [1.0e-3; 5];
    let mats: [u32; 5] = [0, 1, 0, 1, 0];
    let batch = ParticleBatch {
        position: [&xs, &ys, &zs],
        velocity: [&vs, &vs, &zs],
        mass: &ms,
        volume: &vols,
        material: &mats,
    };
    let mut last_mass = ms;
    last_mass[4] = 0.0;
    let mut last_x = xs;
    last_x[4] = o.x + 0.5 * h;
    let mut last_y = ys;
    last_y[4] = Real::NAN;
    let mut last_v = vs;
    last_v[4] = Real::INFINITY;
    let mut last_vol = vols;
    last_vol[4] = -1.0;
    let mut last_mat = mats;
    last_mat[4] = 9;
    let bad_batches = [
        (
            "last mass 0",
            ParticleBatch {
                mass: &last_mass,
                ..batch
            },
            Error::NonPositiveMassOrVolume,
        ),
        (
            "last volume -1",
            ParticleBatch {
                volume: &last_vol,
                ..batch
            },
            Error::NonPositiveMassOrVolume,
        ),
        (
            "last x in the margin",
            ParticleBatch {
                position: [&last_x, &ys, &zs],
                ..batch
            },
            Error::PositionOutsideDomain,
        ),
        (
            "last y NaN",
            ParticleBatch {
                position: [&xs, &last_y, &zs],
                ..batch
            },
            Error::NonFiniteInput,
        ),
        (
            "last velocity inf",
            ParticleBatch {
                velocity: [&last_v, &vs, &zs],
                ..batch
            },
            Error::NonFiniteInput,
        ),
        (
            "last material unknown",
            ParticleBatch {
                material: &last_mat,
                ..batch
            },
            Error::UnknownMaterial,
        ),
        (
            "volume slice shorter",
            ParticleBatch {
                volume: &vols[..4],
                ..batch
            },
            Error::LengthMismatch,
        ),
        (
            "x slice shorter",
            ParticleBatch {
                position: [&xs[..4], &ys, &zs],
                ..batch
            },
            Error::LengthMismatch,
        ),
        (
            "velocity y slice longer",
            ParticleBatch {
                velocity: [&vs[..4], &vs[..4], &zs],
                mass: &ms[..4],
                volume: &vols[..4],
                material: &mats[..4],
                position: [&xs[..4], &ys, &zs[..4]],
            },
            Error::LengthMismatch,
        ),
        (
            "material slice longer",
            ParticleBatch {
                mass: &ms[..4],
                volume: &vols[..4],
                position: [&xs[..4], &ys[..4], &zs],
                velocity: [&vs[..4], &vs[..4], &zs],
                material: &mats,
            },
            Error::LengthMismatch,
        ),
    ];
    for (what, b, expected) in bad_batches {
        assert_rejected(&mut world, what, expected, |w| w.add_particles(&b));
    }

    // A batch one larger than the remaining room adds nothing.
    let room = 64 - world.particle_count();
    let over = room + 1;
    let bx: Vec<Real> = (0..over)
        .map(|i| -0.4 + 0.8 * i as Real / over as Real)
        .collect();
    let by: Vec<Real> = vec![1.0; over];
    let bz: Vec<Real> = vec![0.0; over];
    let bm: Vec<Real> = vec![0.1; over];
    let bmat: Vec<u32> = vec![0; over];
    let big = ParticleBatch {
        position: [&bx, &by, &bz],
        velocity: [&bz, &bz, &bz],
        mass: &bm,
        volume: &bm,
        material: &bmat,
    };
    assert_rejected(
        &mut world,
        "batch of room + 1",
        Error::ParticleCapacityExceeded,
        |w| w.add_particles(&big),
    );

    // Fill helpers.
    let z = Vec3::ZERO;
    assert_rejected(
        &mut world,
        "fill_box over capacity",
        Error::ParticleCapacityExceeded,
        |w| w.fill_box(Vec3::new(-0.4, 0.35, 0.0), Vec3::new(0.4, 1.15, 0.0), 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_box partly outside",
        Error::PositionOutsideDomain,
        |w| w.fill_box(Vec3::new(0.3, 0.5, 0.0), Vec3::new(0.6, 0.6, 0.0), 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_box reaching into the margin",
        Error::PositionOutsideDomain,
        |w| {
            w.fill_box(
                Vec3::new(o.x + 0.5 * h, 0.5, 0.0),
                Vec3::new(0.0, 0.6, 0.0),
                0,
                z,
            )
        },
    );
    assert_rejected(
        &mut world,
        "fill_box min.x > max.x",
        Error::InvalidRegion,
        |w| w.fill_box(Vec3::new(0.2, 0.5, 0.0), Vec3::new(0.1, 0.6, 0.0), 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_box min.y > max.y",
        Error::InvalidRegion,
        |w| w.fill_box(Vec3::new(0.1, 0.6, 0.0), Vec3::new(0.2, 0.5, 0.0), 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_box NaN corner",
        Error::NonFiniteInput,
        |w| {
            w.fill_box(
                Vec3::new(Real::NAN, 0.5, 0.0),
                Vec3::new(0.2, 0.6, 0.0),
                0,
                z,
            )
        },
    );
    assert_rejected(
        &mut world,
        "fill_box unknown material",
        Error::UnknownMaterial,
        |w| w.fill_box(Vec3::new(0.1, 0.5, 0.0), Vec3::new(0.2, 0.6, 0.0), 5, z),
    );
    assert_rejected(&mut world, "fill_sphere in 2D", Error::InvalidRegion, |w| {
        w.fill_sphere(Vec3::new(0.0, 0.7, 0.0), 0.05, 0, z)
    });
    assert_rejected(
        &mut world,
        "fill_disk radius 0",
        Error::InvalidRegion,
        |w| w.fill_disk(Vec3::new(0.0, 0.7, 0.0), 0.0, 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_disk radius -1",
        Error::InvalidRegion,
        |w| w.fill_disk(Vec3::new(0.0, 0.7, 0.0), -1.0, 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_disk radius NaN",
        Error::InvalidRegion,
        |w| w.fill_disk(Vec3::new(0.0, 0.7, 0.0), Real::NAN, 0, z),
    );
    assert_rejected(
        &mut world,
        "fill_disk partly outside",
        Error::PositionOutsideDomain,
        |w| w.fill_disk(Vec3::new(0.42, 0.7, 0.0), 0.05, 0, z),
    );

    // step
    for dt in [
        0.0,
        -0.0,
        -1.0,
        Real::NAN,
        Real::INFINITY,
        Real::NEG_INFINITY,
    ] {
        assert_rejected(
            &mut world,
            &format!("step({dt})"),
            Error::InvalidTimeStep,
            |w| w.step(dt),
        );
    }
    // Finite and positive, but more than `max_substeps` stable substeps.
    assert_rejected(&mut world, "step(1e9)", Error::SubstepLimit, |w| {
        w.step(1.0e9)
    });
    assert_rejected(
        &mut world,
        "remove_tractions without tractions declared",
        Error::EffectNotDeclared,
        |w| w.remove_tractions(0..0),
    );

    // Control: the accepted neighbours of the rejected calls do change the world, so the hash
    // comparison above could have failed.
    let before = hash_bytes(world.as_bytes());
    let id = world
        .add_particle(&part(&|p| p.position.x = o.x + 1.0 * h))
        .expect("x exactly on the margin plane is admissible");
    assert_eq!(id, 16);
    world
        .add_particle(&part(&|p| p.position.y = o.y + 15.0 * h))
        .expect("y exactly on the upper margin plane is admissible");
    world.add_particles(&batch).expect("valid batch");
    assert_eq!(world.particle_count(), 23);
    world.step(1.0 / 240.0).expect("valid step");
    assert_ne!(hash_bytes(world.as_bytes()), before);

    // In 3D the disk is not defined.
    let def3 = WorldDef {
        cells: [8, 8, 8],
        ..def_3d()
    };
    let mut buf3 = buffer_for(&def3);
    let mut world3 = World::init(&def3, buf3.as_mut_bytes()).unwrap();
    let m = world3.add_material(&RUBBER).unwrap();
    world3.fill_sphere(Vec3::splat(0.2), 0.05, m, z).unwrap();
    assert_rejected(&mut world3, "fill_disk in 3D", Error::InvalidRegion, |w| {
        w.fill_disk(Vec3::splat(0.2), 0.05, m, z)
    });
    assert_rejected(
        &mut world3,
        "fill_box inverted z in 3D",
        Error::InvalidRegion,
        |w| w.fill_box(Vec3::new(0.1, 0.1, 0.3), Vec3::new(0.2, 0.2, 0.2), m, z),
    );
    assert_rejected(
        &mut world3,
        "3D particle in the z margin",
        Error::PositionOutsideDomain,
        |w| {
            w.add_particle(&ParticleDef {
                position: Vec3::new(0.2, 0.2, 0.025),
                material: m,
                ..valid_particle()
            })
        },
    );
    assert_rejected(
        &mut world3,
        "3D velocity.z NaN",
        Error::NonFiniteInput,
        |w| {
            w.add_particle(&ParticleDef {
                position: Vec3::splat(0.2),
                velocity: Vec3::new(0.0, 0.0, Real::NAN),
                material: m,
                ..valid_particle()
            })
        },
    );
}

// ---------------------------------------------------------------------------------------------
// 6. Capacity
// ---------------------------------------------------------------------------------------------

#[test]
fn filling_exactly_to_capacity_succeeds_and_one_more_fails() {
    // 100 is not a multiple of the column padding: the limit is the capacity, not the padding.
    let def = WorldDef {
        particle_capacity: 100,
        ..def_2d()
    };
    let mut buf = buffer_for(&def);

    // With single particles and a batch.
    {
        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
        let m = world.add_material(&RUBBER).unwrap();
        let xs: Vec<Real> = (0..99).map(|i| 0.1 + 0.008 * i as Real).collect();
        let ys = vec![0.5 as Real; 99];
        let zeros = vec![0.0 as Real; 99];
        let ms = vec![0.01 as Real; 99];
        let mats = vec![m; 99];
        let ids = world
            .add_particles(&ParticleBatch {
                position: [&xs, &ys, &zeros],
                velocity: [&zeros, &zeros, &zeros],
                mass: &ms,
                volume: &ms,
                material: &mats,
            })
            .expect("99 of 100");
        assert_eq!(ids, 0..99);
        let last = ParticleDef {
            position: Vec3::new(0.5, 0.6, 0.0),
            material: m,
            ..valid_particle()
        };
        assert_eq!(world.add_particle(&last), Ok(99));
        assert_eq!(world.particle_count(), 100);
        assert_rejected(
            &mut world,
            "101st particle",
            Error::ParticleCapacityExceeded,
            |w| w.add_particle(&last),
        );
        assert_rejected(
            &mut world,
            "101st by batch",
            Error::ParticleCapacityExceeded,
            |w| {
                w.add_particles(&ParticleBatch {
                    position: [&xs[..1], &ys[..1], &[]],
                    velocity: [&xs[..1], &ys[..1], &[]],
                    mass: &ms[..1],
                    volume: &ms[..1],
                    material: &mats[..1],
                })
            },
        );
        assert_rejected(
            &mut world,
            "101st by fill_box",
            Error::ParticleCapacityExceeded,
            |w| w.fill_box(Vec3::splat(0.51), Vec3::splat(0.52), m, Vec3::ZERO),
        );
        // A full world still steps.
        world.step(1.0 / 240.0).expect("full world steps");
        assert_eq!(world.particle_count(), 100);
    }

    // With fill_box: 10 x 10 sites (spacing 0.025) is exactly the capacity.
    let (lo, hi) = (Vec3::new(0.3, 0.3, 0.0), Vec3::new(0.55, 0.55, 0.0));
    {
        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
        let m = world.add_material(&RUBBER).unwrap();
        assert_eq!(world.fill_box(lo, hi, m, Vec3::ZERO), Ok(0..100));
        assert_rejected(
            &mut world,
            "fill_box when full",
            Error::ParticleCapacityExceeded,
            |w| w.fill_box(Vec3::splat(0.61), Vec3::splat(0.64), m, Vec3::ZERO),
        );
        assert_rejected(
            &mut world,
            "add_particle when full",
            Error::ParticleCapacityExceeded,
            |w| {
                w.add_particle(&ParticleDef {
                    material: m,
                    ..valid_particle()
                })
            },
        );
    }
    {
        let def99 = WorldDef {
            particle_capacity: 99,
            ..def
        };
        let mut world = World::init(&def99, buf.as_mut_bytes()).unwrap();
        let m = world.add_material(&RUBBER).unwrap();
        assert_rejected(
            &mut world,
            "100 sites in 99",
            Error::ParticleCapacityExceeded,
            |w| w.fill_box(lo, hi, m, Vec3::ZERO),
        );
        assert_eq!(world.particle_count(), 0);
    }
}

// ---------------------------------------------------------------------------------------------
// 7. Error strings
// ---------------------------------------------------------------------------------------------

#[test]
fn every_error_has_a_distinct_message_and_its_one_based_position_as_number() {
    let mut seen = HashSet::new();
    for (i, e) in Error::ALL.iter().enumerate() {
        let s = e.as_str();
        assert!(!s.trim().is_empty(), "{e:?} has an empty message");
        assert!(seen.insert(s), "{e:?} repeats the message {s:?}");
        assert_eq!(*e as u32, i as u32 + 1, "{e:?} is numbered out of place");
        assert_eq!(e.to_string(), s, "{e:?}: Display differs from as_str");
    }
    assert_eq!(seen.len(), Error::ALL.len());
    // Every variant is listed once (distinct numbers, and the last number is the count).
    let numbers: HashSet<u32> = Error::ALL.iter().map(|&e| e as u32).collect();
    assert_eq!(numbers.len(), Error::ALL.len());
    assert_eq!(Error::InvalidBoundary as u32 as usize, Error::ALL.len());
}

// ---------------------------------------------------------------------------------------------
// 8. Fill helpers
// ---------------------------------------------------------------------------------------------

/// Lattice indices k with `origin + (k + 1/2) s` in `[lo, hi]`, counted by brute force in f64.
fn sites_in(origin: f64, s: f64, lo: f64, hi: f64) -> Vec<i64> {
    (-1000..1000)
        .filter(|&k| {
            let x = origin + (k as f64 + 0.5) * s;
            x >= lo && x <= hi
        })
        .collect()
}

/// Checks every particle of `ids` against the fill contract: on a lattice site inside `[lo, hi]`,
/// mass `density s^D`, volume `s^D`, the given velocity, F = I, zero stress, active.
/// Returns the lattice indices of the particles.
#[allow(clippy::too_many_arguments)]
fn check_filled(
    world: &World<'_>,
    ids: std::ops::Range<u32>,
    lo: Vec3,
    hi: Vec3,
    material: u32,
    density: Real,
    velocity: Vec3,
    what: &str,
) -> Vec<[i64; 3]> {
    let def = world.def();
    let d = def.axes();
    let s = def.cell_size / def.particles_per_cell as Real;
    let cell_volume = (0..d).fold(1.0 as Real, |v, _| v * s);
    let tol = 8.0 * Real::EPSILON;
    let p = world.particles();
    let mut sites = Vec::new();
    for i in ids.start as usize..ids.end as usize {
        assert!(
            rel_close(p.volume0[i], cell_volume, tol),
            "{what}: volume {} != {cell_volume}",
            p.volume0[i]
        );
        assert!(
            rel_close(p.mass[i], density * cell_volume, tol),
            "{what}: mass {} != {}",
            p.mass[i],
            density * cell_volume
        );
        assert_eq!(p.material[i], material, "{what}");
        assert_eq!(
            ParticleStatus::from_code(p.status[i]),
            Some(ParticleStatus::Active),
            "{what}"
        );
        let mut k = [0i64; 3];
        for a in 0..d {
            let x = p.position[a][i];
            assert!(
                x >= lo[a] && x <= hi[a],
                "{what}: particle {i} axis {a} at {x} outside the box"
            );
            let t = (x - def.origin[a]) / s - 0.5;
            assert!(
                (t - t.round()).abs() < 1.0e-3,
                "{what}: particle {i} axis {a} at {x} is not on a lattice site"
            );
            k[a] = t.round() as i64;
            assert_eq!(p.velocity[a][i], velocity[a], "{what}: velocity");
            for b in 0..d {
                // F = I: the displacement gradient H = F - I is zero.
                assert_eq!(p.displacement_gradient[a][b][i], 0.0, "{what}: F - I");
            }
        }
        for c in p.stress.iter().filter(|c| !c.is_empty()) {
            assert_eq!(c[i], 0.0, "{what}: stress");
        }
        sites.push(k);
    }
    let distinct: HashSet<[i64; 3]> = sites.iter().copied().collect();
    assert_eq!(
        distinct.len(),
        sites.len(),
        "{what}: two particles on one site"
    );
    sites
}

#[test]
fn fill_box_puts_one_particle_of_sub_cell_mass_and_volume_on_each_site_in_the_box() {
    let density: Real = 1234.0;
    let material = MaterialDef { density, ..RUBBER };
    let v = Vec3::new(0.25, -0.5, 0.125);
    for n in 1..=4u32 {
        // 2D, box edges between sites.
        let def = WorldDef {
            origin: Vec3::new(0.1, -0.2, 7.0),
            particles_per_cell: n,
            particle_capacity: 4096,
            ..def_2d()
        };
        let h = def.cell_size;
        let s = wide(h / n as Real);
        let mut buf = buffer_for(&def);
        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
        let m = world.add_material(&material).unwrap();
        let (lo, hi) = (Vec3::new(0.33, 0.12, 0.0), Vec3::new(0.71, 0.43, 0.0));
        let ids = world.fill_box(lo, hi, m, v).unwrap();
        let kx = sites_in(0.1, s, wide(lo.x), wide(hi.x));
        let ky = sites_in(-0.2, s, wide(lo.y), wide(hi.y));
        let what = format!("2D box, {n} per cell");
        assert!(kx.len() >= 7 * n as usize, "{what}");
        assert_eq!(ids, 0..(kx.len() * ky.len()) as u32, "{what}");
        let sites = check_filled(&world, ids.clone(), lo, hi, m, density, v, &what);
        for k in &sites {
            assert!(kx.contains(&k[0]) && ky.contains(&k[1]), "{what}: {k:?}");
        }

        // 2D, box edges on lattice edges: the total mass is the box's.
        let s_r = h / n as Real;
        let (lo, hi) = (
            Vec3::new(
                0.1 + 4.0 * n as Real * s_r,
                -0.2 + 3.0 * n as Real * s_r,
                0.0,
            ),
            Vec3::new(
                0.1 + 13.0 * n as Real * s_r,
                -0.2 + 9.0 * n as Real * s_r,
                0.0,
            ),
        );
        let before = world.diagnostics().mass;
        let ids = world.fill_box(lo, hi, m, v).unwrap();
        let expect_count = (9 * n * 6 * n) as usize;
        assert_eq!(ids.len(), expect_count, "2D aligned box, {n} per cell");
        check_filled(&world, ids, lo, hi, m, density, v, "2D aligned box");
        let added = world.diagnostics().mass - before;
        let box_mass = wide(density) * (9.0 * wide(h)) * (6.0 * wide(h));
        assert!(
            (added - box_mass).abs() <= 1.0e-5 * box_mass,
            "2D aligned box, {n} per cell: mass {added} != {box_mass}"
        );
    }

    // 3D, box edges between sites, then on lattice edges.
    let def = WorldDef {
        dimension: Dimension::ThreeD,
        origin: Vec3::new(-0.3, 0.0, 0.2),
        cells: [10, 10, 10],
        cell_size: 0.1,
        particles_per_cell: 2,
        particle_capacity: 4096,
        ..def_2d()
    };
    let s = 0.05f64;
    let mut buf = buffer_for(&def);
    let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = world.add_material(&material).unwrap();
    let (lo, hi) = (Vec3::new(-0.12, 0.31, 0.47), Vec3::new(0.18, 0.52, 0.64));
    let ids = world.fill_box(lo, hi, m, v).unwrap();
    let kx = sites_in(-0.3, s, wide(lo.x), wide(hi.x));
    let ky = sites_in(0.0, s, wide(lo.y), wide(hi.y));
    let kz = sites_in(0.2, s, wide(lo.z), wide(hi.z));
    assert_eq!(ids.len(), kx.len() * ky.len() * kz.len(), "3D box");
    let sites = check_filled(&world, ids, lo, hi, m, density, v, "3D box");
    for k in &sites {
        assert!(kx.contains(&k[0]) && ky.contains(&k[1]) && kz.contains(&k[2]));
    }
    let (lo, hi) = (Vec3::new(-0.1, 0.2, 0.4), Vec3::new(0.2, 0.4, 0.9));
    let before = world.diagnostics().mass;
    let ids = world.fill_box(lo, hi, m, v).unwrap();
    assert_eq!(ids.len(), 6 * 4 * 10, "3D aligned box");
    check_filled(&world, ids, lo, hi, m, density, v, "3D aligned box");
    let added = world.diagnostics().mass - before;
    let box_mass = wide(density) * 0.3 * 0.2 * 0.5;
    assert!(
        (added - box_mass).abs() <= 1.0e-5 * box_mass,
        "3D aligned box: mass {added} != {box_mass}"
    );
}

#[test]
fn fill_disk_and_fill_sphere_cover_the_sites_inside_and_match_the_area_and_volume() {
    let density: Real = 900.0;
    let material = MaterialDef { density, ..RUBBER };
    // Disk: r = 12 sites; no site lies at distance exactly r (odd squares sum to 2 mod 8).
    let def = WorldDef {
        particles_per_cell: 2,
        ..def_2d()
    };
    let s: Real = 0.025;
    let mut buf = buffer_for(&def);
    let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = world.add_material(&material).unwrap();
    let (c, r) = (Vec3::new(0.5, 0.5, 0.0), 0.3 as Real);
    let v = Vec3::new(1.0, 2.0, 3.0);
    let ids = world.fill_disk(c, r, m, v).unwrap();
    let r2 = wide(r) * wide(r);
    let mut exact = 0usize;
    for i in 0..40i64 {
        for j in 0..40i64 {
            let x = (i as f64 + 0.5) * wide(s) - 0.5;
            let y = (j as f64 + 0.5) * wide(s) - 0.5;
            if x * x + y * y <= r2 {
                exact += 1;
            }
        }
    }
    assert_eq!(ids.len(), exact, "disk: lattice sites inside");
    let area_count = std::f64::consts::PI * r2 / (wide(s) * wide(s));
    let n = ids.len() as f64;
    assert!(
        (n - area_count).abs() <= 0.03 * area_count,
        "disk: {n} particles for pi r^2 / s^2 = {area_count}"
    );
    let lo = c - Vec3::splat(r);
    let hi = c + Vec3::splat(r);
    check_filled(&world, ids.clone(), lo, hi, m, density, v, "disk");
    let p = world.particles();
    for i in ids.start as usize..ids.end as usize {
        let (dx, dy) = (p.position[0][i] - c.x, p.position[1][i] - c.y);
        assert!(
            dx * dx + dy * dy <= r * r * (1.0 + 1.0e-5),
            "disk: particle {i} outside"
        );
    }
    let mass = world.diagnostics().mass;
    let disk_mass = wide(density) * std::f64::consts::PI * r2;
    assert!(
        (mass - disk_mass).abs() <= 0.03 * disk_mass,
        "disk mass {mass} vs {disk_mass}"
    );

    // Sphere: r = 6 sites; no site at distance exactly r (odd squares sum to 3 mod 8).
    let def = WorldDef {
        dimension: Dimension::ThreeD,
        cells: [12, 12, 12],
        particles_per_cell: 2,
        ..def_2d()
    };
    let mut buf = buffer_for(&def);
    let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = world.add_material(&material).unwrap();
    let (c, r) = (Vec3::splat(0.3), 0.15 as Real);
    let ids = world.fill_sphere(c, r, m, v).unwrap();
    let r2 = wide(r) * wide(r);
    let mut exact = 0usize;
    for i in 0..24i64 {
        for j in 0..24i64 {
            for k in 0..24i64 {
                let q = [i, j, k].map(|t| (t as f64 + 0.5) * wide(s) - 0.3);
                if q.iter().map(|x| x * x).sum::<f64>() <= r2 {
                    exact += 1;
                }
            }
        }
    }
    assert_eq!(ids.len(), exact, "sphere: lattice sites inside");
    let volume_count = 4.0 / 3.0 * std::f64::consts::PI * r2 * wide(r) / wide(s).powi(3);
    let n = ids.len() as f64;
    assert!(
        (n - volume_count).abs() <= 0.05 * volume_count,
        "sphere: {n} particles for 4/3 pi r^3 / s^3 = {volume_count}"
    );
    check_filled(
        &world,
        ids,
        c - Vec3::splat(r),
        c + Vec3::splat(r),
        m,
        density,
        v,
        "sphere",
    );
}
