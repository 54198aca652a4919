//! A scene that starts deformed: `World::set_displacement_gradient` gives particles an initial
//! `F = I + H` and the stress their material gives it. Each test states its exact solution and
//! tolerance.

use crate::common::*;
use mpm_gimp::{
    Boundary, Dimension, Error, Face, MaterialDef, MaterialModel, ParticleBatch, Real, Vec3, World,
    WorldDef,
};

const YOUNG: Real = 1.0e6;
const POISSON: Real = 0.3;
const DENSITY: Real = 1000.0;
const MODELS: [MaterialModel; 3] = [
    MaterialModel::NeoHookean,
    MaterialModel::LinearElastic,
    MaterialModel::FixedCorotated,
];

fn solid(model: MaterialModel) -> MaterialDef {
    MaterialDef {
        model,
        youngs_modulus: YOUNG,
        poisson_ratio: POISSON,
        density: DENSITY,
        ..MaterialDef::DEFAULT
    }
}

/// Lamé constants (lambda, mu) in f64.
fn lame() -> (f64, f64) {
    lame_of(YOUNG, POISSON)
}

/// A symmetric positive-definite `F` (so `R = I`, `U = F` in the polar decomposition), in 3D;
/// 2D worlds use its upper 2 x 2 block and, when axisymmetric, `F_33` as the hoop stretch.
const F: [[f64; 3]; 3] = [
    [1.02, 0.011, 0.005],
    [0.011, 0.985, -0.004],
    [0.005, -0.004, 1.012],
];

/// The deformation gradient a world of `dim` is given: `F` with the entries it does not read
/// replaced by the identity's.
fn f_of(dim: Dimension) -> [[f64; 3]; 3] {
    let mut f = F;
    if dim != Dimension::ThreeD {
        f[0][2] = 0.0;
        f[1][2] = 0.0;
        f[2][0] = 0.0;
        f[2][1] = 0.0;
        if dim == Dimension::Plane2D {
            f[2][2] = 1.0;
        }
    }
    f
}

fn det3(f: &[[f64; 3]; 3]) -> f64 {
    f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1])
        - f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0])
        + f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0])
}

/// The exact Kirchhoff stress and strain energy per unit reference volume of `model` at a
/// symmetric positive-definite `f` (no rotation):
/// - neo-Hookean: `tau = mu (F F^T - I) + lambda ln J I`,
///   `W = mu/2 (tr F F^T - 3) - mu ln J + lambda/2 (ln J)^2`;
/// - corotated linear: `e = U - I = F - I`, `tau = J (lambda tr e I + 2 mu e)`,
///   `W = mu e:e + lambda/2 (tr e)^2`;
/// - fixed-corotated: `tau = 2 mu (F - I) F^T + lambda (J - 1) J I` (R = I),
///   `W = mu |F - I|^2 + lambda/2 (J - 1)^2`.
fn exact(model: MaterialModel, f: &[[f64; 3]; 3]) -> ([[f64; 3]; 3], f64) {
    let (lambda, mu) = lame();
    let j = det3(f);
    let id = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
    let mut tau = [[0.0; 3]; 3];
    let w = match model {
        MaterialModel::NeoHookean => {
            let lnj = j.ln();
            let mut trb = 0.0;
            for (a, row) in tau.iter_mut().enumerate() {
                for (b, t) in row.iter_mut().enumerate() {
                    let bb: f64 = (0..3).map(|k| f[a][k] * f[b][k]).sum();
                    *t = mu * (bb - id(a, b)) + lambda * lnj * id(a, b);
                }
                trb += (0..3).map(|k| f[a][k] * f[a][k]).sum::<f64>();
            }
            0.5 * mu * (trb - 3.0) - mu * lnj + 0.5 * lambda * lnj * lnj
        }
        MaterialModel::LinearElastic => {
            let e = |a: usize, b: usize| f[a][b] - id(a, b);
            let tr = e(0, 0) + e(1, 1) + e(2, 2);
            let mut ee = 0.0;
            for (a, row) in tau.iter_mut().enumerate() {
                for (b, t) in row.iter_mut().enumerate() {
                    *t = j * (lambda * tr * id(a, b) + 2.0 * mu * e(a, b));
                    ee += e(a, b) * e(a, b);
                }
            }
            mu * ee + 0.5 * lambda * tr * tr
        }
        MaterialModel::FixedCorotated => {
            let e = |a: usize, b: usize| f[a][b] - id(a, b);
            let mut ee = 0.0;
            for (a, row) in tau.iter_mut().enumerate() {
                for (b, t) in row.iter_mut().enumerate() {
                    let efb: f64 = (0..3).map(|k| e(a, k) * f[b][k]).sum();
                    *t = 2.0 * mu * efb + lambda * (j - 1.0) * j * id(a, b);
                    ee += e(a, b) * e(a, b);
                }
            }
            mu * ee + 0.5 * lambda * (j - 1.0) * (j - 1.0)
        }
        other => unreachable!("{other:?} is not among the elastic models tested here"),
    };
    (tau, w)
}

/// The stored stress components' (row, column): 2D xx, yy, xy, zz; 3D xx, yy, zz, xy, xz, yz.
fn components(dim: Dimension) -> &'static [(usize, usize)] {
    if dim == Dimension::ThreeD {
        &[(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    } else {
        &[(0, 0), (1, 1), (0, 1), (2, 2)]
    }
}

/// The columns of `H = f - I` for `n` particles, in the setter's layout.
fn h_columns(f: &[[f64; 3]; 3], n: usize) -> [[Vec<Real>; 3]; 3] {
    core::array::from_fn(|a| {
        core::array::from_fn(|b| vec![(f[a][b] - if a == b { 1.0 } else { 0.0 }) as Real; n])
    })
}

fn slices(h: &[[Vec<Real>; 3]; 3]) -> [[&[Real]; 3]; 3] {
    core::array::from_fn(|a| core::array::from_fn(|b| h[a][b].as_slice()))
}

/// A block of 4 cells per axis away from every face.
fn block(dim: Dimension) -> (WorldDef, Vec3, Vec3) {
    let h: Real = 0.05;
    let def = free_space(dim, 12, h);
    let lo = 4.0 * h;
    let z = |v: Real| if dim == Dimension::ThreeD { v } else { 0.0 };
    (
        def,
        Vec3::new(lo, lo, z(lo)),
        Vec3::new(lo + 4.0 * h, lo + 4.0 * h, z(lo + 4.0 * h)),
    )
}

/// Every particle of a block given `F` carries the model's exact stress for `F` (Kirchhoff
/// stress over `rho0`, times `rho0`), its `J` is `det F`, and `Diagnostics::strain` is
/// `W(F) V0` summed: in 2D plane strain, axisymmetric (with the hoop stretch) and 3D, for both
/// models. Tolerance: 2e-5 of the largest stress component (f32 round-off of `H` entries of
/// order 1e-2 and of the models' arithmetic, a few ulp of 1e-2 relative each), 1e-6 on `J`,
/// 1e-4 relative on the energy (f32 sums of the per-particle energies).
#[test]
fn a_set_deformation_gives_the_exact_stress_jacobian_and_energy() {
    for dim in [
        Dimension::Plane2D,
        Dimension::Axisymmetric2D,
        Dimension::ThreeD,
    ] {
        for model in MODELS {
            let (mut def, lo, hi) = block(dim);
            if dim == Dimension::Axisymmetric2D {
                def.origin = Vec3::new(
                    -(def.shape.margin_cells() as Real) * def.cell_size,
                    0.0,
                    0.0,
                );
                def.faces[Face::XMin as usize] = Boundary::Slip;
            }
            let mut buf = buffer_for(&def);
            let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
            let m = w.add_material(&solid(model)).unwrap();
            let ids = w.fill_box(lo, hi, m, Vec3::ZERO).unwrap();
            let n = (ids.end - ids.start) as usize;
            let f = f_of(dim);
            let h = h_columns(&f, n);
            w.set_displacement_gradient(ids.start, slices(&h)).unwrap();
            let (tau, energy) = exact(model, &f);
            let scale = tau.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            let v = w.particles();
            let mut volume = 0.0;
            for i in 0..n {
                for (k, &(a, b)) in components(dim).iter().enumerate() {
                    let got = v.stress[k][i] as f64 * DENSITY as f64;
                    assert!(
                        (got - tau[a][b]).abs() < 2.0e-5 * scale,
                        "{dim:?} {model:?} particle {i} component {a}{b}: {got} vs {}",
                        tau[a][b]
                    );
                }
                assert!(
                    (v.jacobian(i) as f64 - det3(&f)).abs() < 1.0e-6,
                    "{dim:?} J"
                );
                volume += v.volume0[i] as f64;
            }
            let strain = w.diagnostics().strain;
            assert!(
                (strain - energy * volume).abs() < 1.0e-4 * energy * volume,
                "{dim:?} {model:?}: energy {strain} vs {}",
                energy * volume
            );
        }
    }
}

/// A bar pre-stretched along x (`F = diag(1 + e0, 1)`, `e0 = 1e-3`), at rest, between slip
/// walls in y (uniaxial strain) and free at both ends, is released. Until the release waves
/// from the ends meet at the middle (`t < L / 2c`), the stress across the middle stays the
/// initial `sigma_xx`, so the right half's momentum is exactly `-sigma_xx A t` (A the height,
/// per unit thickness) and the left half's `+sigma_xx A t`; checked at `t = L / 4c`. The method
/// keeps this exactly too: where the stress is uniform the nodes' internal forces cancel, and
/// the unbalanced forces at each end sum to `sigma_xx A` (the shape functions' partition of
/// unity), as long as the smeared release front has not reached the middle (it has a quarter
/// of the bar to go). So the tolerance is round-off: 1e-4 relative (seen: 1e-6 in f32), and the
/// total momentum stays 0 to 1e-4 of either half's.
#[test]
fn a_prestretched_bar_released_gains_the_exact_momentum() {
    let h: Real = 0.02;
    let cells: u32 = 80;
    let e0: f64 = 1.0e-3;
    for model in MODELS {
        let shape = WorldDef::DEFAULT.shape;
        let mg = shape.margin_cells();
        let mut def = WorldDef {
            dimension: Dimension::Plane2D,
            cells: [cells + 2 * mg + 10, 4 + 2 * mg, 1],
            cell_size: h,
            gravity: Vec3::ZERO,
            faces: [Boundary::Slip; 6],
            particle_capacity: 4 * cells * 4,
            ..WorldDef::DEFAULT
        };
        def.faces[Face::XMin as usize] = Boundary::Open;
        def.faces[Face::XMax as usize] = Boundary::Open;
        let mut buf = buffer_for(&def);
        let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
        let mat = w.add_material(&solid(model)).unwrap();
        // Particles 2 x 2 per reference cell, placed in the stretched configuration.
        let d = h / 2.0;
        let wall = mg as Real * h;
        let x0 = wall + 5.0 * h;
        let (mut x, mut y, mut right) = (vec![], vec![], vec![]);
        for j in 0..8 {
            for i in 0..2 * cells {
                x.push(x0 + ((i as f64 + 0.5) * d as f64 * (1.0 + e0)) as Real);
                y.push(wall + (j as Real + 0.5) * d);
                right.push(i >= cells);
            }
        }
        let n = x.len();
        let zeros = vec![0.0; n];
        w.add_particles(&ParticleBatch {
            position: [&x, &y, &[]],
            velocity: [&zeros, &zeros, &[]],
            mass: &vec![DENSITY * d * d; n],
            volume: &vec![d * d; n],
            material: &vec![mat; n],
        })
        .unwrap();
        let mut f = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        f[0][0] += e0;
        let hc = h_columns(&f, n);
        w.set_displacement_gradient(0, slices(&hc)).unwrap();
        let (lambda, mu) = lame();
        let c = ((lambda + 2.0 * mu) / DENSITY as f64).sqrt();
        let length = 2.0 * cells as f64 * d as f64 * (1.0 + e0);
        let height = 8.0 * d as f64;
        let sigma_xx = exact(model, &f).0[0][0] / (1.0 + e0);
        let dt = w.stable_dt();
        let steps = (length / (4.0 * c) / dt as f64).round() as usize;
        for _ in 0..steps {
            w.step(dt).unwrap();
        }
        let t = steps as f64 * dt as f64;
        let v = w.particles();
        let (mut p_right, mut p_left) = (0.0, 0.0);
        for (i, &right) in right.iter().enumerate() {
            let p = v.mass[i] as f64 * v.velocity[0][i] as f64;
            if right {
                p_right += p;
            } else {
                p_left += p;
            }
        }
        let want = sigma_xx * height * t;
        assert!(
            (p_right + want).abs() < 1.0e-4 * want && (p_left - want).abs() < 1.0e-4 * want,
            "{model:?}: right {p_right}, left {p_left}, exact -/+ {want}"
        );
        assert!((p_right + p_left).abs() < 1.0e-4 * want, "{model:?}: total");
    }
}

/// An `H` that is not finite, inverts `F`, leaves the volume band, or is given for particles
/// that do not exist or with columns of different lengths is refused with its error, and the
/// world's bytes stay as they were.
#[test]
fn a_bad_displacement_gradient_is_refused_and_changes_nothing() {
    for dim in [Dimension::Plane2D, Dimension::ThreeD] {
        let (def, lo, hi) = block(dim);
        let mut buf = buffer_for(&def);
        let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
        let m = w.add_material(&solid(MaterialModel::NeoHookean)).unwrap();
        let ids = w.fill_box(lo, hi, m, Vec3::ZERO).unwrap();
        let n = (ids.end - ids.start) as usize;
        let before = w.state_bytes().to_vec();
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let with = |a: usize, b: usize, value: f64| {
            let mut f = identity;
            f[a][b] = value;
            h_columns(&f, n)
        };
        let mut nan = with(0, 1, 0.0);
        nan[0][1][n / 2] = Real::NAN;
        let cases = [
            (with(0, 0, -1.0), Error::InvalidDeformation), // F_xx = -1: inverted
            (with(1, 1, 0.0), Error::InvalidDeformation),  // det F = 0
            (with(0, 0, 1000.0), Error::InvalidDeformation), // J past max_volume_ratio
            (nan, Error::InvalidDeformation),
        ];
        for (h, err) in cases {
            assert_eq!(
                w.set_displacement_gradient(0, slices(&h)),
                Err(err),
                "{dim:?}"
            );
            assert!(w.state_bytes() == before.as_slice(), "{dim:?}: changed");
        }
        let h = with(0, 0, 1.01);
        assert_eq!(
            w.set_displacement_gradient(1, slices(&h)),
            Err(Error::UnknownParticle)
        );
        let mut short = with(0, 0, 1.01);
        short[1][1].pop();
        assert_eq!(
            w.set_displacement_gradient(0, slices(&short)),
            Err(Error::LengthMismatch)
        );
        assert!(w.state_bytes() == before.as_slice(), "{dim:?}: changed");
    }
}
