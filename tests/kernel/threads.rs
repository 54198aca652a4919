//! The step on a task system ([`World::step_with_tasks`]) gives, for every worker count, the
//! bits of the step on one worker ([`World::step`]): the state bytes (header, materials, every
//! particle column with the effects' ones), the step reports and the diagnostics are compared
//! exactly after 8 frames, for 1, 2, 3, 4, 7, 8 and 16 workers (and 3 on each instruction
//! set), on every dimension form, shape, update order, transfer, material model and effect.
//! The task system here is a hostile one: it cuts the items into uneven ranges, hands them to
//! its threads in a shuffled order and runs each thread's ranges backwards, so a result that
//! depended on how or in what order the items run would differ.

use mpm_gimp::simd::Simd;
use mpm_gimp::{
    memory_requirements, Boundary, Damping, Dimension, Effects, Face, HeapBuffer, MaterialDef,
    MaterialModel, Real, ScalarField, Schedule, ShapeFunction, StepReport, TaskSystem, Transfer,
    Transport, UpdateOrder, Vec3, World, WorldDef,
};
use std::sync::atomic::{AtomicU64, Ordering};

/// The worker counts every scene is stepped with.
const WORKERS: [usize; 7] = [1, 2, 3, 4, 7, 8, 16];

/// A task system of `n` threads that cuts and orders the items as unhelpfully as its
/// contract allows.
struct Hostile {
    n: usize,
    pool: rayon::ThreadPool,
    seed: AtomicU64,
}

impl Hostile {
    fn new(n: usize) -> Self {
        Hostile {
            n,
            pool: rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("thread pool"),
            seed: AtomicU64::new(0x9e37_79b9_7f4a_7c15 ^ n as u64),
        }
    }

    fn next(&self) -> u64 {
        let s = self
            .seed
            .fetch_add(0x9e37_79b9_7f4a_7c15, Ordering::Relaxed)
            .wrapping_mul(0xbf58_476d_1ce4_e5b9);
        s ^ (s >> 31)
    }
}

// SAFETY: the ranges partition `0..items`; each thread runs its own list, with its own
// index, and the scope returns when every thread has.
unsafe impl TaskSystem for Hostile {
    fn worker_count(&self) -> usize {
        self.n
    }

    fn parallel_for(&self, items: usize, min_range: usize, task: &mpm_gimp::tasks::Task<'_>) {
        // What the trait promises a system that keeps a bit per item (the C adapter).
        assert!(
            items <= mpm_gimp::tasks::MAX_ITEMS,
            "a loop of {items} items"
        );
        // Uneven ranges of at least min_range (the last may be shorter).
        let mut ranges = Vec::new();
        let mut start = 0;
        while start < items {
            let len = min_range.max(1) + (self.next() % 3) as usize;
            let end = (start + len).min(items);
            ranges.push(start..end);
            start = end;
        }
        // Shuffled over the threads; each runs its own backwards.
        let mut per_worker = vec![Vec::new(); self.n];
        for r in ranges {
            let w = (self.next() % self.n as u64) as usize;
            per_worker[w].push(r);
        }
        self.pool.scope(|s| {
            for (w, mine) in per_worker.into_iter().enumerate() {
                s.spawn(move |_| {
                    for r in mine.into_iter().rev() {
                        task(r.start, r.end, w);
                    }
                });
            }
        });
    }
}

/// A block of `material` thrown onto a stick floor, with the effects of `def` given values.
fn scene<'a>(def: &WorldDef, material: &MaterialDef, buf: &'a mut [u8]) -> World<'a> {
    let mut world = World::init(def, buf).expect("init");
    let m = world.add_material(material).expect("material");
    let (lo, hi) = if def.axes() == 3 {
        (Vec3::new(0.3, 0.25, 0.3), Vec3::new(0.6, 0.5, 0.55))
    } else {
        (Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.7, 0.6, 0.0))
    };
    let ids = world
        .fill_box(lo, hi, m, Vec3::new(0.4, -1.5, 0.2))
        .expect("block fits");
    // And a slab two cells thick against the admissible region's end along x: the stencils
    // there reach the grid's last node, whose rows reach past their line's end (the tiles
    // then run in two colours).
    let h = def.cell_size;
    let x_max = def.origin.x + (def.cells[0] as Real - def.shape.margin_cells() as Real) * h;
    let (slab_lo, slab_hi) = (
        Vec3::new(x_max - 2.0 * h, lo.y, lo.z),
        Vec3::new(x_max, hi.y, hi.z),
    );
    let slab = world
        .fill_box(slab_lo, slab_hi, m, Vec3::new(0.0, -1.5, 0.0))
        .expect("slab fits");
    let ids = ids.start..slab.end;
    let n = ids.len();
    let ramp: Vec<Real> = (0..n).map(|i| (i % 17) as Real / 17.0).collect();
    let fx = def.effects;
    if fx.particle_forces {
        let f: Vec<Real> = ramp.iter().map(|r| 1e-3 * (r - 0.5)).collect();
        world
            .set_particle_forces(ids.start, [&f, &ramp, &f])
            .expect("forces");
    }
    if fx.heat.is_some() {
        let t: Vec<Real> = ramp.iter().map(|r| 300.0 + 50.0 * r).collect();
        world
            .set_particle_scalar(ScalarField::Temperature, ids.start, &t)
            .expect("temperatures");
    }
    if fx.diffusion.is_some() {
        world
            .set_particle_scalar(ScalarField::Concentration, ids.start, &ramp)
            .expect("concentrations");
    }
    world
}

/// Steps the scene 8 frames with one worker and with each of [`WORKERS`], and asserts the
/// same state bytes and reports.
fn check(def: &WorldDef, material: &MaterialDef, what: &str) {
    let def = WorldDef {
        workers: 16,
        ..*def
    };
    let bytes = memory_requirements(&def).expect("valid").bytes;
    let mut serial_buf = HeapBuffer::new(bytes);
    let mut serial = scene(&def, material, serial_buf.as_mut_bytes());
    let mut reports: Vec<StepReport> = Vec::new();
    let dt = 1.0 / 240.0;
    for _ in 0..8 {
        reports.push(serial.step(dt).expect("serial step"));
    }
    assert!(
        reports.iter().any(|r| r.substeps > 0) && serial.particle_count() > 100,
        "{what}: scene too small"
    );
    // Every worker count on the instruction set the CPU picks, and 3 workers on the others.
    let runs = WORKERS
        .iter()
        .map(|&n| (n, Simd::Detect))
        .chain([(3, Simd::Avx2), (3, Simd::Baseline)]);
    for (n, simd) in runs {
        let tasks = Hostile::new(n);
        let mut buf = HeapBuffer::new(bytes);
        let mut world = scene(&def, material, buf.as_mut_bytes());
        for (frame, expected) in reports.iter().enumerate() {
            let r = world.step_on(dt, simd, &tasks).expect("parallel step");
            assert_eq!(
                &r, expected,
                "{what}, {n} workers, {simd:?}: report of frame {frame}"
            );
        }
        assert!(
            world.state_bytes() == serial.state_bytes(),
            "{what}, {n} workers, {simd:?}: state differs from one worker's"
        );
        assert_eq!(
            world.diagnostics_with_tasks(&tasks),
            serial.diagnostics(),
            "{what}, {n} workers: diagnostics"
        );
    }
}

fn base(dimension: Dimension) -> WorldDef {
    let mut def = WorldDef {
        dimension,
        cells: if dimension == Dimension::ThreeD {
            [16, 16, 16]
        } else {
            [32, 32, 1]
        },
        cell_size: 1.0 / 32.0,
        particle_capacity: 8192,
        material_capacity: 2,
        ..WorldDef::DEFAULT
    };
    if dimension == Dimension::ThreeD {
        def.cell_size = 1.0 / 16.0;
    }
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def
}

const RUBBER: MaterialDef = MaterialDef {
    youngs_modulus: 2.0e5,
    ..MaterialDef::DEFAULT
};

#[test]
fn every_shape_order_and_transfer_gives_one_workers_bits() {
    for dimension in [
        Dimension::Plane2D,
        Dimension::Axisymmetric2D,
        Dimension::ThreeD,
    ] {
        for shape in [
            ShapeFunction::Linear,
            ShapeFunction::Gimp,
            ShapeFunction::CpGimp,
            ShapeFunction::QuadraticBspline,
            ShapeFunction::CubicBspline,
        ] {
            for order in [UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl] {
                for transfer in [
                    Transfer::Flip,
                    Transfer::FlipParticleVelocity,
                    Transfer::Apic,
                    Transfer::Mls,
                    Transfer::FlipMomentum,
                ] {
                    let mut def = WorldDef {
                        shape,
                        update_order: order,
                        transfer,
                        ..base(dimension)
                    };
                    if dimension == Dimension::Axisymmetric2D {
                        // The axis r = 0 on the lower x face's wall plane.
                        def.origin.x = -(shape.margin_cells() as Real) * def.cell_size;
                        def.faces[Face::XMin as usize] = Boundary::Slip;
                    }
                    if memory_requirements(&def).is_err() {
                        continue; // A combination the definition refuses (MLS with GIMP, ...).
                    }
                    let what = format!("{dimension:?} {shape:?} {order:?} {transfer:?}");
                    check(&def, &RUBBER, &what);
                }
            }
        }
    }
}

#[test]
fn every_material_and_effect_gives_one_workers_bits() {
    for dimension in [Dimension::Plane2D, Dimension::ThreeD] {
        for model in MaterialModel::ALL {
            let def = WorldDef {
                effects: Effects {
                    plasticity: true,
                    ..Effects::NONE
                },
                ..base(dimension)
            };
            let material = MaterialDef {
                model,
                viscosity: if model == MaterialModel::Fluid {
                    1e-3
                } else {
                    0.0
                },
                ..RUBBER
            };
            check(&def, &material, &format!("{dimension:?} {model:?}"));
        }
        let heat = Transport {
            faces: [mpm_gimp::ScalarBoundary::Fixed(290.0); 6],
            ..Transport::INSULATED
        };
        let effects = [
            (
                "damping",
                Effects {
                    damping: Some(Damping {
                        grid: Schedule::constant(2.0),
                        particle: Schedule::constant(1.0),
                        per_particle: true,
                        ..Damping::NONE
                    }),
                    ..Effects::NONE
                },
            ),
            (
                "nodal damping",
                Effects {
                    damping: Some(Damping {
                        grid: Schedule::constant(2.0),
                        grid_on_force: true,
                        zones: [
                            mpm_gimp::DampingZone {
                                min: Vec3::new(0.0, 0.0, 0.0),
                                max: Vec3::new(0.5, 0.4, 0.5),
                                rate: 5.0,
                                ramp: None,
                            },
                            mpm_gimp::DampingZone::NONE,
                            mpm_gimp::DampingZone::NONE,
                            mpm_gimp::DampingZone::NONE,
                        ],
                        zone_count: 1,
                        ..Damping::NONE
                    }),
                    ..Effects::NONE
                },
            ),
            (
                "particle forces",
                Effects {
                    particle_forces: true,
                    ..Effects::NONE
                },
            ),
            (
                "heat and diffusion",
                Effects {
                    heat: Some(heat),
                    diffusion: Some(Transport::INSULATED),
                    ..Effects::NONE
                },
            ),
        ];
        for (name, effects) in effects {
            let def = WorldDef {
                effects,
                ..base(dimension)
            };
            let material = MaterialDef {
                conductivity: 0.5,
                heat_capacity: 1000.0,
                diffusivity: 1e-4,
                thermal_expansion: 1e-5,
                swelling: 1e-3,
                ..RUBBER
            };
            check(&def, &material, &format!("{dimension:?} {name}"));
        }
        // Periodic faces along x (and z in 3D) a tenth of a cell past the block's far side,
        // which its particles cross; heat and diffusion fold across them too.
        let mut def = WorldDef {
            effects: Effects {
                heat: Some(Transport::INSULATED),
                diffusion: Some(Transport::INSULATED),
                ..Effects::NONE
            },
            ..base(dimension)
        };
        let (h, m) = (def.cell_size, def.shape.margin_cells() as Real);
        let far = if dimension == Dimension::ThreeD {
            [0.6, 0.0, 0.55]
        } else {
            [0.7, 0.0, 0.0]
        };
        for a in (0..def.axes()).filter(|&a| a != 1) {
            def.faces[2 * a] = Boundary::Periodic;
            def.faces[2 * a + 1] = Boundary::Periodic;
            def.origin[a] = far[a] + 0.1 * h - (def.cells[a] as Real - m) * h;
        }
        let material = MaterialDef {
            conductivity: 0.5,
            heat_capacity: 1000.0,
            diffusivity: 1e-4,
            ..RUBBER
        };
        check(&def, &material, &format!("{dimension:?} periodic"));
    }
}

#[test]
fn more_workers_than_the_definition_allows_is_refused_and_changes_nothing() {
    let def = WorldDef {
        workers: 2,
        ..base(Dimension::Plane2D)
    };
    let mut buf = HeapBuffer::new(memory_requirements(&def).expect("valid").bytes);
    let mut world = scene(&def, &RUBBER, buf.as_mut_bytes());
    let before = world.state_bytes().to_vec();
    assert_eq!(
        world.step_with_tasks(1.0 / 240.0, &Hostile::new(3)),
        Err(mpm_gimp::Error::InvalidLimit)
    );
    assert!(world.state_bytes() == before.as_slice());
    assert!(world.step_with_tasks(1.0 / 240.0, &Hostile::new(2)).is_ok());
}

/// A task system of two workers that runs every loop on the calling thread and counts the
/// loops it was handed.
struct Counting(AtomicU64);

// SAFETY: one range, `0..items`, on the calling thread, returning when it has run.
unsafe impl TaskSystem for Counting {
    fn worker_count(&self) -> usize {
        2
    }

    fn parallel_for(&self, items: usize, _min_range: usize, task: &mpm_gimp::tasks::Task<'_>) {
        self.0.fetch_add(1, Ordering::Relaxed);
        if items > 0 {
            task(0, items, 0);
        }
    }
}

/// A world too small to share ([`mpm_gimp::PARALLEL_FROM`] particles) steps on the calling
/// thread and hands the task system nothing; one at that size hands it the passes. Both with
/// the bits of [`World::step`].
#[test]
fn a_world_shares_its_step_only_from_the_size_where_it_pays() {
    for n in [mpm_gimp::PARALLEL_FROM - 1, mpm_gimp::PARALLEL_FROM] {
        let def = WorldDef {
            workers: 2,
            particle_capacity: n as u32,
            ..base(Dimension::Plane2D)
        };
        let bytes = memory_requirements(&def).expect("valid").bytes;
        let (mut a, mut b) = (HeapBuffer::new(bytes), HeapBuffer::new(bytes));
        let add = |w: &mut World| {
            let m = w.add_material(&RUBBER).expect("material");
            // A row of `n` particles along x, 0.03 mm apart: the count exact.
            let x: Vec<Real> = (0..n).map(|i| 0.3 + i as Real * 3.0e-5).collect();
            let y = vec![0.5; n];
            let zero = vec![0.0; n];
            let v = vec![1.0e-4; n];
            w.add_particles(&mpm_gimp::ParticleBatch {
                position: [&x, &y, &[]],
                velocity: [&zero, &zero, &[]],
                mass: &v,
                volume: &v,
                material: &vec![m; n],
            })
            .expect("particles");
        };
        let mut serial = World::init(&def, a.as_mut_bytes()).expect("init");
        let mut shared = World::init(&def, b.as_mut_bytes()).expect("init");
        add(&mut serial);
        add(&mut shared);
        let tasks = Counting(AtomicU64::new(0));
        for _ in 0..3 {
            let expected = serial.step(1.0 / 240.0).expect("step");
            assert_eq!(shared.step_with_tasks(1.0 / 240.0, &tasks), Ok(expected));
        }
        assert!(
            shared.state_bytes() == serial.state_bytes(),
            "{n} particles"
        );
        let loops = tasks.0.load(Ordering::Relaxed);
        assert_eq!(
            loops > 0,
            n >= mpm_gimp::PARALLEL_FROM,
            "{n} particles: {loops} loops handed to the system"
        );
    }
}
