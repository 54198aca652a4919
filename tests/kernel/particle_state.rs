//! A particle's whole state out of a world and back in, or into another world: every model in
//! every dimension form, with every per-particle effect declared, moves bit for bit
//! ([`World::add_particles_with_state`], [`World::set_particle_state`]); a state no world
//! holds is refused with its error, changes nothing, and is what [`World::open`] refuses in a
//! snapshot. The reorder by cell ([`World::sort_particles`]) permutes that whole state.

use crate::common::buffer_for;
use mpm_gimp::{
    Boundary, Damping, Dimension, Effects, Error, Face, HeapBuffer, MaterialDef, MaterialModel,
    ParticleState, ParticlesView, Real, ShapeFunction, Transfer, Transport, Vec3, World, WorldDef,
};

const MODELS: [MaterialModel; 7] = [
    MaterialModel::NeoHookean,
    MaterialModel::LinearElastic,
    MaterialModel::FixedCorotated,
    MaterialModel::Fluid,
    MaterialModel::VonMises,
    MaterialModel::DruckerPrager,
    MaterialModel::Snow,
];

const DIMENSIONS: [Dimension; 3] = [
    Dimension::Plane2D,
    Dimension::Axisymmetric2D,
    Dimension::ThreeD,
];

/// The length of a frame, s: several substeps each.
const FRAME: Real = 1.0 / 240.0;

/// A world that keeps every per-particle column there is: MUSL (its start positions), APIC,
/// declared plasticity, particle forces, per-particle damping, heat and diffusion with sources;
/// a stick floor and slip walls. cpGIMP in the plane (its domain stretches), uGIMP
/// axisymmetric, the quadratic B-spline in 3D.
fn scene_def(dimension: Dimension) -> WorldDef {
    let three = dimension == Dimension::ThreeD;
    let (cells, shape) = match dimension {
        Dimension::Plane2D => (24, ShapeFunction::CpGimp),
        Dimension::Axisymmetric2D => (24, ShapeFunction::Gimp),
        Dimension::ThreeD => (12, ShapeFunction::QuadraticBspline),
    };
    let h = 1.0 / cells as Real;
    let margin = shape.margin_cells() as Real * h;
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    let sources = Transport {
        sources: true,
        ..Transport::INSULATED
    };
    WorldDef {
        dimension,
        cells: if three { [cells; 3] } else { [cells, cells, 1] },
        cell_size: h,
        // Axisymmetric: the axis on the lower r face's wall plane.
        origin: if dimension == Dimension::Axisymmetric2D {
            Vec3::new(-margin, 0.0, 0.0)
        } else {
            Vec3::ZERO
        },
        shape,
        transfer: Transfer::Apic,
        gravity: Vec3::new(0.0, -9.81, 0.0),
        faces,
        particle_capacity: 1024,
        material_capacity: 2,
        effects: Effects {
            damping: Some(Damping {
                per_particle: true,
                ..Damping::NONE
            }),
            particle_forces: true,
            heat: Some(sources),
            diffusion: Some(sources),
            plasticity: true,
            traction_capacity: 8,
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    }
}

/// Material `model` with a viscosity (a stress that depends on the velocity gradient, not on
/// F alone), thermal expansion and swelling (a stress that depends on the grid's values at the
/// particle), conduction and diffusion.
fn material(model: MaterialModel) -> MaterialDef {
    MaterialDef {
        model,
        viscosity: 2.0,
        conductivity: 1.0,
        diffusivity: 1.0e-4,
        thermal_expansion: 1.0e-4,
        reference_temperature: 300.0,
        swelling: 1.0e-2,
        ..MaterialDef::DEFAULT
    }
}

/// A block of `model` thrown at the floor, with forces, damping rates, temperatures,
/// concentrations and sources that differ from particle to particle, and particle 3 frozen.
fn scene<'b>(dimension: Dimension, model: MaterialModel, buf: &'b mut HeapBuffer) -> World<'b> {
    let def = scene_def(dimension);
    let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
    let m = w.add_material(&material(model)).unwrap();
    // A second material, so that a material id is not always 0.
    w.add_material(&MaterialDef::DEFAULT).unwrap();
    let (lo, hi) = if dimension == Dimension::ThreeD {
        (Vec3::new(0.3, 0.2, 0.3), Vec3::new(0.55, 0.45, 0.55))
    } else {
        (Vec3::new(0.1, 0.1, 0.0), Vec3::new(0.4, 0.4, 0.0))
    };
    w.fill_box(lo, hi, m, Vec3::new(0.4, -2.0, 0.3)).unwrap();
    let n = w.particle_count();
    let each = |f: &dyn Fn(usize) -> Real| (0..n).map(f).collect::<Vec<Real>>();
    let force = [
        each(&|i| 1.0e-3 * (i % 5) as Real),
        each(&|i| -2.0e-3 * (i % 3) as Real),
        each(&|i| 1.0e-3 * (i % 2) as Real),
    ];
    w.set_particle_forces(0, [&force[0], &force[1], &force[2]])
        .unwrap();
    w.set_particle_damping(
        0,
        &each(&|i| 0.5 * (i % 4) as Real),
        &each(&|i| 0.1 * (i % 3) as Real),
    )
    .unwrap();
    use mpm_gimp::ScalarField::{Concentration, Temperature};
    w.set_particle_scalar(Temperature, 0, &each(&|i| 300.0 + (i % 7) as Real))
        .unwrap();
    w.set_particle_scalar(Concentration, 0, &each(&|i| 0.1 * (i % 3) as Real))
        .unwrap();
    w.set_particle_sources(Temperature, 0, &each(&|i| 1.0e5 * (i % 2) as Real))
        .unwrap();
    w.set_particle_sources(Concentration, 0, &each(&|i| 0.5 * (i % 3) as Real))
        .unwrap();
    let frozen = [mpm_gimp::ParticleStatus::Frozen as u32];
    let status = ParticleState {
        count: 1,
        status: &frozen,
        ..ParticleState::NONE
    };
    w.set_particle_state(3, &status).unwrap();
    w
}

/// The Real columns of a state ([`ParticleState::real_columns`]), with their names.
const COLUMNS: usize = ParticleState::REAL_COLUMNS;

fn name(k: usize) -> String {
    let axis = |base: &str, k: usize| format!("{base}[{k}]");
    match k {
        0..3 => axis("position", k),
        3..6 => axis("position_low", k - 3),
        6..9 => axis("velocity", k - 6),
        9 => "mass".into(),
        10 => "volume0".into(),
        11..20 => axis("displacement_gradient", k - 11),
        20..26 => axis("stress", k - 20),
        26..29 => axis("force", k - 26),
        29..31 => axis("damping", k - 29),
        31 => "temperature".into(),
        32 => "concentration".into(),
        33 => "grid_temperature".into(),
        34 => "grid_concentration".into(),
        35 => "temperature_source".into(),
        36 => "concentration_source".into(),
        37 => "hoop".into(),
        38 => "plastic".into(),
        _ => axis("affine", k - 39),
    }
}

/// Some particles' state as a host keeps it: copies of every column.
#[derive(Clone)]
struct Rows {
    count: usize,
    real: Vec<Vec<Real>>,
    material: Vec<u32>,
    status: Vec<u32>,
}

impl Rows {
    /// Copies of `s`'s columns.
    fn of(s: &ParticleState<'_>) -> Rows {
        Rows {
            count: s.count,
            real: s.real_columns().iter().map(|c| c.to_vec()).collect(),
            material: s.material.to_vec(),
            status: s.status.to_vec(),
        }
    }

    /// Rows `range` of `view`.
    fn cut(view: &ParticlesView<'_>, range: core::ops::Range<usize>) -> Rows {
        Rows::of(&view.state().rows(range).expect("rows within the view"))
    }

    /// The state these columns hold.
    fn state(&self) -> ParticleState<'_> {
        let c = core::array::from_fn(|k| &self.real[k][..]);
        ParticleState::from_real_columns(self.count, c, &self.material, &self.status)
    }
}

/// Panics unless the two worlds' particles are the same to the bit: every column of their
/// views, their diagnostics and their stable step.
fn assert_same(label: &str, a: &World<'_>, b: &World<'_>) {
    let (va, vb) = (a.particles(), b.particles());
    assert_eq!(va.count, vb.count, "{label}: particle count");
    let (ca, cb) = (va.state().real_columns(), vb.state().real_columns());
    for k in 0..COLUMNS {
        let bits = |c: &[Real]| c.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert!(bits(ca[k]) == bits(cb[k]), "{label}: column {}", name(k));
    }
    assert_eq!(va.material, vb.material, "{label}: materials");
    assert_eq!(va.status, vb.status, "{label}: statuses");
    let (da, db) = (a.diagnostics(), b.diagnostics());
    assert_eq!(format!("{da:?}"), format!("{db:?}"), "{label}: diagnostics");
    assert_eq!(
        a.stable_dt().to_bits(),
        b.stable_dt().to_bits(),
        "{label}: stable step"
    );
}

/// Steps `w` `frames` frames; no particle may freeze.
fn frames(w: &mut World<'_>, frames: usize) {
    for _ in 0..frames {
        let r = w.step(FRAME).unwrap();
        assert_eq!(r.frozen, 0);
    }
}

/// A copy of `w` in `buf` (a snapshot, opened with its state checked).
fn twin<'b>(w: &World<'_>, buf: &'b mut HeapBuffer) -> World<'b> {
    let bytes = w.as_bytes();
    buf.as_mut_bytes()[..bytes.len()].copy_from_slice(bytes);
    World::open(buf.as_mut_bytes()).unwrap()
}

/// What each scene must have built up before its particles move: a stress and, for the
/// plastic models, a plastic history in the rows that move.
fn assert_nontrivial(label: &str, model: MaterialModel, rows: &Rows) {
    let some = |k: usize| rows.real[k].iter().any(|&v| v != 0.0);
    assert!((20..24).any(some), "{label}: no stress");
    let plastic = matches!(
        model,
        MaterialModel::VonMises | MaterialModel::DruckerPrager | MaterialModel::Snow
    );
    assert_eq!(some(38), plastic, "{label}: plastic history");
    assert!(some(3) && some(4), "{label}: low parts of the positions");
    assert!(some(33) && some(39), "{label}: grid temperature, affine");
}

/// Removal and addition with the whole state: for every model in every dimension form, a
/// scene stepped 12 frames has the particles from a third of the way on (a tail, so that the
/// rest keep their ids) copied out through the view, removed, and added back with every
/// column, in two calls; the world then equals, column by column to the bit, its twin (a
/// snapshot taken before), and so it does 8 frames on. Then a third of the particles set in
/// place to another's state and back ([`World::set_particle_state`]) leave it equal to the
/// twin again. Exact: no tolerance. (Today the plastic history, the stress as the step left
/// it, the low part of the position and the grid values could not be given back.)
#[test]
fn particles_removed_and_added_back_with_their_state_step_on_bit_for_bit() {
    for dimension in DIMENSIONS {
        for model in MODELS {
            let label = format!("{dimension:?} {model:?}");
            let def = scene_def(dimension);
            let (mut a_buf, mut b_buf) = (buffer_for(&def), buffer_for(&def));
            let mut a = scene(dimension, model, &mut a_buf);
            frames(&mut a, 12);
            let mut b = twin(&a, &mut b_buf);
            let n = a.particle_count();
            let k = n / 3 + 1;
            let tail = Rows::cut(&a.particles(), k..n);
            assert_nontrivial(&label, model, &tail);
            assert_eq!(
                a.remove_particles(mpm_gimp::Removal::Range(k as u32..n as u32)),
                Ok(n - k)
            );
            let half = (n - k) / 2;
            let first = tail.state().rows(0..half).unwrap();
            let second = tail.state().rows(half..n - k).unwrap();
            assert_eq!(
                a.add_particles_with_state(&first),
                Ok(k as u32..(k + half) as u32)
            );
            assert_eq!(
                a.add_particles_with_state(&second),
                Ok((k + half) as u32..n as u32)
            );
            assert_same(&format!("{label}, added back"), &a, &b);
            frames(&mut a, 8);
            frames(&mut b, 8);
            assert_same(&format!("{label}, 8 frames on"), &a, &b);
            // In place: particles 0..m take the state of m..2m, then their own again.
            let m = n / 3;
            let own = Rows::cut(&a.particles(), 0..m);
            let other = Rows::cut(&a.particles(), m..2 * m);
            a.set_particle_state(0, &other.state()).unwrap();
            assert_eq!(Rows::cut(&a.particles(), 0..m).real, other.real, "{label}");
            a.set_particle_state(0, &own.state()).unwrap();
            assert_same(&format!("{label}, set in place and back"), &a, &b);
        }
    }
}

/// Migration: for every model in every dimension form, a scene stepped 12 frames has every
/// particle moved, in three calls, into another world of the same definition and materials
/// (which stepped as many frames empty: the same time); the two worlds then step 8 frames to
/// the same bits, column by column, as do their diagnostics and stable steps. Exact.
#[test]
fn particles_moved_to_another_world_step_as_they_would_have_there() {
    for dimension in DIMENSIONS {
        for model in MODELS {
            let label = format!("{dimension:?} {model:?}");
            let def = scene_def(dimension);
            let (mut a_buf, mut c_buf) = (buffer_for(&def), buffer_for(&def));
            let mut a = scene(dimension, model, &mut a_buf);
            frames(&mut a, 12);
            let mut c = World::init(&def, c_buf.as_mut_bytes()).unwrap();
            c.add_material(&material(model)).unwrap();
            c.add_material(&MaterialDef::DEFAULT).unwrap();
            frames(&mut c, 12);
            assert_eq!(a.time().to_bits(), c.time().to_bits(), "{label}: time");
            let n = a.particle_count();
            let view = a.particles();
            let cuts = [0, n / 4, n / 2 + 3, n];
            for w in cuts.windows(2) {
                let rows = view.state().rows(w[0]..w[1]).unwrap();
                let ids = c.add_particles_with_state(&rows).unwrap();
                assert_eq!(ids, w[0] as u32..w[1] as u32, "{label}");
            }
            assert_same(&format!("{label}, moved"), &a, &c);
            frames(&mut a, 8);
            frames(&mut c, 8);
            assert_same(&format!("{label}, 8 frames on"), &a, &c);
        }
    }
}

impl Rows {
    /// These rows in the order `order` gives (`order[new] = old`); a column not declared
    /// (empty) stays empty.
    fn permuted(&self, order: &[u32]) -> Rows {
        let pick = |c: &Vec<Real>| match c.is_empty() {
            true => vec![],
            false => order.iter().map(|&i| c[i as usize]).collect(),
        };
        let pick_u32 = |c: &Vec<u32>| order.iter().map(|&i| c[i as usize]).collect();
        Rows {
            count: order.len(),
            real: self.real.iter().map(pick).collect(),
            material: pick_u32(&self.material),
            status: pick_u32(&self.status),
        }
    }
}

/// `w`'s particles replaced by `rows`, and tractions (downward, on the top face) on the
/// particles `loaded`.
fn refill(w: &mut World<'_>, rows: &Rows, loaded: &[u32]) {
    w.clear_tractions();
    let n = w.particle_count() as u32;
    w.remove_particles(mpm_gimp::Removal::Range(0..n)).unwrap();
    w.add_particles_with_state(&rows.state()).unwrap();
    for &i in loaded {
        w.add_tractions(i..i + 1, Face::YMax, Vec3::new(0.0, -50.0, 0.0))
            .unwrap();
    }
}

/// The flat index of the cell particle `i` of `w` is in, as the three-node shapes' stencils
/// start (`floor(s + 1/2)` per axis, in cells from the origin; x fastest).
fn cell_of(w: &World<'_>, i: usize) -> usize {
    let (def, v) = (w.def(), w.particles());
    let (mut key, mut stride) = (0, 1);
    for a in 0..def.axes() {
        let s = (v.position[a][i] - def.origin[a]) / def.cell_size;
        key += (s + 0.5).floor() as usize * stride;
        stride *= def.cells[a] as usize + 1;
    }
    key
}

/// The reorder by cell: for every model in every dimension form, a scene stepped 12 frames,
/// its particles put back in a scrambled order with tractions on some of them, is sorted
/// ([`World::sort_particles`]). Then, exactly: the world is byte for byte (every column the
/// layout holds, the header, the tables) the one the same particles and tractions make added
/// in the new order; the particles are in cell order, each cell's groups of four first, those
/// of a cell in their old order; a second sort changes nothing. 8 frames on, the sorted and scrambled worlds agree to
/// round-off (the nodes sum the particles in another order): positions within `2e-5` cells
/// and velocities within `2e-5` of the largest speed in f32, `1e-12` in f64 (measured: at
/// most `1.5e-6` in f32, about 12 units of its last place).
#[test]
fn sorting_by_cell_permutes_the_whole_state_and_steps_on_to_round_off() {
    for dimension in DIMENSIONS {
        for model in MODELS {
            let def = scene_def(dimension);
            let mut u_buf = buffer_for(&def);
            let mut u = scene(dimension, model, &mut u_buf);
            frames(&mut u, 12);
            assert_sorts(&format!("{dimension:?} {model:?}"), &mut u);
        }
    }
}

/// The sort with a grid too small to hold a column (which then follows the permutation's
/// cycles in place, not a copy): about 1,900 particles in a grid of 8 by 8 cells (15 node
/// columns of 96 entries), as
/// [`sorting_by_cell_permutes_the_whole_state_and_steps_on_to_round_off`] checks it.
#[test]
fn sorting_by_cell_in_place_where_the_grid_holds_no_column() {
    let def = WorldDef {
        cells: [8, 8, 1],
        cell_size: 1.0 / 8.0,
        particles_per_cell: 8,
        particle_capacity: 2000,
        ..scene_def(Dimension::Plane2D)
    };
    let mut u_buf = buffer_for(&def);
    let mut u = World::init(&def, u_buf.as_mut_bytes()).unwrap();
    let m = u
        .add_material(&material(MaterialModel::NeoHookean))
        .unwrap();
    u.fill_box(
        Vec3::new(0.15, 0.15, 0.0),
        Vec3::new(0.85, 0.85, 0.0),
        m,
        Vec3::ZERO,
    )
    .unwrap();
    assert!(u.particle_count() > 15 * 96 + 64, "{}", u.particle_count());
    frames(&mut u, 4);
    assert_sorts("in place", &mut u);
}

/// Scrambles `u`'s particles (tractions on four of them), sorts them and checks, as
/// [`sorting_by_cell_permutes_the_whole_state_and_steps_on_to_round_off`] says.
fn assert_sorts(label: &str, u: &mut World<'_>) {
    let bound = if cfg!(feature = "f64") { 1e-12 } else { 2e-5 };
    let def = u.def();
    let (mut s_buf, mut t_buf) = (buffer_for(&def), buffer_for(&def));
    let n = u.particle_count();
    let all = Rows::cut(&u.particles(), 0..n);
    let scramble: Vec<u32> = (0..n as u32).map(|i| (i * 97 + 5) % n as u32).collect();
    let loaded: Vec<u32> = vec![0, 7, n as u32 / 2, n as u32 - 1];
    refill(u, &all.permuted(&scramble), &loaded);
    let mut s = twin(u, &mut s_buf);
    let before = Rows::cut(&u.particles(), 0..n);
    // Refused without room for the permutation, the world unchanged.
    let mut order = vec![u32::MAX; n + 3];
    assert_eq!(
        s.sort_particles(&mut order[..n - 1]),
        Err(Error::LengthMismatch),
        "{label}"
    );
    assert!(s.state_bytes() == u.state_bytes(), "{label}: refused");
    assert!(order.iter().all(|&o| o == u32::MAX), "{label}: refused");
    s.sort_particles(&mut order).unwrap();
    assert!(order[n..].iter().all(|&o| o == u32::MAX), "{label}: past n");
    let order = &order[..n];
    let mut seen = vec![false; n];
    order.iter().for_each(|&o| seen[o as usize] = true);
    assert!(seen.iter().all(|&b| b), "{label}: not a permutation");
    // By cell, each cell's whole groups of four first, its rest after every cell's
    // groups; those of a cell in their old order.
    let cells: Vec<usize> = (0..n).map(|i| cell_of(u, i)).collect();
    let mut count = std::collections::HashMap::new();
    let rank: Vec<usize> = cells
        .iter()
        .map(|&c| {
            let k = count.entry(c).or_insert(0);
            *k += 1;
            *k - 1
        })
        .collect();
    let mut expected: Vec<u32> = (0..n as u32).collect();
    expected.sort_by_key(|&i| {
        let i = i as usize;
        (rank[i] >= count[&cells[i]] / 4 * 4, cells[i])
    });
    assert!(order == expected, "{label}: not in cell order");
    assert!(
        order.windows(2).any(|w| w[0] > w[1]),
        "{label}: nothing moved"
    );
    // The same particles and tractions, added in the new order: the same bytes.
    let mut t = twin(u, &mut t_buf);
    let new_id = |old: u32| order.iter().position(|&o| o == old).unwrap() as u32;
    let moved: Vec<u32> = loaded.iter().map(|&i| new_id(i)).collect();
    refill(&mut t, &before.permuted(order), &moved);
    assert!(s.state_bytes() == t.state_bytes(), "{label}: state bytes");
    let mut again = vec![0; n];
    s.sort_particles(&mut again).unwrap();
    assert!(
        again.iter().enumerate().all(|(i, &o)| o as usize == i),
        "{label}"
    );
    assert!(s.state_bytes() == t.state_bytes(), "{label}: sorted twice");
    frames(u, 8);
    frames(&mut s, 8);
    let (vu, vs) = (u.particles(), s.particles());
    let speed = (0..def.axes())
        .flat_map(|a| vu.velocity[a].iter())
        .fold(0.0 as Real, |m, v| m.max(v.abs()));
    for a in 0..def.axes() {
        for (i, &o) in order.iter().enumerate() {
            let o = o as usize;
            let dx = (vs.position[a][i] - vu.position[a][o]).abs() / def.cell_size;
            let dv = (vs.velocity[a][i] - vu.velocity[a][o]).abs() / speed;
            assert!(dx <= bound && dv <= bound, "{label}: {i}, {dx:e}, {dv:e}");
        }
    }
}

/// The byte offset of column `k` (of [`columns`]; `None`: material, `Some(usize::MAX)`:
/// status) of particle `i` in `w`'s bytes.
fn offset_of(w: &World<'_>, column: Column, i: usize) -> usize {
    let v = w.particles();
    let start = w.as_bytes().as_ptr() as usize;
    let at = match column {
        Column::Real(k) => v.state().real_columns()[k][i..].as_ptr() as usize,
        Column::Material => v.material[i..].as_ptr() as usize,
        Column::Status => v.status[i..].as_ptr() as usize,
    };
    at - start
}

/// A column of a particle's state.
#[derive(Clone, Copy, Debug)]
enum Column {
    Real(usize),
    Material,
    Status,
}

/// Index of the column named `n` in [`columns`].
fn real(n: &str) -> Column {
    Column::Real((0..COLUMNS).find(|&k| name(k) == n).expect("a column name"))
}

/// Misuse: a state with one value no world holds (each column's bound), set on particles in
/// place or added, is refused with its error and leaves the world's bytes as they were; the
/// same value written into a snapshot's bytes is what [`World::open`] refuses
/// (`InvalidState`): the setters check what open checks. So are states of the wrong shape: a
/// column of another length, a group given in part, an undeclared effect's column, particles
/// that do not exist, more than the room left, an added particle without its mass; and a
/// value the dimension does not read is not read. For both dimensions of the plane (snow, von
/// Mises axisymmetric) and 3D (neo-Hookean).
#[test]
fn state_misuse_is_refused_changes_nothing_and_is_what_open_refuses() {
    let nan = Real::NAN;
    for (dimension, model) in [
        (Dimension::Plane2D, MaterialModel::Snow),
        (Dimension::Axisymmetric2D, MaterialModel::VonMises),
        (Dimension::ThreeD, MaterialModel::NeoHookean),
    ] {
        let def = scene_def(dimension);
        let (mut buf, mut copy) = (buffer_for(&def), buffer_for(&def));
        let mut w = scene(dimension, model, &mut buf);
        frames(&mut w, 4);
        let before = w.state_bytes().to_vec();
        let n = w.particle_count();
        let i = 7; // The particle of the bad value, among rows 4..12.
        let rows = Rows::cut(&w.particles(), 4..12);
        let x = rows.real[0][i - 4];
        let ulp = x.abs().next_up() - x.abs();
        let mut bad: Vec<(&str, Column, Real, Error)> = vec![
            (
                "position NaN",
                real("position[0]"),
                nan,
                Error::NonFiniteInput,
            ),
            (
                "position outside",
                real("position[1]"),
                5.0,
                Error::PositionOutsideDomain,
            ),
            (
                "position in the margin",
                real("position[1]"),
                0.01,
                Error::PositionOutsideDomain,
            ),
            (
                "low part NaN",
                real("position_low[0]"),
                nan,
                Error::NonFiniteInput,
            ),
            (
                "low part past an ulp",
                real("position_low[0]"),
                4.0 * ulp,
                Error::InvalidState,
            ),
            (
                "velocity infinite",
                real("velocity[1]"),
                Real::INFINITY,
                Error::NonFiniteInput,
            ),
            (
                "velocity unresolvable",
                real("velocity[0]"),
                1.0e30,
                Error::StableStepTooShort,
            ),
            ("mass NaN", real("mass"), nan, Error::NonFiniteInput),
            ("mass 0", real("mass"), 0.0, Error::NonPositiveMassOrVolume),
            (
                "volume negative",
                real("volume0"),
                -1.0,
                Error::NonPositiveMassOrVolume,
            ),
            (
                "H NaN",
                real("displacement_gradient[4]"),
                nan,
                Error::InvalidDeformation,
            ),
            (
                "F inverted",
                real("displacement_gradient[0]"),
                -3.0,
                Error::InvalidDeformation,
            ),
            (
                "stress NaN",
                real("stress[1]"),
                nan,
                Error::InvalidDeformation,
            ),
            (
                "stress infinite",
                real("stress[3]"),
                Real::INFINITY,
                Error::InvalidDeformation,
            ),
            (
                "plastic NaN",
                real("plastic"),
                nan,
                Error::InvalidDeformation,
            ),
            ("force NaN", real("force[1]"), nan, Error::NonFiniteInput),
            (
                "damping negative",
                real("damping[0]"),
                -1.0,
                Error::InvalidEffect,
            ),
            ("damping NaN", real("damping[1]"), nan, Error::InvalidEffect),
            (
                "damping unresolvable",
                real("damping[1]"),
                1.0e30,
                Error::StableStepTooShort,
            ),
            (
                "temperature NaN",
                real("temperature"),
                nan,
                Error::NonFiniteInput,
            ),
            (
                "grid concentration NaN",
                real("grid_concentration"),
                nan,
                Error::NonFiniteInput,
            ),
            (
                "source infinite",
                real("temperature_source"),
                Real::INFINITY,
                Error::NonFiniteInput,
            ),
            ("affine NaN", real("affine[1]"), nan, Error::NonFiniteInput),
            (
                "material unknown",
                Column::Material,
                2.0,
                Error::UnknownMaterial,
            ),
            ("status 3", Column::Status, 3.0, Error::InvalidState),
        ];
        match model {
            MaterialModel::Snow => {
                bad.push((
                    "snow J_p 0",
                    real("plastic"),
                    -1.0,
                    Error::InvalidDeformation,
                ));
            }
            MaterialModel::VonMises => {
                bad.push((
                    "von Mises history < 0",
                    real("plastic"),
                    -0.1,
                    Error::InvalidDeformation,
                ));
                bad.push((
                    "hoop stretch -1",
                    real("hoop"),
                    -1.0,
                    Error::InvalidDeformation,
                ));
            }
            _ => bad.push((
                "history on an elastic model",
                real("plastic"),
                0.5,
                Error::InvalidDeformation,
            )),
        }
        for (what, column, value, want) in bad {
            let label = format!("{dimension:?} {model:?}: {what}");
            let mut edited = rows.clone();
            match column {
                Column::Real(k) => edited.real[k][i - 4] = value,
                Column::Material => edited.material[i - 4] = value as u32,
                Column::Status => edited.status[i - 4] = value as u32,
            }
            assert_eq!(
                w.set_particle_state(4, &edited.state()),
                Err(want),
                "{label}: set"
            );
            assert!(
                w.state_bytes() == before.as_slice(),
                "{label}: set changed the world"
            );
            assert_eq!(
                w.add_particles_with_state(&edited.state()),
                Err(want),
                "{label}: add"
            );
            assert!(
                w.state_bytes() == before.as_slice(),
                "{label}: add changed the world"
            );
            // The same value in a snapshot's bytes.
            let at = offset_of(&w, column, i);
            let mem = copy.as_mut_bytes();
            mem[..before.len()].copy_from_slice(&before);
            match column {
                Column::Real(_) => {
                    mem[at..at + size_of::<Real>()].copy_from_slice(&value.to_ne_bytes())
                }
                _ => mem[at..at + 4].copy_from_slice(&(value as u32).to_ne_bytes()),
            }
            assert_eq!(
                World::open(mem).err(),
                Some(Error::InvalidState),
                "{label}: open"
            );
        }
        // Shapes.
        let label = format!("{dimension:?} {model:?}");
        let refused = |what: &str, got: Result<(), Error>, want: Error, w: &World<'_>| {
            assert_eq!(got, Err(want), "{label}: {what}");
            assert!(
                w.state_bytes() == before.as_slice(),
                "{label}: {what} changed the world"
            );
        };
        let s = rows.state();
        let short = &rows.real[9][..7];
        let r = w.set_particle_state(4, &ParticleState { mass: short, ..s });
        refused("mass one short", r, Error::LengthMismatch, &w);
        let mut h = s.displacement_gradient;
        h[1][0] = &[];
        let r = w.set_particle_state(
            4,
            &ParticleState {
                displacement_gradient: h,
                ..s
            },
        );
        refused("H given in part", r, Error::LengthMismatch, &w);
        let r = w.set_particle_state(
            4,
            &ParticleState {
                status: &rows.status[1..],
                ..s
            },
        );
        refused("statuses one short", r, Error::LengthMismatch, &w);
        let r = w
            .add_particles_with_state(&ParticleState { mass: &[], ..s })
            .map(drop);
        refused("added without masses", r, Error::LengthMismatch, &w);
        let r = w
            .add_particles_with_state(&ParticleState { material: &[], ..s })
            .map(drop);
        refused("added without materials", r, Error::LengthMismatch, &w);
        let r = w.set_particle_state((n - 7) as u32, &s);
        refused("particles past the end", r, Error::UnknownParticle, &w);
        let r = w.set_particle_state(u32::MAX, &s);
        refused("first id u32::MAX", r, Error::UnknownParticle, &w);
        let big: Vec<Vec<Real>> = (rows.real.iter())
            .map(|c| c.first().map_or(vec![], |&v| vec![v; 1100]))
            .collect();
        let big = Rows {
            count: 1100,
            real: big,
            material: vec![0; 1100],
            status: vec![0; 1100],
        };
        let r = w.add_particles_with_state(&big.state()).map(drop);
        refused("past the capacity", r, Error::ParticleCapacityExceeded, &w);
        // A 2D world reads no z, and no hoop outside the axisymmetric form: NaN there is
        // not read (given to particles in place, nothing changes).
        if dimension != Dimension::ThreeD {
            let nans = vec![nan; rows.count];
            let mut ignored = ParticleState {
                position: [s.position[0], s.position[1], &nans],
                stress: [
                    s.stress[0],
                    s.stress[1],
                    s.stress[2],
                    s.stress[3],
                    &nans,
                    &nans,
                ],
                ..s
            };
            if dimension == Dimension::Plane2D {
                ignored.hoop = &nans;
            }
            w.set_particle_state(4, &ignored).unwrap();
            assert!(w.state_bytes() == before.as_slice(), "{label}: z read");
        }
        // Undeclared effects.
        let plain = WorldDef {
            effects: Effects::NONE,
            transfer: Transfer::Flip,
            ..def
        };
        let mut p_buf = buffer_for(&plain);
        let mut p = World::init(&plain, p_buf.as_mut_bytes()).unwrap();
        p.add_material(&MaterialDef::DEFAULT).unwrap();
        let empty = p.state_bytes().to_vec();
        let elastic = Rows {
            material: vec![0; rows.count],
            ..rows.clone()
        };
        let s = elastic.state();
        let undeclared: [(&str, ParticleState<'_>); 6] = [
            (
                "temperature",
                ParticleState {
                    temperature: s.temperature,
                    ..ParticleState::NONE
                },
            ),
            (
                "sources",
                ParticleState {
                    concentration_source: s.concentration_source,
                    ..ParticleState::NONE
                },
            ),
            (
                "forces",
                ParticleState {
                    force: s.force,
                    ..ParticleState::NONE
                },
            ),
            (
                "damping",
                ParticleState {
                    damping: s.damping,
                    ..ParticleState::NONE
                },
            ),
            (
                "affine",
                ParticleState {
                    affine: s.affine,
                    ..ParticleState::NONE
                },
            ),
            (
                "plastic",
                ParticleState {
                    plastic: s.plastic,
                    ..ParticleState::NONE
                },
            ),
        ];
        for (what, extra) in undeclared {
            let base = ParticleState {
                count: s.count,
                position: s.position,
                mass: s.mass,
                volume0: s.volume0,
                material: s.material,
                ..extra
            };
            let r = p.add_particles_with_state(&base).map(drop);
            assert_eq!(r, Err(Error::EffectNotDeclared), "{label}: {what}");
            assert!(
                p.state_bytes() == empty.as_slice(),
                "{label}: {what} changed the world"
            );
        }
    }
}
