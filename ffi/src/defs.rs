//! The definitions a C host fills: world, material, and the enums that choose the method.
//! Every definition starts from its `*_default()` function, which sets a cookie that init and
//! add check, so a struct the host zeroed or filled by hand is refused instead of misread.
//!
//! Enum-valued fields are plain `uint32_t` on the Rust side (named by their enum type in the
//! header): a value out of range from C is then an `MPM_STATUS_INVALID_ENUM`, never undefined
//! behaviour.

use crate::status::MpmStatus;
use crate::{mpm_real, MpmVec3};
use kernel::{
    Boundary, Dimension, MaterialDef, MaterialModel, ShapeFunction, UpdateOrder, WorldDef,
};

/// Spatial dimension and kinematic assumption (`mpm_gimp::Dimension`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmDimension {
    /// Two dimensions, plane strain (per unit thickness; F_zz = 1).
    Plane2d = 2,
    /// Three dimensions.
    Space3d = 3,
    /// Two dimensions, axisymmetric (r, z). Reserved: init answers `MPM_STATUS_UNSUPPORTED`.
    Axisymmetric2d = 4,
}

/// Grid shape function (`mpm_gimp::ShapeFunction`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmShape {
    /// Classic MPM: linear hats, 2 nodes per axis.
    Linear = 0,
    /// uGIMP (Bardenhagen and Kober 2004), 3 nodes per axis.
    Gimp = 1,
    /// Quadratic B-spline, 3 nodes per axis.
    QuadraticBspline = 2,
    /// Cubic B-spline, 4 nodes per axis.
    CubicBspline = 3,
}

/// Where the stress update sits in a step (`mpm_gimp::UpdateOrder`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmUpdateOrder {
    /// Update stress first.
    Usf = 0,
    /// Update stress last (cheapest).
    Usl = 1,
    /// Modified USL (most robust where nodal masses are tiny).
    Musl = 2,
}

/// Boundary condition of one face of the grid box (`mpm_gimp::Boundary`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmBoundary {
    /// Wall nodes have zero velocity.
    Stick = 0,
    /// Wall nodes have zero normal velocity.
    Slip = 1,
    /// No condition; particles that cross the face leave the simulation.
    Open = 2,
}

/// Index of each face in `MpmWorldDef::faces`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmFace {
    /// Lowest x.
    XMin = 0,
    /// Highest x.
    XMax = 1,
    /// Lowest y.
    YMin = 2,
    /// Highest y.
    YMax = 3,
    /// Lowest z (3D only).
    ZMin = 4,
    /// Highest z (3D only).
    ZMax = 5,
}

/// Constitutive model (`mpm_gimp::MaterialModel`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmMaterialModel {
    /// Corotated isotropic linear elasticity (small strain).
    LinearElastic = 0,
    /// Compressible neo-Hookean.
    NeoHookean = 1,
}

/// Status of a particle in the status column (`mpm_gimp::ParticleStatus`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MpmParticleStatus {
    /// Takes part in every step.
    Active = 0,
    /// Its state turned non-finite (or F inverted): it keeps its last finite position, its
    /// velocity is zero, and it no longer takes part.
    Frozen = 1,
    /// It crossed an open face and no longer takes part.
    Escaped = 2,
}

/// An `MpmDimension` value as stored in a definition (any 32-bit value from C).
pub type MpmDimensionValue = u32;
/// An `MpmShape` value as stored in a definition.
pub type MpmShapeValue = u32;
/// An `MpmUpdateOrder` value as stored in a definition.
pub type MpmUpdateOrderValue = u32;
/// An `MpmBoundary` value as stored in a definition.
pub type MpmBoundaryValue = u32;
/// An `MpmMaterialModel` value as stored in a definition.
pub type MpmMaterialModelValue = u32;

/// Everything that fixes a world's size and method: the C form of `mpm_gimp::WorldDef`, whose
/// documentation gives each field's unit, range and the reason for its default. Get one from
/// `mpm_world_def_default()` and change the fields you need.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmWorldDef {
    /// Default `MPM_DIMENSION_PLANE2D`.
    pub dimension: MpmDimensionValue,
    /// Lowest corner of the grid, m. Default (0, 0, 0).
    pub origin: MpmVec3,
    /// Cell edge length h, m, > 0. Default 0.01.
    pub cell_size: mpm_real,
    /// Cells along x, y, z (z ignored in 2D). Default 100 x 100 x 1.
    pub cells: [u32; 3],
    /// Most particles the world holds. Default 65536.
    pub particle_capacity: u32,
    /// Most materials the world holds. Default 8.
    pub material_capacity: u32,
    /// Default `MPM_SHAPE_GIMP`.
    pub shape: MpmShapeValue,
    /// Particles per cell per axis (uGIMP particle size, fill spacing), 1..=8. Default 2.
    pub particles_per_cell: u32,
    /// FLIP fraction beta in [0, 1]. Default 0.99.
    pub flip_beta: mpm_real,
    /// Default `MPM_UPDATE_ORDER_MUSL`.
    pub update_order: MpmUpdateOrderValue,
    /// Gravity, m/s^2. Default (0, -9.81, 0).
    pub gravity: MpmVec3,
    /// Boundary of each face, indexed by `MpmFace`. Default all `MPM_BOUNDARY_SLIP`.
    pub faces: [MpmBoundaryValue; 6],
    /// Terms of exp(grad v dt), 1..=8. Default 2.
    pub exp_terms: u32,
    /// Courant number in (0, 1]. Default 0.5.
    pub cfl: mpm_real,
    /// Set by `mpm_world_def_default`; do not change.
    pub internal_cookie: u32,
}

/// A material: the C form of `mpm_gimp::MaterialDef`. Get one from
/// `mpm_material_def_default()`.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmMaterialDef {
    /// Default `MPM_MATERIAL_MODEL_NEO_HOOKEAN`.
    pub model: MpmMaterialModelValue,
    /// Young's modulus E, Pa, > 0. Default 1e6.
    pub youngs_modulus: mpm_real,
    /// Poisson's ratio in (-1, 0.5). Default 0.3.
    pub poisson_ratio: mpm_real,
    /// Initial density, kg/m^3, > 0. Default 1000.
    pub density: mpm_real,
    /// Set by `mpm_material_def_default`; do not change.
    pub internal_cookie: u32,
}

/// The cookie of a world definition of this precision ("MPMW" and the size of `mpm_real`).
const WORLD_COOKIE: u32 = u32::from_le_bytes(*b"MPMW") ^ (core::mem::size_of::<mpm_real>() as u32);
/// The cookie of a material definition of this precision.
const MATERIAL_COOKIE: u32 =
    u32::from_le_bytes(*b"MPMM") ^ (core::mem::size_of::<mpm_real>() as u32);

pub(crate) fn vec3(v: MpmVec3) -> kernel::Vec3 {
    kernel::Vec3::new(v.x, v.y, v.z)
}

fn c_vec3(v: kernel::Vec3) -> MpmVec3 {
    MpmVec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// The C definition of a Rust one (with the cookie).
pub(crate) fn world_def_to_c(d: &WorldDef) -> MpmWorldDef {
    MpmWorldDef {
        dimension: d.dimension as u32,
        origin: c_vec3(d.origin),
        cell_size: d.cell_size,
        cells: d.cells,
        particle_capacity: d.particle_capacity,
        material_capacity: d.material_capacity,
        shape: d.shape as u32,
        particles_per_cell: d.particles_per_cell,
        flip_beta: d.flip_beta,
        update_order: d.update_order as u32,
        gravity: c_vec3(d.gravity),
        faces: d.faces.map(|f| f as u32),
        exp_terms: d.exp_terms,
        cfl: d.cfl,
        internal_cookie: WORLD_COOKIE,
    }
}

/// The Rust definition of a C one: the cookie and every enum value checked.
pub(crate) fn world_def_from_c(d: &MpmWorldDef) -> Result<WorldDef, MpmStatus> {
    if d.internal_cookie != WORLD_COOKIE {
        return Err(MpmStatus::DefNotFromDefault);
    }
    let enum_value = MpmStatus::InvalidEnum;
    let dimension = Dimension::from_code(d.dimension).ok_or(enum_value)?;
    let shape = ShapeFunction::from_code(d.shape).ok_or(enum_value)?;
    let update_order = UpdateOrder::from_code(d.update_order).ok_or(enum_value)?;
    let mut faces = [Boundary::Slip; 6];
    for (f, &v) in faces.iter_mut().zip(d.faces.iter()) {
        *f = Boundary::from_code(v).ok_or(enum_value)?;
    }
    Ok(WorldDef {
        dimension,
        origin: vec3(d.origin),
        cell_size: d.cell_size,
        cells: d.cells,
        particle_capacity: d.particle_capacity,
        material_capacity: d.material_capacity,
        shape,
        particles_per_cell: d.particles_per_cell,
        flip_beta: d.flip_beta,
        update_order,
        gravity: vec3(d.gravity),
        faces,
        exp_terms: d.exp_terms,
        cfl: d.cfl,
    })
}

/// The Rust material of a C one: the cookie and the model checked.
pub(crate) fn material_def_from_c(d: &MpmMaterialDef) -> Result<MaterialDef, MpmStatus> {
    if d.internal_cookie != MATERIAL_COOKIE {
        return Err(MpmStatus::DefNotFromDefault);
    }
    let model = MaterialModel::from_code(d.model).ok_or(MpmStatus::InvalidEnum)?;
    Ok(MaterialDef {
        model,
        youngs_modulus: d.youngs_modulus,
        poisson_ratio: d.poisson_ratio,
        density: d.density,
    })
}

/// The documented world defaults (`mpm_gimp::WorldDef::DEFAULT`), with the cookie init checks.
/// The header maps this name to a symbol of the header's precision, so code compiled for one
/// precision does not link against the library of the other.
#[cfg(not(feature = "f64"))]
#[no_mangle]
pub extern "C" fn mpm_world_def_default_f32() -> MpmWorldDef {
    world_def_to_c(&WorldDef::DEFAULT)
}

/// The documented world defaults (`mpm_gimp::WorldDef::DEFAULT`), with the cookie init checks.
/// The header maps this name to a symbol of the header's precision, so code compiled for one
/// precision does not link against the library of the other.
#[cfg(feature = "f64")]
#[no_mangle]
pub extern "C" fn mpm_world_def_default_f64() -> MpmWorldDef {
    world_def_to_c(&WorldDef::DEFAULT)
}

/// The documented material defaults (`mpm_gimp::MaterialDef::DEFAULT`), with the cookie
/// `mpm_world_add_material` checks. Precision-specific symbol, as `mpm_world_def_default`.
#[cfg(not(feature = "f64"))]
#[no_mangle]
pub extern "C" fn mpm_material_def_default_f32() -> MpmMaterialDef {
    material_def_default()
}

/// The documented material defaults (`mpm_gimp::MaterialDef::DEFAULT`), with the cookie
/// `mpm_world_add_material` checks. Precision-specific symbol, as `mpm_world_def_default`.
#[cfg(feature = "f64")]
#[no_mangle]
pub extern "C" fn mpm_material_def_default_f64() -> MpmMaterialDef {
    material_def_default()
}

fn material_def_default() -> MpmMaterialDef {
    let d = MaterialDef::DEFAULT;
    MpmMaterialDef {
        model: d.model as u32,
        youngs_modulus: d.youngs_modulus,
        poisson_ratio: d.poisson_ratio,
        density: d.density,
        internal_cookie: MATERIAL_COOKIE,
    }
}
