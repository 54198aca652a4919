//! The benchmark scene, shared by the criterion benches (`benches/step.rs`) and the cost
//! example (`examples/step_cost.rs`, which includes this file with `#[path]`): a block of
//! elastic material filled at 2 particles per cell per axis, moving down at 0.1 m/s under
//! gravity, inside a grid with slip walls.

use mpm_gimp::{
    memory_requirements, Dimension, HeapBuffer, MaterialDef, MaterialModel, Real, ShapeFunction,
    UpdateOrder, Vec3, World, WorldDef,
};

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
}

/// A world holding the scene, in its own storage.
pub struct Scene {
    pub storage: HeapBuffer,
    pub particles: u32,
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
        let def = WorldDef {
            dimension: s.dimension,
            cell_size: CELL,
            cells: s.grid,
            particle_capacity: expected,
            material_capacity: 1,
            shape: s.shape,
            particles_per_cell: PPC,
            update_order: s.order,
            ..WorldDef::DEFAULT
        };
        let req = memory_requirements(&def).map_err(|e| format!("invalid definition: {e:?}"))?;
        let mut storage = HeapBuffer::new(req.bytes);
        let mut world = World::init(&def, storage.as_mut_bytes())
            .map_err(|e| format!("World::init failed: {e:?}"))?;
        let material = world
            .add_material(&MaterialDef {
                model: s.material,
                ..MaterialDef::DEFAULT
            })
            .map_err(|e| format!("add_material failed: {e:?}"))?;
        // Box bounds a quarter of the particle spacing inside the block's faces: the lattice
        // sites (sub-cell centres) of exactly the block's cells fall inside, with no rounding
        // at the edges.
        let spacing = CELL / PPC as Real;
        let mut lo = Vec3::ZERO;
        let mut hi = Vec3::ZERO;
        for a in 0..axes {
            lo[a] = s.first[a] as Real * CELL + 0.25 * spacing;
            hi[a] = (s.first[a] + s.block[a]) as Real * CELL - 0.25 * spacing;
        }
        let ids = world
            .fill_box(lo, hi, material, Vec3::new(0.0, -0.1, 0.0))
            .map_err(|e| format!("fill_box failed: {e:?}"))?;
        if ids.len() as u32 != expected {
            return Err(format!("{} particles, expected {expected}", ids.len()));
        }
        Ok(Scene {
            storage,
            particles: expected,
        })
    }

    /// The scene's world.
    pub fn world(&mut self) -> World<'_> {
        World::open(self.storage.as_mut_bytes()).expect("the scene's world")
    }
}
