//! The C interface checked from C, against the Rust definitions and the Rust kernel:
//!
//! - layout: every type of the header has, in C99 and in C++17, the size, alignment, field
//!   offsets and field sizes of its Rust definition, and the C program covers every struct,
//!   field and enum the header declares (`tests/c/layout.c`);
//! - misuse: every refused call returns its documented status, changes no world's bytes and
//!   writes no output, in a strict build and under AddressSanitizer and UBSan
//!   (`tests/c/misuse.c`);
//! - hostile hosts: inputs and outputs inside the world, pointers that are not worlds next to
//!   a page without access, damaged snapshots, fills that overflow, runaway particles and
//!   unbounded steps, each answered by its status, in a strict build and under
//!   AddressSanitizer and UBSan (`tests/c/hostile.c`);
//! - same state: two scenes stepped through the C interface leave the same bytes, columns,
//!   diagnostics and step reports as the same scenes stepped through the Rust kernel API
//!   (`tests/c/same_state.c` against [`rust_same_state`]);
//! - tasks: `mpm_world_step_tasks` on pools of worker threads leaves the state `mpm_world_step`
//!   leaves, and refuses misuse and hosts that break its contract (`tests/c/tasks.c`);
//! - and, in Rust through the rlib: the default definitions and the status strings agree with
//!   the kernel's.

mod common;

use common::Lang;
use core::mem::{align_of, offset_of, size_of};
use kernel::{
    memory_requirements, Boundary, Damping, DampingZone, Dimension, Effects, Error, Face, Feedback,
    MaterialDef, MaterialModel, ParticleBatch, Real, ScalarBoundary, ScalarField, Schedule,
    ShapeFunction, Transfer, Transport, UpdateOrder, Vec3, World, WorldDef,
};
use mpm_gimp::*;
use std::collections::BTreeSet;
use std::ffi::CStr;

fn stdout_of(out: &std::process::Output) -> String {
    String::from_utf8(out.stdout.clone()).expect("the program prints UTF-8")
}

/// Compares two texts line by line; panics at the first difference with its line number.
fn assert_same_lines(what: &str, c: &str, rust: &str) {
    let (c_lines, rust_lines): (Vec<&str>, Vec<&str>) =
        (c.lines().collect(), rust.lines().collect());
    for (i, (a, b)) in c_lines.iter().zip(rust_lines.iter()).enumerate() {
        assert_eq!(
            a,
            b,
            "{what}: line {} differs (left: C, right: Rust)",
            i + 1
        );
    }
    assert_eq!(
        c_lines.len(),
        rust_lines.len(),
        "{what}: the C output has {} lines, the Rust one {}",
        c_lines.len(),
        rust_lines.len()
    );
}

// ---------------------------------------------------------------------------------------------
// Layout
// ---------------------------------------------------------------------------------------------

/// Size of the field that `f` projects to.
fn field_size<T, U>(_f: impl Fn(&T) -> &U) -> usize {
    size_of::<U>()
}

/// `type NAME size S align A`, as `tests/c/layout.c` prints it.
macro_rules! type_line {
    ($name:expr, $t:ty) => {
        format!(
            "type {} size {} align {}",
            $name,
            size_of::<$t>(),
            align_of::<$t>()
        )
    };
}

/// The type line of struct `$t`, then `field T.f offset O size S` for each field.
macro_rules! struct_lines {
    ($t:ident { $($f:ident),* $(,)? }) => {{
        let mut v = vec![type_line!(stringify!($t), $t)];
        $(
            v.push(format!(
                "field {}.{} offset {} size {}",
                stringify!($t),
                stringify!($f),
                offset_of!($t, $f),
                field_size(|s: &$t| &s.$f),
            ));
        )*
        v
    }};
}

/// What `tests/c/layout.c` must print: the Rust sizes, alignments and offsets. The enum types
/// are `uint32_t` in C (an enum with that underlying type in C++), and each Rust definition
/// stores its enum fields as `u32`.
fn rust_layout() -> String {
    let mut lines = vec![
        type_line!("mpm_real", mpm_real),
        type_line!("size_t", usize),
        type_line!("MpmStatus", MpmStatus),
        type_line!("MpmDimension", MpmDimension),
        type_line!("MpmShape", MpmShape),
        type_line!("MpmUpdateOrder", MpmUpdateOrder),
        type_line!("MpmTransfer", MpmTransfer),
        type_line!("MpmBoundary", MpmBoundary),
        type_line!("MpmFace", MpmFace),
        type_line!("MpmMaterialModel", MpmMaterialModel),
        type_line!("MpmFrictionFit", MpmFrictionFit),
        type_line!("MpmParticleStatus", MpmParticleStatus),
        type_line!("MpmScalarBoundaryKind", MpmScalarBoundaryKind),
        type_line!("MpmScalarField", MpmScalarField),
        type_line!("MpmColliderShape", MpmColliderShape),
        type_line!("MpmContact", MpmContact),
    ];
    lines.extend(struct_lines!(MpmVec3 { x, y, z }));
    lines.extend(struct_lines!(MpmSchedule {
        points,
        times,
        values
    }));
    lines.extend(struct_lines!(MpmFeedback {
        declared,
        gain,
        target,
        max_alpha,
    }));
    lines.extend(struct_lines!(MpmDamping {
        declared,
        grid,
        particle,
        feedback,
        per_particle,
        grid_on_force,
        zone_count,
        zones,
    }));
    lines.extend(struct_lines!(MpmDampingZone {
        min,
        max,
        rate,
        ramped,
        ramp_face,
    }));
    lines.extend(struct_lines!(MpmScalarBoundary { kind, value }));
    lines.extend(struct_lines!(MpmTransport {
        declared,
        faces,
        sources,
    }));
    lines.extend(struct_lines!(MpmEffects {
        damping,
        particle_forces,
        traction_capacity,
        body_force,
        body_force_scale,
        body_force_gradient,
        traction_schedules,
        heat,
        diffusion,
        plasticity,
        collider_capacity,
        sdf_capacity,
    }));
    lines.extend(struct_lines!(MpmWorldDef {
        dimension,
        origin,
        cell_size,
        cells,
        particle_capacity,
        material_capacity,
        shape,
        particles_per_cell,
        flip_beta,
        pic_rate,
        transfer,
        update_order,
        gravity,
        faces,
        wall_friction,
        wall_velocity,
        exp_terms,
        cfl,
        max_substeps,
        max_volume_ratio,
        workers,
        effects,
        internal_cookie,
    }));
    lines.extend(struct_lines!(MpmMaterialDef {
        model,
        youngs_modulus,
        poisson_ratio,
        density,
        heat_capacity,
        conductivity,
        diffusivity,
        thermal_expansion,
        reference_temperature,
        swelling,
        reference_concentration,
        viscosity,
        bulk_viscosity,
        volume_relaxation,
        bulk_modulus,
        pressure_exponent,
        yield_stress,
        hardening_modulus,
        friction_angle,
        friction_fit,
        cohesion,
        critical_compression,
        critical_stretch,
        hardening_coefficient,
        internal_cookie,
    }));
    lines.extend(struct_lines!(MpmParticlesView {
        count,
        dimension,
        position,
        position_low,
        velocity,
        mass,
        volume0,
        displacement_gradient,
        stress,
        material,
        status,
        force,
        damping,
        affine,
        temperature,
        concentration,
        grid_temperature,
        grid_concentration,
        hoop,
        plastic,
        temperature_source,
        concentration_source,
    }));
    lines.extend(struct_lines!(MpmDiagnostics {
        particle_count,
        time,
        step_count,
        mass,
        momentum,
        angular_momentum,
        center_of_mass,
        kinetic,
        strain,
        potential,
    }));
    lines.extend(struct_lines!(MpmMemoryRequirements { bytes, align }));
    lines.extend(struct_lines!(MpmParticleArrays {
        position,
        velocity,
        mass,
        volume,
        material,
    }));
    lines.extend(struct_lines!(MpmParticleState {
        position,
        position_low,
        velocity,
        mass,
        volume0,
        displacement_gradient,
        stress,
        material,
        status,
        force,
        damping,
        affine,
        temperature,
        concentration,
        grid_temperature,
        grid_concentration,
        hoop,
        plastic,
        temperature_source,
        concentration_source,
    }));
    lines.extend(struct_lines!(MpmIdRange { first, count }));
    lines.extend(struct_lines!(MpmStepReport {
        substeps,
        substep_dt,
        stopped,
        escaped,
        frozen,
        runaway,
        flags,
        first_frozen_count,
        first_frozen,
    }));
    lines.extend(struct_lines!(MpmTaskSystem {
        enqueue_task,
        finish_task,
        user_context,
        worker_count,
    }));
    lines.extend(struct_lines!(MpmColliderDef {
        shape,
        contact,
        radius,
        half_length,
        half_extents,
        inner_radius,
        sdf_first,
        sdf_dims,
        sdf_spacing,
        position,
        rotation,
        velocity,
        angular_velocity,
        friction,
        mass,
        inertia,
        internal_cookie,
    }));
    lines.extend(struct_lines!(MpmColliderState {
        def,
        impulse,
        angular_impulse,
        force,
        torque,
        duration,
    }));
    let mut text = lines.join("\n");
    text.push('\n');
    text
}

/// The structs of the header with their fields in order, and its enums, read from the header
/// text: what the layout program must cover.
fn header_declarations() -> (Vec<(String, Vec<String>)>, BTreeSet<String>) {
    let header = std::fs::read_to_string(common::ffi_dir().join("include/mpm_gimp.h"))
        .expect("read the header");
    let mut structs: Vec<(String, Vec<String>)> = Vec::new();
    let mut enums = BTreeSet::new();
    let mut current: Option<(String, Vec<String>)> = None;
    for line in header.lines() {
        let t = line.trim();
        if let Some(rest) = t.strip_prefix("typedef struct ") {
            if let Some(name) = rest.strip_suffix(" {") {
                current = Some((name.to_string(), Vec::new()));
            }
            continue;
        }
        if let Some(name) = t.strip_prefix("enum ") {
            if !name.contains(['{', ';', ' ']) {
                enums.insert(name.to_string());
            }
            continue;
        }
        if let Some((name, fields)) = current.as_mut() {
            if t.starts_with('}') {
                assert_eq!(
                    t,
                    format!("}} {name};"),
                    "end of struct {name} in the header"
                );
                structs.push(current.take().expect("inside a struct"));
            } else if !t.is_empty() && !t.starts_with("//") {
                let decl = t
                    .strip_suffix(';')
                    .expect("a field declaration ends with ';'");
                let decl = decl.split('[').next().expect("split gives one piece");
                let field = decl.rsplit([' ', '*']).next().expect("a field name");
                fields.push(field.to_string());
            }
        }
    }
    (structs, enums)
}

/// Checks the layout program's output against the Rust layout and the header's declarations.
fn check_layout(lang: Lang, name: &str) -> String {
    let exe = common::build(name, lang, &["tests/c/layout.c"], common::STRICT);
    let c = stdout_of(&common::run(&exe, &[]));
    assert_same_lines(&format!("layout ({lang:?})"), &c, &rust_layout());

    let (structs, enums) = header_declarations();
    assert!(
        structs.len() >= 15,
        "the header parse found only {structs:?}"
    );
    for (s, fields) in &structs {
        let prefix = format!("type {s} size ");
        assert!(
            c.lines().any(|l| l.starts_with(&prefix)),
            "the layout program does not cover struct {s}"
        );
        let printed: Vec<&str> = c
            .lines()
            .filter_map(|l| l.strip_prefix(&format!("field {s}.")))
            .map(|rest| rest.split(' ').next().unwrap_or_default())
            .collect();
        assert_eq!(
            printed, *fields,
            "the layout program's fields of {s} differ from the header's"
        );
    }
    assert!(
        enums.len() >= 11,
        "the header parse found only enums {enums:?}"
    );
    for e in &enums {
        let prefix = format!("type {e} size ");
        assert!(
            c.lines().any(|l| l.starts_with(&prefix)),
            "the layout program does not cover enum {e}"
        );
    }
    c
}

/// Expectation: compiled as C99 with strict warnings, every struct of the header has the size,
/// alignment (offsetof probe), field offsets and field sizes of the Rust struct, every enum
/// type is 4 bytes aligned to 4 like its `#[repr(u32)]` Rust enum, and the program covers
/// every struct, field and enum the header declares.
#[test]
fn layout_c99_matches_rust() {
    check_layout(Lang::C99, "layout-c99");
}

/// Expectation: the same program compiled as C++17 (where the enums are `enum : uint32_t` and
/// the probe is also checked against `alignof`) prints exactly what the C99 build prints, and
/// both match the Rust layout.
#[test]
fn layout_cpp17_matches_rust_and_c99() {
    let cpp = check_layout(Lang::Cpp17, "layout-cpp17");
    let c = check_layout(Lang::C99, "layout-c99-for-cpp");
    assert_same_lines("layout C++17 vs C99", &cpp, &c);
}

// ---------------------------------------------------------------------------------------------
// Misuse
// ---------------------------------------------------------------------------------------------

/// Runs the check program `tests/c/{what}.c` built as `name` with `flags`, and checks that no
/// check failed, that its last line is "all N {what} checks passed" with N its "ok" lines, and
/// that N is at least `floor` (the program's checks as written: a shrinking count means checks
/// went missing).
fn check_program(what: &str, name: &str, flags: &[&str], floor: usize) {
    let source = format!("tests/c/{what}.c");
    let exe = common::build(name, Lang::C99, &[source.as_str()], flags);
    let out = stdout_of(&common::run(&exe, &[]));
    assert!(
        !out.lines().any(|l| l.starts_with("FAIL")),
        "a {what} check failed:\n{out}"
    );
    let last = out.lines().last().unwrap_or_default();
    let suffix = format!(" {what} checks passed");
    let n: usize = last
        .strip_prefix("all ")
        .and_then(|r| r.strip_suffix(suffix.as_str()))
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("unexpected last line {last:?} of:\n{out}"));
    let ok_lines = out.lines().filter(|l| l.starts_with("ok ")).count();
    assert_eq!(n, ok_lines, "the count differs from the printed checks");
    assert!(n >= floor, "only {n} {what} checks ran");
}

/// The misuse program's checks as written.
const MISUSE_FLOOR: usize = 1000;

fn check_misuse(name: &str, flags: &[&str]) {
    check_program("misuse", name, flags, MISUSE_FLOOR);
}

/// Expectation: with strict warnings (C99, -Wall -Wextra -Werror -pedantic), every misuse in
/// `tests/c/misuse.c` (NULL in every pointer argument, buffers too small or misaligned, bad
/// definitions and enums, non-finite and out-of-range inputs, capacity overflow, unknown
/// materials, out-of-domain positions, short output buffers, a disk in 3D and a sphere in 2D,
/// non-worlds, damaged snapshots; and for the effects: flags that are not 0 or 1, schedules and
/// effect values out of range, face kinds and scalar fields out of range, effects not declared
/// (heat, diffusion and their sources included), unknown particle ids (refused before any array
/// is read), non-finite forces, damping, temperatures, concentrations and sources, faces out of
/// range, the traction capacity; materials with a bad heat capacity, conductivity or
/// diffusivity, or a thermal expansion, swelling or reference value not finite; axisymmetric
/// definitions whose axis is not the lower x face's wall plane or whose lower x face is open,
/// and seeding past the axis) is refused with its status, leaves every world's bytes and every
/// output untouched, and every status string is a description ("unknown status" for values
/// outside the enum, never NULL). Accepted controls: an axisymmetric definition of each family
/// with its axis in place, and a GIMP one whose world fills a box on the axis, steps, and has
/// the hoop column in its view (finite, part of J, NULL in every other world). Shape 4 (cpGIMP)
/// is accepted and 5 refused; cpGIMP worlds in 2D and 3D fill a box and step with finite
/// positions, velocities, stress, J and diagnostics, the 2D one ending elsewhere than under
/// GIMP, and keep GIMP's one-cell margin. The program ends with "all N misuse checks passed".
#[test]
fn misuse_from_c_strict() {
    check_misuse("misuse", common::STRICT);
}

/// Expectation: the same program, built with AddressSanitizer and UndefinedBehaviorSanitizer
/// (no recovery), passes the same checks without a sanitizer report. (The library itself is not
/// instrumented; the no-access page in the program is what proves that an over-capacity count
/// reads no array.)
#[test]
fn misuse_from_c_sanitized() {
    check_misuse("misuse-sanitized", &strict_and_sanitized());
}

/// The strict warnings and the sanitizers.
fn strict_and_sanitized() -> Vec<&'static str> {
    common::STRICT
        .iter()
        .chain(common::SANITIZE)
        .copied()
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Same state through the C and the Rust API
// ---------------------------------------------------------------------------------------------

const FNV_START: u64 = 0xcbf2_9ce4_8422_2325;

fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn hash(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a(FNV_START, bytes))
}

fn real_bytes(values: impl IntoIterator<Item = Real>) -> Vec<u8> {
    values.into_iter().flat_map(|x| x.to_ne_bytes()).collect()
}

fn u32_bytes(values: impl IntoIterator<Item = u32>) -> Vec<u8> {
    values.into_iter().flat_map(|x| x.to_ne_bytes()).collect()
}

/// The bytes of a value in memory order, as hex (what the C program's `print_bytes` prints).
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The text of `tests/c/same_state.c`, built with the Rust API.
struct Text(String);

impl Text {
    fn line(&mut self, s: impl AsRef<str>) {
        self.0.push_str(s.as_ref());
        self.0.push('\n');
    }

    /// As the C program's `print_state`.
    fn state(&mut self, label: &str, w: &World<'_>) {
        let bytes = w.as_bytes();
        self.line(format!("{label}: world {} {}", hash(bytes), bytes.len()));
        let v = w.particles();
        let n = v.count;
        let d = if v.dimension == Dimension::ThreeD {
            3
        } else {
            2
        };
        let ns = if d == 3 { 6 } else { 4 };
        let interleaved = |cols: &[&[Real]]| {
            let k = cols.len();
            let bytes = real_bytes((0..n * k).map(|j| cols[j % k][j / k]));
            format!("{} {}", hash(&bytes), n * k)
        };
        self.line(format!(
            "{label}: positions {}",
            interleaved(&v.position[..d])
        ));
        self.line(format!(
            "{label}: velocities {}",
            interleaved(&v.velocity[..d])
        ));
        self.line(format!("{label}: stress {}", interleaved(&v.stress[..ns])));
        let jacobians = real_bytes((0..n).map(|i| v.jacobian(i)));
        self.line(format!("{label}: jacobians {} {n}", hash(&jacobians)));
        let status = u32_bytes(v.status.iter().copied());
        self.line(format!("{label}: status {} {n}", hash(&status)));

        let present = |k: usize, used: &dyn Fn(usize) -> bool| -> String {
            (0..k).map(|i| if used(i) { '1' } else { '0' }).collect()
        };
        // One hash over the columns that are set, in order (the C program's `hash_columns`).
        let columns = |cols: &[&[Real]], used: &dyn Fn(usize) -> bool| {
            let mut h = FNV_START;
            for (_, col) in cols.iter().enumerate().filter(|&(k, _)| used(k)) {
                h = fnv1a(h, &real_bytes(col.iter().copied()));
            }
            format!("{h:016x}")
        };
        let h_used = |k: usize| k / 3 < d && k % 3 < d;
        let h: Vec<&[Real]> = (0..9)
            .map(|k| v.displacement_gradient[k / 3][k % 3])
            .collect();
        self.line(format!(
            "{label}: view count {n} dimension {} present {} {} {} {} mass {} volume0 {} \
             material {} displacement_gradient {}",
            v.dimension as u32,
            present(3, &|a| a < d),
            present(3, &|a| a < d),
            present(9, &h_used),
            present(6, &|k| k < ns),
            hash(&real_bytes(v.mass.iter().copied())),
            hash(&real_bytes(v.volume0.iter().copied())),
            hash(&u32_bytes(v.material.iter().copied())),
            columns(&h, &h_used),
        ));

        let def = w.def();
        let force_used = |a: usize| def.effects.particle_forces && a < d;
        let damping_used = |_: usize| def.effects.damping.is_some_and(|dm| dm.per_particle);
        let affine_used = |k: usize| def.transfer.is_affine() && h_used(k);
        let affine: Vec<&[Real]> = (0..9).map(|k| v.affine[k / 3][k % 3]).collect();
        self.line(format!(
            "{label}: effects present {} {} {} force {} damping {} affine {} tractions {} \
             feedback_alpha {}",
            present(3, &force_used),
            present(2, &damping_used),
            present(9, &affine_used),
            columns(&v.force, &force_used),
            columns(&v.damping, &damping_used),
            columns(&affine, &affine_used),
            w.traction_count(),
            hex(&w.feedback_alpha().to_ne_bytes()),
        ));

        let heat = def.effects.heat.is_some();
        let diffusion = def.effects.diffusion.is_some();
        let scalars = [
            (v.temperature, heat),
            (v.concentration, diffusion),
            (v.grid_temperature, heat),
            (v.grid_concentration, diffusion),
        ];
        let [t, c, gt, gc] = scalars.map(|(col, used)| columns(&[col], &|_| used));
        self.line(format!(
            "{label}: transport present {} temperature {t} concentration {c} grid_temperature \
             {gt} grid_concentration {gc}",
            present(4, &|k| scalars[k].1),
        ));

        let axisymmetric = def.dimension == Dimension::Axisymmetric2D;
        self.line(format!(
            "{label}: hoop present {} hoop {}",
            present(1, &|_| axisymmetric),
            columns(&[v.hoop], &|_| axisymmetric),
        ));

        let s = w.diagnostics();
        let f = |x: f64| hex(&x.to_ne_bytes());
        self.line(format!(
            "{label}: diagnostics particles {} steps {} time {} mass {} momentum {} {} {}",
            w.particle_count(),
            w.step_count(),
            f(w.time()),
            f(s.mass),
            f(s.momentum[0]),
            f(s.momentum[1]),
            f(s.momentum[2]),
        ));
        self.line(format!(
            "{label}: diagnostics center_of_mass {} {} {} kinetic {} strain {} potential {}",
            f(s.center_of_mass[0]),
            f(s.center_of_mass[1]),
            f(s.center_of_mass[2]),
            f(s.kinetic),
            f(s.strain),
            f(s.potential),
        ));
        self.line(format!(
            "{label}: diagnostics angular_momentum {} {} {}",
            f(s.angular_momentum[0]),
            f(s.angular_momentum[1]),
            f(s.angular_momentum[2]),
        ));
    }

    fn seed(&mut self, what: &str, ids: core::ops::Range<u32>) {
        self.line(format!(
            "seed {what}: first {} count {}",
            ids.start,
            ids.end - ids.start
        ));
    }

    /// As the C program's `print_tractions`.
    fn tractions(&mut self, what: &str, ids: core::ops::Range<u32>) {
        self.line(format!(
            "tractions {what}: first {} count {}",
            ids.start,
            ids.end - ids.start
        ));
    }

    /// As the C program's `step_frames`.
    fn frames(&mut self, w: &mut World<'_>, frames: usize, dt: Real) {
        for f in 1..=frames {
            let stable = w.stable_dt();
            let r = w.step(dt).expect("a valid step");
            let frozen: String = r.first_frozen.iter().map(|id| format!(" {id}")).collect();
            self.line(format!(
                "step {f}: stable_dt {} substeps {} substep_dt {} stopped {} escaped {} \
                 frozen {} first_frozen{frozen}",
                hex(&stable.to_ne_bytes()),
                r.substeps,
                hex(&r.substep_dt.to_ne_bytes()),
                r.stopped,
                r.escaped,
                r.frozen,
            ));
            self.state(&format!("after step {f}"), w);
        }
    }
}

/// A zeroed buffer of `def`'s requirement inside `storage`, aligned as required.
fn world_memory<'a>(def: &WorldDef, storage: &'a mut Vec<u8>, text: &mut Text) -> &'a mut [u8] {
    let req = memory_requirements(def).expect("a valid definition");
    text.line(format!(
        "requirements bytes {} align {}",
        req.bytes, req.align
    ));
    *storage = vec![0u8; req.bytes + req.align];
    let offset = storage.as_ptr().align_offset(req.align);
    &mut storage[offset..offset + req.bytes]
}

/// Starts a scene as `tests/c/same_state.c` does: the world of `def` in `storage`, and its empty
/// state.
fn open_scene<'a>(t: &mut Text, def: &WorldDef, storage: &'a mut Vec<u8>) -> World<'a> {
    let w = World::init(def, world_memory(def, storage, t)).expect("init");
    t.state("empty", &w);
    w
}

/// The conducting, diffusing rubber of `tests/c/same_state.c`: thermal diffusivity
/// 4096 / (1000 * 512) = 0.008 m^2/s.
fn conducting_rubber() -> MaterialDef {
    MaterialDef {
        heat_capacity: 512.0,
        conductivity: 4096.0,
        diffusivity: 0.0078125,
        ..MaterialDef::DEFAULT
    }
}

/// The scenes of `tests/c/same_state.c`, through `kernel::World`.
fn rust_same_state() -> String {
    let mut t = Text(String::new());

    // plane2d
    t.line("scene plane2d");
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    let def = WorldDef {
        cells: [32, 32, 1],
        cell_size: 0.03125,
        particle_capacity: 1024,
        material_capacity: 2,
        faces,
        ..WorldDef::DEFAULT
    };
    let mut storage = Vec::new();
    let mut w = open_scene(&mut t, &def, &mut storage);
    let soft = MaterialDef {
        model: MaterialModel::LinearElastic,
        youngs_modulus: 500000.0,
        poisson_ratio: 0.25,
        density: 750.0,
        ..MaterialDef::DEFAULT
    };
    let rubber = w.add_material(&MaterialDef::DEFAULT).expect("rubber");
    let soft = w.add_material(&soft).expect("soft");
    t.line(format!("materials {rubber} {soft}"));
    let ids = w
        .fill_box(
            Vec3::new(0.3125, 0.0625, 0.0),
            Vec3::new(0.5625, 0.1875, 0.0),
            rubber,
            Vec3::new(0.0, -1.0, 0.0),
        )
        .expect("box");
    t.seed("box", ids);
    t.state("after box", &w);
    let ids = w
        .fill_disk(
            Vec3::new(0.75, 0.25, 0.0),
            0.0625,
            soft,
            Vec3::new(-0.5, 0.0, 0.0),
        )
        .expect("disk");
    t.seed("disk", ids);
    t.state("after disk", &w);
    let x: Vec<Real> = (0..6).map(|i| 0.125 + 0.03125 * i as Real).collect();
    let y: Vec<Real> = (0..6).map(|i| 0.125 + 0.0625 * (i % 2) as Real).collect();
    let vx: Vec<Real> = (0..6).map(|i| 0.5 * i as Real - 1.0).collect();
    let vy = [0.25 as Real; 6];
    let mass = [0.25 as Real; 6];
    let volume: [Real; 6] = [1.0 / 4096.0; 6];
    let material: Vec<u32> = (0..6)
        .map(|i| if i % 2 == 1 { soft } else { rubber })
        .collect();
    let ids = w
        .add_particles(&ParticleBatch {
            position: [&x, &y, &[]],
            velocity: [&vx, &vy, &[]],
            mass: &mass,
            volume: &volume,
            material: &material,
        })
        .expect("arrays");
    t.seed("arrays", ids);
    t.state("after arrays", &w);
    t.frames(&mut w, 16, 0.0078125);

    // space3d
    t.line("scene space3d");
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    faces[Face::XMax as usize] = Boundary::Open;
    let def = WorldDef {
        dimension: Dimension::ThreeD,
        cells: [12, 12, 12],
        cell_size: 0.0625,
        particle_capacity: 2048,
        material_capacity: 1,
        shape: ShapeFunction::QuadraticBspline,
        update_order: UpdateOrder::Usl,
        flip_beta: 0.875,
        pic_rate: 12.5,
        gravity: Vec3::new(0.5, -10.0, 0.25),
        faces,
        exp_terms: 3,
        cfl: 0.375,
        ..WorldDef::DEFAULT
    };
    let mut storage = Vec::new();
    let mut w = open_scene(&mut t, &def, &mut storage);
    let id = w.add_material(&MaterialDef::DEFAULT).expect("rubber");
    t.line(format!("materials {id}"));
    let ids = w
        .fill_sphere(Vec3::splat(0.25), 0.125, id, Vec3::new(0.5, -0.5, 0.25))
        .expect("sphere");
    t.seed("sphere", ids);
    t.state("after sphere", &w);
    let ids = w
        .fill_box(
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(0.625, 0.625, 0.625),
            id,
            Vec3::new(2.0, 0.0, 0.0),
        )
        .expect("box");
    t.seed("box", ids);
    t.state("after box", &w);
    t.frames(&mut w, 16, 0.0078125);

    effects2d(&mut t);
    effects3d(&mut t);
    axisym2d(&mut t);
    cpgimp(&mut t, Dimension::Plane2D);
    cpgimp(&mut t, Dimension::ThreeD);

    t.line("end");
    t.0
}

/// A schedule through `points` (time, value).
fn schedule(points: &[(Real, Real)]) -> Schedule {
    Schedule::from_points(points).expect("a valid schedule")
}

/// The scene effects2d of `tests/c/same_state.c`.
fn effects2d(t: &mut Text) {
    t.line("scene effects2d");
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    let mut heat_faces = [ScalarBoundary::Insulated; 6];
    heat_faces[Face::YMin as usize] = ScalarBoundary::Fixed(320.0);
    heat_faces[Face::XMin as usize] = ScalarBoundary::Flux(-2048.0);
    let mut diffusion_faces = [ScalarBoundary::Insulated; 6];
    diffusion_faces[Face::XMax as usize] = ScalarBoundary::Fixed(1.0);
    diffusion_faces[Face::YMin as usize] = ScalarBoundary::Flux(0.25);
    let def = WorldDef {
        cells: [32, 32, 1],
        cell_size: 0.03125,
        particle_capacity: 256,
        material_capacity: 1,
        faces,
        transfer: Transfer::Apic,
        effects: Effects {
            damping: Some(Damping {
                grid: schedule(&[(0.0, 0.5), (0.0625, 2.0)]),
                particle: schedule(&[(0.0, 0.25)]),
                feedback: Some(Feedback {
                    gain: 0.5,
                    target: Schedule::ZERO,
                    max_alpha: 4.0,
                }),
                per_particle: true,
                ..Damping::NONE
            }),
            particle_forces: true,
            traction_capacity: 16,
            body_force: Vec3::new(0.5, 0.25, 0.0),
            body_force_scale: schedule(&[(0.0, 0.0), (0.03125, 1.0), (0.0625, 0.0)]),
            body_force_gradient: [
                Vec3::new(-2.0, 0.5, 0.0),
                Vec3::new(0.25, 1.0, 0.0),
                Vec3::ZERO,
            ],
            traction_schedules: [
                schedule(&[(0.0, 0.5), (0.0625, 1.5)]),
                Schedule::constant(1.0),
                Schedule::constant(1.0),
                Schedule::constant(1.0),
            ],
            heat: Some(Transport {
                faces: heat_faces,
                sources: true,
            }),
            diffusion: Some(Transport {
                faces: diffusion_faces,
                sources: false,
            }),
            plasticity: false,
            collider_capacity: 0,
            sdf_capacity: 0,
        },
        ..WorldDef::DEFAULT
    };
    let mut storage = Vec::new();
    let mut w = open_scene(t, &def, &mut storage);
    let rubber = conducting_rubber();
    let id = w.add_material(&rubber).expect("rubber");
    t.line(format!("materials {id}"));
    let ids = w
        .fill_box(
            Vec3::new(0.25, 0.125, 0.0),
            Vec3::new(0.5, 0.25, 0.0),
            id,
            Vec3::new(0.5, -0.25, 0.0),
        )
        .expect("box");
    let n = ids.end;
    t.seed("box", ids);

    let fx: Vec<Real> = (0..16).map(|i| 0.0625 * i as Real - 0.5).collect();
    let fy = [0.125 as Real; 16];
    w.set_particle_forces(0, [&fx, &fy, &[]]).expect("forces");
    let alpha_g: Vec<Real> = (0..32).map(|i| 0.5 * (i % 4) as Real).collect();
    let alpha_p: Vec<Real> = (0..32).map(|i| 0.25 * (i % 2) as Real).collect();
    w.set_particle_damping(8, &alpha_g, &alpha_p)
        .expect("damping");
    let heat: Vec<Real> = (0..n)
        .map(|i| 256.0 + 8.0 * (i % 8) as Real + 0.5 * (i / 8) as Real)
        .collect();
    w.set_particle_scalar(ScalarField::Temperature, 0, &heat)
        .expect("temperatures");
    let source: Vec<Real> = (0..8).map(|i| 65536.0 * (i % 2) as Real).collect();
    w.set_particle_sources(ScalarField::Temperature, n - 8, &source)
        .expect("sources");
    let top = w
        .add_tractions(n - 16..n, Face::YMax, Vec3::new(0.0, -512.0, 0.0))
        .expect("tractions");
    t.tractions("top", top);
    t.state("after effects", &w);
    t.frames(&mut w, 8, 0.0078125);

    w.set_particle_forces(4, [&[-0.25; 8], &[0.5; 8], &[]])
        .expect("forces again");
    w.clear_tractions();
    let concentration: Vec<Real> = (0..16).map(|i| 0.0625 * i as Real).collect();
    w.set_particle_scalar(ScalarField::Concentration, 8, &concentration)
        .expect("concentrations");
    let left = w
        .add_tractions(0..4, Face::XMin, Vec3::new(128.0, 0.0, 0.0))
        .expect("tractions");
    t.tractions("left", left);
    t.state("after changes", &w);
    t.frames(&mut w, 8, 0.0078125);
}

/// The scene effects3d of `tests/c/same_state.c`.
fn effects3d(t: &mut Text) {
    t.line("scene effects3d");
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    let def = WorldDef {
        dimension: Dimension::ThreeD,
        cells: [8, 8, 8],
        cell_size: 0.0625,
        particle_capacity: 512,
        material_capacity: 1,
        shape: ShapeFunction::CubicBspline,
        update_order: UpdateOrder::Usf,
        transfer: Transfer::Apic,
        faces,
        effects: Effects {
            damping: Some(Damping {
                grid: Schedule::constant(1.0),
                grid_on_force: true,
                zones: {
                    let mut zones = [DampingZone::NONE; 4];
                    zones[0] = DampingZone {
                        min: Vec3::new(-1.0, 0.0, -1.0),
                        max: Vec3::new(1.0, 0.25, 1.0),
                        rate: 3.0,
                        ramp: Some(Face::YMin),
                    };
                    zones
                },
                zone_count: 1,
                ..Damping::NONE
            }),
            particle_forces: true,
            traction_capacity: 8,
            body_force: Vec3::new(0.0, 0.0, -2.0),
            body_force_scale: Schedule::constant(1.0),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    let mut storage = Vec::new();
    let mut w = open_scene(t, &def, &mut storage);
    let id = w.add_material(&MaterialDef::DEFAULT).expect("rubber");
    t.line(format!("materials {id}"));
    let ids = w
        .fill_sphere(Vec3::splat(0.25), 0.09375, id, Vec3::new(0.0, -0.5, 0.25))
        .expect("sphere");
    let n = ids.end as usize;
    t.seed("sphere", ids);
    let fx = vec![0.0 as Real; n];
    let fy: Vec<Real> = (0..n).map(|i| 0.0625 * (i % 3) as Real).collect();
    let fz = vec![-0.125 as Real; n];
    w.set_particle_forces(0, [&fx, &fy, &fz]).expect("forces");
    let top = w
        .add_tractions(0..4, Face::ZMax, Vec3::new(0.0, 0.0, -256.0))
        .expect("tractions");
    t.tractions("top", top);
    let side = w
        .add_tractions(4..8, Face::XMin, Vec3::new(64.0, 0.0, 32.0))
        .expect("tractions");
    t.tractions("side", side);
    t.state("after effects", &w);
    t.frames(&mut w, 8, 0.0078125);
}

/// The scene axisym2d of `tests/c/same_state.c`.
fn axisym2d(t: &mut Text) {
    t.line("scene axisym2d");
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    let mut heat_faces = [ScalarBoundary::Insulated; 6];
    heat_faces[Face::YMin as usize] = ScalarBoundary::Fixed(320.0);
    let mut diffusion_faces = [ScalarBoundary::Insulated; 6];
    diffusion_faces[Face::XMax as usize] = ScalarBoundary::Fixed(1.0);
    let def = WorldDef {
        dimension: Dimension::Axisymmetric2D,
        origin: Vec3::new(-0.03125, 0.0, 0.0),
        cells: [16, 16, 1],
        cell_size: 0.03125,
        particle_capacity: 512,
        material_capacity: 1,
        faces,
        effects: Effects {
            heat: Some(Transport {
                faces: heat_faces,
                sources: false,
            }),
            diffusion: Some(Transport {
                faces: diffusion_faces,
                sources: false,
            }),
            ..Effects::NONE
        },
        ..WorldDef::DEFAULT
    };
    let mut storage = Vec::new();
    let mut w = open_scene(t, &def, &mut storage);
    let rubber = MaterialDef {
        thermal_expansion: 1.0 / 4096.0,
        reference_temperature: 256.0,
        swelling: 0.03125,
        reference_concentration: 0.0,
        ..conducting_rubber()
    };
    let id = w.add_material(&rubber).expect("rubber");
    t.line(format!("materials {id}"));
    let ids = w
        .fill_box(
            Vec3::new(0.0, 0.0625, 0.0),
            Vec3::new(0.25, 0.25, 0.0),
            id,
            Vec3::new(0.25, -0.5, 0.0),
        )
        .expect("box");
    let n = ids.end;
    t.seed("box", ids);
    t.state("after box", &w);
    let heat: Vec<Real> = (0..n).map(|i| 256.0 + 8.0 * (i % 8) as Real).collect();
    w.set_particle_scalar(ScalarField::Temperature, 0, &heat)
        .expect("temperatures");
    let concentration: Vec<Real> = (0..n).map(|i| 0.0625 * (i % 16) as Real).collect();
    w.set_particle_scalar(ScalarField::Concentration, 0, &concentration)
        .expect("concentrations");
    t.state("after scalars", &w);
    t.frames(&mut w, 12, 0.0078125);
}

/// The scenes cpgimp2d and cpgimp3d of `tests/c/same_state.c`.
fn cpgimp(t: &mut Text, dimension: Dimension) {
    let three = dimension == Dimension::ThreeD;
    t.line(if three {
        "scene cpgimp3d"
    } else {
        "scene cpgimp2d"
    });
    let mut faces = [Boundary::Slip; 6];
    faces[Face::YMin as usize] = Boundary::Stick;
    let def = WorldDef {
        dimension,
        cells: if three { [8, 8, 8] } else { [16, 16, 1] },
        cell_size: 0.0625,
        particle_capacity: 256,
        material_capacity: 1,
        shape: ShapeFunction::CpGimp,
        update_order: if three {
            UpdateOrder::Usf
        } else {
            UpdateOrder::Usl
        },
        transfer: if three {
            Transfer::Apic
        } else {
            Transfer::FlipParticleVelocity
        },
        faces,
        ..WorldDef::DEFAULT
    };
    let mut storage = Vec::new();
    let mut w = open_scene(t, &def, &mut storage);
    let soft = MaterialDef {
        youngs_modulus: 500000.0,
        poisson_ratio: 0.25,
        density: 750.0,
        ..MaterialDef::DEFAULT
    };
    let id = w.add_material(&soft).expect("soft");
    t.line(format!("materials {id}"));
    let (lo, hi, v) = if three {
        (
            Vec3::splat(0.125),
            Vec3::splat(0.25),
            Vec3::new(0.5, -2.0, 0.25),
        )
    } else {
        (
            Vec3::new(0.25, 0.125, 0.0),
            Vec3::new(0.5, 0.375, 0.0),
            Vec3::new(0.5, -2.0, 0.0),
        )
    };
    let ids = w.fill_box(lo, hi, id, v).expect("box");
    t.seed("box", ids);
    t.state("after box", &w);
    t.frames(&mut w, if three { 12 } else { 16 }, 0.0078125);
}

/// Expectation: the seven scenes of `tests/c/same_state.c` (a 2D block and disk dropped on a stick
/// floor with particles from arrays, GIMP and MUSL; a 3D sphere and a box moving towards an open
/// face, quadratic B-spline and USL; a 2D block with every effect declared, heat conduction and
/// diffusion in a conducting material with temperatures set included, whose forces, tractions and
/// concentrations change halfway; a 3D sphere with APIC, damping, particle forces, tractions and a
/// body force, cubic B-spline and USF; an axisymmetric cylinder on the axis that moves outwards,
/// expands with temperature and swells with concentration, GIMP and MUSL; a soft block thrown onto
/// a stick floor, where it squashes, in 2D with cpGIMP and USL and in 3D with cpGIMP, APIC and USF)
/// leave, after every seeding call, every change of an effect and every step, the same world bytes,
/// copied-out columns (positions, velocities, stress, J, status), view columns (mass, V0, material,
/// H, forces, damping, APIC moments, temperatures and concentrations and their grid values, the
/// hoop stretch, and which pointers are NULL), traction counts, thermostat alpha, diagnostics
/// (angular momentum included, bit for bit) and step reports through the C interface as through the
/// Rust kernel API. The temperatures change in every step and the concentrations in every step
/// after they are set, so the transport is part of what is compared; so does the hoop stretch of
/// the axisymmetric scene (and it is NULL in every other scene). The cpGIMP blocks deform (J moves
/// away from 1), so the stretched particle domains are part of what is compared.
#[test]
fn same_state_through_c_and_rust() {
    let exe = common::build(
        "same-state",
        Lang::C99,
        &["tests/c/same_state.c"],
        common::STRICT,
    );
    let c = stdout_of(&common::run(&exe, &[]));
    let rust = rust_same_state();
    assert_same_lines("same state", &c, &rust);
    // The escape path is part of what is compared: the whole 3D box (64 particles) leaves
    // through the open face, and none of the 2D scene does (it has no open face).
    assert_eq!(escaped_in(&c, "plane2d"), 0);
    assert_eq!(escaped_in(&c, "space3d"), 64);
    // Conduction and diffusion run: every step changes the temperatures (and their grid
    // values), each step after the concentrations are set changes those.
    let changes = |column: &str, from: usize| {
        let hashes = column_after_steps(&c, "effects2d", "transport", column);
        assert_eq!(hashes.len(), 16, "{column}: {hashes:?}");
        hashes[from..].windows(2).all(|w| w[0] != w[1])
    };
    assert!(changes("temperature", 0), "the temperatures did not change");
    assert!(changes("grid_temperature", 0));
    assert!(
        changes("concentration", 8),
        "the concentrations did not change"
    );
    assert!(changes("grid_concentration", 8));
    // The axisymmetric scene: every step changes the hoop stretch (and the temperatures and
    // concentrations that expand and swell the cylinder); only that scene has the column.
    let axisym = |kind: &str, column: &str| {
        let hashes = column_after_steps(&c, "axisym2d", kind, column);
        assert_eq!(hashes.len(), 12, "{column}: {hashes:?}");
        hashes.windows(2).all(|w| w[0] != w[1])
    };
    assert!(axisym("hoop", "hoop"), "the hoop stretch did not change");
    assert!(axisym("transport", "grid_temperature"));
    assert!(axisym("transport", "grid_concentration"));
    let (mut scene, mut hoop_lines) = ("", 0);
    for line in c.lines() {
        if let Some(name) = line.strip_prefix("scene ") {
            scene = name;
        } else if line.contains(": hoop present ") {
            let present = if scene == "axisym2d" { "1" } else { "0" };
            assert!(
                line.contains(&format!(": hoop present {present} ")),
                "{scene}: {line}"
            );
            hoop_lines += 1;
        }
    }
    assert!(hoop_lines > 0, "no hoop lines");
    for scene in ["cpgimp2d", "cpgimp3d"] {
        let jacobians: Vec<&str> = c
            .lines()
            .skip_while(|l| *l != format!("scene {scene}"))
            .skip(1)
            .take_while(|l| !l.starts_with("scene ") && *l != "end")
            .filter_map(|l| l.split_once(": jacobians ").map(|(_, h)| h))
            .collect();
        let after_box = jacobians.get(1).expect("J after the box");
        assert!(
            jacobians.len() > 3 && jacobians.last() != Some(after_box),
            "{scene}: J did not change: {jacobians:?}"
        );
    }
}

/// The hash of `column` on the `kind` line (`transport` or `hoop`) after each step of `scene`.
fn column_after_steps(text: &str, scene: &str, kind: &str, column: &str) -> Vec<String> {
    let mut current = "";
    let mut hashes = Vec::new();
    let marker = format!(": {kind} present ");
    for line in text.lines() {
        if let Some(name) = line.strip_prefix("scene ") {
            current = name;
        } else if current == scene && line.starts_with("after step ") && line.contains(&marker) {
            let words: Vec<&str> = line.split(' ').collect();
            // The value after the column's name (the last match: `hoop present 1 hoop <hash>`).
            let i = words
                .iter()
                .rposition(|w| *w == column)
                .expect("the column in its line");
            hashes.push(words[i + 1].to_string());
        }
    }
    hashes
}

/// The sum of `escaped` over the step lines of `scene`.
fn escaped_in(text: &str, scene: &str) -> u64 {
    let mut current = "";
    let mut total = 0;
    for line in text.lines() {
        if let Some(name) = line.strip_prefix("scene ") {
            current = name;
        } else if current == scene && line.starts_with("step ") {
            let words: Vec<&str> = line.split(' ').collect();
            let i = words
                .iter()
                .position(|w| *w == "escaped")
                .expect("escaped in a step line");
            total += words[i + 1].parse::<u64>().expect("a count");
        }
    }
    total
}

// ---------------------------------------------------------------------------------------------
// Rust-only checks through the rlib
// ---------------------------------------------------------------------------------------------

/// Expectation: `mpm_world_def_default` and `mpm_material_def_default` carry the kernel's
/// documented defaults field by field (enums as their numbers), with a non-zero cookie, and
/// the world definition read back from a world made of it equals it.
#[test]
fn defaults_match_the_kernel() {
    #[cfg(not(feature = "f64"))]
    let (wd, md) = (mpm_world_def_default_f32(), mpm_material_def_default_f32());
    #[cfg(feature = "f64")]
    let (wd, md) = (mpm_world_def_default_f64(), mpm_material_def_default_f64());
    let k = WorldDef::DEFAULT;
    assert_eq!(wd.dimension, k.dimension as u32);
    assert_eq!([wd.origin.x, wd.origin.y, wd.origin.z], k.origin.to_array());
    assert_eq!(wd.cell_size, k.cell_size);
    assert_eq!(wd.cells, k.cells);
    assert_eq!(wd.particle_capacity, k.particle_capacity);
    assert_eq!(wd.material_capacity, k.material_capacity);
    assert_eq!(wd.shape, k.shape as u32);
    assert_eq!(wd.particles_per_cell, k.particles_per_cell);
    assert_eq!(wd.flip_beta, k.flip_beta);
    assert_eq!(wd.pic_rate, k.pic_rate);
    assert_eq!(wd.transfer, k.transfer.code());
    assert_eq!(wd.transfer, MpmTransfer::Flip as u32);
    assert_eq!(wd.update_order, k.update_order as u32);
    assert_eq!(
        [wd.gravity.x, wd.gravity.y, wd.gravity.z],
        k.gravity.to_array()
    );
    assert_eq!(wd.faces, k.faces.map(|f| f as u32));
    assert_eq!(wd.exp_terms, k.exp_terms);
    assert_eq!(wd.cfl, k.cfl);
    assert_eq!(wd.max_substeps, k.max_substeps);
    assert_eq!(wd.max_volume_ratio, k.max_volume_ratio);
    assert_eq!(wd.workers, k.workers);
    // Effects::NONE: nothing declared, every value zero.
    assert_eq!(k.effects, Effects::NONE);
    let zero = MpmSchedule {
        points: 0,
        times: [0.0; MPM_SCHEDULE_POINTS],
        values: [0.0; MPM_SCHEDULE_POINTS],
    };
    let e = wd.effects;
    assert_eq!(e.damping.declared, 0);
    assert_eq!((e.damping.grid, e.damping.particle), (zero, zero));
    assert_eq!(e.damping.feedback.declared, 0);
    assert_eq!(e.damping.feedback.target, zero);
    assert_eq!(
        (e.damping.feedback.gain, e.damping.feedback.max_alpha),
        (0.0, 0.0)
    );
    assert_eq!(e.damping.per_particle, 0);
    assert_eq!(e.particle_forces, 0);
    assert_eq!(e.traction_capacity, 0);
    assert_eq!(e.body_force, MpmVec3::default());
    assert_eq!(e.body_force_scale, zero);
    assert_eq!(e.body_force_gradient, [MpmVec3::default(); 3]);
    let one = schedules(&[(0.0, 1.0)]).0;
    for s in &e.traction_schedules {
        assert_eq!((s.points, s.values[0]), (one.points, one.values[0]));
    }
    let insulated = MpmScalarBoundary {
        kind: MpmScalarBoundaryKind::Insulated as u32,
        value: 0.0,
    };
    let undeclared = MpmTransport {
        declared: 0,
        faces: [insulated; 6],
        sources: 0,
    };
    assert_eq!((e.heat, e.diffusion), (undeclared, undeclared));
    assert_ne!(wd.internal_cookie, 0);

    let m = MaterialDef::DEFAULT;
    assert_eq!(md.model, m.model as u32);
    assert_eq!(md.youngs_modulus, m.youngs_modulus);
    assert_eq!(md.poisson_ratio, m.poisson_ratio);
    assert_eq!(md.density, m.density);
    assert_eq!(md.heat_capacity, m.heat_capacity);
    assert_eq!(md.conductivity, m.conductivity);
    assert_eq!(md.diffusivity, m.diffusivity);
    assert_eq!(md.thermal_expansion, m.thermal_expansion);
    assert_eq!(md.reference_temperature, m.reference_temperature);
    assert_eq!(md.swelling, m.swelling);
    assert_eq!(md.reference_concentration, m.reference_concentration);
    assert_eq!(md.viscosity, m.viscosity);
    assert_eq!(md.bulk_viscosity, m.bulk_viscosity);
    assert_eq!(md.volume_relaxation, m.volume_relaxation);
    assert_eq!(md.bulk_modulus, m.bulk_modulus);
    assert_eq!(md.pressure_exponent, m.pressure_exponent);
    assert_eq!(md.yield_stress, m.yield_stress);
    assert_eq!(md.hardening_modulus, m.hardening_modulus);
    assert_eq!(md.friction_angle, m.friction_angle);
    assert_eq!(md.friction_fit, m.friction_fit as u32);
    assert_eq!(md.cohesion, m.cohesion);
    assert_eq!(md.critical_compression, m.critical_compression);
    assert_eq!(md.critical_stretch, m.critical_stretch);
    assert_eq!(md.hardening_coefficient, m.hardening_coefficient);
    assert_ne!(md.internal_cookie, 0);
    assert_ne!(md.internal_cookie, wd.internal_cookie);

    // A small world of the default definition: get_def gives back the same definition.
    let mut d = wd;
    d.cells = [8, 8, 1];
    d.particle_capacity = 16;
    let mut storage = Vec::new();
    let (world, _, _) = c_world(&d, &mut storage);
    let mut back = wd;
    back.internal_cookie = 0;
    // SAFETY: `world` is the world just made; `back` is a local.
    assert_eq!(
        unsafe { mpm_world_get_def(world, &mut back) },
        MpmStatus::Ok
    );
    let bits = |x: &MpmWorldDef| format!("{x:?}");
    assert_eq!(bits(&back), bits(&d));
}

/// Expectation: every `MpmShape` value is the kernel's shape function of the same name (cpGIMP
/// included) and the next value is none; a world made from C with each shape stores the
/// kernel's, and `mpm_world_get_def` gives the C value back.
#[test]
fn shapes_match_the_kernel() {
    #[cfg(not(feature = "f64"))]
    let base = mpm_world_def_default_f32();
    #[cfg(feature = "f64")]
    let base = mpm_world_def_default_f64();
    let shapes = [
        MpmShape::Linear,
        MpmShape::Gimp,
        MpmShape::QuadraticBspline,
        MpmShape::CubicBspline,
        MpmShape::CpGimp,
    ];
    for (code, shape) in shapes.into_iter().enumerate() {
        assert_eq!(shape as usize, code);
        let kernel_shape = ShapeFunction::from_code(shape as u32).expect("a kernel shape");
        assert_eq!(format!("{shape:?}"), format!("{kernel_shape:?}"));
        let mut d = base;
        d.shape = shape as u32;
        assert_eq!(stored_def(&d).shape, kernel_shape, "{shape:?}");
        let mut storage = Vec::new();
        let (world, _, _) = c_world(&d, &mut storage);
        let mut back = base;
        // SAFETY: `world` is the world just made; `back` is a local.
        assert_eq!(
            unsafe { mpm_world_get_def(world, &mut back) },
            MpmStatus::Ok
        );
        assert_eq!(back.shape, shape as u32, "{shape:?}");
    }
    assert_eq!(ShapeFunction::from_code(shapes.len() as u32), None);
}

/// Expectation: the status numbers of the kernel's errors are the kernel's own, and
/// `mpm_status_string` gives the kernel's description for each; for the statuses only the C
/// interface has it gives its own description; for every other value up to 4096 and for the
/// extremes, "unknown status".
#[test]
fn status_strings_match_the_kernel() {
    let text = |v: u32| {
        let p = mpm_status_string(v);
        assert!(!p.is_null(), "mpm_status_string({v}) is NULL");
        // SAFETY: non-NULL, and documented as a static NUL-terminated string.
        unsafe { CStr::from_ptr(p) }
            .to_str()
            .expect("UTF-8")
            .to_owned()
    };
    for e in Error::ALL {
        let s = MpmStatus::from(e);
        assert_eq!(s as u32, e as u32, "{e:?} keeps its number");
        assert_eq!(text(e as u32), e.as_str(), "{e:?}");
    }
    let known: BTreeSet<u32> = MpmStatus::ALL.iter().map(|s| *s as u32).collect();
    assert_eq!(known.len(), MpmStatus::ALL.len());
    for s in MpmStatus::ALL {
        assert_eq!(text(s as u32), s.as_cstr().to_str().expect("UTF-8"));
        assert_ne!(text(s as u32), "unknown status", "{s:?}");
    }
    for v in (0..=4096).chain([u32::MAX / 2, u32::MAX / 2 + 1, u32::MAX]) {
        if !known.contains(&v) {
            assert_eq!(text(v), "unknown status", "value {v}");
        }
    }
}

/// A schedule in both forms from (time, value) points.
fn schedules(points: &[(Real, Real)]) -> (MpmSchedule, Schedule) {
    let k = Schedule::from_points(points).expect("a valid schedule");
    let mut c = MpmSchedule {
        points: points.len() as u32,
        times: [0.0; MPM_SCHEDULE_POINTS],
        values: [0.0; MPM_SCHEDULE_POINTS],
    };
    for (i, &(t, v)) in points.iter().enumerate() {
        c.times[i] = t;
        c.values[i] = v;
    }
    (c, k)
}

/// A face condition of a transported scalar in C form.
fn scalar_face(kind: MpmScalarBoundaryKind, value: Real) -> MpmScalarBoundary {
    MpmScalarBoundary {
        kind: kind as u32,
        value,
    }
}

/// The heat (`heat`) or diffusion transport of `d`.
fn transport_of(d: &mut MpmWorldDef, heat: bool) -> &mut MpmTransport {
    if heat {
        &mut d.effects.heat
    } else {
        &mut d.effects.diffusion
    }
}

/// The definition stored in a world made from `c` (which must be accepted).
fn stored_def(c: &MpmWorldDef) -> WorldDef {
    let mut storage = Vec::new();
    let (_, mem, len) = c_world(c, &mut storage);
    // SAFETY: the world spans `len` bytes from `mem`, and nothing else uses it here.
    let bytes = unsafe { core::slice::from_raw_parts(mem, len) };
    kernel::WorldRef::open(bytes).expect("a world").def()
}

/// A world made through the C interface from `c`, in `storage` (sized here to its requirement
/// plus its alignment): the handle, and the start and length of the bytes it spans.
fn c_world(c: &MpmWorldDef, storage: &mut Vec<u8>) -> (*mut MpmWorld, *mut u8, usize) {
    let mut req = MpmMemoryRequirements::default();
    // SAFETY: valid pointers to locals.
    assert_eq!(
        unsafe { mpm_memory_requirements(c, &mut req) },
        MpmStatus::Ok
    );
    *storage = vec![0u8; req.bytes + req.align];
    let offset = storage.as_ptr().align_offset(req.align);
    let mem = storage[offset..].as_mut_ptr();
    let mut world = core::ptr::null_mut();
    // SAFETY: `mem` holds `req.bytes` bytes at the required alignment.
    assert_eq!(
        unsafe { mpm_world_init(c, mem.cast(), req.bytes, &mut world) },
        MpmStatus::Ok
    );
    (world, mem, req.bytes)
}

/// Expectation: a definition that declares every effect (APIC, damping with schedules, a
/// thermostat and per-particle columns, particle forces, tractions, a scaled body force, heat
/// conduction with fixed, flux and insulated faces and sources, diffusion), set field by field
/// from C, makes a world whose stored definition is exactly the Rust one, and
/// `mpm_world_get_def` gives back the C definition. A material with heat capacity,
/// conductivity, diffusivity, thermal expansion and swelling (and their reference values)
/// added from C is the kernel's material. Fields of what is not declared are ignored (and read
/// back as zero), and so is the value of an insulated face; a
/// flag that is not 0 or 1 and a face kind out of range are `MPM_STATUS_INVALID_ENUM`, a fixed
/// or flux value not finite `MPM_STATUS_INVALID_EFFECT`.
#[test]
fn effects_definition_round_trip() {
    #[cfg(not(feature = "f64"))]
    let mut c = mpm_world_def_default_f32();
    #[cfg(feature = "f64")]
    let mut c = mpm_world_def_default_f64();
    c.cells = [8, 8, 1];
    c.particle_capacity = 16;
    c.transfer = MpmTransfer::Apic as u32;
    let (grid_c, grid_k) = schedules(&[(0.0, 1.0), (0.5, 0.25)]);
    let (part_c, part_k) = schedules(&[(0.125, 0.5)]);
    let (target_c, target_k) = schedules(&[(0.0, 2.0), (1.0, 0.0), (2.0, 0.0)]);
    let (scale_c, scale_k) = schedules(&[(0.0, 0.0), (0.25, -1.0)]);
    let (traction_c, traction_k) = schedules(&[(0.0, 1.0), (0.5, 2.0)]);
    let (pulse_c, pulse_k) = schedules(&[(0.0, 0.0), (0.25, 3.0), (0.5, 0.0)]);
    let unread_zone = MpmDampingZone {
        min: MpmVec3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        },
        max: MpmVec3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        },
        rate: -1.0,
        ramped: 7,
        ramp_face: 99,
    };
    c.effects = MpmEffects {
        damping: MpmDamping {
            declared: 1,
            grid: grid_c,
            particle: part_c,
            feedback: MpmFeedback {
                declared: 1,
                gain: 0.75,
                target: target_c,
                max_alpha: Real::INFINITY,
            },
            per_particle: 1,
            grid_on_force: 1,
            zone_count: 2,
            zones: [
                MpmDampingZone {
                    min: MpmVec3 {
                        x: 0.0,
                        y: 0.25,
                        z: 0.0,
                    },
                    max: MpmVec3 {
                        x: 0.5,
                        y: 0.75,
                        z: 0.0,
                    },
                    rate: 2.5,
                    ramped: 1,
                    ramp_face: MpmFace::XMax as u32,
                },
                MpmDampingZone {
                    min: MpmVec3 {
                        x: 0.0,
                        y: 0.0,
                        z: 0.0,
                    },
                    max: MpmVec3 {
                        x: 1.0,
                        y: 0.125,
                        z: 0.0,
                    },
                    rate: 4.0,
                    ramped: 0,
                    ramp_face: 0,
                },
                // Past `zone_count`: not read (an invalid flag would be refused if it were).
                unread_zone,
                unread_zone,
            ],
        },
        particle_forces: 1,
        traction_capacity: 5,
        body_force: MpmVec3 {
            x: 1.5,
            y: -2.0,
            z: 0.0,
        },
        body_force_scale: scale_c,
        body_force_gradient: [
            MpmVec3 {
                x: -1.0,
                y: 0.5,
                z: 0.0,
            },
            MpmVec3 {
                x: 0.25,
                y: 2.0,
                z: 0.0,
            },
            MpmVec3 {
                x: 0.0,
                y: 0.0,
                z: 0.0,
            },
        ],
        traction_schedules: [traction_c, pulse_c, traction_c, pulse_c],
        heat: MpmTransport {
            declared: 1,
            faces: [
                scalar_face(MpmScalarBoundaryKind::Fixed, 300.5),
                scalar_face(MpmScalarBoundaryKind::Flux, -12.25),
                scalar_face(MpmScalarBoundaryKind::Insulated, 0.0),
                scalar_face(MpmScalarBoundaryKind::Fixed, -4.0),
                scalar_face(MpmScalarBoundaryKind::Flux, 8.0),
                scalar_face(MpmScalarBoundaryKind::Insulated, 0.0),
            ],
            sources: 1,
        },
        diffusion: MpmTransport {
            declared: 1,
            faces: [
                scalar_face(MpmScalarBoundaryKind::Insulated, 0.0),
                scalar_face(MpmScalarBoundaryKind::Fixed, 1.0),
                scalar_face(MpmScalarBoundaryKind::Flux, 0.5),
                scalar_face(MpmScalarBoundaryKind::Insulated, 0.0),
                scalar_face(MpmScalarBoundaryKind::Insulated, 0.0),
                scalar_face(MpmScalarBoundaryKind::Fixed, 0.0),
            ],
            sources: 0,
        },
        plasticity: 1,
        collider_capacity: 3,
        sdf_capacity: 7,
    };
    let heat = Transport {
        faces: [
            ScalarBoundary::Fixed(300.5),
            ScalarBoundary::Flux(-12.25),
            ScalarBoundary::Insulated,
            ScalarBoundary::Fixed(-4.0),
            ScalarBoundary::Flux(8.0),
            ScalarBoundary::Insulated,
        ],
        sources: true,
    };
    let diffusion = Transport {
        faces: [
            ScalarBoundary::Insulated,
            ScalarBoundary::Fixed(1.0),
            ScalarBoundary::Flux(0.5),
            ScalarBoundary::Insulated,
            ScalarBoundary::Insulated,
            ScalarBoundary::Fixed(0.0),
        ],
        sources: false,
    };
    let expected = WorldDef {
        cells: [8, 8, 1],
        particle_capacity: 16,
        transfer: Transfer::Apic,
        effects: Effects {
            damping: Some(Damping {
                grid: grid_k,
                particle: part_k,
                feedback: Some(Feedback {
                    gain: 0.75,
                    target: target_k,
                    max_alpha: Real::INFINITY,
                }),
                per_particle: true,
                grid_on_force: true,
                zones: [
                    DampingZone {
                        min: Vec3::new(0.0, 0.25, 0.0),
                        max: Vec3::new(0.5, 0.75, 0.0),
                        rate: 2.5,
                        ramp: Some(Face::XMax),
                    },
                    DampingZone {
                        min: Vec3::ZERO,
                        max: Vec3::new(1.0, 0.125, 0.0),
                        rate: 4.0,
                        ramp: None,
                    },
                    DampingZone::NONE,
                    DampingZone::NONE,
                ],
                zone_count: 2,
            }),
            particle_forces: true,
            traction_capacity: 5,
            body_force: Vec3::new(1.5, -2.0, 0.0),
            body_force_scale: scale_k,
            body_force_gradient: [
                Vec3::new(-1.0, 0.5, 0.0),
                Vec3::new(0.25, 2.0, 0.0),
                Vec3::ZERO,
            ],
            traction_schedules: [traction_k, pulse_k, traction_k, pulse_k],
            heat: Some(heat),
            diffusion: Some(diffusion),
            plasticity: true,
            collider_capacity: 3,
            sdf_capacity: 7,
        },
        ..WorldDef::DEFAULT
    };

    let mut storage = Vec::new();
    let (world, mem, len) = c_world(&c, &mut storage);
    assert_eq!(len, memory_requirements(&expected).expect("valid").bytes);
    // SAFETY: the world spans `len` bytes from `mem`, and nothing else uses it here.
    let bytes = unsafe { core::slice::from_raw_parts(mem, len) };
    let stored = kernel::WorldRef::open(bytes).expect("a world").def();
    assert_eq!(stored, expected);
    let mut back = c;
    back.internal_cookie = 0;
    // SAFETY: `world` is the world just made; `back` is a local.
    assert_eq!(
        unsafe { mpm_world_get_def(world, &mut back) },
        MpmStatus::Ok
    );
    let bits = |x: &MpmWorldDef| format!("{x:?}");
    // The zones past the count are not stored: they come back zero.
    let mut want = c;
    for z in &mut want.effects.damping.zones[2..] {
        *z = MpmDampingZone {
            rate: 0.0,
            ramped: 0,
            ramp_face: 0,
            ..*z
        };
    }
    assert_eq!(bits(&back), bits(&want));

    // A conducting, diffusing, expanding and swelling material from C is the kernel's
    // material.
    #[cfg(not(feature = "f64"))]
    let mut m = mpm_material_def_default_f32();
    #[cfg(feature = "f64")]
    let mut m = mpm_material_def_default_f64();
    m.heat_capacity = 2048.0;
    m.conductivity = 0.75;
    m.diffusivity = 1.0 / 1024.0;
    m.thermal_expansion = 1.0 / 65536.0;
    m.reference_temperature = 293.5;
    m.swelling = -0.0625;
    m.reference_concentration = 0.25;
    m.model = MpmMaterialModel::Snow as u32;
    m.viscosity = 0.5;
    m.bulk_modulus = 3.0e5;
    m.pressure_exponent = 3.0;
    m.yield_stress = 2.0e4;
    m.hardening_modulus = 1.0e5;
    m.friction_angle = 35.0;
    m.cohesion = 10.0;
    m.critical_compression = 0.03125;
    m.critical_stretch = 0.005;
    m.hardening_coefficient = 8.0;
    let mut id = u32::MAX;
    // SAFETY: `world` is the world just made; the other pointers are locals.
    assert_eq!(
        unsafe { mpm_world_add_material(world, &m, &mut id) },
        MpmStatus::Ok
    );
    // SAFETY: as above.
    let bytes = unsafe { core::slice::from_raw_parts(mem, len) };
    assert_eq!(
        kernel::WorldRef::open(bytes).expect("a world").material(id),
        Some(MaterialDef {
            heat_capacity: 2048.0,
            conductivity: 0.75,
            diffusivity: 1.0 / 1024.0,
            thermal_expansion: 1.0 / 65536.0,
            reference_temperature: 293.5,
            swelling: -0.0625,
            reference_concentration: 0.25,
            model: kernel::MaterialModel::Snow,
            viscosity: 0.5,
            bulk_modulus: 3.0e5,
            pressure_exponent: 3.0,
            yield_stress: 2.0e4,
            hardening_modulus: 1.0e5,
            friction_angle: 35.0,
            cohesion: 10.0,
            critical_compression: 0.03125,
            critical_stretch: 0.005,
            hardening_coefficient: 8.0,
            ..MaterialDef::DEFAULT
        })
    );

    // The value of an insulated face is not read.
    let mut ignored = c;
    ignored.effects.heat.faces[2].value = Real::NAN;
    ignored.effects.diffusion.faces[0].value = Real::INFINITY;
    assert_eq!(stored_def(&ignored), expected);

    // Transports not declared: their other fields are not read, and read back as zero.
    let mut no_transport = c;
    no_transport.effects.heat.declared = 0;
    no_transport.effects.heat.sources = 7;
    no_transport.effects.heat.faces[0] = MpmScalarBoundary {
        kind: 99,
        value: Real::NAN,
    };
    no_transport.effects.diffusion.declared = 0;
    no_transport.effects.diffusion.sources = u32::MAX;
    no_transport.effects.diffusion.faces[5].kind = u32::MAX;
    let without = WorldDef {
        effects: Effects {
            heat: None,
            diffusion: None,
            ..expected.effects
        },
        ..expected
    };
    assert_eq!(stored_def(&no_transport), without);
    {
        let mut storage = Vec::new();
        let (w, _, bare) = c_world(&no_transport, &mut storage);
        assert!(bare < len, "declared transports take memory");
        let mut back = c;
        // SAFETY: `w` is the world just made; `back` is a local.
        assert_eq!(unsafe { mpm_world_get_def(w, &mut back) }, MpmStatus::Ok);
        let zero = MpmTransport {
            declared: 0,
            faces: [scalar_face(MpmScalarBoundaryKind::Insulated, 0.0); 6],
            sources: 0,
        };
        assert_eq!((back.effects.heat, back.effects.diffusion), (zero, zero));
    }

    // Not declared: the other fields are not read, and read back as zero.
    let mut undeclared = c;
    undeclared.effects.damping.declared = 0;
    undeclared.effects.damping.per_particle = 7;
    undeclared.effects.damping.grid.points = 99;
    undeclared.effects.damping.feedback.declared = 5;
    let mut req2 = MpmMemoryRequirements::default();
    // SAFETY: valid pointers to locals.
    assert_eq!(
        unsafe { mpm_memory_requirements(&undeclared, &mut req2) },
        MpmStatus::Ok
    );
    let no_damping = WorldDef {
        effects: Effects {
            damping: None,
            ..expected.effects
        },
        ..expected
    };
    assert_eq!(
        req2.bytes,
        memory_requirements(&no_damping).expect("valid").bytes
    );

    // Flags other than 0 or 1.
    let refused = |d: &MpmWorldDef| {
        let mut r = MpmMemoryRequirements::default();
        // SAFETY: valid pointers to locals.
        unsafe { mpm_memory_requirements(d, &mut r) }
    };
    for v in [2, 3, 0x8000_0000, u32::MAX] {
        let mut d = c;
        d.effects.damping.declared = v;
        assert_eq!(refused(&d), MpmStatus::InvalidEnum, "damping.declared {v}");
        let mut d = c;
        d.effects.damping.feedback.declared = v;
        assert_eq!(refused(&d), MpmStatus::InvalidEnum, "feedback.declared {v}");
        let mut d = c;
        d.effects.damping.per_particle = v;
        assert_eq!(refused(&d), MpmStatus::InvalidEnum, "per_particle {v}");
        let mut d = c;
        d.effects.particle_forces = v;
        assert_eq!(refused(&d), MpmStatus::InvalidEnum, "particle_forces {v}");
        // 2 and 3 are MPM_TRANSFER_FLIP_PARTICLE_VELOCITY and MPM_TRANSFER_MLS.
        if v != 2 && v != 3 {
            let mut d = c;
            d.transfer = v;
            assert_eq!(refused(&d), MpmStatus::InvalidEnum, "transfer {v}");
        }
        for (name, heat) in [("heat", true), ("diffusion", false)] {
            let mut d = c;
            transport_of(&mut d, heat).declared = v;
            assert_eq!(refused(&d), MpmStatus::InvalidEnum, "{name}.declared {v}");
            let mut d = c;
            transport_of(&mut d, heat).sources = v;
            assert_eq!(refused(&d), MpmStatus::InvalidEnum, "{name}.sources {v}");
        }
    }

    // Face kinds out of range, and fixed or flux values that are not finite.
    for k in 0..6 {
        for v in [3, 4, 0x8000_0000, u32::MAX] {
            let mut d = c;
            d.effects.heat.faces[k].kind = v;
            assert_eq!(
                refused(&d),
                MpmStatus::InvalidEnum,
                "heat face {k} kind {v}"
            );
            let mut d = c;
            d.effects.diffusion.faces[k].kind = v;
            assert_eq!(
                refused(&d),
                MpmStatus::InvalidEnum,
                "diffusion face {k} kind {v}"
            );
        }
        // The values of faces the dimension lacks (z in 2D) are not read.
        let axes = if c.dimension == MpmDimension::Space3d as u32 {
            3
        } else {
            2
        };
        let expect = if k < 2 * axes {
            MpmStatus::InvalidEffect
        } else {
            MpmStatus::Ok
        };
        for kind in [MpmScalarBoundaryKind::Fixed, MpmScalarBoundaryKind::Flux] {
            for x in [Real::NAN, Real::INFINITY, Real::NEG_INFINITY] {
                let mut d = c;
                d.effects.heat.faces[k] = scalar_face(kind, x);
                assert_eq!(refused(&d), expect, "heat face {k} {kind:?} {x}");
                let mut d = c;
                d.effects.diffusion.faces[k] = scalar_face(kind, x);
                assert_eq!(refused(&d), expect, "diffusion face {k} {kind:?} {x}");
            }
        }
    }
}

/// Expectation: an axisymmetric definition from C whose lower x face is a wall at the axis
/// (`origin.x = -margin_cells * cell_size`: one cell for GIMP, cpGIMP and the B-splines, none
/// for linear hats) makes a world whose stored definition is the kernel's; the axis a cell off or
/// an open lower x face is `MPM_STATUS_INVALID_AXIS`, for every family. The view's `hoop`
/// pointer is the kernel's hoop column (NULL in plane strain), and `MPM_STATUS_INVALID_AXIS`
/// keeps the kernel's number.
#[test]
fn axisymmetric_definition_and_hoop_column() {
    assert_eq!(MpmStatus::from(Error::InvalidAxis) as u32, 27);
    #[cfg(not(feature = "f64"))]
    let mut c = mpm_world_def_default_f32();
    #[cfg(feature = "f64")]
    let mut c = mpm_world_def_default_f64();
    c.dimension = MpmDimension::Axisymmetric2d as u32;
    c.cells = [8, 8, 1];
    c.cell_size = 0.0625;
    c.particle_capacity = 64;
    let requirements = |d: &MpmWorldDef| {
        let mut r = MpmMemoryRequirements::default();
        // SAFETY: valid pointers to locals.
        unsafe { mpm_memory_requirements(d, &mut r) }
    };
    for shape in [
        MpmShape::Linear,
        MpmShape::Gimp,
        MpmShape::QuadraticBspline,
        MpmShape::CubicBspline,
        MpmShape::CpGimp,
    ] {
        let kernel_shape = ShapeFunction::from_code(shape as u32).expect("a shape");
        let axis = -(kernel_shape.margin_cells() as Real) * c.cell_size;
        let mut d = c;
        d.shape = shape as u32;
        d.origin.x = axis;
        assert_eq!(
            stored_def(&d),
            WorldDef {
                dimension: Dimension::Axisymmetric2D,
                origin: Vec3::new(axis, 0.0, 0.0),
                cells: [8, 8, 1],
                cell_size: 0.0625,
                particle_capacity: 64,
                shape: kernel_shape,
                ..WorldDef::DEFAULT
            },
            "{shape:?}"
        );
        for off in [-c.cell_size, c.cell_size] {
            let mut bad = d;
            bad.origin.x = axis + off;
            assert_eq!(
                requirements(&bad),
                MpmStatus::InvalidAxis,
                "{shape:?} {off}"
            );
        }
        let mut open = d;
        open.faces[MpmFace::XMin as usize] = MpmBoundary::Open as u32;
        assert_eq!(
            requirements(&open),
            MpmStatus::InvalidAxis,
            "{shape:?} open"
        );
        let mut plane = open;
        plane.dimension = MpmDimension::Plane2d as u32;
        assert_eq!(
            requirements(&plane),
            MpmStatus::Ok,
            "{shape:?} plane strain"
        );
    }

    // A GIMP world with a box on the axis: the view's hoop is the kernel's column.
    c.origin.x = -c.cell_size;
    for (dimension, axisymmetric) in [
        (MpmDimension::Axisymmetric2d, true),
        (MpmDimension::Plane2d, false),
    ] {
        let mut d = c;
        d.dimension = dimension as u32;
        let mut storage = Vec::new();
        let (world, mem, len) = c_world(&d, &mut storage);
        let mut view = core::mem::MaybeUninit::<MpmParticlesView>::uninit();
        // SAFETY: `world` is the world just made; the other pointers are locals.
        unsafe {
            #[cfg(not(feature = "f64"))]
            let m = mpm_material_def_default_f32();
            #[cfg(feature = "f64")]
            let m = mpm_material_def_default_f64();
            let mut id = u32::MAX;
            assert_eq!(mpm_world_add_material(world, &m, &mut id), MpmStatus::Ok);
            let mut ids = MpmIdRange::default();
            let (lo, hi, v) = (
                MpmVec3 {
                    x: 0.0,
                    y: 0.125,
                    z: 0.0,
                },
                MpmVec3 {
                    x: 0.125,
                    y: 0.25,
                    z: 0.0,
                },
                MpmVec3 {
                    x: 0.5,
                    y: 0.0,
                    z: 0.0,
                },
            );
            assert_eq!(
                mpm_world_fill_box(world, lo, hi, id, v, &mut ids),
                MpmStatus::Ok
            );
            let mut report = MpmStepReport::default();
            assert_eq!(
                mpm_world_step(world, 1.0 / 256.0, &mut report),
                MpmStatus::Ok
            );
            assert_eq!(mpm_world_particles(world, view.as_mut_ptr()), MpmStatus::Ok);
        }
        // SAFETY: written by the successful call above.
        let view = unsafe { view.assume_init() };
        // SAFETY: the world spans `len` bytes from `mem`, and nothing else uses it here.
        let bytes = unsafe { core::slice::from_raw_parts(mem, len) };
        let w = kernel::WorldRef::open(bytes).expect("a world");
        let hoop = w.particles().hoop;
        assert_eq!(view.dimension, dimension as u32);
        if axisymmetric {
            assert_eq!(view.hoop, hoop.as_ptr());
            assert_eq!(hoop.len(), view.count);
            assert!(view.count > 0);
            assert!(hoop.iter().all(|x| x.is_finite()), "{hoop:?}");
            assert!(hoop.iter().any(|&x| x != 0.0), "{hoop:?}");
        } else {
            assert!(view.hoop.is_null());
            assert!(hoop.is_empty());
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Hostile inputs
// ---------------------------------------------------------------------------------------------

fn check_hostile(name: &str, flags: &[&str]) {
    check_program("hostile", name, flags, HOSTILE_FLOOR);
}

/// About 90% of the 332 checks `tests/c/hostile.c` runs.
const HOSTILE_FLOOR: usize = 300;

/// Expectation: with strict warnings (C99, -Wall -Wextra -Werror -pedantic), the reliability
/// contract holds against the hostile inputs of `tests/c/hostile.c`: an input array or an
/// output that overlaps the world's memory (inside it or straddling either end; world_out of
/// init and open inside the memory handed in) is `MPM_STATUS_OVERLAPPING_MEMORY` and changes
/// no byte, while caller-owned copies and arrays that only touch the world's ends are
/// accepted; a pointer 64 bytes before a page without access (zeroed or random, not the magic
/// number) is `MPM_STATUS_NOT_A_WORLD` for every entry point, without a crash; a snapshot with
/// a NaN velocity does not open while the thermostat world it came from keeps stepping, and a
/// fill whose mass overflows (2D and 3D) or underflows is refused with
/// `MPM_STATUS_NON_FINITE_INPUT` / `MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME` (a NaN z in a 2D
/// fill_box is ignored); single edits of a snapshot's state (mass, volume, status, material,
/// position, velocity, stress, displacement gradient, inverted F, effect columns) are
/// `MPM_STATUS_INVALID_STATE` without a write, and 5000 copies with 1 to 8 random bytes
/// changed either open, step (or hit `MPM_STATUS_SUBSTEP_LIMIT` unchanged) and read finite
/// diagnostics, or are refused with NOT_A_WORLD / INVALID_STATE / BUFFER_TOO_SMALL without a
/// write; linear-shape USL runs on a stick floor report flags that agree with their frozen and
/// runaway counts and end with every active particle's J in the band and a world that reopens;
/// steel stepped by 1/60 s is `MPM_STATUS_SUBSTEP_LIMIT` (max_substeps is exact, S - 1
/// refused and S accepted); a thermostat of gain 1e12 takes the substeps of the same scene
/// without it; limits out of range are `MPM_STATUS_INVALID_LIMIT`; the four new statuses have
/// their numbers and distinct descriptions. The program ends with "all N hostile checks
/// passed".
#[test]
fn hostile_from_c_strict() {
    check_hostile("hostile", common::STRICT);
}

/// Expectation: the same program, built with AddressSanitizer and UndefinedBehaviorSanitizer
/// (no recovery), passes the same checks without a sanitizer report. (The library itself is not
/// instrumented; the page without access in the program is what proves that a non-world is read
/// no further than its magic number.)
#[test]
fn hostile_from_c_sanitized() {
    check_hostile("hostile-sanitized", &strict_and_sanitized());
}

// ---------------------------------------------------------------------------------------------
// Values in range
// ---------------------------------------------------------------------------------------------

/// The checks `tests/c/ranges.c` runs, as written (62 in single precision, 61 in double).
const RANGES_FLOOR: usize = 60;

/// Expectation: with strict warnings, a snapshot whose low part of a position is not finite
/// or more than one unit in the last place of the position, or whose plastic history is out
/// of its model's range (snow with `J_p <= 0` or hardened past any resolved step, a negative
/// von Mises or Drucker-Prager history, a history on a model without one), is
/// `MPM_STATUS_INVALID_STATE` without a write, while one within range opens and steps; snow
/// with xi = 10, 100 and 1000 dropped on a stick floor for 300 frames never has more energy
/// than it started with (5 % for round-off), and what froze is counted as runaway; damping
/// rates, viscosities, wave speeds, per-particle rates and particle speeds that no step above
/// `MPM_MIN_STABLE_DT` resolves are `MPM_STATUS_STABLE_STEP_TOO_SHORT`, moduli that overflow
/// `MPM_STATUS_INVALID_MATERIAL`, and a world just inside the bounds steps at its stable step
/// with nothing frozen; a snapshot whose collider record holds what `mpm_world_add_collider`
/// could not have written (a value past `mpm_real`'s range, a radius of 0, a negative friction,
/// a rotation not of unit length, a pose time other than the world's, a z component in 2D, an
/// unknown contact or shape) is `MPM_STATUS_INVALID_STATE` without a write, and the intact one
/// opens, steps and reads its collider back. The program ends with "all N ranges checks
/// passed".
#[test]
fn ranges_from_c_strict() {
    check_program("ranges", "ranges", common::STRICT, RANGES_FLOOR);
}

/// Expectation: the same program under AddressSanitizer and UndefinedBehaviorSanitizer.
#[test]
fn ranges_from_c_sanitized() {
    check_program(
        "ranges",
        "ranges-sanitized",
        &strict_and_sanitized(),
        RANGES_FLOOR,
    );
}

// ---------------------------------------------------------------------------------------------
// The host's task system
// ---------------------------------------------------------------------------------------------

/// The checks `tests/c/tasks.c` runs, as written.
const TASKS_FLOOR: usize = 71;

/// Expectation: with strict warnings, three scenes (2D, 2D with every effect declared, 3D)
/// stepped with `mpm_world_step_tasks` on a host that runs each task on the calling thread
/// and on pools of 1, 2, 3, 4, 7, 8 and 16 worker threads (one range per worker, or ranges of
/// `min_range` items taken by whichever thread is free) have, after every frame, the particle
/// columns, diagnostics and step report of `mpm_world_step`, bit for bit; a NULL world, task
/// system, callback or report is `MPM_STATUS_NULL_POINTER`, a `worker_count` of 0, past the
/// definition's `workers` or `UINT32_MAX` is `MPM_STATUS_INVALID_LIMIT`, a bad dt, a dt past
/// `max_substeps`, a report inside the world and a non-world have their statuses, each without
/// a change, a report or a callback; a host that runs ranges past the items, with a worker
/// index past `worker_count`, leaves an item out, runs one twice, or runs ranges twice and
/// leaves as many items out gets `MPM_STATUS_TASK_CONTRACT` without a report whenever the step
/// hands it a task, and the snapshot taken before restores a world that steps as one that
/// never met the host. The program ends with "all N tasks checks passed".
#[test]
fn tasks_from_c_strict() {
    check_program("tasks", "tasks", common::STRICT, TASKS_FLOOR);
}

/// Expectation: the same program under AddressSanitizer and UndefinedBehaviorSanitizer.
#[test]
fn tasks_from_c_sanitized() {
    check_program(
        "tasks",
        "tasks-sanitized",
        &strict_and_sanitized(),
        TASKS_FLOOR,
    );
}

// ---------------------------------------------------------------------------------------------
// A particle's whole state
// ---------------------------------------------------------------------------------------------

/// The checks `tests/c/state.c` runs, as written.
const STATE_FLOOR: usize = 82;

/// Expectation: with strict warnings, in each dimension form (Drucker-Prager sand under
/// cpGIMP, von Mises metal axisymmetric, snow in 3D; APIC, MUSL, plasticity, particle forces,
/// per-particle damping, heat and diffusion with sources declared), particles copied out of
/// the view into host arrays, removed and added back with `mpm_world_add_particles_with_state`
/// leave every view column, the diagnostics and the stable step equal to the bytes of a twin
/// that never lost them, then and 8 frames on; set in place to another's state and back with
/// `mpm_world_set_particle_state` they are equal again; every particle moved into another
/// world of the same definition and materials steps 8 frames to the same bytes. NULL pointers,
/// arrays and outputs inside the world, unknown particles and counts past the capacity (before
/// any array is read), undeclared effects' arrays, groups given in part and a value no world
/// holds in each kind of column are refused with their status, without a change or an output,
/// and each such value written into a snapshot is what `mpm_world_open` refuses. The program
/// ends with "all N state checks passed".
#[test]
fn state_from_c_strict() {
    check_program("state", "state", common::STRICT, STATE_FLOOR);
}

/// Expectation: the same program under AddressSanitizer and UndefinedBehaviorSanitizer.
#[test]
fn state_from_c_sanitized() {
    check_program(
        "state",
        "state-sanitized",
        &strict_and_sanitized(),
        STATE_FLOOR,
    );
}
