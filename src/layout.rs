//! Memory requirements, and carving aligned columns out of the caller's buffer by offset.
//!
//! A world's buffer is, in order:
//! 1. the [`Header`] (definition, counts, time; plain old data, 8-byte fields only);
//! 2. the material table, `material_capacity` [`MaterialRecord`]s;
//! 3. the particle columns, one per scalar component, each `capacity` rounded up to
//!    [`CHUNK`] entries and starting on a [`ALIGN`]-byte boundary;
//! 4. the grid node columns, likewise, one entry per node.
//!
//! Nothing in the buffer is a pointer: every column is found from the definition stored in the
//! header, so a byte copy of the buffer is a second, independent world.

use crate::def::{Boundary, Dimension, ShapeFunction, UpdateOrder, WorldDef};
use crate::{Error, Real, Vec3};
use bytemuck::{Pod, Zeroable};
use core::mem::size_of;

/// Alignment of the buffer and of every column, bytes (a cache line; enough for any SIMD width).
pub const ALIGN: usize = 64;
/// Columns are padded to a multiple of this many entries so chunked loops need no remainder.
pub const CHUNK: usize = 16;

const MAGIC: u64 = u64::from_le_bytes(*b"MPMGIMP\0");
/// Layout version: bumped whenever the buffer format changes.
const VERSION: u64 = 1;

/// Bytes and alignment a world needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryRequirements {
    /// Size of the buffer, bytes.
    pub bytes: usize,
    /// Alignment of the buffer's first byte, bytes.
    pub align: usize,
}

/// The world header at offset 0 of the buffer. All fields are 8 bytes wide so the struct has no
/// padding and is plain old data in both precisions.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct Header {
    pub magic: u64,
    pub version: u64,
    pub real_bytes: u64,
    pub total_bytes: u64,
    // The definition, widened to u64 / f64 (exact for f32 and f64).
    pub dimension: u64,
    pub origin: [f64; 3],
    pub cell_size: f64,
    pub cells: [u64; 3],
    pub particle_capacity: u64,
    pub material_capacity: u64,
    pub shape: u64,
    pub particles_per_cell: u64,
    pub flip_beta: f64,
    pub update_order: u64,
    pub gravity: [f64; 3],
    pub faces: [u64; 6],
    pub exp_terms: u64,
    pub cfl: f64,
    // State.
    pub particle_count: u64,
    pub material_count: u64,
    pub time: f64,
    pub step_count: u64,
    /// Smallest particle mass added so far: scales the nodal mass cutoff.
    pub min_particle_mass: f64,
}

// SAFETY: Header is repr(C), every field is a u64, f64 or an array of them (8-byte size and
// alignment), so there is no padding; all bit patterns are valid for these types.
unsafe impl Zeroable for Header {}
// SAFETY: as above; Header is Copy and 'static.
unsafe impl Pod for Header {}

const _: () = assert!(size_of::<Header>() == 8 * 34);

/// One material in the buffer's table: parameters and what the step derives from them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub(crate) struct MaterialRecord {
    /// [`crate::MaterialModel`] as a number (exact in any float type).
    pub model: Real,
    pub youngs_modulus: Real,
    pub poisson_ratio: Real,
    pub density: Real,
    pub lambda: Real,
    pub mu: Real,
    pub wave_speed: Real,
    pub reserved: Real,
}

// SAFETY: MaterialRecord is repr(C) with eight fields of one float type: no padding, and every
// bit pattern is a valid float.
unsafe impl Zeroable for MaterialRecord {}
// SAFETY: as above; it is Copy and 'static.
unsafe impl Pod for MaterialRecord {}

/// Number of stored stress components (tau/rho0): 2D xx, yy, xy, zz; 3D xx, yy, zz, xy, xz, yz.
pub(crate) const fn stress_components(d: usize) -> usize {
    if d == 2 {
        4
    } else {
        6
    }
}

/// Where every column of a world lives, computed from its definition alone.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    pub d: usize,
    pub padded_capacity: usize,
    pub nodes: usize,
    pub materials_offset: usize,
    pub particle_offset: usize,
    pub real_column_bytes: usize,
    pub u32_column_bytes: usize,
    /// Particle Real columns: x[D], v[D], mass, vol0, H[D*D], tau[NS], then x_next[D] (MUSL).
    pub particle_real_columns: usize,
    pub grid_offset: usize,
    pub node_column_bytes: usize,
    /// Grid columns: mass, velocity[D], acceleration[D], then the stress-update velocity[D]
    /// (USF and MUSL).
    pub grid_columns: usize,
    pub total: usize,
}

const fn round_up(x: usize, to: usize) -> usize {
    x.div_ceil(to) * to
}

impl Layout {
    /// Layout of a validated definition.
    pub fn of(def: &WorldDef) -> Layout {
        let d = def.axes();
        let cap = round_up(def.particle_capacity as usize, CHUNK);
        let nodes: usize = (0..d).map(|a| def.cells[a] as usize + 1).product();
        let musl = def.update_order == UpdateOrder::Musl;
        let real_column_bytes = round_up(cap * size_of::<Real>(), ALIGN);
        let u32_column_bytes = round_up(cap * 4, ALIGN);
        let particle_real_columns =
            2 * d + 2 + d * d + stress_components(d) + if musl { d } else { 0 };
        // Stencil rows may reach past the last node: see `crate::shape::ROW`.
        let node_column_bytes = round_up(
            round_up(nodes + crate::shape::ROW, CHUNK) * size_of::<Real>(),
            ALIGN,
        );
        let stress_velocity = def.update_order != UpdateOrder::Usl;
        let grid_columns = 1 + 2 * d + if stress_velocity { d } else { 0 };
        let materials_offset = round_up(size_of::<Header>(), ALIGN);
        let particle_offset = round_up(
            materials_offset + def.material_capacity as usize * size_of::<MaterialRecord>(),
            ALIGN,
        );
        let grid_offset =
            particle_offset + particle_real_columns * real_column_bytes + 2 * u32_column_bytes;
        let total = grid_offset + grid_columns * node_column_bytes;
        Layout {
            d,
            padded_capacity: cap,
            nodes,
            materials_offset,
            particle_offset,
            real_column_bytes,
            u32_column_bytes,
            particle_real_columns,
            grid_offset,
            node_column_bytes,
            grid_columns,
            total,
        }
    }
}

/// Largest count of particles or nodes a world may index (u32 ids, and room for padding).
const MAX_ITEMS: u64 = 1 << 30;

/// Checks every field of a definition; the error names the first one that is wrong.
pub(crate) fn validate(def: &WorldDef) -> Result<(), Error> {
    if def.dimension == Dimension::Axisymmetric2D {
        return Err(Error::Unsupported);
    }
    if !(def.cell_size.is_finite() && def.cell_size > 0.0) {
        return Err(Error::InvalidCellSize);
    }
    let used_finite = |v: Vec3| (0..def.axes()).all(|a| v[a].is_finite());
    if !used_finite(def.origin) || !used_finite(def.gravity) {
        return Err(Error::NonFiniteDefinition);
    }
    let min_cells = 2 + 2 * def.shape.margin_cells();
    let mut nodes: u64 = 1;
    for a in 0..def.axes() {
        if def.cells[a] < min_cells {
            return Err(Error::InvalidCellCount);
        }
        nodes = nodes.saturating_mul(def.cells[a] as u64 + 1);
        // The far corner of the grid must stay finite in Real.
        let extent = def.origin[a] + def.cell_size * def.cells[a] as Real;
        if !extent.is_finite() {
            return Err(Error::InvalidCellCount);
        }
    }
    if nodes > MAX_ITEMS {
        return Err(Error::InvalidCellCount);
    }
    if def.particle_capacity == 0
        || def.particle_capacity as u64 > MAX_ITEMS
        || def.material_capacity == 0
        || def.material_capacity > 1 << 16
    {
        return Err(Error::InvalidCapacity);
    }
    if !(0.0..=1.0).contains(&def.flip_beta) {
        return Err(Error::InvalidFlipBeta);
    }
    if !(def.cfl > 0.0 && def.cfl <= 1.0) {
        return Err(Error::InvalidCfl);
    }
    if !(1..=8).contains(&def.exp_terms) {
        return Err(Error::InvalidExpTerms);
    }
    if !(1..=8).contains(&def.particles_per_cell) {
        return Err(Error::InvalidParticlesPerCell);
    }
    Ok(())
}

/// Bytes and alignment a world of this definition needs: a pure function of the definition.
pub fn memory_requirements(def: &WorldDef) -> Result<MemoryRequirements, Error> {
    validate(def)?;
    Ok(MemoryRequirements {
        bytes: Layout::of(def).total,
        align: ALIGN,
    })
}

impl Header {
    pub fn new(def: &WorldDef, total_bytes: usize) -> Header {
        let w = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        Header {
            magic: MAGIC,
            version: VERSION,
            real_bytes: size_of::<Real>() as u64,
            total_bytes: total_bytes as u64,
            dimension: def.dimension as u64,
            origin: w(def.origin),
            cell_size: def.cell_size as f64,
            cells: def.cells.map(|c| c as u64),
            particle_capacity: def.particle_capacity as u64,
            material_capacity: def.material_capacity as u64,
            shape: def.shape as u64,
            particles_per_cell: def.particles_per_cell as u64,
            flip_beta: def.flip_beta as f64,
            update_order: def.update_order as u64,
            gravity: w(def.gravity),
            faces: def.faces.map(|f| f as u64),
            exp_terms: def.exp_terms as u64,
            cfl: def.cfl as f64,
            particle_count: 0,
            material_count: 0,
            time: 0.0,
            step_count: 0,
            min_particle_mass: f64::INFINITY,
        }
    }

    /// The definition stored in the header, or `NotAWorld` if the header is not one this build
    /// wrote (wrong magic, version, precision or an enum value out of range).
    pub fn def(&self) -> Result<WorldDef, Error> {
        if self.magic != MAGIC
            || self.version != VERSION
            || self.real_bytes != size_of::<Real>() as u64
        {
            return Err(Error::NotAWorld);
        }
        let small = |v: u64| u32::try_from(v).map_err(|_| Error::NotAWorld);
        let code = |v: u64| u32::try_from(v).ok();
        let not_a_world = Error::NotAWorld;
        let dimension = code(self.dimension)
            .and_then(Dimension::from_code)
            .ok_or(not_a_world)?;
        let shape = code(self.shape)
            .and_then(ShapeFunction::from_code)
            .ok_or(not_a_world)?;
        let update_order = code(self.update_order)
            .and_then(UpdateOrder::from_code)
            .ok_or(not_a_world)?;
        let mut faces = [Boundary::Slip; 6];
        for (f, &c) in faces.iter_mut().zip(self.faces.iter()) {
            *f = code(c).and_then(Boundary::from_code).ok_or(not_a_world)?;
        }
        let v = |a: [f64; 3]| Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
        Ok(WorldDef {
            dimension,
            origin: v(self.origin),
            cell_size: self.cell_size as Real,
            cells: [
                small(self.cells[0])?,
                small(self.cells[1])?,
                small(self.cells[2])?,
            ],
            particle_capacity: small(self.particle_capacity)?,
            material_capacity: small(self.material_capacity)?,
            shape,
            particles_per_cell: small(self.particles_per_cell)?,
            flip_beta: self.flip_beta as Real,
            update_order,
            gravity: v(self.gravity),
            faces,
            exp_terms: small(self.exp_terms)?,
            cfl: self.cfl as Real,
        })
    }
}

/// Index of each particle Real column (see [`Layout::real_col`]), for dimension `d`.
pub(crate) mod col {
    pub const fn x(a: usize) -> usize {
        a
    }
    pub const fn v(d: usize, a: usize) -> usize {
        d + a
    }
    pub const fn mass(d: usize) -> usize {
        2 * d
    }
    pub const fn vol0(d: usize) -> usize {
        2 * d + 1
    }
    /// Displacement gradient `H = F - I`, entry (a, b).
    pub const fn h(d: usize, a: usize, b: usize) -> usize {
        2 * d + 2 + a * d + b
    }
    pub const fn tau(d: usize, k: usize) -> usize {
        2 * d + 2 + d * d + k
    }
    /// u32 columns.
    pub const MATERIAL: usize = 0;
    pub const STATUS: usize = 1;
}

impl Layout {
    /// Byte range of particle Real column `j` (first `capacity` entries).
    pub fn real_col(&self, j: usize, count: usize) -> core::ops::Range<usize> {
        let start = self.particle_offset + j * self.real_column_bytes;
        start..start + count * size_of::<Real>()
    }

    /// Byte range of particle u32 column `j` (first `count` entries).
    pub fn u32_col(&self, j: usize, count: usize) -> core::ops::Range<usize> {
        let start = self.particle_offset
            + self.particle_real_columns * self.real_column_bytes
            + j * self.u32_column_bytes;
        start..start + count * 4
    }
}
