//! The example scenes, defined once for the programs that run, draw or render them (the
//! kernel's `drop` example, the `pictures` example).

use mpm_gimp::{Boundary, Dimension, Error, Face, MaterialDef, Vec3, World, WorldDef};

/// The drop scene's definition: a 1 m box of 40 cells per axis (2D, or 3D with `three_d`)
/// whose floor is a stick wall; `classic` switches to classic MPM (linear shape functions with
/// USL, unstable where particles cross cells).
pub fn drop_def(three_d: bool, classic: bool) -> WorldDef {
    let mut def = WorldDef {
        cells: [40, 40, if three_d { 40 } else { 1 }],
        cell_size: 0.025,
        particle_capacity: 100_000,
        dimension: if three_d {
            Dimension::ThreeD
        } else {
            Dimension::Plane2D
        },
        ..WorldDef::DEFAULT
    };
    def.faces[Face::YMin as usize] = Boundary::Stick;
    if classic {
        def.shape = mpm_gimp::ShapeFunction::Linear;
        def.update_order = mpm_gimp::UpdateOrder::Usl;
    }
    def
}

/// Fills a world made from [`drop_def`]: a soft rubber block (E = 200 kPa) at rest, 0.4 m by
/// 0.3 m (by 0.3 m) with its bottom 0.4 m above the floor. Returns how many particles it holds.
pub fn drop_fill(world: &mut World) -> Result<usize, Error> {
    let rubber = world.add_material(&MaterialDef {
        youngs_modulus: 2.0e5,
        ..MaterialDef::DEFAULT
    })?;
    let (lo, hi) = if world.def().dimension == Dimension::ThreeD {
        (Vec3::new(0.35, 0.4, 0.35), Vec3::new(0.65, 0.7, 0.65))
    } else {
        (Vec3::new(0.3, 0.4, 0.0), Vec3::new(0.7, 0.7, 0.0))
    };
    Ok(world.fill_box(lo, hi, rubber, Vec3::ZERO)?.len())
}
