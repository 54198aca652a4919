//! Isotropic eigenstrain (thermal expansion and swelling: the stress update takes
//! `F_0 = (1 + d) I` out of F, `d = alpha (T_g->p - T_0) + beta (c_g->p - c_0)`) against exact
//! solutions. Each test states the exact solution, its tolerance and why.
//!
//! The exact solutions are those of the kernel's own finite-strain models (the corotated linear
//! model and the compressible neo-Hookean), evaluated in f64 below: with the eigenstrain
//! `d = 5e-3` used here they differ from the small-strain formulas (quoted with each test) by
//! O(d): 0.5 % for the linear model's clamped stress, 1.1 % for the neo-Hookean's, too much
//! for a 1 % tolerance against the small-strain formulas (each test checks that its exact
//! value is that close to the small-strain one).

use crate::common::*;
use mpm_gimp::{
    Boundary, Damping, Dimension, Effects, MaterialDef, MaterialModel, Real, ScalarField, Schedule,
    ShapeFunction, Transport, Vec3, World, WorldDef,
};

/// Young's modulus, Pa.
const YOUNG: Real = 1.0e6;
/// Poisson's ratio.
const POISSON: Real = 0.3;
/// Density, kg/m^3.
const DENSITY: Real = 1000.0;
/// Stress-free temperature `T_0`, K.
const T0: Real = 300.0;
/// Thermal expansion coefficient alpha, 1/K.
const ALPHA: Real = 1.0e-4;
/// Temperature rise, K: the eigenstrain `alpha dT` is 5e-3.
const HEATING: Real = 50.0;
/// Cell size, m.
const H: Real = 0.05;

const MODELS: [MaterialModel; 3] = [
    MaterialModel::LinearElastic,
    MaterialModel::NeoHookean,
    MaterialModel::FixedCorotated,
];

/// The solid of these tests: it expands with temperature (alpha, `T_0`), and conducts heat and
/// the concentration potential a little (with a uniform field and insulated faces that changes
/// nothing, but it runs the conduction).
fn solid(model: MaterialModel) -> MaterialDef {
    MaterialDef {
        model,
        youngs_modulus: YOUNG,
        poisson_ratio: POISSON,
        density: DENSITY,
        heat_capacity: 1000.0,
        conductivity: 1.0,
        diffusivity: 1.0e-6,
        thermal_expansion: ALPHA,
        reference_temperature: T0,
        ..MaterialDef::DEFAULT
    }
}

/// Heat conduction declared, every face insulated.
fn heat() -> Effects {
    Effects {
        heat: Some(Transport::INSULATED),
        ..Effects::NONE
    }
}

/// `alpha dT` in f64, from the values the kernel is given.
fn thermal_strain() -> f64 {
    ALPHA as f64 * HEATING as f64
}

/// Lamé constants (lambda, mu) in f64.
fn lame() -> (f64, f64) {
    lame_of(YOUNG, POISSON)
}

/// Bulk modulus `K = E / (3 (1 - 2 nu))`, Pa.
fn bulk() -> f64 {
    YOUNG as f64 / (3.0 * (1.0 - 2.0 * POISSON as f64))
}

/// The exact state of a material of `model` under the diagonal deformation `F = diag(s)` (the
/// three principal stretches; plane strain has `s[2] = 1`) carrying the eigenstrain `d`: the
/// model sees `F_e = F / (1 + d)`, so the Cauchy stress is
/// `sigma = tau / J = (1 + d)^3 tau(F_e) / J`, and the strain energy per unit initial volume is
/// `(1 + d)^3 W(F_e)` (the elastic part's energy per volume of the stress-free configuration,
/// as `Diagnostics::strain` counts it). Returns the principal Cauchy stresses and that energy.
/// - corotated linear: `e = F_e - I` (no rotation), `tau = J_e (lambda tr e I + 2 mu e)`,
///   `W = mu e:e + lambda (tr e)^2 / 2`;
/// - neo-Hookean: `tau = mu (B_e - I) + lambda ln J_e I`,
///   `W = mu/2 (tr B_e - 3) - mu ln J_e + lambda/2 (ln J_e)^2`;
/// - fixed-corotated: `tau = 2 mu (F_e - I) F_e + lambda (J_e - 1) J_e I` (no rotation),
///   `W = mu |F_e - I|^2 + lambda/2 (J_e - 1)^2`.
fn exact_state(model: MaterialModel, s: [f64; 3], d: f64) -> ([f64; 3], f64) {
    let (lambda, mu) = lame();
    let fe = s.map(|v| v / (1.0 + d));
    let je = fe[0] * fe[1] * fe[2];
    let (tau_e, w) = match model {
        MaterialModel::LinearElastic => {
            let e = fe.map(|v| v - 1.0);
            let tr: f64 = e.iter().sum();
            let ee: f64 = e.iter().map(|v| v * v).sum();
            (
                e.map(|ea| je * (lambda * tr + 2.0 * mu * ea)),
                mu * ee + 0.5 * lambda * tr * tr,
            )
        }
        MaterialModel::NeoHookean => {
            let lnj = je.ln();
            let trb: f64 = fe.iter().map(|v| v * v).sum();
            (
                fe.map(|f| mu * (f * f - 1.0) + lambda * lnj),
                0.5 * mu * (trb - 3.0) - mu * lnj + 0.5 * lambda * lnj * lnj,
            )
        }
        MaterialModel::FixedCorotated => {
            let ee: f64 = fe.iter().map(|v| (v - 1.0) * (v - 1.0)).sum();
            (
                fe.map(|f| 2.0 * mu * (f - 1.0) * f + lambda * (je - 1.0) * je),
                mu * ee + 0.5 * lambda * (je - 1.0) * (je - 1.0),
            )
        }
        other => unreachable!("{other:?} is not among the elastic models tested here"),
    };
    let cube = (1.0 + d).powi(3);
    let j = s[0] * s[1] * s[2];
    (tau_e.map(|t| cube * t / j), cube * w)
}

/// The in-plane stretch `1 + e` of a free plane-strain block with eigenstrain `d` (`F_zz = 1`,
/// `sigma_xx = sigma_yy = 0`), by bisection on `sigma_xx` (it increases with the stretch).
/// For the corotated linear model it is `1 + (1 + nu) d` exactly (see
/// [`free_plane_strain_expansion_is_one_plus_nu_times_alpha_dt`]).
fn free_plane_strain_stretch(model: MaterialModel, d: f64) -> f64 {
    let (mut lo, mut hi) = (1.0, 1.0 + 3.0 * d);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if exact_state(model, [mid, mid, 1.0], d).0[0] < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Cauchy stress component `k` (stored order: 2D xx, yy, xy, zz; 3D xx, yy, zz, xy, xz, yz) of
/// particle `i`: `rho0 / J` times the stored `tau / rho0`.
fn cauchy(v: &mpm_gimp::ParticlesView<'_>, i: usize, k: usize) -> f64 {
    DENSITY as f64 * v.stress[k][i] as f64 / (1.0 + v.jacobian_minus_one(i) as f64)
}

/// The stored stress components that are normal (2D: xx, yy, zz) and shear.
fn normal_and_shear(dim: Dimension) -> (&'static [usize], &'static [usize]) {
    if dim == Dimension::ThreeD {
        (&[0, 1, 2], &[3, 4, 5])
    } else {
        (&[0, 1, 3], &[2])
    }
}

/// Runs `f` on a new world of definition `def`.
fn with_world<R>(def: &WorldDef, f: impl FnOnce(&mut World) -> R) -> R {
    let mut buf = buffer_for(def);
    let mut w = World::init(def, buf.as_mut_bytes()).unwrap();
    f(&mut w)
}

/// Fills the box `[lo, hi]` on every axis of `dim` with `material`, at rest.
fn fill_cube(w: &mut World, dim: Dimension, lo: Real, hi: Real, material: &MaterialDef) {
    let m = w.add_material(material).unwrap();
    let z = |v: Real| if dim == Dimension::ThreeD { v } else { 0.0 };
    w.fill_box(
        Vec3::new(lo, lo, z(lo)),
        Vec3::new(hi, hi, z(hi)),
        m,
        Vec3::ZERO,
    )
    .unwrap();
}

/// Sets every particle's value of `field` to `value`.
fn set_uniform(w: &mut World, field: ScalarField, value: Real) {
    let n = w.particle_count();
    w.set_particle_scalar(field, 0, &vec![value; n]).unwrap();
}

/// Steps `steps` times with the stable time step of the initial state.
fn run(w: &mut World, steps: usize) {
    let dt = w.stable_dt();
    for _ in 0..steps {
        w.step(dt).unwrap();
    }
}

// ---------------------------------------------------------------------------------------------
// 1. Free expansion
// ---------------------------------------------------------------------------------------------

/// What a settled free block measured.
struct Free {
    /// Mean `H_aa` over the particles, per axis used.
    mean_stretch: Vec<f64>,
    /// Largest deviation of any particle's `H` entry from the mean `H_aa I`.
    spread: f64,
    /// Extent (span of the particle centres) over its initial value, minus 1, per axis used.
    span: Vec<f64>,
    /// Largest magnitude of the volume-weighted mean of each in-plane Kirchhoff stress
    /// component `sum V0_p tau_p / sum V0_p` (3D: every component), Pa.
    mean_stress: f64,
    /// Largest in-plane Cauchy stress component magnitude of any particle, Pa.
    particle_stress: f64,
    /// 2D only: the volume-weighted mean out-of-plane Cauchy stress, Pa.
    mean_zz: f64,
    /// `Diagnostics::strain`, J (per unit thickness in 2D), and the initial volume.
    strain: f64,
    volume: f64,
    /// Largest deviation of the grid temperature at a particle from `T_0 + dT`, K.
    temperature_spread: f64,
}

/// A block of `cells` cells per axis (3D: 6, 2D: 8) at 2 particles per cell per axis, in the
/// middle of an open grid twice its size (no wall near it), no gravity, every particle at
/// `T_0 + dT` with insulated faces, damped by the grid damping so that it settles; measured
/// after `steps` stable steps.
///
/// The damping: the slowest mode the uniform expansion excites is the block's breathing mode,
/// `omega ~ pi c / L` (`c` the dilatational wave speed, `L` the block's side). A grid damping
/// of `2 omega` damps it critically; every faster mode then decays at `omega` or faster, so
/// the residue falls as `exp(-omega t)`: below 1e-6 of the initial stress in `14 / omega`,
/// about 90 steps (3D) and 120 (2D) here; the runs take 300 and 400.
fn free_block(dim: Dimension, shape: ShapeFunction, model: MaterialModel, steps: usize) -> Free {
    let cells: u32 = if dim == Dimension::ThreeD { 6 } else { 8 };
    let side = cells as Real * H;
    let mut def = free_space(dim, 2 * cells, H);
    def.shape = shape;
    def.particle_capacity = (2 * cells).pow(def.axes() as u32);
    let material = solid(model);
    let omega = std::f64::consts::PI * material.wave_speed() as f64 / side as f64;
    def.effects = Effects {
        damping: Some(Damping {
            grid: Schedule::constant((2.0 * omega) as Real),
            ..Damping::NONE
        }),
        ..heat()
    };
    let d = def.axes();
    with_world(&def, |w| {
        let lo = 0.5 * side;
        fill_cube(w, dim, lo, lo + side, &material);
        set_uniform(w, ScalarField::Temperature, T0 + HEATING);
        let span = |w: &World| -> Vec<f64> {
            let v = w.particles();
            (0..d)
                .map(|a| {
                    let x = v.position[a];
                    let max = x.iter().fold(Real::MIN, |m, &x| m.max(x));
                    let min = x.iter().fold(Real::MAX, |m, &x| m.min(x));
                    (max - min) as f64
                })
                .collect()
        };
        let span0 = span(w);
        run(w, steps);
        let v = w.particles();
        let n = v.count as f64;
        let mean_stretch: Vec<f64> = (0..d)
            .map(|a| {
                v.displacement_gradient[a][a]
                    .iter()
                    .map(|&x| x as f64)
                    .sum::<f64>()
                    / n
            })
            .collect();
        let mut spread: f64 = 0.0;
        for (a, &mean) in mean_stretch.iter().enumerate() {
            for b in 0..d {
                let expect = if a == b { mean } else { 0.0 };
                for &x in v.displacement_gradient[a][b] {
                    spread = spread.max((x as f64 - expect).abs());
                }
            }
        }
        let volume: f64 = v.volume0.iter().map(|&x| x as f64).sum();
        let components = if d == 3 { 0..6 } else { 0..3 };
        let mut mean_stress: f64 = 0.0;
        for k in components.clone() {
            let mean = (0..v.count)
                .map(|i| v.volume0[i] as f64 * DENSITY as f64 * v.stress[k][i] as f64)
                .sum::<f64>()
                / volume;
            mean_stress = mean_stress.max(mean.abs());
        }
        let particle_stress = (0..v.count)
            .flat_map(|i| components.clone().map(move |k| (i, k)))
            .map(|(i, k)| cauchy(&v, i, k).abs())
            .fold(0.0, f64::max);
        let mean_zz = if d == 2 {
            (0..v.count)
                .map(|i| v.volume0[i] as f64 * cauchy(&v, i, 3))
                .sum::<f64>()
                / volume
        } else {
            0.0
        };
        let temperature_spread = v
            .grid_temperature
            .iter()
            .map(|&t| (t as f64 - (T0 + HEATING) as f64).abs())
            .fold(0.0, f64::max);
        let now = span(w);
        Free {
            mean_stretch,
            spread,
            span: (0..d).map(|a| now[a] / span0[a] - 1.0).collect(),
            mean_stress,
            particle_stress,
            mean_zz,
            strain: w.diagnostics().strain,
            volume,
            temperature_spread,
        }
    })
}

/// Checks a settled free block against the in-plane strain `want` (the tolerances are
/// explained at [`free_thermal_expansion_3d_grows_each_axis_by_alpha_dt_stress_free`]).
/// Returns, for the report, the worst relative error of the mean `H_aa`, of the extent, the
/// spread of H over `want`, the mean and the largest particle stress over `E alpha dT`.
fn check_free(label: &str, f: &Free, want: f64) -> [f64; 5] {
    let scale = YOUNG as f64 * thermal_strain();
    let mut worst = [0.0f64; 5];
    for (a, (&m, &s)) in f.mean_stretch.iter().zip(&f.span).enumerate() {
        worst[0] = worst[0].max((m / want - 1.0).abs());
        worst[1] = worst[1].max((s / want - 1.0).abs());
        assert!(
            (m / want - 1.0).abs() < 0.01,
            "{label}: axis {a}: mean H_aa {m:.6e}, exact {want:.6e}"
        );
        assert!(
            (s / want - 1.0).abs() < 0.03,
            "{label}: axis {a}: extent grew by {s:.6e}, exact {want:.6e}"
        );
    }
    worst[2] = f.spread / want;
    worst[3] = f.mean_stress / scale;
    worst[4] = f.particle_stress / scale;
    assert!(
        worst[2] < 0.03,
        "{label}: a particle's H is {:.3e} off the uniform stretch {want:.3e}",
        f.spread
    );
    assert!(
        worst[3] < 1e-4,
        "{label}: mean in-plane stress {:.3e} Pa = {:.2e} E alpha dT",
        f.mean_stress,
        worst[3]
    );
    assert!(
        worst[4] < 0.03,
        "{label}: particle in-plane stress {:.3e} Pa = {:.2e} E alpha dT",
        f.particle_stress,
        worst[4]
    );
    // Insulated faces and a uniform start: the temperature stays uniform (to round-off).
    assert!(
        f.temperature_spread < 1e-3,
        "{label}: grid temperature off by {} K",
        f.temperature_spread
    );
    println!(
        "{label}: mean H_aa {:?} (exact {want:.6e}): error {:.1e}; extent error {:.1e}; H \
         spread {:.1e} of it; stress {:.1e} (mean), {:.1e} (largest) of E alpha dT",
        f.mean_stretch, worst[0], worst[1], worst[2], worst[3], worst[4]
    );
    worst
}

/// 3D free thermal expansion: a block at uniform `T_0 + dT`, free on every face, settles to
/// the stress-free state `F = (1 + alpha dT) I` exactly (for both models: `F_e = I`), so each
/// axis grows by `alpha dT = 5e-3`.
///
/// Tolerances, for this test and the plane-strain one:
/// - the mean `H_aa` of each axis within 1 % of the exact stretch (measured 1e-6 in f32 and
///   f64: the settled mean is exact up to the damped residue);
/// - the volume-weighted mean of each in-plane stress component below `1e-3 E alpha dT`: at
///   rest every nodal force `f_i = -sum_p V0_p tau_p G_ip` is zero, and since
///   `sum_i G_ip (x) x_i = I`, `sum_p V0_p tau_p = -sum_i f_i (x) x_i = 0` exactly (measured
///   below 1e-5);
/// - every particle's stress below `3e-2 E alpha dT` and its H within 3 % of the uniform
///   stretch: the settled state is not exactly uniform. There are more particles than nodes, so
///   zero nodal forces leave room for a self-equilibrated stress, and the incremental
///   `F <- dF F`, with the weights' gradients taken where the particles are, locks some in
///   while the particles move (1 mm here, 2 % of a cell). It grows as d^2 (halving dT halves
///   it relative to `E alpha dT`): measured 1.7e-2 (uGIMP) and 1.8e-3 (linear) of
///   `E alpha dT`, H within 0.9 % and 0.3 %;
/// - each axis's extent (span of the particle centres) within 3 %: positions move with the
///   grid velocity at the particle, F with the velocity gradient, and near a free surface the
///   two are not consistent (a partly covered node's velocity is a mass average, not the
///   field's value at the node); measured 1.6 % (2D, 8 cells), 0.2 % (3D, 6 cells) with MUSL,
///   the same with and without the eigenstrain's part in it (independent of dT).
/// - the grid temperature at every particle within 1e-3 K of `T_0 + dT` (insulated, uniform).
#[test]
fn free_thermal_expansion_3d_grows_each_axis_by_alpha_dt_stress_free() {
    for model in MODELS {
        for shape in [ShapeFunction::Linear, ShapeFunction::Gimp] {
            let f = free_block(Dimension::ThreeD, shape, model, 300);
            check_free(
                &format!("3D free {model:?} {shape:?}"),
                &f,
                thermal_strain(),
            );
        }
    }
}

/// 2D plane strain free thermal expansion. Plane strain holds `F_zz = 1`, so the block cannot
/// expand along z. With `sigma_xx = sigma_yy = 0`, the eigenstrain `d = alpha dT` on all three
/// axes and the in-plane strain e, small-strain Hooke's law on the elastic strain `e - d`,
/// `-d` (z) reads
///   `sigma_xx = lambda (2 e - 3 d) + 2 mu (e - d) = 0`,
///   `sigma_zz = lambda (2 e - 3 d) + 2 mu (0 - d)`,
/// so `e (2 lambda + 2 mu) = d (3 lambda + 2 mu)`; with `3 lambda + 2 mu = E / (1 - 2 nu)` and
/// `lambda + mu = E / (2 (1 + nu)(1 - 2 nu))`, the in-plane strain is `e = (1 + nu) alpha dT`
/// per axis (6.5e-3 here), and `sigma_zz = lambda (2 nu - 1) d - 2 mu d = -E alpha dT`: the
/// block is stressed along z as a bar held at both ends.
/// For the corotated linear model the stretch is exact at any d: its strain is `F_e - I` with
/// `F_e = F / (1 + d)`, so `sigma_xx = 0` gives `e_e = -lambda e_zz,e / (2 (lambda + mu))
/// = nu d / (1 + d)` and the stretch `(1 + d)(1 + e_e) = 1 + (1 + nu) d`; `sigma_zz` is
/// `-E d / (1 + d)` per unit current area. For the neo-Hookean model the in-plane stretch `a` of `F_e` solves
/// `mu (a^2 - 1) + lambda ln(a^2 / (1 + d)) = 0` ([`free_plane_strain_stretch`]).
/// Tolerances: as in 3D (see there), and the volume-mean `sigma_zz` and the stored strain
/// energy `(1 + d)^3 W(F_e) V` (about `E d^2 / 2` per unit volume, in the constrained axis)
/// within 1 % of their exact values for the model (measured 3e-5 and 7e-5).
#[test]
fn free_plane_strain_expansion_is_one_plus_nu_times_alpha_dt() {
    let d = thermal_strain();
    for model in MODELS {
        let stretch = free_plane_strain_stretch(model, d);
        if model == MaterialModel::LinearElastic {
            let closed = (1.0 + POISSON as f64) * d;
            assert!((stretch - 1.0 - closed).abs() < 1e-9 * closed);
        }
        let want = stretch - 1.0;
        let (sigma, energy) = exact_state(model, [stretch, stretch, 1.0], d);
        for shape in [ShapeFunction::Linear, ShapeFunction::Gimp] {
            let f = free_block(Dimension::Plane2D, shape, model, 400);
            let label = format!("plane strain free {model:?} {shape:?}");
            check_free(&label, &f, want);
            let zz_err = (f.mean_zz / sigma[2] - 1.0).abs();
            let energy_err = (f.strain / (energy * f.volume) - 1.0).abs();
            println!(
                "{label}: exact in-plane strain {want:.6e} ((1 + nu) alpha dT {:.6e}); mean \
                 sigma_zz {:.2} Pa (exact {:.2}, -E alpha dT {:.2}): error {zz_err:.1e}; \
                 energy error {energy_err:.1e}",
                (1.0 + POISSON as f64) * d,
                f.mean_zz,
                sigma[2],
                -(YOUNG as f64) * d,
            );
            assert!(
                zz_err < 0.01,
                "{label}: sigma_zz {}, exact {}",
                f.mean_zz,
                sigma[2]
            );
            assert!(
                energy_err < 0.01,
                "{label}: strain energy {}, exact {}",
                f.strain,
                energy * f.volume
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 2, 3. Clamped block: thermal expansion and swelling
// ---------------------------------------------------------------------------------------------

/// What a clamped block measured.
struct Clamped {
    /// Largest relative error of any normal Cauchy stress component of any particle against
    /// the exact `sigma`.
    normal: f64,
    /// Largest shear Cauchy stress magnitude over `|sigma|`.
    shear: f64,
    /// Largest `|H|` entry: how far the clamped block moved.
    h: f64,
    /// `Diagnostics::strain`, J, and the initial volume.
    strain: f64,
    volume: f64,
}

/// A block filling the whole admissible region (4 cells per axis, 2 particles per cell per
/// axis) between stick walls on every face, with `fx` declared and `set` giving the
/// particles their temperature or concentration; after `steps` stable steps, its stress
/// against the exact clamped stress `sigma` (the same on every normal axis).
fn clamped_block(
    dim: Dimension,
    shape: ShapeFunction,
    material: &MaterialDef,
    fx: Effects,
    set: impl Fn(&mut World),
    sigma: f64,
    steps: usize,
) -> Clamped {
    let m = shape.margin_cells();
    let n = 4;
    let def = WorldDef {
        dimension: dim,
        cells: if dim == Dimension::ThreeD {
            [n + 2 * m; 3]
        } else {
            [n + 2 * m, n + 2 * m, 1]
        },
        cell_size: H,
        shape,
        gravity: Vec3::ZERO,
        faces: [Boundary::Stick; 6],
        particle_capacity: (2 * n).pow(3),
        effects: fx,
        ..WorldDef::DEFAULT
    };
    let (normal, shear) = normal_and_shear(dim);
    with_world(&def, |w| {
        let wall = m as Real * H;
        fill_cube(w, dim, wall, wall + n as Real * H, material);
        set(w);
        run(w, steps);
        let v = w.particles();
        let mut out = Clamped {
            normal: 0.0,
            shear: 0.0,
            h: 0.0,
            strain: w.diagnostics().strain,
            volume: v.volume0.iter().map(|&x| x as f64).sum(),
        };
        for i in 0..v.count {
            for &k in normal {
                out.normal = out.normal.max((cauchy(&v, i, k) / sigma - 1.0).abs());
            }
            for &k in shear {
                out.shear = out.shear.max((cauchy(&v, i, k) / sigma).abs());
            }
        }
        for row in v.displacement_gradient.iter() {
            for col in row.iter() {
                for &x in col.iter() {
                    out.h = out.h.max((x as f64).abs());
                }
            }
        }
        out
    })
}

/// Checks a clamped block: every normal component within 1 % of `sigma`, shear below
/// `1e-4 |sigma|`.
fn check_clamped(label: &str, c: &Clamped, sigma: f64) {
    println!(
        "{label}: sigma exact {sigma:.3} Pa: normal error {:.2e}, shear {:.2e} |sigma|, \
         |H| {:.2e}",
        c.normal, c.shear, c.h
    );
    assert!(
        c.normal < 0.01,
        "{label}: normal stress off by {:.3e}",
        c.normal
    );
    assert!(
        c.shear < 1e-4,
        "{label}: shear stress {:.3e} |sigma|",
        c.shear
    );
}

/// Clamped thermal stress: a block filling the admissible region between stick walls on every
/// face (in 2D also held along z by plane strain), at uniform `T_0 + dT`, cannot expand, so
/// `F = I` and the stress is the same on every normal axis (2D: xx, yy and zz):
/// `sigma = -E alpha dT / (1 - 2 nu) = -3 K alpha dT` in small strain (-12 500 Pa here); the
/// models' exact values at `d = 5e-3`: corotated linear `-3 K d / (1 + d)` (-12 437.8 Pa),
/// neo-Hookean `(1 + d)^3 (mu ((1 + d)^-2 - 1) - 3 lambda ln(1 + d))` ([`exact_state`]). Shear 0.
/// The uniform stress is a discrete equilibrium for every shape: with linear and uGIMP weights
/// the particles' `sum_p V_p grad S_ip` is the integral of `grad N_i` over the filled region,
/// zero at every free node; the B-splines' stencils reach past the wall planes, whose nodes
/// are the mirror images of those inside (`Geom::for_each_wall_image`), so the block meets its
/// own reflection, under the same stress, and again no free node is pushed and F stays I
/// (before the images, those nodes were zeroed and the block's stress next to the walls was
/// 15 % (quadratic) and 21 % (cubic) off).
/// Tolerance: 1 % on every normal component of every particle against the model's exact
/// value (it is exact up to round-off: measured at most 1e-6 in f32 for linear and uGIMP, 9e-6
/// for the cubic B-spline in 3D); shear below `1e-4 |sigma|`. Run for 100 steps, so that the
/// state is shown to stay, for both models and every shape.
#[test]
fn clamped_block_thermal_stress_is_minus_e_alpha_dt_over_one_minus_two_nu() {
    let d = thermal_strain();
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        for model in MODELS {
            let sigma = exact_state(model, [1.0; 3], d).0[0];
            let small = -(YOUNG as f64) * d / (1.0 - 2.0 * POISSON as f64);
            assert!((sigma / small - 1.0).abs() < 3.0 * d);
            for shape in SHAPES {
                let c = clamped_block(
                    dim,
                    shape,
                    &solid(model),
                    heat(),
                    |w| set_uniform(w, ScalarField::Temperature, T0 + HEATING),
                    sigma,
                    100,
                );
                check_clamped(&format!("clamped {dim:?} {model:?} {shape:?}"), &c, sigma);
            }
        }
    }
}

/// Swelling: the clamped block of the thermal test with diffusion declared instead and a
/// uniform concentration potential `c_0 + dc`, `beta dc = 5e-3`: the same exact stress,
/// `sigma = -E beta dc / (1 - 2 nu)` in small strain. Then both fields together
/// (`alpha dT = 2e-3`, `beta dc = 3e-3`): the eigenstrains add, `d = alpha dT + beta dc`, and
/// the stress is again that of `d = 5e-3`. Tolerances as in the thermal test.
#[test]
fn clamped_block_swelling_stress_is_minus_e_beta_dc_over_one_minus_two_nu() {
    let (beta, c0): (Real, Real) = (0.01, 0.2);
    let swelling = |model| MaterialDef {
        swelling: beta,
        reference_concentration: c0,
        thermal_expansion: 0.0,
        ..solid(model)
    };
    let diffusion = Effects {
        diffusion: Some(Transport::INSULATED),
        ..Effects::NONE
    };
    let both = Effects {
        diffusion: Some(Transport::INSULATED),
        ..heat()
    };
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        for model in MODELS {
            for shape in SHAPES {
                let dc: Real = 0.5;
                let d = beta as f64 * dc as f64;
                let sigma = exact_state(model, [1.0; 3], d).0[0];
                let c = clamped_block(
                    dim,
                    shape,
                    &swelling(model),
                    diffusion,
                    |w| set_uniform(w, ScalarField::Concentration, c0 + dc),
                    sigma,
                    100,
                );
                check_clamped(&format!("swelling {dim:?} {model:?} {shape:?}"), &c, sigma);
                // Both: alpha dT = 1e-4 x 20 K, beta dc = 0.01 x 0.3.
                let (dt, dc): (Real, Real) = (20.0, 0.3);
                let d = ALPHA as f64 * dt as f64 + beta as f64 * dc as f64;
                let sigma = exact_state(model, [1.0; 3], d).0[0];
                let material = MaterialDef {
                    thermal_expansion: ALPHA,
                    ..swelling(model)
                };
                let c = clamped_block(
                    dim,
                    shape,
                    &material,
                    both,
                    |w| {
                        set_uniform(w, ScalarField::Temperature, T0 + dt);
                        set_uniform(w, ScalarField::Concentration, c0 + dc);
                    },
                    sigma,
                    100,
                );
                check_clamped(&format!("both {dim:?} {model:?} {shape:?}"), &c, sigma);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Zero coefficients change nothing
// ---------------------------------------------------------------------------------------------

/// The mechanical state of every particle (positions, velocities, H, stress, status) as bits.
fn mechanics(w: &World) -> Vec<u64> {
    let v = w.particles();
    let mut out = Vec::new();
    let columns = v
        .position
        .iter()
        .chain(v.velocity.iter())
        .chain(v.displacement_gradient.iter().flatten())
        .chain(v.stress.iter());
    for c in columns {
        out.extend(c.iter().map(|x| x.to_bits() as u64));
    }
    out.extend(v.status.iter().map(|&s| s as u64));
    out
}

/// Index of the first difference of two states, if any.
fn first_difference(a: &[u64], b: &[u64]) -> Option<usize> {
    if a.len() != b.len() {
        return Some(a.len().min(b.len()));
    }
    a.iter().zip(b).position(|(x, y)| x != y)
}

/// A block (2D 0.3 m square, 3D 0.2 m cube) thrown at (1, -2, 0.5) m/s onto the slip floor
/// under gravity, `fx` declared, material `material`, each particle's temperature and
/// concentration from `scalars(i)` (when declared); its mechanical state after 200 steps of
/// 4e-4 s (below the stable step; the same step in every world compared).
fn thrown_block(
    dim: Dimension,
    material: &MaterialDef,
    fx: Effects,
    scalars: impl Fn(usize) -> (Real, Real),
) -> Vec<u64> {
    let mut def = free_space(dim, 12, H);
    def.faces = [Boundary::Slip; 6];
    def.gravity = WorldDef::DEFAULT.gravity;
    def.effects = fx;
    def.particle_capacity = 1000;
    with_world(&def, |w| {
        let m = w.add_material(material).unwrap();
        let (lo, hi) = if dim == Dimension::ThreeD {
            (Vec3::new(0.15, 0.1, 0.2), Vec3::new(0.35, 0.3, 0.4))
        } else {
            (Vec3::new(0.15, 0.1, 0.0), Vec3::new(0.45, 0.4, 0.0))
        };
        w.fill_box(lo, hi, m, Vec3::new(1.0, -2.0, 0.5)).unwrap();
        let n = w.particle_count();
        let (t, c): (Vec<Real>, Vec<Real>) = (0..n).map(&scalars).unzip();
        if fx.heat.is_some() {
            w.set_particle_scalar(ScalarField::Temperature, 0, &t)
                .unwrap();
        }
        if fx.diffusion.is_some() {
            w.set_particle_scalar(ScalarField::Concentration, 0, &c)
                .unwrap();
        }
        for _ in 0..200 {
            w.step(4e-4).unwrap();
        }
        assert!(all_finite(w));
        mechanics(w)
    })
}

/// Zero coefficients change nothing, bit for bit (the thrown block deforms, rotates and
/// slides on the floor, so every part of the stress update runs):
/// - heat conduction and diffusion declared with `alpha = beta = 0` and hot, non-uniform,
///   conducting temperature and concentration fields give the mechanical state of the same
///   world with neither field declared;
/// - `alpha, beta != 0` with `T = T_0` and `c = c_0` everywhere give the state of
///   `alpha = beta = 0`: the eigenstrain path runs with `d = 0` and must be the identity.
///   (`T = T_0 = 0`: only a zero field is carried through the grid without round-off, so only
///   then is `T_g->p - T_0` exactly 0; for any other `T_0` it is a few ulps of `T_0`, and
///   `d` a few ulps of `alpha T_0`, a legitimately different state.)
///
/// Both models (the neo-Hookean one runs the vectorised path, the linear one the scalar
/// path), 2D and 3D.
#[test]
fn zero_coefficients_or_reference_values_change_nothing_bit_for_bit() {
    let both = Effects {
        diffusion: Some(Transport::INSULATED),
        ..heat()
    };
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        for model in MODELS {
            let inert = MaterialDef {
                thermal_expansion: 0.0,
                swelling: 0.0,
                ..solid(model)
            };
            let expanding = MaterialDef {
                thermal_expansion: ALPHA,
                reference_temperature: 0.0,
                swelling: 0.01,
                reference_concentration: 0.0,
                ..inert
            };
            let plain = thrown_block(dim, &inert, Effects::NONE, |_| (0.0, 0.0));
            let hot = |i: usize| (T0 + 40.0 * (i % 7) as Real, 0.1 * (i % 5) as Real);
            let conducting = MaterialDef {
                conductivity: 50.0,
                diffusivity: 1e-3,
                ..inert
            };
            let with_fields = thrown_block(dim, &conducting, both, hot);
            assert_eq!(
                first_difference(&plain, &with_fields),
                None,
                "{dim:?} {model:?}: alpha = beta = 0 with the fields declared"
            );
            let at_rest = thrown_block(dim, &inert, both, |_| (0.0, 0.0));
            let at_reference = thrown_block(dim, &expanding, both, |_| (0.0, 0.0));
            assert_eq!(
                first_difference(&at_rest, &at_reference),
                None,
                "{dim:?} {model:?}: T = T_0, c = c_0"
            );
            assert_eq!(first_difference(&plain, &at_rest), None);
            // And the test can fail: the same expanding material 50 K above T_0 differs.
            let heated = thrown_block(dim, &expanding, both, |_| (50.0, 0.0));
            assert!(first_difference(&at_rest, &heated).is_some());
        }
    }
}

/// A material that does not expand is not affected by one that does: two blocks (the left
/// one expanding, the right one not, both 50 K above `T_0`) falling side by side, far enough
/// apart to share no node; the right block's state is bit for bit that of the same world where
/// neither expands (the per-particle `d = 0 x (T - T_0)` is exactly 0, also in chunks that
/// hold particles of both materials and so take the scalar path), while the left block's is
/// not.
#[test]
fn a_material_without_expansion_is_bit_for_bit_unaffected_by_one_with() {
    for model in MODELS {
        let run = |alpha_left: Real| -> (Vec<Vec<u64>>, usize) {
            let mut def = free_space(Dimension::Plane2D, 20, H);
            def.faces = [Boundary::Slip; 6];
            def.gravity = WorldDef::DEFAULT.gravity;
            def.effects = heat();
            def.particle_capacity = 1000;
            with_world(&def, |w| {
                let left = MaterialDef {
                    thermal_expansion: alpha_left,
                    ..solid(model)
                };
                let right = MaterialDef {
                    thermal_expansion: 0.0,
                    ..solid(model)
                };
                let (a, b) = (
                    w.add_material(&left).unwrap(),
                    w.add_material(&right).unwrap(),
                );
                // 12 x 11 particles: a count that is no multiple of the chunk, so one chunk
                // holds particles of both blocks.
                w.fill_box(
                    Vec3::new(0.1, 0.1, 0.0),
                    Vec3::new(0.4, 0.375, 0.0),
                    a,
                    Vec3::ZERO,
                )
                .unwrap();
                let split = w.particle_count();
                w.fill_box(
                    Vec3::new(0.6, 0.1, 0.0),
                    Vec3::new(0.9, 0.375, 0.0),
                    b,
                    Vec3::ZERO,
                )
                .unwrap();
                set_uniform(w, ScalarField::Temperature, T0 + HEATING);
                for _ in 0..200 {
                    w.step(4e-4).unwrap();
                }
                let v = w.particles();
                let cols: Vec<Vec<u64>> = v
                    .position
                    .iter()
                    .chain(v.velocity.iter())
                    .chain(v.displacement_gradient.iter().flatten())
                    .chain(v.stress.iter())
                    .map(|c| c.iter().map(|x| x.to_bits() as u64).collect())
                    .collect();
                (cols, split)
            })
        };
        let ((expanding, split), (inert, _)) = (run(ALPHA), run(0.0));
        assert!(split % 16 != 0);
        for (k, (x, y)) in expanding.iter().zip(&inert).enumerate() {
            if x.is_empty() {
                continue;
            }
            assert_eq!(
                first_difference(&x[split..], &y[split..]),
                None,
                "{model:?}: column {k} of the block that does not expand"
            );
        }
        // The left block did expand.
        assert!(first_difference(&expanding[0][..split], &inert[0][..split]).is_some());
    }
}

// ---------------------------------------------------------------------------------------------
// 5. Energy
// ---------------------------------------------------------------------------------------------

/// Energy: `Diagnostics::strain` counts the elastic part's energy only, `(1 + d)^3 W(F_e)` per
/// unit initial volume. The clamped block (`F = I`, `F_e = I / (1 + d)`) stores
/// `(1 + d)^3 W(I / (1 + d)) V`: in small strain `9/2 K d^2 V = 3/2 E d^2 V / (1 - 2 nu)`,
/// 0.75 J for the 0.2 m cube at `d = 5e-3` ([`exact_state`] gives each model's value). The
/// settled free block (`F = (1 + d) I`, `F_e = I`) stores none; an energy that counted the
/// whole F would give it about as much per unit volume as the clamped block.
/// Tolerances: the clamped block's energy within 1 % of the exact value (its state is exact up
/// to round-off: measured 1e-6); the settled free block's below 1e-4 of the clamped block's at
/// the same volume (what remains is the energy of the locked-in self-equilibrated stress
/// described at [`free_thermal_expansion_3d_grows_each_axis_by_alpha_dt_stress_free`], second
/// order in its 1.4 %: measured 5e-6).
#[test]
fn strain_energy_counts_only_the_elastic_part() {
    let d = thermal_strain();
    for model in MODELS {
        let (_, w_clamped) = exact_state(model, [1.0; 3], d);
        let small = 4.5 * bulk() * d * d;
        assert!((w_clamped / small - 1.0).abs() < 3.0 * d);
        let sigma = exact_state(model, [1.0; 3], d).0[0];
        let c = clamped_block(
            Dimension::ThreeD,
            ShapeFunction::Gimp,
            &solid(model),
            heat(),
            |w| set_uniform(w, ScalarField::Temperature, T0 + HEATING),
            sigma,
            20,
        );
        let stored = w_clamped * c.volume;
        let clamped_err = (c.strain / stored - 1.0).abs();
        let f = free_block(Dimension::ThreeD, ShapeFunction::Gimp, model, 300);
        let free_ratio = f.strain / (w_clamped * f.volume);
        println!(
            "{model:?}: clamped energy {:.6e} J (exact {stored:.6e}, error {clamped_err:.2e}); \
             free energy {:.3e} J = {free_ratio:.2e} of the clamped block's at its volume",
            c.strain, f.strain
        );
        assert!(clamped_err < 0.01, "{model:?}: clamped energy {}", c.strain);
        assert!(
            free_ratio.abs() < 1e-4,
            "{model:?}: free block energy {} = {free_ratio:.3e} of the clamped",
            f.strain
        );
    }
}
