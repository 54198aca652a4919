//! Randomised robustness through the public API: worlds built from extreme but valid inputs
//! (velocities up to 1e30 m/s and moduli from 1e-3 to 1e30 Pa, each up to what a step above
//! `MIN_STABLE_DT` resolves; masses and volumes over 60 decades)
//! and stepped with random time steps. Whatever happens to the physics, the step must not
//! panic, every particle value must stay finite, every particle must stay inside the grid, the
//! status codes must be valid, and the step report must agree with the statuses.

use crate::common::*;
use mpm_gimp::{
    Boundary, Dimension, Error, MaterialDef, MaterialModel, ParticleBatch, ParticleStatus, Real,
    UpdateOrder, Vec3, World, WorldDef,
};

/// Deterministic pseudo-random numbers (no dependency needed).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 11
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        self.next_u64() as f64 / (1u64 << 53) as f64
    }

    /// 10^u for u uniform in [lo, hi).
    fn decades(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(lo + (hi - lo) * self.unit())
    }

    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[(self.next_u64() % items.len() as u64) as usize]
    }
}

#[test]
fn extreme_inputs_never_panic_never_leave_the_grid_and_stay_finite() {
    let mut rng = Rng(0x5eed);
    for case in 0..400 {
        let dim = rng.pick(&[Dimension::Plane2D, Dimension::ThreeD]);
        let shape = rng.pick(&SHAPES);
        let order = rng.pick(&[UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl]);
        let h = rng.decades(-3.0, 1.0) as Real;
        let cells = 6 + (rng.next_u64() % 6) as u32;
        let mut def = WorldDef {
            dimension: dim,
            shape,
            update_order: order,
            cell_size: h,
            cells: if dim == Dimension::ThreeD {
                [cells; 3]
            } else {
                [cells, cells, 1]
            },
            flip_beta: rng.unit() as Real,
            particle_capacity: 256,
            material_capacity: 2,
            ..WorldDef::DEFAULT
        };
        for f in def.faces.iter_mut() {
            *f = rng.pick(&[Boundary::Stick, Boundary::Slip, Boundary::Open]);
        }
        let mut buf = buffer_for(&def);
        let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
        // What a step above MIN_STABLE_DT resolves: faster wave speeds and particles are
        // refused; such a material is added again at the bound's wave speed (to round-off).
        let limit = def.resolvable().speed;
        for _ in 0..2 {
            let mut m = MaterialDef {
                model: rng.pick(&[MaterialModel::NeoHookean, MaterialModel::LinearElastic]),
                youngs_modulus: rng.decades(-3.0, 30.0) as Real,
                poisson_ratio: (-0.9 + 1.39 * rng.unit()) as Real,
                density: rng.decades(-6.0, 6.0) as Real,
                ..MaterialDef::DEFAULT
            };
            let c = m.wave_speed() as f64;
            if c > limit {
                let refused = w.add_material(&m);
                assert_eq!(
                    refused,
                    Err(Error::StableStepTooShort),
                    "wave speed {c} m/s"
                );
                m.youngs_modulus = (m.youngs_modulus as f64 * (limit / c).powi(2) * 0.99) as Real;
            }
            w.add_material(&m).unwrap();
        }
        // Random particles inside the admissible region.
        let d = def.axes();
        let margin = shape.margin_cells() as f64;
        let n = 1 + (rng.next_u64() % 200) as usize;
        let mut cols: [Vec<Real>; 6] = Default::default();
        for _ in 0..n {
            for a in 0..3 {
                let x = if a < d {
                    (margin + (cells as f64 - 2.0 * margin) * rng.unit()) * h as f64
                } else {
                    0.0
                };
                let speed = if rng.unit() < 0.2 {
                    rng.decades(0.0, 30.0).min(0.5 * limit)
                } else {
                    rng.unit()
                };
                let v = if a < d {
                    (2.0 * rng.unit() - 1.0) * speed
                } else {
                    0.0
                };
                cols[a].push(x as Real);
                cols[3 + a].push(v as Real);
            }
        }
        let mass: Vec<Real> = (0..n).map(|_| rng.decades(-30.0, 30.0) as Real).collect();
        let volume: Vec<Real> = (0..n).map(|_| rng.decades(-30.0, 30.0) as Real).collect();
        let material: Vec<u32> = (0..n).map(|_| (rng.next_u64() % 2) as u32).collect();
        w.add_particles(&ParticleBatch {
            position: [&cols[0], &cols[1], &cols[2]],
            velocity: [&cols[3], &cols[4], &cols[5]],
            mass: &mass,
            volume: &volume,
            material: &material,
        })
        .unwrap();
        let label = format!("case {case}: {dim:?} {shape:?} {order:?}");
        let (mut frozen, mut escaped, mut taken) = (0usize, 0usize, 0usize);
        for _ in 0..8 {
            // Random step lengths from far below the stable step to 30 times it (substeps).
            let dt = (w.stable_dt().min(1.0) as f64 * rng.decades(-3.0, 1.5)) as Real;
            match w.step(dt) {
                Ok(r) => {
                    taken += 1;
                    frozen += r.frozen as usize;
                    escaped += r.escaped as usize;
                }
                // Only a step that would need more than `max_substeps` is refused.
                Err(e) => assert_eq!(e, mpm_gimp::Error::SubstepLimit, "{label}"),
            }
        }
        assert!(taken >= 6, "{label}: only {taken} of 8 steps were taken");
        assert!(all_finite(&w), "{label}: non-finite particle state");
        let v = w.particles();
        for i in 0..v.count {
            assert!(
                ParticleStatus::from_code(v.status[i]).is_some(),
                "{label}: bad status"
            );
            for a in 0..d {
                let s = (v.position[a][i] - def.origin[a]) / h;
                assert!(
                    s >= margin as Real * 0.999 - 1e-3
                        && s <= (cells as f64 - margin) as Real * 1.001 + 1e-3,
                    "{label}: particle {i} at {s} cells on axis {a}"
                );
            }
        }
        assert_eq!(frozen, count_status(&w, ParticleStatus::Frozen), "{label}");
        assert_eq!(
            escaped,
            count_status(&w, ParticleStatus::Escaped),
            "{label}"
        );
    }
}

/// A host may hand back a snapshot whose bytes were damaged. Corrupting random bytes of a
/// valid world (particle columns, material table, and sometimes the header):
/// - `open` (the untrusted path) refuses the damage with `NotAWorld` (header) or
///   `InvalidState` (state), or opens a world whose state still holds (the damage hit
///   scratch, padding or a value still in range), which then steps, with finite diagnostics
///   in f32 (whose values cannot overflow the f64 sums);
/// - `reopen` (constant-time header checks, the C interface's path on every call) lets the
///   damaged state through, and whatever a damaged column holds (NaN, huge values, unknown
///   material ids or status codes), `step`, `stable_dt`, `particles` and `diagnostics` must
///   not panic or touch memory outside the buffer: the step only freezes or skips particles.
#[test]
fn corrupted_snapshots_never_panic() {
    let mut rng = Rng(0xbad5eed);
    let (mut stepped, mut refused) = (0, 0);
    for case in 0..200 {
        let dim = rng.pick(&[Dimension::Plane2D, Dimension::ThreeD]);
        let shape = rng.pick(&SHAPES);
        let order = rng.pick(&[UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl]);
        let mut def = free_space(dim, 8, 0.05);
        def.shape = shape;
        def.update_order = order;
        def.particle_capacity = 512;
        let mut buf = buffer_for(&def);
        let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
        let mat = w.add_material(&MaterialDef::DEFAULT).unwrap();
        let c = if dim == Dimension::ThreeD { 0.2 } else { 0.0 };
        let lo = mpm_gimp::Vec3::new(0.15, 0.15, c);
        let hi = mpm_gimp::Vec3::new(0.3, 0.3, if dim == Dimension::ThreeD { 0.3 } else { 0.0 });
        w.fill_box(lo, hi, mat, mpm_gimp::Vec3::new(1.0, -1.0, 0.5))
            .unwrap();
        w.step(0.001).unwrap();
        let mut bytes = w.as_bytes().to_vec();
        // Corrupt: mostly past the header (offset 512 is past the header and into the material
        // table or the columns), sometimes the header itself.
        let flips = 1 + rng.next_u64() % 64;
        for _ in 0..flips {
            let start = if rng.unit() < 0.1 { 0 } else { 512 };
            let at = start + (rng.next_u64() as usize % (bytes.len() - start));
            bytes[at] = rng.next_u64() as u8;
        }
        let mut copy = buffer_for(&def);
        copy.as_mut_bytes()[..bytes.len()].copy_from_slice(&bytes);
        match World::open(copy.as_mut_bytes()) {
            Ok(mut w) => {
                // A state open accepts has a stable step a step takes (MIN_STABLE_DT / 2 at
                // least).
                let dt = w.stable_dt().min(1.0e-3);
                assert!(dt > 0.0, "case {case}: stable dt {dt}");
                if let Err(e) = w.step(dt) {
                    assert_eq!(e, mpm_gimp::Error::SubstepLimit, "case {case}");
                }
                // f32 values cannot overflow the f64 sums; in f64 a value that opens may be as
                // large as 1e200 (as `add_particles` accepts), whose square overflows them.
                let s = w.diagnostics();
                let sums = [s.mass, s.kinetic, s.strain, s.potential, w.time()];
                let f32_build = core::mem::size_of::<Real>() == 4;
                assert!(
                    !f32_build || sums.iter().all(|v| v.is_finite()),
                    "case {case}: {s:?}"
                );
            }
            Err(e) => {
                let expected = [mpm_gimp::Error::NotAWorld, mpm_gimp::Error::InvalidState];
                assert!(expected.contains(&e), "case {case}: {e:?}");
                refused += 1;
            }
        }
        let Ok(mut w) = World::reopen(copy.as_mut_bytes()) else {
            continue; // A damaged header is refused: fine.
        };
        stepped += 1;
        for _ in 0..4 {
            // A damaged speed may be one no stable step integrates: then stable_dt is 0 (never
            // raised to a floor) and the step of 0 is refused as such.
            let dt = w.stable_dt().min(1.0e-3);
            if let Err(e) = w.step(dt) {
                let expected = if dt == 0.0 {
                    mpm_gimp::Error::InvalidTimeStep
                } else {
                    mpm_gimp::Error::SubstepLimit
                };
                assert_eq!(e, expected, "case {case}");
            }
        }
        let _ = w.particles();
        let _ = w.diagnostics();
    }
    // Most corruptions miss the header: the test must have stepped damaged worlds; and open
    // must have refused many (95 of 200 when written: the rest hit scratch columns, unused
    // capacity or values still in range).
    assert!(
        stepped >= 100,
        "only {stepped} of 200 damaged worlds stepped"
    );
    assert!(
        refused >= 50,
        "open refused only {refused} of 200 damaged worlds"
    );
}

/// The grid is scratch: a substep resets every node value it reads, so whatever the grid's
/// bytes hold before a step (values left outside the nodes the last substep touched, or
/// anything at all) cannot change its result, and a snapshot needs only
/// [`World::state_bytes`]. Here, before each step of a block thrown across cells onto a stick
/// floor (hitting it after about 20 steps), a second world is opened from the first's state
/// bytes with every grid byte 0xFF (NaN), for every dimension, shape function and update
/// order: the state after the step must equal, bit for bit, that of the first world stepped
/// with its own grid bytes. A zero-weighted read of a node the substep did not reset would
/// make a particle NaN (frozen) and the bytes differ.
#[test]
fn grid_bytes_before_a_step_never_change_it() {
    let mut dims = vec![Dimension::Plane2D, Dimension::ThreeD];
    if cfg!(feature = "effects") {
        dims.push(Dimension::Axisymmetric2D);
    }
    for dim in dims {
        for shape in SHAPES {
            for order in [UpdateOrder::Usf, UpdateOrder::Usl, UpdateOrder::Musl] {
                let three = dim == Dimension::ThreeD;
                let mut faces = [Boundary::Open; 6];
                faces[2] = Boundary::Stick;
                faces[0] = Boundary::Slip;
                let mut def = WorldDef {
                    dimension: dim,
                    cells: if three { [14, 14, 14] } else { [24, 24, 1] },
                    cell_size: 0.05,
                    shape,
                    update_order: order,
                    faces,
                    particle_capacity: 4096,
                    ..WorldDef::DEFAULT
                };
                // Axisymmetric: the axis on the lower r face's wall plane, and the block
                // against it, so that the B-splines reach the nodes before the axis.
                let axi = dim == Dimension::Axisymmetric2D;
                if axi {
                    def.origin.x = -(shape.margin_cells() as Real) * def.cell_size;
                }
                let (x0, vx) = if axi { (0.0, 0.5) } else { (0.2, 2.0) };
                let z = |v: Real| if three { v } else { 0.0 };
                let mut a_buf = buffer_for(&def);
                let mut a = World::init(&def, a_buf.as_mut_bytes()).unwrap();
                let mat = a.add_material(&MaterialDef::DEFAULT).unwrap();
                a.fill_box(
                    Vec3::new(x0, 0.3, z(0.2)),
                    Vec3::new(x0 + 0.2, 0.45, z(0.35)),
                    mat,
                    Vec3::new(vx, -6.0, z(1.5)),
                )
                .unwrap();
                let mut b_buf = buffer_for(&def);
                for step in 0..25 {
                    let state = a.state_bytes();
                    let total = a.as_bytes().len();
                    assert!(state.len() < total && a.as_bytes().starts_with(state));
                    let b_bytes = b_buf.as_mut_bytes();
                    b_bytes[..state.len()].copy_from_slice(state);
                    b_bytes[state.len()..total].fill(0xff);
                    let mut b = World::open(b_bytes).unwrap();
                    let ra = a.step(0.002).unwrap();
                    let rb = b.step(0.002).unwrap();
                    let case = (dim, shape, order, step);
                    assert_eq!(ra.frozen, rb.frozen, "{case:?}");
                    assert!(a.state_bytes() == b.state_bytes(), "{case:?}");
                }
            }
        }
    }
}
