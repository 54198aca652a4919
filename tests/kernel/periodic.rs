//! Periodic faces (E95): material that leaves through one face comes back through the other,
//! and the nodes past each face's plane are the images of the nodes one period on. Each test
//! states its exact answer and its tolerance.

use crate::common::*;
use mpm_gimp::{
    Boundary, Dimension, MaterialDef, MaterialModel, ParticleBatch, Real, ShapeFunction, Transfer,
    Vec3, World, WorldDef,
};

/// A box periodic on every axis, `cells[a]` cells of `h` inside its faces' planes along each,
/// the planes' lowest corner at the origin.
fn periodic_box(dim: Dimension, shape: ShapeFunction, cells: [u32; 3], h: Real) -> WorldDef {
    let m = shape.margin_cells();
    let d = if dim == Dimension::ThreeD { 3 } else { 2 };
    let mut def = WorldDef {
        dimension: dim,
        shape,
        cells: core::array::from_fn(|a| if a < d { cells[a] + 2 * m } else { 1 }),
        cell_size: h,
        origin: Vec3::splat(-(m as Real) * h),
        gravity: Vec3::ZERO,
        faces: [Boundary::Periodic; 6],
        particle_capacity: 8 * cells.iter().product::<u32>(),
        ..WorldDef::DEFAULT
    };
    if d == 2 {
        def.origin.z = 0.0;
    }
    def
}

/// Fills the periodic box of `def` at 2 particles per cell per axis, moving at `v(x)`.
fn fill(
    world: &mut World,
    def: &WorldDef,
    material: &MaterialDef,
    v: impl Fn([Real; 3]) -> [Real; 3],
) {
    let mat = world.add_material(material).unwrap();
    let d = def.axes();
    let m = def.shape.margin_cells();
    let spacing = def.cell_size / 2.0;
    let sites = core::array::from_fn(|a| {
        if a < d {
            2 * (def.cells[a] - 2 * m) as usize
        } else {
            1
        }
    });
    let mut cols: [Vec<Real>; 6] = Default::default();
    box_lattice(&mut cols, d, [0.0; 3], sites, spacing, v);
    let count = cols[0].len();
    let vol = spacing.powi(d as i32);
    world
        .add_particles(&ParticleBatch {
            position: [&cols[0], &cols[1], &cols[2]],
            velocity: [&cols[3], &cols[4], &cols[5]],
            mass: &vec![material.density * vol; count],
            volume: &vec![vol; count],
            material: &vec![mat; count],
        })
        .unwrap();
}

/// Total momentum per axis and the momentum scale `sum m |v|`, in f64.
fn momentum(world: &World) -> ([f64; 3], f64) {
    let v = world.particles();
    let mut p = [0.0; 3];
    let mut scale = 0.0;
    for i in 0..v.count {
        let m = v.mass[i] as f64;
        for (a, p) in p.iter_mut().enumerate().take(world.def().axes()) {
            *p += m * v.velocity[a][i] as f64;
            scale += m * (v.velocity[a][i] as f64).abs();
        }
    }
    (p, scale)
}

/// A standing shear wave `v_y = V sin(k (x - U t)) cos(omega t)` in an elastic body that fills
/// a box periodic on every axis and drifts along x at U (and along z at U/2 in 3D), so that
/// every particle crosses the x faces' planes. Exact answers:
/// - the total momentum is constant: there is no wall, and the images carry what the
///   particles put past the planes to the nodes inside (`sum_i f_i = 0` over the period), so
///   it changes only by round-off, bound `1e-6 sum m |v|` (f32 round-off of the grid sums over
///   the run, as in `conservation`);
/// - every particle is at its start plus the drift, brought back into the period, within
///   the wave's own displacement `V / omega` (about 3e-4 m);
/// - the wave's amplitude first crosses zero at a quarter period, `t = pi / (2 c_s k)` with
///   `c_s = sqrt(mu / rho)`, the particles' velocities taken as the mid-step's (the explicit
///   update is symplectic Euler), within 1.5 % at 32 cells a wavelength: the grid's
///   dispersion, second order in `k h` (measured with uGIMP and FLIP: 0.66 %, 0.15 % and
///   0.03 % at 32, 64 and 128 cells; 1.2 % with the cubic B-spline).
#[test]
fn shear_wave_crosses_periodic_faces_with_exact_momentum() {
    let material = MaterialDef {
        model: MaterialModel::LinearElastic,
        youngs_modulus: 1.0e5,
        poisson_ratio: 0.3,
        density: 1000.0,
        ..MaterialDef::DEFAULT
    };
    let (_, mu) = lame_of(material.youngs_modulus, material.poisson_ratio);
    let c_s = (mu / material.density as f64).sqrt();
    let pi = std::f64::consts::PI;
    let k = 2.0 * pi; // One wavelength over the 1 m period.
    let omega = c_s * k;
    let (amp, drift) = (0.01, 2.0);
    let mut transfers = vec![Transfer::Flip];
    if cfg!(feature = "effects") {
        transfers.push(Transfer::Apic);
    }
    for (dim, shape, cells) in [
        (Dimension::Plane2D, ShapeFunction::Gimp, [32, 4, 1]),
        (Dimension::Plane2D, ShapeFunction::CubicBspline, [32, 8, 1]),
        (Dimension::ThreeD, ShapeFunction::Gimp, [32, 4, 4]),
    ] {
        for &transfer in &transfers {
            let h = 1.0 / cells[0] as Real;
            let def = WorldDef {
                transfer,
                ..periodic_box(dim, shape, cells, h)
            };
            let mut buf = buffer_for(&def);
            let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
            let drift_z = if dim == Dimension::ThreeD {
                drift / 2.0
            } else {
                0.0
            };
            fill(&mut world, &def, &material, |x| {
                let vy = amp * (k * x[0] as f64).sin();
                [drift as Real, vy as Real, drift_z as Real]
            });
            let start = world.particles().position.map(|c| c.to_vec());
            let (p0, _) = momentum(&world);
            let label = format!("{dim:?} {shape:?} {transfer:?}");
            // The wave's amplitude, its projection on the drifting mode.
            let amplitude = |w: &World| {
                let v = w.particles();
                let t = w.time();
                let (mut num, mut den) = (0.0, 0.0);
                for i in 0..v.count {
                    let s = (k * (v.position[0][i] as f64 - drift * t)).sin();
                    num += v.mass[i] as f64 * v.velocity[1][i] as f64 * s;
                    den += v.mass[i] as f64 * s * s;
                }
                num / den
            };
            let quarter = pi / (2.0 * omega);
            let dt = (quarter / 40.0).min(world.stable_dt() as f64) as Real;
            let (mut before, mut t_before) = (amplitude(&world), 0.0);
            let mut crossing = None;
            while world.time() < 1.5 * quarter {
                let report = world.step(dt).unwrap();
                assert_eq!(
                    report.escaped + report.frozen + report.stopped,
                    0,
                    "{label}"
                );
                let (p, scale) = momentum(&world);
                for a in 0..def.axes() {
                    assert!(
                        (p[a] - p0[a]).abs() <= 1.0e-6 * scale,
                        "{label}: momentum {a} moved from {} to {} (scale {scale})",
                        p0[a],
                        p[a]
                    );
                }
                // The explicit update's velocity is the mid-step one (symplectic Euler).
                let (now, t) = (amplitude(&world), world.time() - 0.5 * dt as f64);
                if crossing.is_none() && before > 0.0 && now <= 0.0 {
                    crossing = Some(t_before + (t - t_before) * before / (before - now));
                }
                (before, t_before) = (now, t);
            }
            let crossing = crossing.unwrap_or_else(|| panic!("{label}: the wave never turned"));
            let error = (crossing / quarter - 1.0).abs();
            eprintln!(
                "{label}: quarter period {crossing:.5} s against {quarter:.5} s ({error:.4})"
            );
            assert!(
                error < 0.015,
                "{label}: quarter period {crossing} s, exact {quarter} s"
            );
            // Every particle drifted and came back into the period.
            let v = world.particles();
            let t = world.time();
            let period = |a: usize| cells[a] as f64 * h as f64;
            let shift = [drift * t, 0.0, drift_z * t];
            let mut worst: f64 = 0.0;
            for a in 0..def.axes() {
                for (&from, &got) in start[a].iter().zip(v.position[a]) {
                    let want = (from as f64 + shift[a]).rem_euclid(period(a));
                    let d = (got as f64 - want).abs();
                    worst = worst.max(d.min(period(a) - d));
                }
            }
            assert!(
                worst < 1.0e-3,
                "{label}: a particle is {worst} m off its drift"
            );
        }
    }
}

/// Sound in a fluid with a bulk viscosity: in the weakly compressible fluid filling a box
/// periodic on every axis (K = 1e5 Pa, 1000 kg/m^3: c = 10 m/s, 1 m along x), the standing
/// wave `v_x = V sin(k x)`, `k = 2 pi`, loses its energy as `exp(-2 alpha t)` with
/// `alpha = (zeta + 4 eta / 3) k^2 / (2 rho)` (E46; the acoustic damping of a viscous fluid,
/// for `alpha` well below `c k`). With `zeta = 40 Pa s` and no shear viscosity, `alpha =
/// 0.79 / s` over 2 s (20 periods). The rate the bulk viscosity adds, the run's less the same
/// run's without it (the transfer's own losses), is within 3 % of `alpha` at 64 cells a
/// wavelength, the grid's error being second order in `k h` (measured with uGIMP in f32:
/// 0.24 % and 0.38 % in 2D, 1.1 % and 0.58 % in 3D, FLIP and APIC; 0.1 % to 0.33 % in f64).
#[test]
fn a_bulk_viscosity_damps_sound_at_the_exact_rate() {
    let (zeta, rho) = (40.0, 1000.0);
    let k = 2.0 * std::f64::consts::PI;
    let alpha = zeta * k * k / (2.0 * rho);
    let mut transfers = vec![Transfer::Flip];
    if cfg!(feature = "effects") {
        transfers.push(Transfer::Apic);
    }
    for (dim, cells) in [
        (Dimension::Plane2D, [64, 2, 1]),
        (Dimension::ThreeD, [64, 2, 2]),
    ] {
        for &transfer in &transfers {
            let label = format!("{dim:?} {transfer:?}");
            let h = 1.0 / cells[0] as Real;
            let def = WorldDef {
                transfer,
                ..periodic_box(dim, ShapeFunction::Gimp, cells, h)
            };
            // The energy's decay rate over `seconds`, with bulk viscosity `zeta`.
            let rate = |zeta: Real| {
                let material = MaterialDef {
                    model: MaterialModel::Fluid,
                    density: rho as Real,
                    bulk_modulus: 1.0e5,
                    bulk_viscosity: zeta,
                    ..MaterialDef::DEFAULT
                };
                let mut buf = buffer_for(&def);
                let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
                fill(&mut world, &def, &material, |x| {
                    [(0.01 * (k * x[0] as f64).sin()) as Real, 0.0, 0.0]
                });
                let e0 = world.diagnostics().total_energy();
                while world.time() < 2.0 {
                    let report = world.step(0.01).unwrap();
                    assert_eq!(report.frozen + report.stopped, 0, "{label}");
                }
                let e = world.diagnostics().total_energy();
                -(e / e0).ln() / (2.0 * world.time())
            };
            let (with, without) = (rate(zeta as Real), rate(0.0));
            let error = ((with - without) / alpha - 1.0).abs();
            eprintln!("{label}: rate {with:.4} - {without:.4} / s against {alpha:.4} ({error:.4})");
            assert!(
                error < 0.03,
                "{label}: the bulk viscosity damps at {} / s, exact {alpha}",
                with - without
            );
        }
    }
}

/// The PIC share is a rate in time (E22): a velocity the grid cannot carry decays at
/// `pic_rate` per second whatever the substep. Particles at rest but for a velocity
/// `+-v0` along x that alternates from one particle plane to the next fill a box periodic on
/// every axis: every node sits between planes of opposite velocity at mirrored weights, so
/// its momentum is zero (to round-off), no material deforms, and each substep only blends
/// the particle velocity toward the grid's zero. Exact answers after time `t`:
/// - `flip_beta` 1, `pic_rate` 30/s: `v = v0 exp(-30 t)`, to `1e-5` relative, whether `t` is
///   stepped in 4 or 16 calls;
/// - `flip_beta` 0.99, `pic_rate` 0 (a share per substep): `v = v0 0.99^n` after `n` substeps,
///   which changes with the substep.
///
/// Plane strain and 3D, every shape function, FLIP and its particle-velocity variant.
#[test]
fn the_pic_share_decays_grid_noise_at_its_rate_whatever_the_substep() {
    let t = 0.02;
    for (dim, cells) in [
        (Dimension::Plane2D, [8, 8, 1]),
        (Dimension::ThreeD, [4, 4, 4]),
    ] {
        for shape in SHAPES {
            for transfer in [Transfer::Flip, Transfer::FlipParticleVelocity] {
                for (beta, rate) in [(1.0, 30.0), (0.99, 0.0)] {
                    for calls in [4, 16] {
                        let label = format!(
                            "{dim:?} {shape:?} {transfer:?} beta {beta} rate {rate}, {calls} calls"
                        );
                        let def = WorldDef {
                            transfer,
                            flip_beta: beta,
                            pic_rate: rate,
                            ..periodic_box(dim, shape, cells, 1.0 / 8.0)
                        };
                        let mut buf = buffer_for(&def);
                        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
                        let v0: Real = 0.01;
                        let h = def.cell_size;
                        fill(&mut world, &def, &MaterialDef::DEFAULT, |x| {
                            let plane = (x[0] / (h / 2.0)).floor() as i64;
                            [if plane % 2 == 0 { v0 } else { -v0 }, 0.0, 0.0]
                        });
                        let mut substeps = 0;
                        for _ in 0..calls {
                            substeps += world.step((t / calls as f64) as Real).unwrap().substeps;
                        }
                        let expected = if rate > 0.0 {
                            (-(rate as f64) * t).exp()
                        } else {
                            (beta as f64).powi(substeps as i32)
                        };
                        let p = world.particles();
                        for i in 0..p.count {
                            let ratio = (p.velocity[0][i] / v0).abs() as f64;
                            assert!(
                                (ratio / expected - 1.0).abs() < 1.0e-5,
                                "{label}: particle {i} keeps {ratio} of its velocity, exact {expected}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A crowded fluid relaxes its volume at its stated rate (E97). A fluid at rest fills a box
/// periodic on every axis at 2 particles per cell per axis, each particle's `J` set to `J0`:
/// every node's fill is `J0` exactly (the particles' weights sum to 1 and the lattice is the
/// same seen from every node), the uniform pressure puts no force on any node, so the only
/// change is the relaxation. Exact answers after a step of `n` substeps of `dt`, with rate `k`:
/// - `J0 = 1.1`, a crowd: `J = c (J0 / c)^((1 - k dt)^n)`, `c = 1 + 1e-4` the least crowd
///   relaxed, every particle, to `1e-5` (f32's round-off
///   through `ln`, `exp` and the stress);
/// - `J0 = 0.9`, a fill below 1 (which the relaxation takes for a surface, not a void):
///   `J = J0`, and with `k = 0`, `J0 = 1.1` stays.
///
/// Plane strain and 3D, every shape function, FLIP and APIC.
#[test]
fn a_crowded_fluid_relaxes_its_volume_at_its_rate() {
    let mut transfers = vec![Transfer::Flip];
    if cfg!(feature = "effects") {
        transfers.push(Transfer::Apic);
    }
    let dt: Real = 5.0e-4;
    for (dim, cells) in [
        (Dimension::Plane2D, [8, 8, 1]),
        (Dimension::ThreeD, [4, 4, 4]),
    ] {
        for shape in SHAPES {
            for &transfer in &transfers {
                for (j0, k) in [(1.1, 20.0), (1.1, 0.0), (0.9, 20.0)] {
                    let label = format!("{dim:?} {shape:?} {transfer:?} J0 {j0} k {k}");
                    let def = WorldDef {
                        transfer,
                        ..periodic_box(dim, shape, cells, 1.0 / 8.0)
                    };
                    let material = MaterialDef {
                        model: MaterialModel::Fluid,
                        volume_relaxation: k,
                        ..MaterialDef::DEFAULT
                    };
                    let mut buf = buffer_for(&def);
                    let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
                    fill(&mut world, &def, &material, |_| [0.0; 3]);
                    let (n, d) = (world.particles().count, def.axes());
                    let e = (j0 as f64).powf(1.0 / d as f64) as Real - 1.0;
                    let (diagonal, zero) = (vec![e; n], vec![0.0; n]);
                    let none: Vec<Real> = Vec::new();
                    let h: [[&[Real]; 3]; 3] = core::array::from_fn(|a| {
                        core::array::from_fn(|b| {
                            if a >= d || b >= d {
                                &none[..]
                            } else if a == b {
                                &diagonal[..]
                            } else {
                                &zero[..]
                            }
                        })
                    });
                    world.set_displacement_gradient(0, h).unwrap();
                    let report = world.step(dt).unwrap();
                    let substeps = report.substeps as i32;
                    let expected = if j0 > 1.0 && k > 0.0 {
                        let c = 1.0 + 1.0e-4;
                        c * (j0 as f64 / c)
                            .powf((1.0 - k as f64 * dt as f64 / substeps as f64).powi(substeps))
                    } else {
                        j0 as f64
                    };
                    let p = world.particles();
                    for i in 0..n {
                        let hh = |a: usize, b: usize| p.displacement_gradient[a][b][i] as f64;
                        let f: [[f64; 3]; 3] = core::array::from_fn(|a| {
                            core::array::from_fn(|b| {
                                if a < d && b < d {
                                    hh(a, b) + if a == b { 1.0 } else { 0.0 }
                                } else if a == b {
                                    1.0
                                } else {
                                    0.0
                                }
                            })
                        });
                        let j = f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1])
                            - f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0])
                            + f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0]);
                        assert!(
                            (j / expected - 1.0).abs() < 1.0e-5,
                            "{label}: particle {i} has J {j}, exact {expected}"
                        );
                    }
                }
            }
        }
    }
}

/// Heat across periodic faces: in a conductor at rest that fills a box periodic on every axis
/// (diffusivity `kappa = 0.1 m^2/s`, 1 m along x), the mode `T = 300 + 10 sin(k x)` with
/// `k = 2 pi` decays as `exp(-kappa k^2 t)`. Exact answers:
/// - at `t = 1 / (kappa k^2)` the particles' temperatures match the decayed mode within 1.5 %
///   of its amplitude (RMS) at 32 cells a wavelength: the error is second order in `k h`
///   (measured 0.57 % with uGIMP and 1.25 % with the quadratic B-spline, whose wider stencil
///   smooths more, each a quarter of that at 64 cells);
/// - the heat `sum m C T` is constant to round-off (`sum_i Q_i = 0` with no face: the images
///   take what the particles put past the planes), bound `1e-6` of it (f32).
#[cfg(feature = "effects")]
#[test]
fn heat_crosses_periodic_faces() {
    use mpm_gimp::{Effects, ScalarField, Transport};
    let kappa = 0.1;
    let material = conductor(kappa as Real);
    let pi = std::f64::consts::PI;
    let k = 2.0 * pi;
    for (dim, shape, cells) in [
        (Dimension::Plane2D, ShapeFunction::Gimp, [32, 4, 1]),
        (
            Dimension::Plane2D,
            ShapeFunction::QuadraticBspline,
            [32, 4, 1],
        ),
        (Dimension::ThreeD, ShapeFunction::Gimp, [32, 4, 4]),
    ] {
        let def = WorldDef {
            effects: Effects {
                heat: Some(Transport::INSULATED),
                ..Effects::NONE
            },
            ..periodic_box(dim, shape, cells, 1.0 / cells[0] as Real)
        };
        let mut buf = buffer_for(&def);
        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
        fill(&mut world, &def, &material, |_| [0.0; 3]);
        let x: Vec<f64> = world.particles().position[0]
            .iter()
            .map(|&x| x as f64)
            .collect();
        let t0: Vec<Real> = x
            .iter()
            .map(|x| (300.0 + 10.0 * (k * x).sin()) as Real)
            .collect();
        world
            .set_particle_scalar(ScalarField::Temperature, 0, &t0)
            .unwrap();
        let heat = |w: &World| {
            let v = w.particles();
            (0..v.count)
                .map(|i| v.mass[i] as f64 * v.temperature[i] as f64)
                .sum::<f64>()
        };
        let h0 = heat(&world);
        let t_end = 1.0 / (kappa * k * k);
        let steps = (t_end / world.stable_dt() as f64).ceil() as usize;
        let dt = (t_end / steps as f64) as Real;
        let label = format!("{dim:?} {shape:?}");
        for _ in 0..steps {
            world.step(dt).unwrap();
            let h = heat(&world);
            assert!(
                (h - h0).abs() <= 1.0e-6 * h0,
                "{label}: heat {h0} became {h}"
            );
        }
        let decay = (-kappa * k * k * world.time()).exp();
        let v = world.particles();
        let err2 = (0..v.count)
            .map(|i| {
                let exact = 300.0 + 10.0 * (k * x[i]).sin() * decay;
                (v.temperature[i] as f64 - exact).powi(2)
            })
            .sum::<f64>()
            / v.count as f64;
        let error = err2.sqrt() / (10.0 * decay);
        eprintln!("{label}: RMS error {error:.4} of the amplitude");
        assert!(
            error < 0.015,
            "{label}: RMS error {error} of the decayed amplitude"
        );
    }
}

/// What a periodic axis cannot be, refused by `memory_requirements` (and so by `init`): a
/// periodic face whose opposite face is not periodic, the axisymmetric radial axis, a wall
/// friction or velocity on a periodic face, a heat or diffusion condition other than
/// insulated there (each `InvalidBoundary`). The smallest axis any face takes, `2 + 2 margin`
/// cells, is periodic too.
#[test]
fn periodic_faces_refuse_what_they_cannot_be() {
    use mpm_gimp::{memory_requirements, Error, Face};
    let good = periodic_box(
        Dimension::Plane2D,
        ShapeFunction::CubicBspline,
        [8, 8, 1],
        0.1,
    );
    assert!(memory_requirements(&good).is_ok());
    let refused = |change: &dyn Fn(&mut WorldDef), want: Error| {
        let mut def = good;
        change(&mut def);
        assert_eq!(memory_requirements(&def).err(), Some(want), "{def:?}");
    };
    refused(
        &|d| d.faces[Face::XMax as usize] = Boundary::Slip,
        Error::InvalidBoundary,
    );
    refused(
        &|d| d.faces[Face::YMin as usize] = Boundary::Open,
        Error::InvalidBoundary,
    );
    refused(
        &|d| d.wall_friction[Face::XMin as usize] = 0.3,
        Error::InvalidBoundary,
    );
    refused(
        &|d| d.wall_velocity[Face::YMax as usize] = Vec3::X,
        Error::InvalidBoundary,
    );
    refused(&|d| d.cells[1] = 3, Error::InvalidCellCount);
    let mut smallest = good;
    smallest.cells[1] = 4;
    assert!(memory_requirements(&smallest).is_ok());
    #[cfg(feature = "effects")]
    {
        use mpm_gimp::{ScalarBoundary, Transport};
        let mut heat = Transport::INSULATED;
        heat.faces[Face::XMin as usize] = ScalarBoundary::Fixed(300.0);
        refused(&|d| d.effects.heat = Some(heat), Error::InvalidBoundary);
        refused(
            &|d| d.effects.diffusion = Some(heat),
            Error::InvalidBoundary,
        );
        // The axis r = 0 on the lower x face's wall plane, as `periodic_box` puts it.
        refused(
            &|d| d.dimension = Dimension::Axisymmetric2D,
            Error::InvalidBoundary,
        );
        let mut axial = good;
        axial.dimension = Dimension::Axisymmetric2D;
        axial.faces[Face::XMin as usize] = Boundary::Slip;
        axial.faces[Face::XMax as usize] = Boundary::Slip;
        assert!(memory_requirements(&axial).is_ok());
    }
}
