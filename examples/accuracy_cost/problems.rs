//! The verification problems of the accuracy report, each with its exact solution, and the
//! schemes they are run with. Everything goes through the public API. Shared by the report
//! (`examples/accuracy_cost/main.rs`) and its quick checks in the tests
//! (`tests/kernel/accuracy.rs`), which include this file with `#[path]`.

use mpm_gimp::{
    memory_requirements, Boundary, Dimension, Effects, Face, HeapBuffer, MaterialDef,
    MaterialModel, ParticleBatch, Real, ScalarBoundary, ScalarField, ShapeFunction, Transfer,
    Transport, UpdateOrder, Vec3, World, WorldDef,
};
use std::f64::consts::PI;

/// A numerical method: what a user picks in [`WorldDef`]. Every field not set here keeps the
/// kernel's default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scheme {
    /// Short label: what differs from the kernel's defaults.
    pub label: &'static str,
    pub shape: ShapeFunction,
    pub transfer: Transfer,
    pub flip_beta: Real,
    pub order: UpdateOrder,
    pub exp_terms: u32,
}

impl Scheme {
    /// The kernel's defaults ([`WorldDef::DEFAULT`]).
    pub const DEFAULTS: Scheme = Scheme {
        label: "defaults",
        shape: WorldDef::DEFAULT.shape,
        transfer: WorldDef::DEFAULT.transfer,
        flip_beta: WorldDef::DEFAULT.flip_beta,
        order: WorldDef::DEFAULT.update_order,
        exp_terms: WorldDef::DEFAULT.exp_terms,
    };

    /// Writes the scheme into a definition.
    pub fn apply(&self, def: &mut WorldDef) {
        def.shape = self.shape;
        def.transfer = self.transfer;
        def.flip_beta = self.flip_beta;
        def.update_order = self.order;
        def.exp_terms = self.exp_terms;
    }

    /// The full setting, for the report's legend.
    pub fn describe(&self) -> String {
        let transfer = match self.transfer {
            Transfer::Apic => "APIC".to_string(),
            Transfer::Flip => format!("FLIP beta={}", self.flip_beta),
            Transfer::FlipParticleVelocity => {
                format!("FLIP beta={}, x += v(n+1) dt", self.flip_beta)
            }
            Transfer::Mls => "MLS-MPM (APIC, MLS gradient)".to_string(),
            Transfer::FlipMomentum => format!("FLIP beta={}, momentum approach", self.flip_beta),
            Transfer::Xpic(k) => format!("XPIC({k})"),
            Transfer::Fmpm(k) => format!("FMPM({k})"),
        };
        format!(
            "{:?}, {transfer}, {:?}, exp terms {}",
            self.shape, self.order, self.exp_terms
        )
    }
}

/// Every scheme of the report: the kernel's defaults, then one factor changed at a time (shape
/// function, transfer, update order, terms of `exp(grad v dt)`), then combinations users ask
/// for. A scheme the kernel gains is one more line here.
pub const SCHEMES: &[Scheme] = &[
    Scheme::DEFAULTS,
    // Shape functions.
    Scheme {
        label: "linear",
        shape: ShapeFunction::Linear,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "cpGIMP",
        shape: ShapeFunction::CpGimp,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "B2",
        shape: ShapeFunction::QuadraticBspline,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "B3",
        shape: ShapeFunction::CubicBspline,
        ..Scheme::DEFAULTS
    },
    // Transfers.
    Scheme {
        label: "FLIP",
        flip_beta: 1.0,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "PIC/FLIP 0.5",
        flip_beta: 0.5,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "PIC",
        flip_beta: 0.0,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "APIC",
        transfer: Transfer::Apic,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "FLIP x+=v dt",
        transfer: Transfer::FlipParticleVelocity,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "momentum",
        transfer: Transfer::FlipMomentum,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "XPIC(3)",
        transfer: Transfer::Xpic(3),
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "FMPM(2)",
        transfer: Transfer::Fmpm(2),
        ..Scheme::DEFAULTS
    },
    // Update orders.
    Scheme {
        label: "USF",
        order: UpdateOrder::Usf,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "USL",
        order: UpdateOrder::Usl,
        ..Scheme::DEFAULTS
    },
    // Terms of exp(grad v dt): 1 (dF = I + L dt), the default 2, and 8 (converged).
    Scheme {
        label: "dF 1 term",
        exp_terms: 1,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "dF 8 terms",
        exp_terms: 8,
        ..Scheme::DEFAULTS
    },
    // Combinations.
    Scheme {
        label: "B2 APIC USL",
        shape: ShapeFunction::QuadraticBspline,
        transfer: Transfer::Apic,
        order: UpdateOrder::Usl,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "B2 MLS USL",
        shape: ShapeFunction::QuadraticBspline,
        transfer: Transfer::Mls,
        order: UpdateOrder::Usl,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "B3 MLS USL",
        shape: ShapeFunction::CubicBspline,
        transfer: Transfer::Mls,
        order: UpdateOrder::Usl,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "cpGIMP FLIP",
        shape: ShapeFunction::CpGimp,
        flip_beta: 1.0,
        ..Scheme::DEFAULTS
    },
    Scheme {
        label: "cpGIMP FLIP USF",
        shape: ShapeFunction::CpGimp,
        flip_beta: 1.0,
        order: UpdateOrder::Usf,
        ..Scheme::DEFAULTS
    },
];

/// What one run measured: one error per metric of its problem (NaN if the run failed), and its
/// size (for the cost of a run: particles x steps x ns per particle-step).
#[derive(Clone, Debug)]
pub struct Outcome {
    pub errors: Vec<f64>,
    pub particles: usize,
    pub steps: usize,
}

/// The effect a problem declares, for pricing its scheme in the step_cost scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Declares {
    Nothing,
    ParticleForces,
    Heat,
    /// No effect: the fluid model (priced in the step_cost scene made of it).
    Fluid,
}

/// A verification problem: its metrics, its refinement series and how to run one level.
pub struct Problem {
    /// File-name-safe key.
    pub key: &'static str,
    pub title: &'static str,
    /// The exact solution and what is measured, for the report.
    pub about: &'static str,
    /// One name per error the run returns.
    pub metrics: &'static [&'static str],
    /// The error each metric's "cost to reach" column is read at.
    pub targets: &'static [f64],
    /// Cells per unit length of the refinement series: the full report and the quick checks.
    pub levels: &'static [u32],
    pub quick_levels: &'static [u32],
    pub declares: Declares,
    pub run: fn(&Scheme, u32) -> Outcome,
}

pub const PROBLEMS: &[Problem] = &[
    Problem {
        key: "bar",
        title: "Vibrating bar (small amplitude)",
        about: "Fixed-free elastic bar (nu = 0, linear elastic), first mode, amplitude 1e-3 L. \
Exact: u = (v0/omega) sin(pi X / 2L) sin(omega t). Error: RMS of the particles' displacement \
error over the amplitude at t = 1.25 periods.",
        metrics: &["displacement"],
        targets: &[1e-2],
        levels: &[16, 32, 64, 128],
        quick_levels: &[16, 32],
        declares: Declares::Nothing,
        run: vibrating_bar,
    },
    Problem {
        key: "bar-far",
        title: "Vibrating bar 100 m from the origin",
        about: "The vibrating bar with the grid's origin at (100 m, 100 m): a step moves a \
particle by less than the last bit of its f32 coordinate (8 um), which positions rounded to \
f32 after every step lost. Same exact solution and error as the bar; the f32 rows against the \
f64 rows show what f32 keeps.",
        metrics: &["displacement"],
        targets: &[1e-2],
        levels: &[16, 32, 64, 128],
        quick_levels: &[16, 32],
        declares: Declares::Nothing,
        run: vibrating_bar_far,
    },
    Problem {
        key: "mms",
        title: "Manufactured large deformation (1D, body force)",
        about: "u = A sin(2 pi X) sin(pi c t) on [0, 1] between stick walls, neo-Hookean with \
nu = 0 (P = E/2 (F - 1/F)), A = 0.05: peak strain 31 %, particles cross several cells; the body \
force b = u_tt - (1/rho0) dP/dX is applied as particle forces (Steffen, Kirby and Berzins 2008). \
The time step falls as h^2 (CFL 0.4 at 16 cells per unit length), so that the spatial order \
shows. Error: RMS of the particles' displacement error over A at t = 1.25 periods, when the \
strain peaks.",
        metrics: &["displacement"],
        targets: &[1e-3],
        levels: &[16, 32, 64, 128, 256],
        quick_levels: &[16, 32, 64],
        declares: Declares::ParticleForces,
        run: manufactured,
    },
    Problem {
        key: "disk",
        title: "Spinning elastic disk",
        about: "A free neo-Hookean disk (radius 0.5 m, E = 1 MPa, nu = 0.3) spinning at a rim \
speed of 0.1 c, for half a turn. Exact: angular momentum and energy (kinetic + strain) are \
conserved. Errors: |L - L0| / L0 and |E - E0| / E0.",
        metrics: &["angular momentum", "energy"],
        targets: &[1e-4, 1e-2],
        levels: &[8, 16, 32],
        quick_levels: &[8],
        declares: Declares::Nothing,
        run: spinning_disk,
    },
    Problem {
        key: "heat",
        title: "Heat sin-mode decay",
        about: "T = sin(pi x / L) exp(-pi^2 kappa t / L^2) between faces held at 0, particles \
at rest. Error: RMS of the particle temperatures' error over the mode's amplitude when it has \
fallen to 1/e.",
        metrics: &["temperature"],
        targets: &[1e-3],
        levels: &[16, 32, 64],
        quick_levels: &[16, 32],
        declares: Declares::Heat,
        run: heat_mode,
    },
    Problem {
        key: "poiseuille",
        title: "Plane Poiseuille flow from rest (fluid)",
        about: "Fluid (K = 100 kPa, eta = 100 Pa s, rho = 1000) between stick walls W = 0.2 m \
apart, driven by a body force g = 1 m/s^2 along them with free ends (open faces, a channel 3 W \
long). Exact (series): u = g x (W - x) / (2 nu) - sum_(n odd) 4 g W^2 / (nu pi^3 n^3) \
sin(n pi x / W) exp(-n^2 pi^2 nu t / W^2). Error: RMS of the particles' velocity error over \
the centre speed g W^2 / (8 nu) = 5 cm/s in the channel's middle third at t = 0.25 s (six \
time constants). Cells per unit length: 40 is 8 across the channel.",
        metrics: &["velocity"],
        targets: &[1e-2],
        levels: &[20, 40, 80],
        quick_levels: &[40],
        declares: Declares::Fluid,
        run: poiseuille,
    },
];

/// A world in its own storage.
struct Run {
    storage: HeapBuffer,
}

impl Run {
    fn new(def: &WorldDef) -> Run {
        let bytes = memory_requirements(def).expect("a valid definition").bytes;
        let mut storage = HeapBuffer::new(bytes);
        World::init(def, storage.as_mut_bytes()).expect("a valid definition");
        Run { storage }
    }

    fn world(&mut self) -> World<'_> {
        World::reopen(self.storage.as_mut_bytes()).expect("the run's world")
    }
}

/// Adds particles of `material` on the lattice of `n` sites per cell per axis (sub-cell
/// centres) of the 2D box `[lo, hi]`, those where `inside` holds, each with velocity `v(x)`.
/// Returns the reference positions (x, y) of the particles added.
fn lattice(
    world: &mut World,
    material: &MaterialDef,
    (lo, hi): ([f64; 2], [f64; 2]),
    inside: impl Fn(f64, f64) -> bool,
    v: impl Fn(f64, f64) -> [f64; 2],
) -> (Vec<f64>, Vec<f64>) {
    let def = world.def();
    let id = world.add_material(material).expect("a valid material");
    let d = def.cell_size as f64 / def.particles_per_cell as f64;
    let (nx, ny) = (
        ((hi[0] - lo[0]) / d).round() as usize,
        ((hi[1] - lo[1]) / d).round() as usize,
    );
    let (mut xs, mut ys) = (vec![], vec![]);
    let mut cols: [Vec<Real>; 4] = Default::default();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (lo[0] + (i as f64 + 0.5) * d, lo[1] + (j as f64 + 0.5) * d);
            if inside(x, y) {
                let vel = v(x, y);
                xs.push(x);
                ys.push(y);
                for (c, value) in cols.iter_mut().zip([x, y, vel[0], vel[1]]) {
                    c.push(value as Real);
                }
            }
        }
    }
    let n = xs.len();
    let vol = (d * d) as Real;
    world
        .add_particles(&ParticleBatch {
            position: [&cols[0], &cols[1], &[]],
            velocity: [&cols[2], &cols[3], &[]],
            mass: &vec![material.density * vol; n],
            volume: &vec![vol; n],
            material: &vec![id; n],
        })
        .expect("particles inside the grid");
    (xs, ys)
}

/// Steps `world` to `t_end` in equal steps no longer than `max_dt` (one substep each),
/// calling `before(world, t)` before each step. Returns the number of steps, or None if a step
/// failed or froze a particle (the scheme lost the run).
fn run_to(
    world: &mut World,
    t_end: f64,
    max_dt: f64,
    mut before: impl FnMut(&mut World, f64),
) -> Option<usize> {
    let steps = (t_end / max_dt).ceil() as usize;
    let dt = t_end / steps as f64;
    for s in 0..steps {
        before(world, s as f64 * dt);
        let report = world.step(dt as Real).ok()?;
        if report.frozen > 0 {
            return None;
        }
    }
    Some(steps)
}

/// RMS of `err(i)` over the particles.
fn rms(n: usize, err: impl Fn(usize) -> f64) -> f64 {
    ((0..n).map(|i| err(i).powi(2)).sum::<f64>() / n as f64).sqrt()
}

/// A strip of material along x, `length` long from the lower x wall plane, 2 cells high
/// between slip walls, `cells` cells per unit length; the upper x face `x_max`.
fn strip(scheme: &Scheme, cells: u32, length: f64, room: u32, x_max: Boundary) -> WorldDef {
    let m = scheme.shape.margin_cells();
    let along = (length * cells as f64).round() as u32;
    let mut def = WorldDef {
        dimension: Dimension::Plane2D,
        cells: [along + room + 2 * m, 2 + 2 * m, 1],
        cell_size: (1.0 / cells as f64) as Real,
        gravity: Vec3::ZERO,
        faces: [Boundary::Slip; 6],
        particle_capacity: 8 * along,
        material_capacity: 1,
        ..WorldDef::DEFAULT
    };
    scheme.apply(&mut def);
    def.faces[Face::XMin as usize] = Boundary::Stick;
    def.faces[Face::XMax as usize] = x_max;
    def
}

/// Fills the strip of [`strip`] with `material` moving along x at `v(X)`, `X` the distance
/// from the lower x wall plane. Returns the wall plane's x and every particle's `X`. The grid's
/// origin is on the diagonal (`origin.x = origin.y`).
fn fill_strip(
    world: &mut World,
    material: &MaterialDef,
    length: f64,
    v: impl Fn(f64) -> f64,
) -> (f64, Vec<f64>) {
    let def = world.def();
    let wall = def.origin.x as f64 + def.shape.margin_cells() as f64 * def.cell_size as f64;
    let bounds = (
        [wall, wall],
        [wall + length, wall + 2.0 * def.cell_size as f64],
    );
    let (x, _) = lattice(
        world,
        material,
        bounds,
        |_, _| true,
        |x, _| [v(x - wall), 0.0],
    );
    (wall, x.iter().map(|x| x - wall).collect())
}

/// An elastic material with `nu = 0` (so that uniaxial strain is exactly one-dimensional),
/// E = 1 MPa, rho = 1000 kg/m^3: c = 31.6 m/s.
fn one_dimensional(model: MaterialModel) -> MaterialDef {
    MaterialDef {
        model,
        youngs_modulus: 1.0e6,
        poisson_ratio: 0.0,
        density: 1000.0,
        ..MaterialDef::DEFAULT
    }
}

/// Problem 1: the fixed-free bar's first mode.
pub fn vibrating_bar(scheme: &Scheme, cells: u32) -> Outcome {
    vibrating_bar_at(scheme, cells, 0.0)
}

/// Problem 1 with the grid's origin 100 m from the coordinate origin: a step moves a particle
/// by less than the last bit of its f32 coordinate there (8 um), which a position kept only
/// as that coordinate lost.
pub fn vibrating_bar_far(scheme: &Scheme, cells: u32) -> Outcome {
    vibrating_bar_at(scheme, cells, 100.0)
}

/// The fixed-free bar's first mode on a grid whose origin is at `origin` on the diagonal.
/// Displacements are read from the position and its low part, in f64.
fn vibrating_bar_at(scheme: &Scheme, cells: u32, origin: Real) -> Outcome {
    let length = 1.0;
    let material = one_dimensional(MaterialModel::LinearElastic);
    let c = (material.youngs_modulus as f64 / material.density as f64).sqrt();
    let omega = PI * c / (2.0 * length);
    let v0 = 1.0e-3 * omega * length;
    let k = PI / (2.0 * length);
    let mut def = strip(scheme, cells, length, cells / 4, Boundary::Open);
    def.origin = Vec3::new(origin, origin, 0.0);
    let mut run = Run::new(&def);
    let mut w = run.world();
    let (wall, x0) = fill_strip(&mut w, &material, length, |x| v0 * (k * x).sin());
    let t_end = 1.25 * 4.0 * length / c;
    let max_dt = w.stable_dt() as f64;
    let steps = run_to(&mut w, t_end, max_dt, |_, _| {});
    let amplitude = v0 / omega;
    let v = w.particles();
    let error = rms(v.count, |i| {
        let exact = amplitude * (k * x0[i]).sin() * (omega * w.time()).sin();
        let x = v.position[0][i] as f64 + v.position_low[0][i] as f64;
        (x - wall - x0[i]) - exact
    }) / amplitude;
    outcome(vec![error], v.count, steps)
}

fn outcome(errors: Vec<f64>, particles: usize, steps: Option<usize>) -> Outcome {
    match steps {
        Some(steps) => Outcome {
            errors: errors
                .into_iter()
                .map(|e| if e.is_finite() { e } else { f64::NAN })
                .collect(),
            particles,
            steps,
        },
        None => Outcome {
            errors: vec![f64::NAN; errors.len()],
            particles,
            steps: 0,
        },
    }
}

/// Problem 2: the manufactured large-deformation solution. With `nu = 0` the neo-Hookean
/// model under uniaxial strain `F = diag(F, 1, 1)` has `P = mu (F - 1/F)`, `mu = E/2`; with
/// `u = A sin(k X) sin(omega t)`, `k = 2 pi / L`, momentum `rho0 u_tt = dP/dX + rho0 b` gives
/// `b = -omega^2 u - (mu / rho0) (1 + 1/F^2) dF/dX`, `F = 1 + A k cos(k X) sin(omega t)`.
pub fn manufactured(scheme: &Scheme, cells: u32) -> Outcome {
    let length = 1.0;
    let amp = 0.05;
    let material = one_dimensional(MaterialModel::NeoHookean);
    let rho0 = material.density as f64;
    let mu = material.youngs_modulus as f64 / 2.0;
    let c = (material.youngs_modulus as f64 / rho0).sqrt();
    let (k, omega) = (2.0 * PI / length, PI * c / length);
    let u = |x: f64, t: f64| amp * (k * x).sin() * (omega * t).sin();
    let body = |x: f64, t: f64| {
        let f = 1.0 + amp * k * (k * x).cos() * (omega * t).sin();
        let df = -amp * k * k * (k * x).sin() * (omega * t).sin();
        -omega * omega * u(x, t) - mu / rho0 * (1.0 + 1.0 / (f * f)) * df
    };
    let mut def = strip(scheme, cells, length, 0, Boundary::Stick);
    def.effects = Effects {
        particle_forces: true,
        ..Effects::NONE
    };
    // dt falls as h^2 (CFL 0.4 at 16 cells, halved with h): the FLIP update (E25-E26 of
    // docs/equations.md) is first order in time (it advances positions with the acceleration of the
    // step before, see the vibrating bar), and with dt ~ h that error would hide the spatial
    // order. (0.4 also leaves room for the stiffening: at F = 0.69 the wave speed is 1.25 c.)
    def.cfl = 0.4 * 16.0 / cells as Real;
    let mut run = Run::new(&def);
    let mut w = run.world();
    let (wall, x) = fill_strip(&mut w, &material, length, |x| amp * omega * (k * x).sin());
    let mass: Vec<f64> = w.particles().mass.iter().map(|&m| m as f64).collect();
    let zero = vec![0.0; x.len()];
    let mut force = vec![0.0; x.len()];
    let t_end = 1.25 * 2.0 * length / c;
    let max_dt = w.stable_dt() as f64;
    let steps = run_to(&mut w, t_end, max_dt, |w, t| {
        for (i, f) in force.iter_mut().enumerate() {
            *f = (mass[i] * body(x[i], t)) as Real;
        }
        w.set_particle_forces(0, [&force, &zero, &zero])
            .expect("one force per particle");
    });
    let v = w.particles();
    let error = rms(v.count, |i| {
        (v.position[0][i] as f64 - wall - x[i]) - u(x[i], w.time())
    }) / amp;
    outcome(vec![error], v.count, steps)
}

/// Problem 3: a free disk spinning for half a turn; `cells` per unit length, radius 0.5.
pub fn spinning_disk(scheme: &Scheme, cells: u32) -> Outcome {
    let radius = 0.5;
    let material = MaterialDef {
        model: MaterialModel::NeoHookean,
        ..MaterialDef::DEFAULT
    };
    let c = material.wave_speed() as f64;
    let omega = 0.1 * c / radius;
    let h = 1.0 / cells as f64;
    let m = scheme.shape.margin_cells();
    // The disk, two cells of room around it for the centrifugal growth, and the margin.
    let across = (2.0 * radius / h).round() as u32 + 4;
    let mut def = WorldDef {
        dimension: Dimension::Plane2D,
        cells: [across + 2 * m, across + 2 * m, 1],
        cell_size: h as Real,
        gravity: Vec3::ZERO,
        faces: [Boundary::Open; 6],
        particle_capacity: 4 * across * across,
        material_capacity: 1,
        ..WorldDef::DEFAULT
    };
    scheme.apply(&mut def);
    let centre = (across / 2 + m) as f64 * h;
    let mut run = Run::new(&def);
    let mut w = run.world();
    let bounds = (
        [centre - radius, centre - radius],
        [centre + radius, centre + radius],
    );
    let inside = |x: f64, y: f64| (x - centre).powi(2) + (y - centre).powi(2) < radius * radius;
    lattice(&mut w, &material, bounds, inside, |x, y| {
        [-omega * (y - centre), omega * (x - centre)]
    });
    let start = w.diagnostics();
    let max_dt = w.stable_dt() as f64;
    let steps = run_to(&mut w, PI / omega, max_dt, |_, _| {});
    let end = w.diagnostics();
    let l0 = start.angular_momentum[2];
    outcome(
        vec![
            ((end.angular_momentum[2] - l0) / l0).abs(),
            ((end.total_energy() - start.total_energy()) / start.total_energy()).abs(),
        ],
        w.particle_count(),
        steps,
    )
}

/// Problem 4: the sin mode of heat conduction between two faces held at 0 (E54-E64 of
/// docs/equations.md).
pub fn heat_mode(scheme: &Scheme, cells: u32) -> Outcome {
    let length = 1.0;
    let kappa = 0.1;
    let mut heat = Transport::INSULATED;
    heat.faces[Face::XMin as usize] = ScalarBoundary::Fixed(0.0);
    heat.faces[Face::XMax as usize] = ScalarBoundary::Fixed(0.0);
    let mut def = strip(scheme, cells, length, 0, Boundary::Slip);
    def.faces[Face::XMin as usize] = Boundary::Slip;
    def.effects = Effects {
        heat: Some(heat),
        ..Effects::NONE
    };
    // Thermal diffusivity kappa; stiff enough that the mechanics (at rest) takes no part.
    let material = MaterialDef {
        model: MaterialModel::LinearElastic,
        youngs_modulus: 1.0e4,
        poisson_ratio: 0.0,
        density: 1000.0,
        heat_capacity: 1000.0,
        conductivity: (kappa * 1.0e6) as Real,
        ..MaterialDef::DEFAULT
    };
    let mut run = Run::new(&def);
    let mut w = run.world();
    let (_, x) = fill_strip(&mut w, &material, length, |_| 0.0);
    let mode: Vec<Real> = x.iter().map(|&x| (PI * x / length).sin() as Real).collect();
    w.set_particle_scalar(ScalarField::Temperature, 0, &mode)
        .expect("one temperature per particle");
    let t_end = length * length / (PI * PI * kappa);
    let max_dt = w.stable_dt() as f64;
    let steps = run_to(&mut w, t_end, max_dt, |_, _| {});
    let decay = (-PI * PI * kappa * w.time() / (length * length)).exp();
    let v = w.particles();
    let error = rms(v.count, |i| {
        v.temperature[i] as f64 - (PI * x[i] / length).sin() * decay
    }) / decay;
    outcome(vec![error], v.count, steps)
}

/// Problem 5: plane Poiseuille flow started from rest between stick walls, driven by a body
/// force along the channel whose ends are open (no pressure gradient builds).
pub fn poiseuille(scheme: &Scheme, cells: u32) -> Outcome {
    let (width, g, eta, rho) = (0.2f64, 1.0f64, 100.0f64, 1000.0f64);
    let nu = eta / rho;
    let m = scheme.shape.margin_cells();
    let across = (width * cells as f64).round() as u32;
    let mut def = WorldDef {
        dimension: Dimension::Plane2D,
        cells: [across + 2 * m, 3 * across + 2 * m, 1],
        cell_size: (1.0 / cells as f64) as Real,
        gravity: Vec3::new(0.0, -g as Real, 0.0),
        faces: [Boundary::Stick; 6],
        particle_capacity: 4 * across * 3 * across,
        material_capacity: 1,
        ..WorldDef::DEFAULT
    };
    scheme.apply(&mut def);
    def.faces[Face::YMin as usize] = Boundary::Open;
    def.faces[Face::YMax as usize] = Boundary::Open;
    let fluid = MaterialDef {
        model: MaterialModel::Fluid,
        bulk_modulus: 1.0e5,
        viscosity: eta as Real,
        density: rho as Real,
        ..MaterialDef::DEFAULT
    };
    let mut run = Run::new(&def);
    let mut w = run.world();
    let h = def.cell_size as f64;
    let wall = def.origin.x as f64 + m as f64 * h;
    let length = 3.0 * width;
    lattice(
        &mut w,
        &fluid,
        ([wall, wall], [wall + width, wall + length]),
        |_, _| true,
        |_, _| [0.0, 0.0],
    );
    let t_end = 0.25;
    let max_dt = w.stable_dt() as f64;
    let Some(steps) = run_to(&mut w, t_end, max_dt, |_, _| {}) else {
        return outcome(vec![f64::NAN], w.particle_count(), None);
    };
    let exact = |x: f64| {
        let mut u = g * x * (width - x) / (2.0 * nu);
        for n in (1..200).step_by(2) {
            let n = n as f64;
            u -= 4.0 * g * width * width / (nu * PI.powi(3) * n.powi(3))
                * (n * PI * x / width).sin()
                * (-n * n * PI * PI * nu * t_end / (width * width)).exp();
        }
        u
    };
    let centre = g * width * width / (8.0 * nu);
    let v = w.particles();
    let middle: Vec<usize> = (0..v.count)
        .filter(|&i| {
            let y = v.position[1][i] as f64 - wall;
            v.status[i] == 0 && (width..2.0 * width).contains(&y)
        })
        .collect();
    let error = rms(middle.len(), |k| {
        let i = middle[k];
        let x = v.position[0][i] as f64 - wall;
        (-(v.velocity[1][i] as f64) - exact(x)) / centre
    });
    outcome(vec![error], v.count, Some(steps))
}

/// Observed order of convergence between two levels: `log(e_coarse / e_fine) / log(n_fine /
/// n_coarse)`.
pub fn order(coarse: (u32, f64), fine: (u32, f64)) -> f64 {
    (coarse.1 / fine.1).ln() / (fine.0 as f64 / coarse.0 as f64).ln()
}
