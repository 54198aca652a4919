//! Random sequences of C interface calls (init with arbitrary dimension, shape (cpGIMP included),
//! transfer and effects, axisymmetric worlds with their axis mostly in place, heat conduction and
//! diffusion included; add material, thermal expansion and swelling included; add particles, seed,
//! set particle forces, damping, temperatures, concentrations and sources, add (on a face or
//! with any normal), schedule and clear tractions, step, read, open a damaged snapshot) with arbitrary
//! values, through the same `extern "C"` functions a C host calls. After every call, either it
//! returned a status and the world's bytes are unchanged, or it succeeded and every particle
//! value (forces, damping, APIC moments, temperatures and concentrations and their grid values,
//! hoop stretches included) is finite and every position inside the grid box. Single precision
//! (the default build of the library).
#![no_main]

use libfuzzer_sys::fuzz_target;
use mpm_gimp::*;

/// Reads the fuzzer's bytes as a stream of choices; zeros once exhausted.
struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> u8 {
        let (b, rest) = self.0.split_first().map_or((0, &[][..]), |(b, r)| (*b, r));
        self.0 = rest;
        b
    }

    fn u32_below(&mut self, n: u32) -> u32 {
        let v = u32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()]);
        v % n.max(1)
    }

    /// A real that is often special (NaN, infinities, zero, tiny, huge) and otherwise a value
    /// of moderate size: what breaks numerical code.
    fn real(&mut self) -> mpm_real {
        match self.byte() % 16 {
            0 => mpm_real::NAN,
            1 => mpm_real::INFINITY,
            2 => -mpm_real::INFINITY,
            3 => 0.0,
            4 => -0.0,
            5 => mpm_real::MIN_POSITIVE,
            6 => mpm_real::MAX,
            7 => -1.0,
            _ => (self.u32_below(1 << 20) as mpm_real / (1 << 16) as mpm_real) - 4.0,
        }
    }

    /// A real in `[lo, hi]` most of the time, any real otherwise.
    fn real_in(&mut self, lo: mpm_real, hi: mpm_real) -> mpm_real {
        if self.byte() % 8 == 0 {
            self.real()
        } else {
            lo + (hi - lo) * (self.u32_below(1 << 16) as mpm_real / (1 << 16) as mpm_real)
        }
    }

    fn vec3_in(&mut self, lo: mpm_real, hi: mpm_real) -> MpmVec3 {
        MpmVec3 {
            x: self.real_in(lo, hi),
            y: self.real_in(lo, hi),
            z: self.real_in(lo, hi),
        }
    }
}

/// Memory for one world, aligned by hand.
struct Memory {
    bytes: Vec<u8>,
}

impl Memory {
    fn aligned(&mut self, len: usize, align: usize) -> *mut u8 {
        self.bytes = vec![0xA5; len + align];
        let p = self.bytes.as_mut_ptr();
        p.wrapping_add(p.align_offset(align))
    }
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A byte copy of world `w` opens.
fn reopens(w: *const MpmWorld) {
    let mut n = 0usize;
    // SAFETY: `w` is a world this target initialised, in memory it still owns.
    assert_eq!(unsafe { mpm_world_bytes(w, &mut n) }, MpmStatus::Ok);
    let mut copy = Memory { bytes: Vec::new() };
    let p = copy.aligned(n, 64);
    // SAFETY: the world spans `n` bytes, and `p` has room for `n` bytes in other memory.
    unsafe { core::ptr::copy_nonoverlapping(w as *const u8, p, n) };
    let mut opened = core::ptr::null_mut();
    // SAFETY: `p` has `n` bytes; `opened` is valid.
    let s = unsafe { mpm_world_open(p.cast(), n, &mut opened) };
    assert_eq!(s, MpmStatus::Ok, "a state the interface produced does not open");
}

/// The hash of the world's bytes (every column and the header).
fn world_hash(w: *const MpmWorld) -> u64 {
    let mut n = 0usize;
    // SAFETY: `w` is a world this target initialised, in memory it still owns.
    assert_eq!(unsafe { mpm_world_bytes(w, &mut n) }, MpmStatus::Ok);
    // SAFETY: the world spans `n` bytes from `w`.
    fnv1a(unsafe { core::slice::from_raw_parts(w as *const u8, n) })
}

/// Every particle value finite and every position inside the grid box, and a byte copy of
/// the world opens (`mpm_world_open` checks every value against its range: every state the
/// interface produces must pass).
fn check_state(w: *const MpmWorld) {
    reopens(w);
    let mut def = mpm_world_def_default_f32();
    let mut view = core::mem::MaybeUninit::<MpmParticlesView>::uninit();
    // SAFETY: `w` is a world; the outputs are valid.
    unsafe {
        assert_eq!(mpm_world_get_def(w, &mut def), MpmStatus::Ok);
        assert_eq!(mpm_world_particles(w, view.as_mut_ptr()), MpmStatus::Ok);
    }
    // SAFETY: written by the successful call above.
    let v = unsafe { view.assume_init() };
    let d = if def.dimension == MpmDimension::Space3d as u32 {
        3
    } else {
        2
    };
    let origin = [def.origin.x, def.origin.y, def.origin.z];
    let col = |p: *const mpm_real| {
        // SAFETY: every column the view names holds `count` values until the next mutation.
        unsafe { core::slice::from_raw_parts(p, v.count) }
    };
    for a in 0..d {
        let lo = origin[a];
        let hi = origin[a] + def.cells[a] as mpm_real * def.cell_size;
        for &x in col(v.position[a]) {
            assert!(
                x.is_finite() && x >= lo && x <= hi,
                "position {x} outside [{lo}, {hi}]"
            );
        }
        assert!(
            col(v.velocity[a]).iter().all(|x| x.is_finite()),
            "velocity not finite"
        );
    }
    let mut columns = vec![v.mass, v.volume0];
    columns.extend(v.displacement_gradient.iter().filter(|p| !p.is_null()));
    columns.extend(v.stress.iter().filter(|p| !p.is_null()));
    columns.extend(v.force.iter().filter(|p| !p.is_null()));
    columns.extend(v.affine.iter().filter(|p| !p.is_null()));
    let scalars = [
        v.temperature,
        v.concentration,
        v.grid_temperature,
        v.grid_concentration,
    ];
    columns.extend(scalars.iter().filter(|p| !p.is_null()));
    let heat = def.effects.heat.declared == 1;
    let diffusion = def.effects.diffusion.declared == 1;
    assert_eq!(
        scalars.map(|p| !p.is_null()),
        [heat, diffusion, heat, diffusion],
        "the view's scalar columns do not follow the declarations"
    );
    let axisymmetric = def.dimension == MpmDimension::Axisymmetric2d as u32;
    assert_eq!(
        !v.hoop.is_null(),
        axisymmetric,
        "the view's hoop column does not follow the dimension"
    );
    if axisymmetric {
        columns.push(v.hoop);
    }
    for &p in v.damping.iter().filter(|p| !p.is_null()) {
        assert!(
            col(p).iter().all(|x| x.is_finite() && *x >= 0.0),
            "a damping value is negative or not finite"
        );
    }
    for p in columns {
        assert!(
            col(p).iter().all(|x| x.is_finite()),
            "a particle value is not finite"
        );
    }
}

/// A snapshot of `world` damaged, opened from `memory`: up to 8 bytes anywhere in it
/// overwritten, or (one time in two) one value of one particle column (any column the view
/// names: position and its low part, velocity, mass, volume, H, stress, the effects' columns,
/// the plastic history) set to a value at or past the edge of its range. `mpm_world_open`
/// must refuse it (a damaged header is `NOT_A_WORLD`, a damaged state `INVALID_STATE`) or
/// open a world whose every value is finite and inside the grid, which then steps (or
/// refuses a dt past its substep limit) and stays so.
fn corrupted_snapshot(inp: &mut Input<'_>, world: *const MpmWorld, memory: &mut Memory) {
    let mut n = 0usize;
    // SAFETY: `world` is a world this target initialised, in memory it still owns.
    assert_eq!(unsafe { mpm_world_bytes(world, &mut n) }, MpmStatus::Ok);
    let p = memory.aligned(n, 64);
    // SAFETY: the world spans `n` bytes, and `p` has room for `n` bytes in other memory.
    unsafe { core::ptr::copy_nonoverlapping(world as *const u8, p, n) };
    let column = if inp.byte() % 2 == 0 {
        value_in_column(inp, world)
    } else {
        None
    };
    if let Some((offset, value)) = column {
        // SAFETY: `offset` is that of a value of a particle column, inside the world's `n`
        // bytes; the copy has the world's alignment.
        unsafe { p.add(offset).cast::<mpm_real>().write(value) };
    } else {
        for _ in 0..1 + inp.byte() % 8 {
            let at = inp.u32_below(n as u32) as usize;
            // SAFETY: `at < n`.
            unsafe { *p.add(at) = inp.byte() };
        }
    }
    let mut copy = core::ptr::null_mut();
    // SAFETY: `p` has `n` bytes; `copy` is valid.
    let s = unsafe { mpm_world_open(p.cast(), n, &mut copy) };
    match s {
        MpmStatus::Ok => {
            check_state(copy);
            let mut dt = 0.0;
            // SAFETY: `copy` is the world just opened; the outputs are valid.
            unsafe {
                assert_eq!(mpm_world_stable_dt(copy, &mut dt), MpmStatus::Ok);
                // Infinite when nothing limits the step (no particle moves, no material has a
                // wave speed): then any finite step is stable.
                if !dt.is_finite() {
                    dt = 1e-3;
                }
                let mut report = MpmStepReport::default();
                let s = mpm_world_step(copy, dt, &mut report);
                assert!(
                    matches!(s, MpmStatus::Ok | MpmStatus::SubstepLimit),
                    "a snapshot that opened did not step: {s:?}"
                );
            }
            check_state(copy);
        }
        MpmStatus::NotAWorld | MpmStatus::InvalidState => {}
        other => panic!("open answered {other:?} for a damaged snapshot"),
    }
}

/// The offset in `world` of one value of one of its particle Real columns, and a value to put
/// there at or past the edge of a range (non-finite, huge, negative, a multiple of the
/// value's last place, `J_p = 0`); `None` for a world without particles.
fn value_in_column(inp: &mut Input<'_>, world: *const MpmWorld) -> Option<(usize, mpm_real)> {
    let mut view = core::mem::MaybeUninit::<MpmParticlesView>::uninit();
    // SAFETY: `world` is a world; the output is valid.
    assert_eq!(
        unsafe { mpm_world_particles(world, view.as_mut_ptr()) },
        MpmStatus::Ok
    );
    // SAFETY: written by the successful call above.
    let v = unsafe { view.assume_init() };
    if v.count == 0 {
        return None;
    }
    let mut columns: Vec<*const mpm_real> = vec![v.mass, v.volume0, v.hoop, v.plastic];
    for group in [&v.position[..], &v.position_low, &v.velocity, &v.force, &v.damping] {
        columns.extend_from_slice(group);
    }
    columns.extend_from_slice(&v.displacement_gradient);
    columns.extend_from_slice(&v.stress);
    columns.extend_from_slice(&v.affine);
    columns.extend_from_slice(&[v.temperature, v.concentration]);
    columns.retain(|c| !c.is_null());
    let column = columns[inp.u32_below(columns.len() as u32) as usize];
    let i = inp.u32_below(v.count as u32) as usize;
    // SAFETY: every column the view names holds `count` values.
    let old = unsafe { *column.add(i) };
    let ulp = |x: mpm_real| x.abs().next_up() - x.abs();
    let value = match inp.byte() % 12 {
        0 => mpm_real::NAN,
        1 => mpm_real::INFINITY,
        2 => -mpm_real::MAX,
        3 => 1.0e30,
        4 => -1.0,
        5 => -2.0,
        6 => -1.0e-3,
        7 => 0.25,
        8 => old + 4.0 * ulp(old),
        9 => ulp(old) / 2.0,
        10 => 0.0,
        _ => inp.real(),
    };
    Some((column as usize - world as usize + i * core::mem::size_of::<mpm_real>(), value))
}

/// A schedule of up to 9 points (one more than allowed), mostly with increasing times.
fn schedule(inp: &mut Input<'_>, lo: mpm_real, hi: mpm_real) -> MpmSchedule {
    let mut s = MpmSchedule {
        points: inp.u32_below(MPM_SCHEDULE_POINTS as u32 + 2),
        times: [0.0; MPM_SCHEDULE_POINTS],
        values: [0.0; MPM_SCHEDULE_POINTS],
    };
    let mut t = 0.0;
    for k in 0..MPM_SCHEDULE_POINTS {
        t += inp.real_in(0.0, 0.05);
        s.times[k] = t;
        s.values[k] = inp.real_in(lo, hi);
    }
    s
}

/// A flag: 0 or 1, sometimes a value that is neither.
fn flag(inp: &mut Input<'_>) -> u32 {
    match inp.byte() % 16 {
        0 => 2 + inp.u32_below(u32::MAX - 2),
        b => (b % 2) as u32,
    }
}

/// A transport (heat conduction or diffusion): declared about half the time, each face
/// insulated, fixed or flux (sometimes a kind out of range), values mostly in range.
fn transport(inp: &mut Input<'_>, lo: mpm_real, hi: mpm_real) -> MpmTransport {
    let mut t = mpm_world_def_default_f32().effects.heat;
    t.declared = match inp.byte() % 4 {
        0 | 1 => 0,
        _ => flag(inp),
    };
    for f in t.faces.iter_mut() {
        f.kind = match inp.byte() % 32 {
            0 => inp.u32_below(u32::MAX),
            b => (b % 3) as u32,
        };
        f.value = inp.real_in(lo, hi);
    }
    t.sources = flag(inp);
    t
}

/// Effects, each declared about half the time, with values mostly in range.
fn effects(inp: &mut Input<'_>) -> MpmEffects {
    let mut e = mpm_world_def_default_f32().effects;
    if inp.byte() % 2 == 0 {
        return e;
    }
    let d = &mut e.damping;
    d.declared = flag(inp);
    d.grid = schedule(inp, 0.0, 20.0);
    d.particle = schedule(inp, 0.0, 20.0);
    d.feedback.declared = flag(inp);
    d.feedback.gain = inp.real_in(0.0, 10.0);
    d.feedback.target = schedule(inp, 0.0, 1.0);
    d.feedback.max_alpha = inp.real_in(0.0, 50.0);
    d.per_particle = flag(inp);
    d.grid_on_force = flag(inp);
    // Zones: mostly 0 to 2 in use, sometimes more than there is room for; boxes within and
    // across the grid (sometimes empty or inverted), graded toward any face or none.
    d.zone_count = match inp.byte() % 16 {
        0 => inp.u32_below(u32::MAX),
        b => (b % 3) as u32,
    };
    for z in d.zones.iter_mut() {
        z.min = inp.vec3_in(-0.5, 1.0);
        z.max = inp.vec3_in(0.0, 1.5);
        z.rate = inp.real_in(-1.0, 50.0);
        z.ramped = flag(inp);
        z.ramp_face = inp.u32_below(8);
    }
    e.particle_forces = flag(inp);
    e.traction_capacity = if inp.byte() % 32 == 0 {
        inp.u32_below(u32::MAX)
    } else {
        inp.u32_below(24)
    };
    e.body_force = inp.vec3_in(-20.0, 20.0);
    e.body_force_scale = schedule(inp, -2.0, 2.0);
    for row in &mut e.body_force_gradient {
        *row = inp.vec3_in(-50.0, 50.0);
    }
    for s in e.traction_schedules.iter_mut() {
        *s = schedule(inp, -2.0, 2.0);
    }
    e.heat = transport(inp, -500.0, 500.0);
    e.diffusion = transport(inp, -2.0, 2.0);
    // The plastic models' history column, about half the time (2: an invalid flag).
    e.plasticity = inp.u32_below(3) % 3;
    // Room for a few colliders, sometimes none, sometimes past the limit.
    e.collider_capacity = match inp.byte() % 16 {
        0 => inp.u32_below(u32::MAX),
        1..=4 => 0,
        b => (b % 4) as u32,
    };
    e.sdf_capacity = match inp.byte() % 8 {
        0 => inp.u32_below(u32::MAX),
        1..=3 => 0,
        _ => inp.u32_below(600),
    };
    e
}

fn new_def(inp: &mut Input<'_>) -> MpmWorldDef {
    let mut def = mpm_world_def_default_f32();
    if inp.byte() % 16 == 0 {
        def.internal_cookie ^= 1; // a definition not from the default function
    }
    def.dimension = [2, 3, 4, 7][inp.byte() as usize % 4];
    def.cell_size = inp.real_in(0.01, 0.2);
    def.origin = inp.vec3_in(-1.0, 1.0);
    for c in def.cells.iter_mut() {
        *c = inp.u32_below(if def.dimension == 3 { 12 } else { 24 }) + 1;
    }
    def.particle_capacity = inp.u32_below(300) + if inp.byte() % 32 == 0 { 0 } else { 1 };
    def.material_capacity = inp.u32_below(4);
    def.shape = inp.u32_below(6); // 0..=4 the shapes (cpGIMP 4), 5 out of range
    def.particles_per_cell = inp.u32_below(5);
    def.flip_beta = inp.real_in(0.0, 1.0);
    def.pic_rate = inp.real_in(0.0, 100.0);
    def.update_order = inp.u32_below(4);
    def.gravity = inp.vec3_in(-20.0, 20.0);
    for f in def.faces.iter_mut() {
        *f = inp.u32_below(5); // 0..=3 the boundaries (periodic 3), 4 out of range
    }
    // Periodic faces mostly in pairs (a lone one is refused with `InvalidBoundary`).
    if inp.byte() % 4 != 0 {
        for a in 0..3 {
            if def.faces[2 * a] == MpmBoundary::Periodic as u32 {
                def.faces[2 * a + 1] = MpmBoundary::Periodic as u32;
            }
        }
    }
    def.exp_terms = inp.u32_below(10);
    def.cfl = inp.real_in(0.05, 1.0);
    def.transfer = inp.u32_below(6); // 0..=4 the transfers (MLS 3, FLIP momentum 4), 5 out of range
    // The limits: mostly the defaults, sometimes anything (0 and NaN refused).
    if inp.byte() % 8 == 0 {
        def.max_substeps = inp.u32_below(2000);
        def.max_volume_ratio = inp.real_in(0.5, 4.0);
    }
    def.effects = effects(inp);
    // Axisymmetric: mostly with the lower x face a wall at the axis r = 0 (the grid's face
    // `margin` cells below it), else the definition is refused with `InvalidAxis`.
    if def.dimension == MpmDimension::Axisymmetric2d as u32 && inp.byte() % 4 != 0 {
        let margin = if def.shape == MpmShape::Linear as u32 {
            0.0
        } else {
            1.0
        };
        def.origin.x = -margin * def.cell_size;
        if def.faces[MpmFace::XMin as usize] == MpmBoundary::Open as u32 {
            def.faces[MpmFace::XMin as usize] = inp.u32_below(2);
        }
    }
    def
}

/// A particle range: mostly inside the world's particles, sometimes past them or past u32.
fn particle_range(inp: &mut Input<'_>, w: *const MpmWorld) -> (u32, u32) {
    let mut diag = MpmDiagnostics::default();
    // SAFETY: `w` is a world; `diag` is a local.
    assert_eq!(
        unsafe { mpm_world_diagnostics(w, &mut diag) },
        MpmStatus::Ok
    );
    let n = diag.particle_count as u32;
    if inp.byte() % 16 == 0 {
        return (inp.u32_below(u32::MAX), inp.u32_below(u32::MAX));
    }
    let first = inp.u32_below(n + 2);
    (first, inp.u32_below(n.saturating_sub(first) + 2))
}

fuzz_target!(|data: &[u8]| {
    let mut inp = Input(data);
    let mut memory = Memory { bytes: Vec::new() };
    let mut world: *mut MpmWorld = core::ptr::null_mut();
    let mut snapshot = Memory { bytes: Vec::new() };
    for _ in 0..64 {
        if inp.0.is_empty() {
            break;
        }
        let op = inp.byte() % 17;
        if world.is_null() || op == 0 {
            let def = new_def(&mut inp);
            let mut req = MpmMemoryRequirements::default();
            // SAFETY: valid pointers.
            if unsafe { mpm_memory_requirements(&def, &mut req) } != MpmStatus::Ok {
                continue;
            }
            let short = inp.byte() % 16 == 0;
            let len = if short { req.bytes / 2 } else { req.bytes };
            let p = memory.aligned(req.bytes, req.align);
            let mut w = core::ptr::null_mut();
            // SAFETY: `p` has `req.bytes >= len` bytes.
            let s = unsafe { mpm_world_init(&def, p.cast(), len, &mut w) };
            if s == MpmStatus::Ok {
                assert_eq!(w, p.cast());
                world = w;
                check_state(world);
            } else {
                // Nothing written on failure: the memory keeps its fill pattern.
                // SAFETY: `p` has `req.bytes` bytes.
                let bytes = unsafe { core::slice::from_raw_parts(p, req.bytes) };
                assert!(
                    bytes.iter().all(|&b| b == 0xA5),
                    "init failed after writing"
                );
                world = core::ptr::null_mut();
            }
            continue;
        }
        if op == 13 {
            corrupted_snapshot(&mut inp, world, &mut snapshot);
            continue;
        }
        let before = world_hash(world);
        // SAFETY (every call below): `world` is a world in `memory`; every other pointer
        // refers to a local that lives across the call, and each array holds `count` values.
        let status = unsafe {
            match op {
                1 => {
                    let mut m = mpm_material_def_default_f32();
                    // Every model and one past them.
                    m.model = inp.u32_below(8);
                    m.youngs_modulus = inp.real_in(1.0e3, 1.0e7);
                    m.poisson_ratio = inp.real_in(-0.9, 0.49);
                    m.density = inp.real_in(10.0, 5000.0);
                    m.heat_capacity = inp.real_in(100.0, 5000.0);
                    m.conductivity = inp.real_in(0.0, 500.0);
                    m.diffusivity = inp.real_in(0.0, 1.0e-2);
                    // Expansion and swelling about half the time each; a non-finite value or
                    // reference is refused.
                    if inp.byte() % 2 == 0 {
                        m.thermal_expansion = inp.real_in(-1.0e-3, 1.0e-3);
                        m.reference_temperature = inp.real_in(-500.0, 500.0);
                    }
                    if inp.byte() % 2 == 0 {
                        m.swelling = inp.real_in(-0.1, 0.1);
                        m.reference_concentration = inp.real_in(-2.0, 2.0);
                    }
                    // The fluid, plastic and viscous parameters, half the time (else the
                    // defaults), each from below its range to past it.
                    if inp.byte() % 2 == 0 {
                        m.viscosity = inp.real_in(-1.0, 50.0);
                        m.bulk_viscosity = inp.real_in(-1.0, 50.0);
                        m.volume_relaxation = inp.real_in(-1.0, 100.0);
                        m.bulk_modulus = inp.real_in(-1.0e3, 1.0e7);
                        m.pressure_exponent = inp.real_in(0.0, 10.0);
                        m.yield_stress = inp.real_in(-1.0e3, 1.0e6);
                        m.hardening_modulus = inp.real_in(-1.0e3, 1.0e7);
                        m.friction_angle = inp.real_in(-5.0, 95.0);
                        m.friction_fit = (inp.byte() % 6) as u32;
                        m.cohesion = inp.real_in(-1.0e2, 1.0e4);
                        m.critical_compression = inp.real_in(-0.1, 1.1);
                        m.critical_stretch = inp.real_in(-0.1, 0.5);
                        m.hardening_coefficient = inp.real_in(-1.0, 20.0);
                    }
                    let mut id = 0;
                    mpm_world_add_material(world, &m, &mut id)
                }
                2 => {
                    let count = inp.u32_below(9) as usize;
                    let mut cols: Vec<Vec<mpm_real>> = (0..8)
                        .map(|k| {
                            (0..count)
                                .map(|_| {
                                    if k < 6 {
                                        inp.real_in(-0.5, 3.0)
                                    } else {
                                        inp.real_in(0.0, 1.0)
                                    }
                                })
                                .collect()
                        })
                        .collect();
                    let material: Vec<u32> = (0..count).map(|_| inp.u32_below(4)).collect();
                    let arrays = MpmParticleArrays {
                        position: [cols[0].as_ptr(), cols[1].as_ptr(), cols[2].as_ptr()],
                        velocity: [cols[3].as_ptr(), cols[4].as_ptr(), cols[5].as_ptr()],
                        mass: cols[6].as_ptr(),
                        volume: cols[7].as_ptr(),
                        material: material.as_ptr(),
                    };
                    let mut ids = MpmIdRange::default();
                    let s = mpm_world_add_particles(world, &arrays, count, &mut ids);
                    cols.clear();
                    s
                }
                3 => {
                    let (a, b, v) = (
                        inp.vec3_in(-0.5, 3.0),
                        inp.vec3_in(-0.5, 3.0),
                        inp.vec3_in(-5.0, 5.0),
                    );
                    let material = inp.u32_below(4);
                    let mut ids = MpmIdRange::default();
                    match inp.byte() % 3 {
                        0 => mpm_world_fill_box(world, a, b, material, v, &mut ids),
                        1 => mpm_world_fill_disk(
                            world,
                            a,
                            inp.real_in(0.0, 0.5),
                            material,
                            v,
                            &mut ids,
                        ),
                        _ => mpm_world_fill_sphere(
                            world,
                            a,
                            inp.real_in(0.0, 0.5),
                            material,
                            v,
                            &mut ids,
                        ),
                    }
                }
                8 => {
                    let (first, count) = particle_range(&mut inp, world);
                    let count = count as usize;
                    let cols: Vec<Vec<mpm_real>> = (0..3)
                        .map(|_| {
                            (0..count.min(512))
                                .map(|_| inp.real_in(-5.0, 5.0))
                                .collect()
                        })
                        .collect();
                    // A count past the particles is refused before any array is read.
                    let (fx, fy, fz) = if count <= 512 {
                        (cols[0].as_ptr(), cols[1].as_ptr(), cols[2].as_ptr())
                    } else {
                        let dangling = core::ptr::NonNull::<mpm_real>::dangling().as_ptr();
                        (
                            dangling.cast_const(),
                            dangling.cast_const(),
                            dangling.cast_const(),
                        )
                    };
                    let fz = if inp.byte() % 4 == 0 {
                        core::ptr::null()
                    } else {
                        fz
                    };
                    mpm_world_set_particle_forces(world, first, fx, fy, fz, count)
                }
                14 => {
                    // An initial displacement gradient: small, large, inverting or not finite
                    // entries; sometimes a NULL pointer or a count past the particles (refused
                    // before any array is read).
                    let (first, count) = particle_range(&mut inp, world);
                    let count = count as usize;
                    let cols: Vec<Vec<mpm_real>> = (0..9)
                        .map(|_| {
                            (0..count.min(512))
                                .map(|_| match inp.byte() % 32 {
                                    0 => mpm_real::NAN,
                                    1 => inp.real_in(-3.0, 3.0),
                                    _ => inp.real_in(-0.05, 0.05),
                                })
                                .collect()
                        })
                        .collect();
                    let dangling = core::ptr::NonNull::<mpm_real>::dangling().as_ptr();
                    let mut h: [*const mpm_real; 9] = core::array::from_fn(|k| {
                        if count <= 512 {
                            cols[k].as_ptr()
                        } else {
                            dangling.cast_const()
                        }
                    });
                    if inp.byte() % 8 == 0 {
                        h[inp.u32_below(9) as usize] = core::ptr::null();
                    }
                    let hp = if inp.byte() % 16 == 0 {
                        core::ptr::null()
                    } else {
                        h.as_ptr()
                    };
                    mpm_world_set_displacement_gradient(world, first, hp, count)
                }
                12 => {
                    // Temperatures, concentrations or their sources; sometimes a field out of
                    // range, a NULL array or a count past the particles (refused before the
                    // array is read).
                    let (first, count) = particle_range(&mut inp, world);
                    let count = count as usize;
                    let field = match inp.byte() % 16 {
                        0 => 2 + inp.u32_below(u32::MAX - 2),
                        b => (b % 2) as u32,
                    };
                    let values: Vec<mpm_real> = (0..count.min(512))
                        .map(|_| inp.real_in(-1000.0, 1000.0))
                        .collect();
                    let p = match inp.byte() % 16 {
                        0 => core::ptr::null(),
                        _ if count > 512 => core::ptr::NonNull::<mpm_real>::dangling()
                            .as_ptr()
                            .cast_const(),
                        _ => values.as_ptr(),
                    };
                    if inp.byte() % 2 == 0 {
                        mpm_world_set_particle_scalar(world, field, first, p, count)
                    } else {
                        mpm_world_set_particle_sources(world, field, first, p, count)
                    }
                }
                9 => {
                    let (first, count) = particle_range(&mut inp, world);
                    let count = (count as usize).min(512);
                    let g: Vec<mpm_real> = (0..count).map(|_| inp.real_in(0.0, 20.0)).collect();
                    let p: Vec<mpm_real> = (0..count).map(|_| inp.real_in(0.0, 20.0)).collect();
                    mpm_world_set_particle_damping(world, first, g.as_ptr(), p.as_ptr(), count)
                }
                10 => {
                    if inp.byte() % 4 == 0 {
                        mpm_world_clear_tractions(world)
                    } else if inp.byte() % 4 == 0 {
                        let (first, count) = (inp.u32_below(40), inp.u32_below(40));
                        mpm_world_remove_tractions(world, first, count)
                    } else if inp.byte() % 4 == 0 {
                        let (first, count) = (inp.u32_below(40), inp.u32_below(40));
                        mpm_world_set_traction_schedule(world, first, count, inp.u32_below(6))
                    } else {
                        let (first, count) = particle_range(&mut inp, world);
                        let traction = inp.vec3_in(-1.0e4, 1.0e4);
                        let mut ids = MpmIdRange::default();
                        let kind = inp.byte() % 3;
                        let s = if kind == 0 {
                            let face = inp.u32_below(7);
                            mpm_world_add_tractions(world, first, count, face, traction, &mut ids)
                        } else {
                            // Any normal (zero and non-finite ones included) and any area.
                            let normal = inp.vec3_in(-1.0, 1.0);
                            let area = inp.real();
                            let add = if kind == 1 {
                                mpm_world_add_surface_tractions
                            } else {
                                mpm_world_add_follower_tractions
                            };
                            add(world, first, count, normal, area, traction, &mut ids)
                        };
                        if s == MpmStatus::Ok {
                            // The ids are new: removing them works, and once only.
                            let mut n = 0;
                            assert_eq!(mpm_world_traction_count(world, &mut n), MpmStatus::Ok);
                            assert!(ids.count as usize <= n);
                        }
                        s
                    }
                }
                11 => {
                    let (mut n, mut alpha) = (0usize, 0.0f64);
                    let mut diag = MpmDiagnostics::default();
                    assert_eq!(mpm_world_traction_count(world, &mut n), MpmStatus::Ok);
                    assert_eq!(mpm_world_feedback_alpha(world, &mut alpha), MpmStatus::Ok);
                    assert!(alpha.is_finite() && alpha >= 0.0, "feedback alpha {alpha}");
                    let s = mpm_world_diagnostics(world, &mut diag);
                    assert_eq!(world_hash(world), before, "a read changed the world");
                    s
                }
                15 => {
                    // Colliders: any shape and contact number (one past them too), sizes,
                    // poses, velocities and masses in and out of range, a def not from the default
                    // now and then; set one, or read one back (a read changes nothing).
                    let mut c = mpm_collider_def_default_f32();
                    c.shape = inp.u32_below(7);
                    c.contact = inp.u32_below(4);
                    c.radius = inp.real_in(-0.1, 0.5);
                    c.half_length = inp.real_in(-0.1, 0.5);
                    c.half_extents = inp.vec3_in(-0.1, 0.5);
                    c.inner_radius = inp.real_in(-0.1, 0.5);
                    c.sdf_first = inp.u32_below(600);
                    c.sdf_dims = [inp.u32_below(12), inp.u32_below(12), inp.u32_below(3)];
                    c.sdf_spacing = inp.real_in(-0.01, 0.1);
                    c.position = inp.vec3_in(-0.5, 1.5);
                    c.rotation = core::array::from_fn(|_| inp.real_in(-1.0, 1.0));
                    c.velocity = inp.vec3_in(-5.0, 5.0);
                    c.angular_velocity = inp.vec3_in(-20.0, 20.0);
                    c.friction = inp.real_in(-0.5, 2.0);
                    // Kinematic or dynamic (a mass, moments of inertia; some out of range).
                    if inp.byte() % 2 == 0 {
                        c.mass = inp.real_in(-1.0, 50.0);
                        c.inertia = inp.vec3_in(-0.1, 1.0);
                    }
                    if inp.byte() % 32 == 0 {
                        c.internal_cookie ^= 1;
                    }
                    if inp.byte() % 32 == 0 {
                        c.velocity.x = mpm_real::NAN;
                    }
                    match inp.byte() % 4 {
                        0 => {
                            let mut id = 0;
                            mpm_world_add_collider(world, &c, &mut id)
                        }
                        3 => {
                            // Distance samples: some out of range or not finite.
                            let n = inp.u32_below(700) as usize;
                            let samples: Vec<mpm_real> = (0..n)
                                .map(|_| match inp.byte() % 64 {
                                    0 => mpm_real::NAN,
                                    _ => inp.real_in(-0.5, 0.5),
                                })
                                .collect();
                            let mut first = 0;
                            mpm_world_add_distance_field(world, samples.as_ptr(), n, &mut first)
                        }
                        1 => mpm_world_set_collider(world, inp.u32_below(6), &c),
                        _ => {
                            let mut state = core::mem::zeroed::<MpmColliderState>();
                            let s = mpm_world_get_collider(world, inp.u32_below(6), &mut state);
                            if s == MpmStatus::Ok {
                                assert!(state.impulse.x.is_finite() && state.duration >= 0.0);
                            }
                            assert_eq!(world_hash(world), before, "a read changed the world");
                            s
                        }
                    }
                }
                16 => {
                    // Particles after they are in: moved, sped up, given an affine matrix or a
                    // material (values in and out of range, some not finite), their whole
                    // state set or added, removed by range, list, box or status, or reordered
                    // by cell.
                    let (first, count) = particle_range(&mut inp, world);
                    let n = (count as usize).min(512);
                    let values = |inp: &mut Input<'_>, lo: mpm_real, hi: mpm_real| {
                        (0..n)
                            .map(|_| match inp.byte() % 64 {
                                0 => mpm_real::NAN,
                                _ => inp.real_in(lo, hi),
                            })
                            .collect::<Vec<mpm_real>>()
                    };
                    match inp.byte() % 10 {
                        0 | 1 => {
                            let c: [Vec<mpm_real>; 3] = core::array::from_fn(|_| values(&mut inp, -0.2, 1.2));
                            let (x, y, z) = (c[0].as_ptr(), c[1].as_ptr(), c[2].as_ptr());
                            if inp.byte() % 2 == 0 {
                                mpm_world_set_particle_positions(world, first, x, y, z, n)
                            } else {
                                mpm_world_set_particle_velocities(world, first, x, y, z, n)
                            }
                        }
                        2 => {
                            let c: [Vec<mpm_real>; 9] = core::array::from_fn(|_| values(&mut inp, -5.0, 5.0));
                            let p: [*const mpm_real; 9] = core::array::from_fn(|k| c[k].as_ptr());
                            mpm_world_set_particle_affine(world, first, p.as_ptr(), n)
                        }
                        3 => {
                            let ids: Vec<u32> = (0..n).map(|_| inp.u32_below(5)).collect();
                            mpm_world_set_particle_materials(world, first, ids.as_ptr(), n)
                        }
                        4 => {
                            let mut removed = 0;
                            mpm_world_remove_particles(world, first, count, &mut removed)
                        }
                        5 => {
                            let ids: Vec<u32> = (0..n).map(|_| inp.u32_below(first.saturating_add(4))).collect();
                            let mut removed = 0;
                            mpm_world_remove_particle_list(world, ids.as_ptr(), n, &mut removed)
                        }
                        6 => {
                            let (lo, hi) = (inp.vec3_in(-0.2, 1.2), inp.vec3_in(-0.2, 1.2));
                            let mut removed = 0;
                            mpm_world_remove_particles_in_box(world, lo, hi, &mut removed)
                        }
                        7 if inp.u32_below(2) == 0 => {
                            let mut removed = 0;
                            mpm_world_remove_inactive_particles(world, &mut removed)
                        }
                        7 => {
                            // A collider id in range or past it.
                            let mut removed = 0;
                            mpm_world_remove_particles_in_collider(world, inp.u32_below(4), &mut removed)
                        }
                        8 => {
                            // An order as long as the range: short of the count or not.
                            let mut order = vec![0u32; (count as usize).min(1 << 16)];
                            mpm_world_sort_particles(world, order.as_mut_ptr(), order.len())
                        }
                        _ => {
                            // A particle's whole state, set or added: each column given or
                            // NULL, values in and out of range (F, stress, statuses and
                            // materials among them), some not finite.
                            let reals: Vec<Vec<mpm_real>> =
                                (0..40).map(|_| values(&mut inp, -2.0, 2.0)).collect();
                            let words: [Vec<u32>; 2] =
                                core::array::from_fn(|_| (0..n).map(|_| inp.u32_below(6)).collect());
                            let mut next = 0;
                            let mut col = |inp: &mut Input<'_>| {
                                next += 1;
                                if inp.byte() % 4 == 0 {
                                    core::ptr::null()
                                } else {
                                    reals[next - 1].as_ptr()
                                }
                            };
                            let mut st = core::mem::zeroed::<MpmParticleState>();
                            st.position = core::array::from_fn(|_| col(&mut inp));
                            st.position_low = core::array::from_fn(|_| col(&mut inp));
                            st.velocity = core::array::from_fn(|_| col(&mut inp));
                            st.mass = col(&mut inp);
                            st.volume0 = col(&mut inp);
                            st.displacement_gradient = core::array::from_fn(|_| col(&mut inp));
                            st.stress = core::array::from_fn(|_| col(&mut inp));
                            st.plastic = col(&mut inp);
                            st.temperature = col(&mut inp);
                            st.affine = core::array::from_fn(|_| col(&mut inp));
                            st.material = words[0].as_ptr();
                            st.status = if inp.byte() % 2 == 0 { words[1].as_ptr() } else { core::ptr::null() };
                            if inp.byte() % 2 == 0 {
                                let mut ids = MpmIdRange::default();
                                mpm_world_add_particles_with_state(world, &st, n, &mut ids)
                            } else {
                                mpm_world_set_particle_state(world, first, &st, n)
                            }
                        }
                    }
                }
                4 | 5 => {
                    let mut dt = 0.0;
                    assert_eq!(mpm_world_stable_dt(world, &mut dt), MpmStatus::Ok);
                    assert!(dt > 0.0, "stable dt {dt}");
                    // Mostly up to 8 stable steps (so an input stays fast), sometimes a value
                    // that must be refused or is harmlessly tiny (a large finite dt needs more
                    // substeps than the definition allows and is refused).
                    const ODD: [mpm_real; 7] = [
                        mpm_real::NAN,
                        mpm_real::INFINITY,
                        -mpm_real::INFINITY,
                        0.0,
                        -1.0,
                        mpm_real::MIN_POSITIVE,
                        mpm_real::MAX,
                    ];
                    let dt = if inp.byte() % 8 == 0 {
                        ODD[inp.byte() as usize % ODD.len()]
                    } else {
                        dt * inp.real_in(0.1, 8.0)
                    };
                    let mut report = MpmStepReport::default();
                    mpm_world_step(world, dt, &mut report)
                }
                _ => {
                    let len = inp.u32_below(4000) as usize;
                    let mut out = vec![0.0 as mpm_real; len];
                    let mut status_out = vec![0u32; len];
                    let mut n = 0;
                    let s = match inp.byte() % 5 {
                        0 => mpm_world_copy_positions(world, out.as_mut_ptr(), len, &mut n),
                        1 => mpm_world_copy_velocities(world, out.as_mut_ptr(), len, &mut n),
                        2 => mpm_world_copy_stress(world, out.as_mut_ptr(), len, &mut n),
                        3 => mpm_world_copy_jacobians(world, out.as_mut_ptr(), len, &mut n),
                        _ => mpm_world_copy_status(world, status_out.as_mut_ptr(), len, &mut n),
                    };
                    if s == MpmStatus::Ok {
                        assert!(n <= len);
                        assert!(
                            out[..n].iter().all(|x| x.is_finite()),
                            "a copied value is not finite"
                        );
                    }
                    // Reading never changes the world, whatever it answers.
                    assert_eq!(world_hash(world), before, "a read changed the world");
                    s
                }
            }
        };
        if status == MpmStatus::Ok {
            check_state(world);
        } else {
            assert_ne!(status, MpmStatus::Internal, "a panic was caught");
            assert_eq!(
                world_hash(world),
                before,
                "a failed call changed the world ({status:?})"
            );
        }
    }
});
