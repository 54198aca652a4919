//! Reliability under a careless or hostile host, through the public API: snapshots are
//! untrusted input (`open` checks every particle), seeding validates what adding validates,
//! runaway particles are frozen and reported, and every call's cost is bounded by its inputs
//! (the substep limit, fills in proportion to their region, a thermostat that cannot add
//! substeps).

use crate::common::*;
use mpm_gimp::{
    Boundary, Dimension, Error, Face, MaterialDef, ParticleStatus, Real, ShapeFunction,
    UpdateOrder, Vec3, World, WorldDef,
};

/// A 2D world with a block of rubber in it, stepped once: the snapshot the edits damage.
fn block_world(def: &WorldDef, buf: &mut [u8]) -> Vec<u8> {
    let mut w = World::init(def, buf).expect("init");
    let rubber = w.add_material(&MaterialDef::DEFAULT).expect("material");
    w.fill_box(
        Vec3::new(0.3, 0.3, 0.0),
        Vec3::new(0.5, 0.45, 0.0),
        rubber,
        Vec3::new(0.5, -0.5, 0.0),
    )
    .expect("fill");
    w.step(1.0e-3).expect("step");
    w.as_bytes().to_vec()
}

/// Byte offset, from the world's start, of value `i` of the column `col` of a world whose
/// bytes start at `base`.
fn offset_of<T>(base: &[u8], col: &[T], i: usize) -> usize {
    col.as_ptr() as usize - base.as_ptr() as usize + i * core::mem::size_of::<T>()
}

/// Every edit of one particle's state that no step can produce is refused by `open` with
/// `InvalidState`, leaving the bytes as they were, while `reopen` (the constant-time header
/// check) still accepts the buffer; the intact snapshot opens and steps, and so does one with a
/// particle frozen as a step freezes it.
#[test]
fn open_refuses_every_damaged_particle_state() {
    let def = WorldDef {
        cells: [40, 40, 1],
        cell_size: 0.025,
        particle_capacity: 2048,
        ..WorldDef::DEFAULT
    };
    let mut buf = buffer_for(&def);
    let snapshot = block_world(&def, buf.as_mut_bytes());
    let w = World::reopen(buf.as_mut_bytes()).expect("the world itself");
    let v = w.particles();
    let base = w.as_bytes();
    let k = v.count / 2;
    let real = |col: &[Real]| offset_of(base, col, k);
    let r = core::mem::size_of::<Real>();
    type Edit = (&'static str, usize, Vec<u8>);
    let put_real = |at: usize, x: Real| -> (usize, Vec<u8>) { (at, x.to_le_bytes()[..r].to_vec()) };
    let edits: Vec<Edit> = [
        ("NaN mass", put_real(real(v.mass), Real::NAN)),
        ("negative mass", put_real(real(v.mass), -1.0)),
        ("zero volume", put_real(real(v.volume0), 0.0)),
        ("infinite volume", put_real(real(v.volume0), Real::INFINITY)),
        ("NaN position", put_real(real(v.position[0]), Real::NAN)),
        (
            "position outside the grid",
            put_real(real(v.position[1]), 1.0e6),
        ),
        ("position in the margin", put_real(real(v.position[0]), 0.0)),
        ("NaN velocity", put_real(real(v.velocity[1]), Real::NAN)),
        (
            "infinite H",
            put_real(real(v.displacement_gradient[0][1]), Real::INFINITY),
        ),
        (
            "inverted F",
            put_real(real(v.displacement_gradient[0][0]), -2.0),
        ),
        ("NaN stress", put_real(real(v.stress[2]), Real::NAN)),
        (
            "unknown status",
            (offset_of(base, v.status, k), 7u32.to_le_bytes().to_vec()),
        ),
        (
            "unknown material",
            (offset_of(base, v.material, k), 3u32.to_le_bytes().to_vec()),
        ),
    ]
    .into_iter()
    .map(|(what, (at, bytes))| (what, at, bytes))
    .collect();
    let n = snapshot.len();
    let mut copy = buffer_for(&def);
    for (what, at, bytes) in &edits {
        let mem = copy.as_mut_bytes();
        mem[..n].copy_from_slice(&snapshot);
        mem[*at..*at + bytes.len()].copy_from_slice(bytes);
        let before = mem[..n].to_vec();
        assert_eq!(
            World::open(&mut mem[..]).err(),
            Some(Error::InvalidState),
            "{what}"
        );
        assert_eq!(
            mem[..n],
            before[..],
            "{what}: the refused open changed the bytes"
        );
        assert!(
            World::reopen(&mut mem[..]).is_ok(),
            "{what}: the header is sound"
        );
    }
    // The intact snapshot opens and steps.
    let mem = copy.as_mut_bytes();
    mem[..n].copy_from_slice(&snapshot);
    World::open(&mut mem[..])
        .expect("intact")
        .step(1.0e-3)
        .expect("steps");
    // A frozen particle (as a step leaves it: its last finite state) opens, and the world
    // steps and reads; one holding a NaN velocity, which no step leaves, does not open.
    mem[..n].copy_from_slice(&snapshot);
    let frozen = ParticleStatus::Frozen as u32;
    let at = offset_of(base, v.status, k);
    mem[at..at + 4].copy_from_slice(&frozen.to_le_bytes());
    let mut opened = World::open(&mut mem[..]).expect("a frozen particle");
    opened.step(1.0e-3).expect("steps");
    let d = opened.diagnostics();
    assert!(d.kinetic.is_finite() && d.mass.is_finite() && d.strain.is_finite());
    mem[..n].copy_from_slice(&snapshot);
    mem[at..at + 4].copy_from_slice(&frozen.to_le_bytes());
    let at = real(v.velocity[0]);
    mem[at..at + r].copy_from_slice(&Real::NAN.to_le_bytes()[..r]);
    assert_eq!(World::open(&mut mem[..]).err(), Some(Error::InvalidState));
}

/// A fill validates each particle it seeds as `add_particles` does: a mass that overflows to
/// infinity is `NonFiniteInput`, one that underflows to zero `NonPositiveMassOrVolume`, for the
/// box, the disk and the sphere, and the world is unchanged. The same particle through
/// `add_particle` gets the same answer. In 2D the fills ignore z, as `add_particles` does.
#[test]
fn fills_validate_what_adding_validates() {
    // (cell size, density, expected): 50 m sub-cells (2500 m^2) of a density a tenth of the
    // largest Real overflow the mass; sub-cells whose square (and cube) underflow to 0 (1e-23
    // m in f32, 1e-163 m in f64) leave a volume of 0. The modulus is the smallest normal Real,
    // so that the wave speed is one such cells resolve above MIN_STABLE_DT.
    #[cfg(not(feature = "f64"))]
    const TINY: Real = 1.0e-23;
    #[cfg(feature = "f64")]
    const TINY: Real = 1.0e-163;
    let cases = [
        (100.0, Real::MAX / 10.0, Error::NonFiniteInput),
        (TINY, 1.0e9, Error::NonPositiveMassOrVolume),
    ];
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        for (h, density, expected) in cases {
            let mut def = free_space(dim, 12, h);
            def.particle_capacity = 20_000;
            let mut buf = buffer_for(&def);
            let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
            let m = w
                .add_material(&MaterialDef {
                    density,
                    youngs_modulus: Real::MIN_POSITIVE,
                    ..MaterialDef::DEFAULT
                })
                .expect("a valid material");
            let at = |c: f64| (c * h as f64) as Real;
            let z = |c: f64| if dim == Dimension::ThreeD { at(c) } else { 0.0 };
            let before = w.as_bytes().to_vec();
            let label = format!("{dim:?}, h {h}, density {density}");
            let (lo, hi) = (
                Vec3::new(at(4.0), at(4.0), z(4.0)),
                Vec3::new(at(6.0), at(6.0), z(6.0)),
            );
            assert_eq!(
                w.fill_box(lo, hi, m, Vec3::ZERO).err(),
                Some(expected),
                "{label}"
            );
            let centre = Vec3::new(at(6.0), at(6.0), z(6.0));
            let ball = if dim == Dimension::ThreeD {
                w.fill_sphere(centre, at(1.0), m, Vec3::ZERO)
            } else {
                w.fill_disk(centre, at(1.0), m, Vec3::ZERO)
            };
            assert_eq!(ball.err(), Some(expected), "{label}");
            assert!(
                w.as_bytes() == &before[..],
                "{label}: a refused fill changed the world"
            );
            // The particle the fill would have made, added directly.
            let site = h / def.particles_per_cell as Real;
            let volume = if dim == Dimension::ThreeD {
                site * site * site
            } else {
                site * site
            };
            let p = mpm_gimp::ParticleDef {
                position: centre,
                velocity: Vec3::ZERO,
                mass: volume * density,
                volume,
                material: m,
            };
            assert_eq!(
                w.add_particle(&p).err(),
                Some(expected),
                "{label}: add_particle"
            );
        }
    }
    // 2D: a NaN z is ignored by the fills as by add_particles.
    let def = free_space(Dimension::Plane2D, 12, 0.1);
    let mut buf = buffer_for(&def);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
    let nan_z = |x: Real, y: Real| Vec3::new(x, y, Real::NAN);
    w.fill_box(nan_z(0.4, 0.4), nan_z(0.6, 0.6), m, nan_z(1.0, 0.0))
        .expect("2D fill_box ignores z");
    w.fill_disk(nan_z(0.8, 0.8), 0.1, m, nan_z(0.0, 1.0))
        .expect("2D fill_disk ignores z");
    assert!(all_finite(&w));
}

/// Disks and spheres visit only the rows of bins their chord crosses (what keeps a fill's cost
/// in proportion to its region): checked against the brute-force lattice, for balls at random
/// places, partly outside the grid included, every shape family's bin shift and 1 to 3
/// particles per cell. A fill that succeeds seeds exactly the lattice sites inside the ball
/// (compared as sets of positions); one refused as `PositionOutsideDomain` has a site inside
/// the ball outside the admissible region.
#[test]
fn ball_fills_seed_exactly_the_lattice_sites_inside() {
    let mut state = 0x6a11u64;
    let mut unit = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut seeded, mut refused) = (0, 0);
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        for shape in [
            ShapeFunction::Linear,
            ShapeFunction::Gimp,
            ShapeFunction::CubicBspline,
        ] {
            for ppc in 1..=3u32 {
                for _ in 0..12 {
                    let cells = 14u32;
                    let mut def = free_space(dim, cells, 0.1);
                    def.shape = shape;
                    def.particles_per_cell = ppc;
                    def.origin = Vec3::new(-0.35, 0.2, -0.6);
                    def.particle_capacity = 40_000;
                    let d = def.axes();
                    let mut buf = buffer_for(&def);
                    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
                    let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
                    let c: [Real; 3] = core::array::from_fn(|a| {
                        def.origin[a] + (unit() * 1.6 - 0.3) as Real * cells as Real * 0.1
                    });
                    let radius = (0.05 + unit() * 0.6) as Real;
                    let centre = Vec3::from(c);
                    let result = if d == 3 {
                        w.fill_sphere(centre, radius, m, Vec3::ZERO)
                    } else {
                        w.fill_disk(centre, radius, m, Vec3::ZERO)
                    };
                    // The lattice sites inside the ball, as the kernel computes both: the
                    // lattice reaches one site past the admissible region (so that a region
                    // reaching out of it meets a site there and is refused).
                    let spacing = def.cell_size / ppc as Real;
                    let margin = shape.margin_cells() as Real;
                    let sites = (cells * ppc) as f64;
                    let edge = margin as f64 * ppc as f64;
                    let (k0, k1) = (
                        (edge - 1.5).ceil() as i64,
                        (sites - edge + 0.5).floor() as i64,
                    );
                    let mut inside = Vec::new();
                    let mut outside_admissible = false;
                    let range = |a: usize| if a < d { k0..k1 + 1 } else { 0..1 };
                    for kz in range(2) {
                        for ky in range(1) {
                            for kx in range(0) {
                                let k = [kx, ky, kz];
                                let x: [Real; 3] = core::array::from_fn(|a| {
                                    if a < d {
                                        def.origin[a] + (k[a] as Real + 0.5) * spacing
                                    } else {
                                        0.0
                                    }
                                });
                                let mut q = 0.0;
                                for a in 0..d {
                                    q += (x[a] - c[a]) * (x[a] - c[a]);
                                }
                                if q <= radius * radius {
                                    let s = |a: usize| (x[a] - def.origin[a]) / def.cell_size;
                                    let ok = (0..d)
                                        .all(|a| s(a) >= margin && s(a) <= cells as Real - margin);
                                    outside_admissible |= !ok;
                                    inside.push(x.map(|v| v.to_bits()));
                                }
                            }
                        }
                    }
                    let label = format!("{dim:?} {shape:?} ppc {ppc} ball {c:?} r {radius}");
                    match result {
                        Ok(ids) => {
                            assert!(!outside_admissible, "{label}: seeded past the margin");
                            let v = w.particles();
                            let mut got: Vec<[_; 3]> = (ids.start as usize..ids.end as usize)
                                .map(|i| {
                                    core::array::from_fn(|a| {
                                        if a < d { v.position[a][i] } else { 0.0 }.to_bits()
                                    })
                                })
                                .collect();
                            got.sort_unstable();
                            inside.sort_unstable();
                            assert_eq!(got, inside, "{label}");
                            seeded += 1;
                        }
                        Err(e) => {
                            assert_eq!(e, Error::PositionOutsideDomain, "{label}");
                            assert!(outside_admissible, "{label}: refused, but all inside");
                            refused += 1;
                        }
                    }
                }
            }
        }
    }
    // Both outcomes were exercised.
    assert!(
        seeded >= 40 && refused >= 40,
        "seeded {seeded}, refused {refused}"
    );
}

/// Classic MPM (linear shape functions with USL) is unstable: a block dropped on a stick floor
/// gains energy from the grid until particle volumes run away. Every step still answers Ok;
/// the runaway particles are frozen as they leave the volume bound and reported
/// (`runaway`, `went_bad`), so that after a long run every active particle has `J` inside
/// `[1 / max_volume_ratio, max_volume_ratio]` and a finite stress, and the diagnostics stay
/// finite. (Without the bound, the same run ended with active particles at `J` up to 1e21
/// and a strain energy 1e31 times the start.)
#[test]
fn classic_mpm_runaway_is_frozen_and_reported() {
    let mut def = WorldDef {
        cells: [24, 24, 1],
        cell_size: 0.05,
        shape: ShapeFunction::Linear,
        update_order: UpdateOrder::Usl,
        particle_capacity: 1024,
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    let mut buf = buffer_for(&def);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
    w.fill_box(
        Vec3::new(0.3, 0.3, 0.0),
        Vec3::new(0.9, 0.9, 0.0),
        m,
        Vec3::ZERO,
    )
    .unwrap();
    let (mut frozen, mut runaway, mut flagged_steps) = (0u32, 0u32, 0u32);
    for step in 0..10_000 {
        let dt = w.stable_dt();
        let r = w.step(dt).unwrap_or_else(|e| panic!("step {step}: {e}"));
        assert_eq!(r.went_bad(), r.frozen > 0);
        assert!(r.runaway <= r.frozen);
        frozen += r.frozen;
        runaway += r.runaway;
        flagged_steps += r.went_bad() as u32;
    }
    let r = def.max_volume_ratio;
    let v = w.particles();
    for i in 0..v.count {
        if v.status[i] == ParticleStatus::Active as u32 {
            let j = v.jacobian(i);
            assert!(j >= 1.0 / r && j <= r, "particle {i}: J = {j}");
            assert!(
                v.stress.iter().take(4).all(|s| s[i].is_finite()),
                "particle {i}"
            );
        }
    }
    let d = w.diagnostics();
    assert!(
        [d.kinetic, d.strain, d.potential, d.mass]
            .iter()
            .all(|x| x.is_finite()),
        "{d:?}"
    );
    assert_eq!(frozen as usize, count_status(&w, ParticleStatus::Frozen));
    assert!(
        runaway > 0,
        "the unstable scheme never ran away ({frozen} frozen)"
    );
    assert!(flagged_steps > 0);
}

/// The substep limit bounds a call's cost: steel on the default grid at 60 Hz needs about
/// 20,000 substeps, past the default limit of 1000, and is refused at once with
/// `SubstepLimit`, changing nothing; a step within the limit is taken, and a definition that
/// raises the limit takes the frame.
#[test]
fn the_substep_limit_refuses_and_changes_nothing() {
    let steel = MaterialDef {
        youngs_modulus: 200.0e9,
        poisson_ratio: 0.3,
        density: 7850.0,
        ..MaterialDef::DEFAULT
    };
    for max_substeps in [WorldDef::DEFAULT.max_substeps, 30_000] {
        let def = WorldDef {
            max_substeps,
            particle_capacity: 4096,
            ..WorldDef::DEFAULT
        };
        let mut buf = buffer_for(&def);
        let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
        let m = w.add_material(&steel).unwrap();
        w.fill_box(
            Vec3::new(0.4, 0.4, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            m,
            Vec3::ZERO,
        )
        .unwrap();
        let needed = (1.0 / 60.0 / w.stable_dt()).ceil();
        assert!(needed > 15_000.0 && needed < 30_000.0, "{needed} substeps");
        let before = w.as_bytes().to_vec();
        match w.step(1.0 / 60.0) {
            Ok(r) => {
                assert!(max_substeps >= r.substeps && r.substeps as Real == needed);
            }
            Err(e) => {
                assert_eq!((e, max_substeps), (Error::SubstepLimit, 1000));
                assert!(
                    w.as_bytes() == &before[..],
                    "the refused step changed the world"
                );
                let r = w.step(999.0 * w.stable_dt()).expect("within the limit");
                assert_eq!(r.substeps, 999);
            }
        }
    }
}

/// The thermostat cannot drive the step into more substeps: with a huge gain and bound, its
/// alpha is clamped each substep to what the substep integrates stably, so the substeps of
/// every frame are those the wave speed and the fastest particle ask for (`stable_dt` is
/// `cfl h / (c + |v|_max)`, computed here from the view), exactly as many as a twin scene
/// without the thermostat takes in the first frame (same state); its alpha stays finite and
/// within the bound, and it holds the falling block near rest.
#[cfg(feature = "effects")]
#[test]
fn the_thermostat_never_adds_substeps() {
    use mpm_gimp::{Damping, Effects, Feedback, Schedule};
    let feedback = Feedback {
        gain: 1.0e12,
        target: Schedule::ZERO,
        max_alpha: 1.0e12,
    };
    let damped = WorldDef {
        particle_capacity: 4096,
        effects: Effects {
            damping: Some(Damping {
                feedback: Some(feedback),
                ..Damping::NONE
            }),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    let plain = WorldDef {
        effects: Effects::NONE,
        ..damped
    };
    let (mut b1, mut b2) = (buffer_for(&damped), buffer_for(&plain));
    let mut worlds = [
        World::init(&damped, b1.as_mut_bytes()).unwrap(),
        World::init(&plain, b2.as_mut_bytes()).unwrap(),
    ];
    for w in worlds.iter_mut() {
        let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
        w.fill_box(
            Vec3::new(0.3, 0.3, 0.0),
            Vec3::new(0.6, 0.5, 0.0),
            m,
            Vec3::new(0.0, -2.0, 0.0),
        )
        .unwrap();
    }
    let [w, twin] = &mut worlds;
    let dt = 1.0 / 60.0;
    let start = w.diagnostics().kinetic;
    assert_eq!(
        w.step(dt).unwrap().substeps,
        twin.step(dt).unwrap().substeps
    );
    let c = MaterialDef::DEFAULT.wave_speed() as f64;
    for frame in 1..30 {
        let v = w.particles();
        let v_max = (0..v.count)
            .map(|i| (v.velocity[0][i] as f64).hypot(v.velocity[1][i] as f64))
            .fold(0.0, f64::max);
        let expected = damped.cfl as f64 * damped.cell_size as f64 / (c + v_max);
        let stable = w.stable_dt();
        assert!(
            (stable as f64 / expected - 1.0).abs() < 1.0e-4,
            "frame {frame}: stable dt {stable}, expected {expected}"
        );
        let r = w.step(dt).unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        assert_eq!(
            r.substeps as Real,
            (dt / stable).ceil().max(1.0),
            "frame {frame}"
        );
        let alpha = w.feedback_alpha();
        assert!(
            alpha.is_finite() && (0.0..=1.0e12).contains(&alpha),
            "alpha {alpha}"
        );
        // Gravity keeps feeding it, the damping holds the block near rest (at about
        // g / alpha): far below the 2 m/s it started with.
        let k = w.diagnostics().kinetic;
        assert!(k <= 1.0e-3 * start, "frame {frame}: {k} of {start}");
    }
}

/// The definition's limits are validated: `max_substeps` in `1..=MAX_SUBSTEPS`,
/// `max_volume_ratio` > 1 (infinity allowed: no bound).
#[test]
fn definition_limits_are_validated() {
    let with = |max_substeps: u32, max_volume_ratio: Real| {
        mpm_gimp::memory_requirements(&WorldDef {
            max_substeps,
            max_volume_ratio,
            ..WorldDef::DEFAULT
        })
        .map(|_| ())
    };
    let bad = Err(Error::InvalidLimit);
    assert_eq!(with(0, 100.0), bad);
    assert_eq!(with(mpm_gimp::MAX_SUBSTEPS + 1, 100.0), bad);
    for r in [1.0, 0.5, 0.0, -1.0, Real::NAN, Real::NEG_INFINITY] {
        assert_eq!(with(1000, r), bad, "max_volume_ratio {r}");
    }
    assert_eq!(with(1, 1.0 + Real::EPSILON * 2.0), Ok(()));
    assert_eq!(with(mpm_gimp::MAX_SUBSTEPS, Real::INFINITY), Ok(()));
}
