//! The benchmark scene, shared by the criterion benches (`benches/step.rs`) and the cost
//! example (`examples/step_cost.rs`, which includes this file with `#[path]`): a block of
//! elastic material filled at 2 particles per cell per axis, moving down at 0.1 m/s under
//! gravity, inside a grid with slip walls.

use mpm_gimp::{
    memory_requirements, Boundary, Damping, DampingZone, Dimension, Face, Feedback, HeapBuffer,
    MaterialDef, MaterialModel, ParticleBatch, Real, Schedule, ShapeFunction, Transfer, Transport,
    UpdateOrder, Vec3, World, WorldDef, DAMPING_ZONES,
};

/// One effect declared in the scene (or none), to price it: what the scene declares and what
/// it sets once the block is filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Nothing declared.
    None,
    /// Constant grid and particle damping.
    Damping,
    /// Grid damping driven by the kinetic-energy thermostat (target 0).
    Feedback,
    /// Per-particle damping columns, set to 1/s on every particle.
    LocalDamping,
    /// Nodal damping: the grid rate on the nodal force and a zone graded toward the x-min
    /// face over the grid's lower half in x (an absorbing layer).
    DampingZones,
    /// A per-particle force column, set to the particle's weight along x.
    ParticleForces,
    /// A traction on the +x face of every particle of the block's last column.
    Tractions,
    /// A body force besides gravity, constant.
    BodyForce,
    /// The APIC transfer.
    Apic,
    /// MLS-MPM (the quadratic and cubic B-splines only: `--shape quadratic` or `cubic`).
    Mls,
    /// FLIP in the momentum approach.
    Momentum,
    /// Heat conduction, insulated faces (the material's conductivity is 0: the passes run, the
    /// temperatures stay).
    Heat,
    /// Diffusion, insulated faces.
    Diffusion,
    /// Thermal expansion: heat declared as [`Effect::Heat`] does, and the material's expansion
    /// coefficient 1e-5 /K (reference temperature 0, the particles' temperature too: the
    /// eigenstrain is 0, but the stress update takes it out all the same). Its marginal cost
    /// includes heat's.
    ThermalExpansion,
    /// The axisymmetric dimension (2D only): x becomes the radius, the grid's origin moves by
    /// its margin so that the axis r = 0 is the lower x face's wall plane (a slip wall), and the
    /// block keeps its cells (so its size), at r >= 0.
    Axisymmetric,
    /// Four colliders, spheres (circles in 2D) of a tenth of the block's height at rest in
    /// it (their nodes follow them; the block's particles there stay): what each collider
    /// costs per node of the node box, which every collider visits.
    Colliders,
    /// The same four spheres as distance fields sampled every half cell: what a distance
    /// field costs against the analytic solid.
    SdfColliders,
}

impl Effect {
    /// Every effect, with the name the cost example takes.
    pub const ALL: [(Effect, &'static str); 17] = [
        (Effect::None, "none"),
        (Effect::Damping, "damping"),
        (Effect::Feedback, "feedback"),
        (Effect::LocalDamping, "local_damping"),
        (Effect::DampingZones, "damping_zones"),
        (Effect::ParticleForces, "particle_forces"),
        (Effect::Tractions, "tractions"),
        (Effect::BodyForce, "body_force"),
        (Effect::Apic, "apic"),
        (Effect::Mls, "mls"),
        (Effect::Momentum, "momentum"),
        (Effect::Heat, "heat"),
        (Effect::Diffusion, "diffusion"),
        (Effect::ThermalExpansion, "thermal_expansion"),
        (Effect::Axisymmetric, "axisymmetric"),
        (Effect::Colliders, "colliders"),
        (Effect::SdfColliders, "sdf_colliders"),
    ];

    /// The effect's name.
    pub fn name(self) -> &'static str {
        Effect::ALL
            .iter()
            .find(|(e, _)| *e == self)
            .map_or("?", |(_, n)| n)
    }

    fn declare(self, def: &mut WorldDef, block_particles: u32) -> Result<(), String> {
        let fx = &mut def.effects;
        match self {
            Effect::None => {}
            Effect::Damping => {
                fx.damping = Some(Damping {
                    grid: Schedule::constant(1.0),
                    particle: Schedule::constant(1.0),
                    ..Damping::NONE
                })
            }
            Effect::Feedback => {
                fx.damping = Some(Damping {
                    feedback: Some(Feedback {
                        gain: 1.0,
                        target: Schedule::ZERO,
                        max_alpha: 10.0,
                    }),
                    ..Damping::NONE
                })
            }
            Effect::LocalDamping => {
                fx.damping = Some(Damping {
                    per_particle: true,
                    ..Damping::NONE
                })
            }
            Effect::DampingZones => {
                let (lo, hi) = (
                    def.origin,
                    def.origin
                        + CELL
                            * Vec3::new(
                                def.cells[0] as Real,
                                def.cells[1] as Real,
                                def.cells[2] as Real,
                            ),
                );
                let mut zones = [DampingZone::NONE; DAMPING_ZONES];
                zones[0] = DampingZone {
                    min: lo,
                    max: Vec3::new(0.5 * (lo.x + hi.x), hi.y, hi.z),
                    rate: 1.0,
                    ramp: Some(Face::XMin),
                };
                fx.damping = Some(Damping {
                    grid: Schedule::constant(1.0),
                    grid_on_force: true,
                    zones,
                    zone_count: 1,
                    ..Damping::NONE
                })
            }
            Effect::ParticleForces => fx.particle_forces = true,
            Effect::Tractions => fx.traction_capacity = block_particles,
            Effect::BodyForce => {
                fx.body_force = Vec3::new(0.1, 0.0, 0.0);
                fx.body_force_scale = Schedule::constant(1.0);
            }
            Effect::Apic => def.transfer = Transfer::Apic,
            Effect::Mls => {
                if !matches!(
                    def.shape,
                    ShapeFunction::QuadraticBspline | ShapeFunction::CubicBspline
                ) {
                    return Err(format!(
                        "the {} transfer needs the quadratic or cubic B-spline (--shape)",
                        self.name()
                    ));
                }
                def.transfer = Transfer::Mls;
            }
            Effect::Momentum => def.transfer = Transfer::FlipMomentum,
            Effect::Heat | Effect::ThermalExpansion => fx.heat = Some(Transport::INSULATED),
            Effect::Diffusion => fx.diffusion = Some(Transport::INSULATED),
            Effect::Colliders => fx.collider_capacity = 4,
            Effect::SdfColliders => {
                fx.collider_capacity = 4;
                fx.sdf_capacity = 1 << 23;
            }
            Effect::Axisymmetric => {
                if def.dimension == Dimension::ThreeD {
                    return Err(format!(
                        "the {} effect is 2D only; this scene is 3D",
                        self.name()
                    ));
                }
                def.dimension = Dimension::Axisymmetric2D;
                def.origin.x = -(def.shape.margin_cells() as Real) * def.cell_size;
                def.faces[Face::XMin as usize] = Boundary::Slip;
            }
        }
        Ok(())
    }

    /// The scene's material with this effect's parameters.
    fn material(self, model: MaterialModel) -> MaterialDef {
        let mut m = MaterialDef {
            model,
            ..MaterialDef::DEFAULT
        };
        if self == Effect::ThermalExpansion {
            m.thermal_expansion = 1.0e-5;
            m.reference_temperature = 0.0;
        }
        m
    }

    fn set_up(self, world: &mut World) -> Result<(), String> {
        let n = world.particle_count();
        let err = |e| format!("setting up {}: {e:?}", self.name());
        match self {
            Effect::LocalDamping => world
                .set_particle_damping(0, &vec![1.0; n], &vec![1.0; n])
                .map_err(err),
            Effect::ParticleForces => {
                let fx: Vec<Real> = world.particles().mass.iter().map(|m| 9.81 * m).collect();
                let zero = vec![0.0; n];
                world
                    .set_particle_forces(0, [&fx, &zero, &zero])
                    .map_err(err)
            }
            Effect::Tractions => {
                // One traction per particle of the block's +x face: those on the last lattice
                // column (the fill's order is not x fastest, so pick them by position).
                let x = &world.particles().position[0];
                let x_max = x.iter().fold(Real::MIN, |m, &v| m.max(v));
                let last: Vec<u32> = (0..n as u32)
                    .filter(|&i| x[i as usize] > x_max - 0.25 * CELL / PPC as Real)
                    .collect();
                for i in last {
                    world
                        .add_tractions(i..i + 1, Face::XMax, Vec3::new(1.0e3, 0.0, 0.0))
                        .map_err(err)?;
                }
                Ok(())
            }
            Effect::Colliders | Effect::SdfColliders => {
                // Four spheres along the block's middle, at its particles' mean height.
                let p = world.particles();
                let lo = p
                    .position
                    .map(|c| c.iter().fold(Real::MAX, |m, &v| m.min(v)));
                let hi = p
                    .position
                    .map(|c| c.iter().fold(Real::MIN, |m, &v| m.max(v)));
                let d = world.def().axes();
                let mid = |a: usize| if a < d { 0.5 * (lo[a] + hi[a]) } else { 0.0 };
                let radius = 0.1 * (hi[1] - lo[1]);
                // The sampled sphere: every half cell over its box and a cell more.
                let spacing = 0.5 * CELL;
                let m = 2 * ((radius + CELL) / spacing).ceil() as usize + 1;
                let dims = [m, m, if d == 3 { m } else { 1 }];
                let shape = if self == Effect::SdfColliders {
                    let half = 0.5 * (m - 1) as Real * spacing;
                    let at = |i: usize| i as Real * spacing - half;
                    let samples: Vec<Real> = (0..dims[0] * dims[1] * dims[2])
                        .map(|k| {
                            let (i, j, l) = (k % m, (k / m) % m, k / (m * m));
                            let z = if d == 3 { at(l) } else { 0.0 };
                            (at(i).powi(2) + at(j).powi(2) + z * z).sqrt() - radius
                        })
                        .collect();
                    let first = world.add_distance_field(&samples).map_err(err)?;
                    mpm_gimp::ColliderShape::Sdf {
                        first,
                        dims: dims.map(|n| n as u32),
                        spacing,
                    }
                } else {
                    mpm_gimp::ColliderShape::Sphere { radius }
                };
                for k in 0..4 {
                    let x = lo[0] + (k as Real + 0.5) * 0.25 * (hi[0] - lo[0]);
                    world
                        .add_collider(&mpm_gimp::ColliderDef {
                            shape,
                            position: Vec3::new(x, mid(1), mid(2)),
                            contact: mpm_gimp::Contact::Stick,
                            ..mpm_gimp::ColliderDef::DEFAULT
                        })
                        .map_err(err)?;
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }
}

/// The order of the particles in their columns (which the step's scatter sums in runs that
/// share a stencil: [`World::fill_box`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(dead_code)] // The criterion benches use the fill order only.
pub enum ParticleOrder {
    /// As `fill_box` writes them: the sites of each stencil bin together.
    Fill,
    /// Lattice rows, x fastest (a host adding its particles row by row): runs of about 2.
    Rows,
    /// A fixed random permutation: runs of 1 and no locality.
    Shuffled,
}

#[allow(dead_code)]
impl ParticleOrder {
    pub const ALL: [(ParticleOrder, &'static str); 3] = [
        (ParticleOrder::Fill, "fill"),
        (ParticleOrder::Rows, "rows"),
        (ParticleOrder::Shuffled, "shuffled"),
    ];

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(o, _)| *o == self)
            .map_or("?", |(_, n)| n)
    }

    /// The permutation that puts the particles of `world` (positions `x`) in this order: entry
    /// `i` is the index of the particle that goes to place `i`.
    fn permutation(self, x: &[&[Real]; 3]) -> Vec<usize> {
        let n = x[0].len();
        let mut p: Vec<usize> = (0..n).collect();
        match self {
            ParticleOrder::Fill => {}
            ParticleOrder::Rows => p.sort_by(|&i, &j| {
                let at = |a: usize, k: usize| x[a].get(k).copied().unwrap_or(0.0); // 2D: no z
                let key = |k: usize| [at(2, k), at(1, k), at(0, k)];
                key(i).partial_cmp(&key(j)).expect("finite positions")
            }),
            ParticleOrder::Shuffled => {
                // Fisher-Yates with a fixed 64-bit LCG: the same permutation every run.
                let mut state: u64 = 0x2545_f491_4f6c_dd1d;
                for i in (1..n).rev() {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    p.swap(i, ((state >> 33) % (i as u64 + 1)) as usize);
                }
            }
        }
        p
    }
}

/// Particles per cell per axis of the filled block.
pub const PPC: u32 = 2;
/// Cell size, m.
pub const CELL: Real = 0.01;

/// The scene's method and geometry.
pub struct SceneDef {
    pub dimension: Dimension,
    pub shape: ShapeFunction,
    pub material: MaterialModel,
    pub order: UpdateOrder,
    /// Grid cells per axis.
    pub grid: [u32; 3],
    /// The block: its first cell and its cell count per axis.
    pub first: [u32; 3],
    pub block: [u32; 3],
    /// The effect declared, if any.
    pub effect: Effect,
    /// The order of the particles in their columns.
    pub particle_order: ParticleOrder,
    /// Velocity transfer, FLIP fraction and terms of `exp(grad v dt)` (the kernel's defaults
    /// unless a caller prices another method).
    pub transfer: Transfer,
    pub flip_beta: Real,
    pub exp_terms: u32,
    /// The most workers a task system may step the world on (`WorldDef::workers`).
    pub workers: u32,
}

impl SceneDef {
    /// The 2D step_cost scene (a 256 x 128 cell block in a 260 x 132 grid: 131072 particles)
    /// with the kernel's default method and no effect.
    pub const PLANE_2D: SceneDef = SceneDef {
        dimension: Dimension::Plane2D,
        shape: WorldDef::DEFAULT.shape,
        material: MaterialModel::NeoHookean,
        order: WorldDef::DEFAULT.update_order,
        grid: [260, 132, 1],
        first: [2, 2, 0],
        block: [256, 128, 1],
        effect: Effect::None,
        particle_order: ParticleOrder::Fill,
        transfer: WorldDef::DEFAULT.transfer,
        flip_beta: WorldDef::DEFAULT.flip_beta,
        exp_terms: WorldDef::DEFAULT.exp_terms,
        workers: 1,
    };
}

/// A world holding the scene, in its own storage.
pub struct Scene {
    pub storage: HeapBuffer,
    pub particles: u32,
    /// Bytes of the world (its memory requirement); step_cost reports it, the criterion
    /// benches do not.
    #[allow(dead_code)]
    pub bytes: usize,
}

impl Scene {
    /// Builds the scene, or says which step failed.
    pub fn new(s: &SceneDef) -> Result<Scene, String> {
        let axes = if s.dimension == Dimension::ThreeD {
            3
        } else {
            2
        };
        let expected: u32 = (0..axes).map(|a| s.block[a] * PPC).product();
        let mut def = WorldDef {
            dimension: s.dimension,
            cell_size: CELL,
            cells: s.grid,
            particle_capacity: expected,
            material_capacity: 1,
            shape: s.shape,
            particles_per_cell: PPC,
            update_order: s.order,
            transfer: s.transfer,
            flip_beta: s.flip_beta,
            exp_terms: s.exp_terms,
            workers: s.workers,
            ..WorldDef::DEFAULT
        };
        s.effect.declare(&mut def, expected)?;
        // The plastic models keep their history in a column of their own.
        def.effects.plasticity = s.material.plastic();
        let req = memory_requirements(&def).map_err(|e| format!("invalid definition: {e:?}"))?;
        let mut storage = HeapBuffer::new(req.bytes);
        let mut world = World::init(&def, storage.as_mut_bytes())
            .map_err(|e| format!("World::init failed: {e:?}"))?;
        let material = world
            .add_material(&s.effect.material(s.material))
            .map_err(|e| format!("add_material failed: {e:?}"))?;
        // Box bounds a quarter of the particle spacing inside the block's faces: the lattice
        // sites (sub-cell centres) of exactly the block's cells fall inside, with no rounding
        // at the edges. Cells count from the grid's origin.
        let spacing = CELL / PPC as Real;
        let mut lo = Vec3::ZERO;
        let mut hi = Vec3::ZERO;
        for a in 0..axes {
            lo[a] = def.origin[a] + s.first[a] as Real * CELL + 0.25 * spacing;
            hi[a] = def.origin[a] + (s.first[a] + s.block[a]) as Real * CELL - 0.25 * spacing;
        }
        let ids = world
            .fill_box(lo, hi, material, Vec3::new(0.0, -0.1, 0.0))
            .map_err(|e| format!("fill_box failed: {e:?}"))?;
        if ids.len() as u32 != expected {
            return Err(format!("{} particles, expected {expected}", ids.len()));
        }
        if s.particle_order != ParticleOrder::Fill {
            // Read the filled block back, permute it, and add it again to a fresh world.
            let v = world.particles();
            let perm = s.particle_order.permutation(&v.position);
            let take = |c: &[Real]| -> Vec<Real> {
                if c.is_empty() {
                    Vec::new()
                } else {
                    perm.iter().map(|&i| c[i]).collect()
                }
            };
            let position = v.position.map(take);
            let velocity = v.velocity.map(take);
            let (mass, volume) = (take(v.mass), take(v.volume0));
            let ids: Vec<u32> = perm.iter().map(|&i| v.material[i]).collect();
            world = World::init(&def, storage.as_mut_bytes())
                .map_err(|e| format!("World::init failed: {e:?}"))?;
            world
                .add_material(&s.effect.material(s.material))
                .map_err(|e| format!("add_material failed: {e:?}"))?;
            world
                .add_particles(&ParticleBatch {
                    position: position.each_ref().map(|c| c.as_slice()),
                    velocity: velocity.each_ref().map(|c| c.as_slice()),
                    mass: &mass,
                    volume: &volume,
                    material: &ids,
                })
                .map_err(|e| format!("add_particles failed: {e:?}"))?;
        }
        s.effect.set_up(&mut world)?;
        Ok(Scene {
            storage,
            particles: expected,
            bytes: req.bytes,
        })
    }

    /// The scene's world.
    pub fn world(&mut self) -> World<'_> {
        World::reopen(self.storage.as_mut_bytes()).expect("the scene's world")
    }
}
