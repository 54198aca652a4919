//! Stiffness for a substep budget: the modulus that lets a material run in a chosen number of
//! substeps a frame.
//!
//! The kernel's stable step is `dt = cfl h / (c_max + |v|_max)` (E88 of `docs/equations.md`;
//! `cfl` is [`WorldDef::cfl`], `h` the cell size), and a frame of `frame_dt` takes
//! `n = ceil(frame_dt / dt)` substeps (E89). A material's dilatational wave speed is
//! `c = sqrt(M / rho)` ([`MaterialDef::wave_speed`]), with `M` its P-wave modulus: `K + 4G/3`
//! for a solid, `E (1 - nu) / ((1 + nu) (1 - 2 nu))` in terms of Young's modulus and Poisson's
//! ratio, and the bulk modulus `K` for the fluid. So a frame costs
//!
//! ```text
//! n = ceil(frame_dt (sqrt(M / rho) + v_max) / (cfl h))
//! ```
//!
//! substeps, and the stiffest material that `n` substeps carry has
//!
//! ```text
//! M = rho (cfl h n / frame_dt - v_max)^2
//! ```
//!
//! Stiffness is a knob: for a slow scene, halving the substeps quarters `M`. What softer
//! material costs is compression: under gravity a column of height `H` is compressed by about
//! `rho g H / M` at its foot (`rho g H / K` for a fluid), and an impact at speed `v` squeezes
//! it by about `v / c`.
//!
//! ```
//! use mpm_gimp::{MaterialDef, WorldDef};
//! use mpm_gimp_output::stiffness::{modulus_for_substeps, substeps_per_frame, youngs_modulus};
//!
//! let def = WorldDef { cells: [40, 40, 1], cell_size: 0.025, ..WorldDef::DEFAULT };
//! // Rubber of 1000 kg/m^3 in 16 substeps a 1/60 s frame, moving at up to 3 m/s:
//! let m = modulus_for_substeps(&def, 1000.0, 1.0 / 60.0, 16, 3.0);
//! let rubber = MaterialDef { youngs_modulus: youngs_modulus(m, 0.3), ..MaterialDef::DEFAULT };
//! assert!((rubber.youngs_modulus - 6.0e4).abs() < 1.0e3); // E = 60 kPa
//! assert_eq!(substeps_per_frame(&def, &rubber, 1.0 / 60.0, 3.0), 16);
//! ```
//!
//! These cover the wave limit only: damping, conduction, diffusion and viscosity bound the step
//! too (E88), and snow stiffens as it compacts (its hardened wave speed sets the step).

use mpm_gimp::{MaterialDef, Real, WorldDef};

/// How far below the exact budget [`modulus_for_substeps`] aims its wave speed (0.1 %), so that
/// rounding of the stored wave speed and of `frame_dt / dt` does not tip a frame into one
/// substep more.
const MARGIN: f64 = 1.0e-3;

/// The P-wave modulus `M` (Pa) of the stiffest material of `density` (kg/m^3) that a world of
/// `def` steps in `substeps` substeps per frame of `frame_dt` (s) while no particle moves faster
/// than `max_speed` (m/s): `M = rho (cfl h n / frame_dt - v_max)^2`, its wave speed 0.1 % under
/// the budget's. For a solid, [`youngs_modulus`] turns it into `E`; for the fluid it is the bulk
/// modulus. 0 when `max_speed` alone uses up the budget (`cfl h n / frame_dt <= v_max`): no
/// material fits, more substeps are needed.
pub fn modulus_for_substeps(
    def: &WorldDef,
    density: Real,
    frame_dt: Real,
    substeps: u32,
    max_speed: Real,
) -> Real {
    let budget = def.cfl as f64 * def.cell_size as f64 * substeps as f64 / frame_dt as f64;
    let c = (budget * (1.0 - MARGIN) - max_speed as f64).max(0.0);
    (density as f64 * c * c) as Real
}

/// The bulk modulus `K = rho (ratio v_max)^2` (Pa) of a weakly compressible fluid of `density`
/// (kg/m^3) whose sound speed is `ratio` times the fastest flow `max_speed` (m/s): the knob
/// that trades a fluid's compression for substeps (they fall about as `ratio + 1`). A dam
/// break (`cargo run --release --example dambreak -- --bulk K`: water 0.4 m high, 20 cells
/// across its 0.2 m width, APIC, flowing at up to Ritter's `2 sqrt(g H)` = 3.96 m/s) keeps its
/// front within 2 % from ratio 8 down to 2 while the substeps fall 3.2 times and the most
/// squeezed water goes from 4 % to 20 %:
///
/// | ratio | K, Pa | substeps a 60 Hz frame | front speed `dZ/dT` | least `J` |
/// |---:|---:|---:|---:|---:|
/// | 8.0 | 1e6 | 114.5 | 1.458 | 0.958 |
/// | 5.1 | 4e5 | 76.0 | 1.456 | 0.945 |
/// | 3.4 | 1.8e5 | 53.8 | 1.455 | 0.915 |
/// | 2.5 | 1e5 | 42.4 | 1.449 | 0.848 |
/// | 2.0 | 6.4e4 | 35.8 | 1.429 | 0.795 |
///
/// The usual weakly compressible choice is 10 (density within about 1 %); a game that can show
/// water squeezed by a fifth on impact can take 2.
pub fn bulk_modulus_for_speed_ratio(density: Real, max_speed: Real, ratio: Real) -> Real {
    let c = ratio as f64 * max_speed as f64;
    (density as f64 * c * c) as Real
}

/// Young's modulus `E = M (1 + nu) (1 - 2 nu) / (1 - nu)` (Pa) of a solid whose P-wave modulus
/// is `p_wave_modulus` (Pa) at Poisson's ratio `poisson_ratio` (E33: 3D and plane strain).
pub fn youngs_modulus(p_wave_modulus: Real, poisson_ratio: Real) -> Real {
    let nu = poisson_ratio as f64;
    (p_wave_modulus as f64 * (1.0 + nu) * (1.0 - 2.0 * nu) / (1.0 - nu)) as Real
}

/// The substeps a frame of `frame_dt` (s) takes in a world of `def` for `material` alone, its
/// particles moving at up to `max_speed` (m/s): `ceil(frame_dt (c + v) / (cfl h))`, at least 1,
/// with `c` the material's unhardened wave speed ([`MaterialDef::wave_speed`]). The wave limit
/// only (see the [module](self) notes).
pub fn substeps_per_frame(
    def: &WorldDef,
    material: &MaterialDef,
    frame_dt: Real,
    max_speed: Real,
) -> u32 {
    let speed = material.wave_speed() as f64 + max_speed as f64;
    let dt = def.cfl as f64 * def.cell_size as f64 / speed;
    (frame_dt as f64 / dt).ceil().max(1.0) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_gimp::{MaterialModel, Vec3, World};

    /// A world of `def` holding a block of `material` at rest: its stable step.
    fn stable_dt(def: &WorldDef, material: &MaterialDef) -> Real {
        let mut storage = crate::scenes::Scene::storage(def).unwrap();
        let mut world = World::init(def, storage.as_mut_bytes()).unwrap();
        let id = world.add_material(material).unwrap();
        let lo = def.origin + Vec3::splat(0.3);
        world
            .fill_box(lo, lo + Vec3::splat(0.2), id, Vec3::ZERO)
            .unwrap();
        world.stable_dt()
    }

    /// A solid and a fluid of the modulus asked for `n` substeps run, at rest, in `n` substeps
    /// a frame by the kernel's own stable step (within 0.3 %, just under), for several cell
    /// sizes, densities, Courant numbers and dimensions.
    #[test]
    fn the_kernel_steps_the_modulus_in_its_budget() {
        let frame = 1.0 / 60.0;
        for (cells, h, cfl, three_d) in [
            (40, 0.025, 0.5, false),
            (50, 0.02, 0.5, false),
            (80, 1.0 / 80.0, 0.3, false),
            (20, 0.05, 0.9, true),
        ] {
            let def = WorldDef {
                cells: [cells, cells, if three_d { cells } else { 1 }],
                cell_size: h,
                cfl,
                dimension: if three_d {
                    mpm_gimp::Dimension::ThreeD
                } else {
                    mpm_gimp::Dimension::Plane2D
                },
                ..WorldDef::DEFAULT
            };
            for (density, nu, n) in [(1000.0, 0.3, 16), (600.0, 0.2, 10), (2700.0, 0.45, 30)] {
                let m = modulus_for_substeps(&def, density, frame, n, 0.0);
                let solid = MaterialDef {
                    youngs_modulus: youngs_modulus(m, nu),
                    poisson_ratio: nu,
                    density,
                    ..MaterialDef::DEFAULT
                };
                let fluid = MaterialDef {
                    model: MaterialModel::Fluid,
                    bulk_modulus: m,
                    density,
                    ..MaterialDef::DEFAULT
                };
                for material in [solid, fluid] {
                    let ratio = frame / stable_dt(&def, &material);
                    let n = n as Real;
                    assert!(
                        ratio <= n && ratio > n * 0.997,
                        "h {h}, cfl {cfl}, rho {density}, nu {nu}: {ratio} substeps for {n}"
                    );
                    assert_eq!(substeps_per_frame(&def, &material, frame, 0.0), n as u32);
                    let c = material.wave_speed() as f64;
                    assert!(((density as f64 * c * c) / m as f64 - 1.0).abs() < 1.0e-4);
                }
            }
        }
    }

    /// A fluid of the bulk modulus for a speed ratio has that ratio's sound speed (to f32's
    /// round-off), for several densities, speeds and ratios, and a world steps it in the
    /// substeps that speed and its flow ask: `ceil(frame (c + v) / (cfl h))`.
    #[test]
    fn a_speed_ratio_gives_its_sound_speed() {
        let def = WorldDef {
            cells: [40, 40, 1],
            cell_size: 0.025,
            ..WorldDef::DEFAULT
        };
        for (density, speed, ratio) in [(1000.0, 3.9, 8.0), (1000.0, 3.9, 2.0), (800.0, 0.5, 10.0)]
        {
            let water = MaterialDef {
                model: MaterialModel::Fluid,
                density,
                bulk_modulus: bulk_modulus_for_speed_ratio(density, speed, ratio),
                ..MaterialDef::DEFAULT
            };
            let c = water.wave_speed() as f64;
            assert!(
                (c / (ratio as f64 * speed as f64) - 1.0).abs() < 1.0e-6,
                "{c}"
            );
            let frame = 1.0 / 60.0;
            let n = (frame * (c + speed as f64) / (0.5 * 0.025)).ceil() as u32;
            assert_eq!(substeps_per_frame(&def, &water, frame as Real, speed), n);
        }
    }

    /// A speed to allow for lowers the modulus to what leaves room for it; a speed that takes
    /// the whole budget leaves none.
    #[test]
    fn speed_takes_its_share_of_the_budget() {
        let def = WorldDef {
            cells: [40, 40, 1],
            cell_size: 0.025,
            ..WorldDef::DEFAULT
        };
        let frame = 1.0 / 60.0;
        // 16 substeps carry c + v = 0.5 * 0.025 * 16 * 60 = 12 m/s.
        let m = modulus_for_substeps(&def, 1000.0, frame, 16, 3.0) as f64;
        let c = (m / 1000.0).sqrt();
        assert!((c - (12.0 * (1.0 - MARGIN) - 3.0)).abs() < 1.0e-3, "{c}");
        let rubber = MaterialDef {
            youngs_modulus: youngs_modulus(m as Real, 0.3),
            ..MaterialDef::DEFAULT
        };
        assert_eq!(substeps_per_frame(&def, &rubber, frame, 3.0), 16);
        assert_eq!(substeps_per_frame(&def, &rubber, frame, 3.1), 17);
        assert_eq!(modulus_for_substeps(&def, 1000.0, frame, 16, 12.0), 0.0);
    }

    /// `youngs_modulus` inverts the kernel's Lamé constants: `lambda + 2 mu` of the result is
    /// the modulus asked for.
    #[test]
    fn youngs_modulus_inverts_the_p_wave_modulus() {
        for nu in [0.0, 0.2, 0.3, 0.45] {
            let m = 1.0e6;
            let def = MaterialDef {
                youngs_modulus: youngs_modulus(m, nu),
                poisson_ratio: nu,
                ..MaterialDef::DEFAULT
            };
            let (lambda, mu) = def.lame();
            assert!(((lambda + 2.0 * mu) / m - 1.0).abs() < 1.0e-5, "nu {nu}");
        }
    }
}
