//! Particles that come and go: removal (by range, list, box and status), which frees room and
//! leaves the rest as a world built with them alone; the setters of position, velocity, affine
//! matrix and material; a tap that pours for ten minutes with its particle count bounded, and
//! the viewer's tap, whose stream stays continuous.

use crate::common::*;
use mpm_gimp::{
    Boundary, Dimension, Error, Face, HeapBuffer, MaterialDef, ParticleBatch, Real, Removal,
    Transfer, Vec3, World, WorldDef,
};

/// A world of `def` holding `p`'s particles (one material, `MaterialDef::DEFAULT`), in order.
fn built_with<'b>(def: &WorldDef, p: &Particles, buf: &'b mut HeapBuffer) -> World<'b> {
    let mut w = World::init(def, buf.as_mut_bytes()).unwrap();
    w.add_material(&MaterialDef::DEFAULT).unwrap();
    w.add_particles(&p.batch()).unwrap();
    w
}

/// Which particles of a world stay, by id.
type Keep<'k> = Box<dyn Fn(usize) -> bool + 'k>;

/// Particle columns as a host keeps them.
#[derive(Clone, Default)]
struct Particles {
    x: [Vec<Real>; 3],
    v: [Vec<Real>; 3],
    m: Vec<Real>,
    vol: Vec<Real>,
    mat: Vec<u32>,
}

impl Particles {
    fn of(w: &World<'_>) -> Particles {
        let p = w.particles();
        Particles {
            x: p.position.map(|c| c.to_vec()),
            v: p.velocity.map(|c| c.to_vec()),
            m: p.mass.to_vec(),
            vol: p.volume0.to_vec(),
            mat: p.material.to_vec(),
        }
    }

    fn keep(&self, keep: impl Fn(usize) -> bool) -> Particles {
        let pick = |c: &Vec<Real>| (0..c.len()).filter(|&i| keep(i)).map(|i| c[i]).collect();
        Particles {
            x: self.x.each_ref().map(pick),
            v: self.v.each_ref().map(pick),
            m: pick(&self.m),
            vol: pick(&self.vol),
            mat: (0..self.mat.len())
                .filter(|&i| keep(i))
                .map(|i| self.mat[i])
                .collect(),
        }
    }

    fn batch(&self) -> ParticleBatch<'_> {
        ParticleBatch {
            position: [&self.x[0], &self.x[1], &self.x[2]],
            velocity: [&self.v[0], &self.v[1], &self.v[2]],
            mass: &self.m,
            volume: &self.vol,
            material: &self.mat,
        }
    }
}

/// A 2D world (or 3D) with a stick floor and a spinning, sheared block: 32 cells of 1/32 m.
fn scene_def(dim: Dimension) -> WorldDef {
    let mut def = free_space(
        dim,
        if dim == Dimension::ThreeD { 16 } else { 32 },
        1.0 / 32.0,
    );
    def.gravity = Vec3::new(0.0, -9.81, 0.0);
    def.transfer = if cfg!(feature = "effects") {
        Transfer::Apic
    } else {
        Transfer::Flip
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    def.particle_capacity = 20_000;
    def
}

fn block(dim: Dimension, world: &mut World<'_>) {
    let m = world.add_material(&MaterialDef::DEFAULT).unwrap();
    let hi = if dim == Dimension::ThreeD { 0.4 } else { 0.7 };
    world
        .fill_box(
            Vec3::new(0.1, 0.1, 0.1),
            Vec3::new(hi, hi, hi),
            m,
            Vec3::new(0.3, -0.5, 0.1),
        )
        .unwrap();
}

/// Removal leaves the rest as a world built with them alone: for each kind of removal, in 2D
/// and 3D, the state bytes (every column of every particle, the header, the tables) after the
/// removal equal those of a world built with the remaining particles in their order, and so do
/// they after 10 steps (the step is a function of those bytes). Exact: no tolerance.
#[test]
fn removal_leaves_the_world_a_world_built_with_the_rest_would_be() {
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        let def = scene_def(dim);
        let bytes = mpm_gimp::memory_requirements(&def).unwrap().bytes;
        let (mut a_buf, mut b_buf) = (HeapBuffer::new(bytes), HeapBuffer::new(bytes));
        let probe = {
            let mut w = World::init(&def, a_buf.as_mut_bytes()).unwrap();
            block(dim, &mut w);
            Particles::of(&w)
        };
        let n = probe.m.len() as u32;
        let list: Vec<u32> = (0..n).filter(|i| i % 7 == 3 || i % 11 == 0).rev().collect();
        let (lo, hi) = (Vec3::new(0.2, 0.3, 0.2), Vec3::new(0.45, 0.5, 0.3));
        let in_box =
            |i: usize| (0..def.axes()).all(|a| probe.x[a][i] >= lo[a] && probe.x[a][i] <= hi[a]);
        let cases: [(Removal<'_>, Keep<'_>); 3] = [
            (
                Removal::Range(n / 3..n / 2),
                Box::new(move |i| !(n as usize / 3..n as usize / 2).contains(&i)),
            ),
            (
                Removal::List(&list),
                Box::new(|i| !list.contains(&(i as u32))),
            ),
            (
                Removal::Box { min: lo, max: hi },
                Box::new(move |i| !in_box(i)),
            ),
        ];
        for (which, keep) in cases {
            let label = format!("{dim:?} {which:?}");
            let mut a = World::init(&def, a_buf.as_mut_bytes()).unwrap();
            block(dim, &mut a);
            let kept = probe.keep(&keep);
            let removed = a.remove_particles(which.clone()).unwrap();
            assert_eq!(removed, n as usize - kept.m.len(), "{label}");
            let mut b = built_with(&def, &kept, &mut b_buf);
            assert!(
                a.state_bytes() == b.state_bytes(),
                "{label}: state after removal"
            );
            let dt = a.stable_dt();
            for _ in 0..10 {
                a.step(dt).unwrap();
                b.step(dt).unwrap();
            }
            assert!(
                a.state_bytes() == b.state_bytes(),
                "{label}: state 10 steps on"
            );
        }
    }
}

/// Removal mid-run: the remaining particles' mass and momentum are, bit for bit, what they
/// were (their columns move, their values do not); the room is free again (a world full to
/// capacity takes as many new particles as were removed); a snapshot of the world after the
/// removal opens and steps on as the world does, to the bit.
#[test]
fn removal_mid_run_keeps_the_rest_and_frees_their_room() {
    let mut def = scene_def(Dimension::Plane2D);
    def.particle_capacity = 0; // Set below: exactly the block.
    let probe = {
        let mut d = def;
        d.particle_capacity = 20_000;
        let mut buf = HeapBuffer::new(mpm_gimp::memory_requirements(&d).unwrap().bytes);
        let mut w = World::init(&d, buf.as_mut_bytes()).unwrap();
        block(Dimension::Plane2D, &mut w);
        Particles::of(&w)
    };
    def.particle_capacity = probe.m.len() as u32;
    let bytes = mpm_gimp::memory_requirements(&def).unwrap().bytes;
    let mut buf = HeapBuffer::new(bytes);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    block(Dimension::Plane2D, &mut w);
    let dt = w.stable_dt();
    for _ in 0..20 {
        w.step(dt).unwrap();
    }
    let before = Particles::of(&w);
    let keep = |i: usize| i % 3 != 1;
    let kept = before.keep(keep);
    let removed = w.remove_particles(Removal::List(
        &(0..before.m.len() as u32)
            .filter(|&i| !keep(i as usize))
            .collect::<Vec<_>>(),
    ));
    let after = Particles::of(&w);
    assert_eq!(removed.unwrap(), before.m.len() - kept.m.len());
    for a in 0..2 {
        assert_eq!(after.x[a], kept.x[a], "positions");
        assert_eq!(after.v[a], kept.v[a], "velocities");
    }
    assert_eq!(after.m, kept.m, "masses");
    // Room for exactly the removed ones again.
    let extra = before.keep(|i| !keep(i));
    let extra = extra.keep(|i| i < 5);
    let mut moved = extra.clone();
    for y in moved.x[1].iter_mut() {
        *y += 0.2;
    }
    let ids = w.add_particles(&moved.batch()).unwrap();
    assert_eq!(ids.start as usize, kept.m.len());
    // A snapshot after removal and addition steps on as the world does.
    let mut copy = HeapBuffer::new(bytes);
    copy.as_mut_bytes()[..w.state_bytes().len()].copy_from_slice(w.state_bytes());
    let mut c = World::open(copy.as_mut_bytes()).unwrap();
    for _ in 0..10 {
        w.step(dt).unwrap();
        c.step(dt).unwrap();
    }
    assert!(w.state_bytes() == c.state_bytes(), "snapshot after removal");
}

/// `Removal::Inactive` takes out the particles that escaped through an open face (and only
/// them), and tractions follow their particles: those on removed particles go, the others
/// load the same particles under their new ids (the world equals one built with the rest and
/// their tractions, to the bit, 10 steps on).
#[cfg(feature = "effects")]
#[test]
fn inactive_particles_go_and_tractions_follow_their_particles() {
    use mpm_gimp::ParticleStatus;
    let mut def = scene_def(Dimension::Plane2D);
    def.faces[Face::XMax as usize] = Boundary::Open;
    def.effects.traction_capacity = 64;
    let bytes = mpm_gimp::memory_requirements(&def).unwrap().bytes;
    let mut buf = HeapBuffer::new(bytes);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
    // A block flying out through the open x face, fast enough to leave within 0.1 s.
    w.fill_box(
        Vec3::new(0.8, 0.3, 0.0),
        Vec3::new(0.95, 0.45, 0.0),
        m,
        Vec3::new(3.0, 0.0, 0.0),
    )
    .unwrap();
    let dt = w.stable_dt();
    while count_status(&w, ParticleStatus::Escaped) == 0 {
        w.step(dt).unwrap();
    }
    let escaped = count_status(&w, ParticleStatus::Escaped);
    let n = w.particle_count();
    assert!(escaped < n, "some particles must stay");
    let status = w.particles().status.to_vec();
    let loaded: Vec<u32> = (0..n as u32).step_by(9).collect();
    for &i in &loaded {
        w.add_tractions(i..i + 1, Face::YMax, Vec3::new(0.0, -500.0, 0.0))
            .unwrap();
    }
    let removed = w.remove_particles(Removal::Inactive).unwrap();
    assert_eq!(removed, escaped);
    assert_eq!(count_status(&w, ParticleStatus::Escaped), 0);
    let active = |i: usize| status[i] == ParticleStatus::Active as u32;
    let survivors = loaded.iter().filter(|&&i| active(i as usize)).count();
    assert_eq!(
        w.traction_count(),
        survivors,
        "tractions on removed particles go"
    );
    // The same world built with the rest and their tractions: new id = old id minus the
    // removed ones before it.
    let new_id = |i: usize| (0..i).filter(|&j| active(j)).count() as u32;
    let mut copy = HeapBuffer::new(bytes);
    copy.as_mut_bytes()[..w.state_bytes().len()].copy_from_slice(w.state_bytes());
    let mut b = World::open(copy.as_mut_bytes()).unwrap();
    b.clear_tractions();
    for &i in loaded.iter().filter(|&&i| active(i as usize)) {
        let j = new_id(i as usize);
        b.add_tractions(j..j + 1, Face::YMax, Vec3::new(0.0, -500.0, 0.0))
            .unwrap();
    }
    // The removed tractions' ids stay unused in `w`'s table (the others keep theirs): the
    // two worlds step alike.
    let dt = w.stable_dt();
    w.step(dt).unwrap();
    b.step(dt).unwrap();
    let (pw, pb) = (w.particles(), b.particles());
    for a in 0..2 {
        assert!(
            pw.position[a] == pb.position[a] && pw.velocity[a] == pb.velocity[a],
            "tractions follow their particles"
        );
    }
}

/// Misuse: each refused with its error, the world unchanged (its state bytes).
#[test]
fn removal_and_setter_misuse_is_refused_and_changes_nothing() {
    let def = scene_def(Dimension::Plane2D);
    let mut buf = HeapBuffer::new(mpm_gimp::memory_requirements(&def).unwrap().bytes);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    block(Dimension::Plane2D, &mut w);
    let n = w.particle_count() as u32;
    let before = w.state_bytes().to_vec();
    let nan = Real::NAN;
    // Each call checked as it returns: refused with its error, the world as it was.
    let refused = |what: &str, got: Result<(), Error>, want: Error, w: &World<'_>| {
        assert_eq!(got, Err(want), "{what}");
        assert!(
            w.state_bytes() == before.as_slice(),
            "{what} changed the world"
        );
    };
    let r = w.remove_particles(Removal::Range(n - 1..n + 1)).map(drop);
    refused("range past the end", r, Error::UnknownParticle, &w);
    let r = w.remove_particles(Removal::List(&[0, n])).map(drop);
    refused("list past the end", r, Error::UnknownParticle, &w);
    let min = Vec3::new(nan, 0.0, 0.0);
    let r = w
        .remove_particles(Removal::Box {
            min,
            max: Vec3::ONE,
        })
        .map(drop);
    refused("box with a NaN", r, Error::NonFiniteInput, &w);
    let (min, max) = (Vec3::ONE, Vec3::ZERO);
    let r = w.remove_particles(Removal::Box { min, max }).map(drop);
    refused("box inside out", r, Error::InvalidRegion, &w);
    let ok = [0.5 as Real; 2];
    let short = [0.5 as Real; 1];
    let far = [5.0 as Real; 2];
    let bad = [0.5, nan];
    let fast = [1.0e30 as Real; 2];
    let r = w.set_particle_positions(n - 1, [&ok, &ok, &[]]);
    refused("positions past the end", r, Error::UnknownParticle, &w);
    let r = w.set_particle_positions(0, [&ok, &short, &[]]);
    refused("positions of two lengths", r, Error::LengthMismatch, &w);
    let r = w.set_particle_positions(0, [&bad, &ok, &[]]);
    refused("position NaN", r, Error::NonFiniteInput, &w);
    let r = w.set_particle_positions(0, [&far, &ok, &[]]);
    refused("position outside", r, Error::PositionOutsideDomain, &w);
    let r = w.set_particle_velocities(0, [&ok, &bad, &[]]);
    refused("velocity NaN", r, Error::NonFiniteInput, &w);
    let r = w.set_particle_velocities(0, [&fast, &ok, &[]]);
    refused("velocity unresolvable", r, Error::StableStepTooShort, &w);
    let r = w.set_particle_velocities(n, [&ok, &ok, &[]]);
    refused("velocities past the end", r, Error::UnknownParticle, &w);
    let r = w.set_particle_materials(0, &[0, 7]);
    refused("material unknown", r, Error::UnknownMaterial, &w);
    let r = w.set_particle_materials(n - 1, &[0, 0]);
    refused("materials past the end", r, Error::UnknownParticle, &w);
    let r = w.set_particle_affine(0, [[&ok, &bad, &[]], [&ok, &ok, &[]], [&[], &[], &[]]]);
    let want = if cfg!(feature = "effects") {
        Error::NonFiniteInput
    } else {
        Error::EffectNotDeclared
    };
    refused("affine NaN", r, want, &w);
}

/// The setters make the world a world built with the values they set: particles added at one
/// place, velocity and material and then moved, sped up and given another material equal,
/// byte for byte, particles added with the new values (the deformation is still 0, so the
/// material's stress is too). The affine matrix read back and set again leaves the world as it
/// was, and set to zero it is zero.
#[test]
fn setters_give_what_adding_with_those_values_gives() {
    let def = scene_def(Dimension::Plane2D);
    let bytes = mpm_gimp::memory_requirements(&def).unwrap().bytes;
    let (mut a_buf, mut b_buf) = (HeapBuffer::new(bytes), HeapBuffer::new(bytes));
    let mut a = World::init(&def, a_buf.as_mut_bytes()).unwrap();
    let soft = MaterialDef {
        youngs_modulus: 2.0e5,
        ..MaterialDef::DEFAULT
    };
    a.add_material(&MaterialDef::DEFAULT).unwrap();
    a.add_material(&soft).unwrap();
    a.fill_box(
        Vec3::new(0.2, 0.2, 0.0),
        Vec3::new(0.4, 0.4, 0.0),
        0,
        Vec3::ZERO,
    )
    .unwrap();
    let start = Particles::of(&a);
    let n = start.m.len();
    let mut target = start.clone();
    for i in 0..n {
        target.x[0][i] += 0.3;
        target.x[1][i] += 0.1 * (i % 3) as Real / 3.0;
        target.v[0][i] = (i % 5) as Real * 0.1;
        target.v[1][i] = -0.2;
        target.mat[i] = (i % 2) as u32;
    }
    a.set_particle_positions(0, [&target.x[0], &target.x[1], &[]])
        .unwrap();
    a.set_particle_velocities(0, [&target.v[0], &target.v[1], &[]])
        .unwrap();
    a.set_particle_materials(0, &target.mat).unwrap();
    let mut b = World::init(&def, b_buf.as_mut_bytes()).unwrap();
    b.add_material(&MaterialDef::DEFAULT).unwrap();
    b.add_material(&soft).unwrap();
    b.add_particles(&target.batch()).unwrap();
    assert!(a.state_bytes() == b.state_bytes(), "set against added");
    #[cfg(feature = "effects")]
    {
        let dt = a.stable_dt();
        for _ in 0..5 {
            a.step(dt).unwrap();
        }
        let state = a.state_bytes().to_vec();
        let affine: Vec<Vec<Real>> = (0..4)
            .map(|k| a.particles().affine[k / 2][k % 2].to_vec())
            .collect();
        assert!(
            affine.iter().flatten().any(|&v| v != 0.0),
            "APIC moved the block"
        );
        a.set_particle_affine(
            0,
            [
                [&affine[0], &affine[1], &[]],
                [&affine[2], &affine[3], &[]],
                [&[], &[], &[]],
            ],
        )
        .unwrap();
        assert!(
            a.state_bytes() == state.as_slice(),
            "the affine matrix round-trips"
        );
        let zero = vec![0.0; n];
        a.set_particle_affine(
            0,
            [[&zero, &zero, &[]], [&zero, &zero, &[]], [&[], &[], &[]]],
        )
        .unwrap();
        assert!(a.particles().affine[0][1].iter().all(|&v| v == 0.0));
    }
}

/// A tap ([`mpm_gimp_output::tap::Tap`]: a stream added each frame, a drain that removes what
/// reaches it) pours water into a 1 m box for ten minutes of simulated time at 60 Hz: it adds
/// every particle its stream delivers (64 a second: the world never runs out of room), the
/// drain takes the rest, no particle freezes, and the count stays at most 200 of the
/// capacity of 2000: the stream's rate times the 3 s a particle may take from the nozzle to
/// the drain (measured: at most 83 in f32, 84 in f64).
#[test]
fn a_tap_pours_for_ten_minutes_with_its_particle_count_bounded() {
    use mpm_gimp_output::tap::Tap;
    let def = WorldDef {
        cells: [18, 18, 1],
        cell_size: 1.0 / 16.0,
        origin: Vec3::new(-1.0 / 16.0, -1.0 / 16.0, 0.0),
        particle_capacity: 2000,
        ..WorldDef::DEFAULT
    };
    let frame: Real = 1.0 / 60.0;
    let water = MaterialDef {
        model: mpm_gimp::MaterialModel::Fluid,
        bulk_modulus: mpm_gimp_output::stiffness::modulus_for_substeps(&def, 1000.0, frame, 4, 3.0),
        viscosity: 1.0,
        ..MaterialDef::DEFAULT
    };
    let mut buf = HeapBuffer::new(mpm_gimp::memory_requirements(&def).unwrap().bytes);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let material = w.add_material(&water).unwrap();
    let tap = Tap {
        nozzle: Vec3::new(0.3, 0.8, 0.0),
        width: 1.0 / 16.0,
        speed: 1.0,
        material,
        density: 1000.0,
        spacing: 1.0 / 32.0,
        drain: (Vec3::new(0.8, 0.0, 0.0), Vec3::new(1.0, 0.125, 0.0)),
    };
    let (mut most, mut added, mut removed) = (0, 0, 0);
    for f in 0..36_000 {
        let (r, a) = tap.frame(&mut w, frame).unwrap();
        let report = w.step(frame).unwrap();
        assert_eq!(report.frozen, 0, "frame {f}");
        (added, removed) = (added + a, removed + r);
        most = most.max(w.particle_count());
    }
    // Two particles a row, one row per 1/32 m of the stream's travel (64 a second): the rows
    // of each frame telescope to those of the whole run.
    let rows = (1.0 * w.time() / (1.0 / 32.0)).floor() as usize;
    assert_eq!(added, 2 * rows, "the tap poured what it should");
    assert!(rows >= 32 * 600 - 1, "{rows} rows in ten minutes");
    assert_eq!(added - removed, w.particle_count());
    eprintln!("tap: at most {most} particles, {removed} drained");
    assert!(most <= 200, "{most} particles");
}

/// The viewer's tap scene pours a continuous stream: from its second second to its third, at
/// every frame, the particles of the stream between 0.2 m above the floor and the nozzle lie
/// less than a cell apart along it (each row a cell or less behind the last: rows joined
/// across frames, and a fall that stretches them at most 1.9 times, E26's free flight).
#[test]
fn the_tap_scene_pours_a_continuous_stream() {
    let scene = mpm_gimp_output::scenes::find("tap").expect("the tap scene");
    let def = (scene.def)();
    let mut storage = mpm_gimp_output::scenes::Scene::storage(&def).expect("valid");
    let mut w = World::init(&def, storage.as_mut_bytes()).expect("fits");
    (scene.fill)(&mut w).expect("basin");
    let (h, floor) = (
        def.cell_size,
        def.origin.y + def.shape.margin_cells() as Real * def.cell_size,
    );
    for f in 0..180 {
        scene.frame(&mut w, scene.frame_dt).expect("frame");
        if f < 120 {
            continue;
        }
        let p = w.particles();
        let mut ys: Vec<Real> = (0..p.count)
            .filter(|&i| {
                (p.position[0][i] - 0.3).abs() < 0.05
                    && p.position[1][i] > floor + 0.2
                    && p.position[1][i] < floor + 0.78
            })
            .map(|i| p.position[1][i])
            .collect();
        ys.sort_by(Real::total_cmp);
        let gap = ys.windows(2).map(|w| w[1] - w[0]).fold(0.0, Real::max);
        assert!(
            ys.len() > 50,
            "frame {f}: {} particles in the stream",
            ys.len()
        );
        assert!(
            gap < h,
            "frame {f}: a gap of {gap} m in the stream (cell {h} m)"
        );
    }
}
