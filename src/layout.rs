//! Memory requirements, and carving aligned columns out of the caller's buffer by offset.
//!
//! A world's buffer is, in order:
//! 1. the [`Header`] (definition, counts, time; plain old data, 8-byte fields only);
//! 2. the material table, `material_capacity` [`MaterialRecord`]s;
//! 3. the traction table, `traction_capacity` [`TractionRecord`]s (none unless declared);
//!    the collider table, `collider_capacity` [`ColliderRecord`]s, then as many
//!    [`ColliderImpulse`]s, then `sdf_capacity` distance samples (none unless declared);
//! 4. the particle columns, one per scalar component, each `capacity` rounded up to
//!    [`CHUNK`] entries and starting on a [`ALIGN`]-byte boundary, columns of 4 KiB or more
//!    a page multiple plus 5 cache lines apart (`column_stride`: no 4K aliasing);
//!    The columns of an effect come after the always-present ones and exist only when the
//!    definition declares the effect;
//! 5. the grid node columns, likewise, one entry per node.
//!
//! Nothing in the buffer is a pointer: every column is found from the definition stored in the
//! header, so a byte copy of the buffer is a second, independent world.

use crate::cut::{Partial, REACH_GROUP, SLOTS_PER_WORKER};
use crate::def::{Boundary, Dimension, Face, ShapeFunction, Transfer, UpdateOrder, WorldDef};
use crate::def::{
    Damping, DampingZone, Effects, Feedback, ScalarBoundary, Schedule, Transport, DAMPING_ZONES,
    SCHEDULE_POINTS, TRACTION_SCHEDULES,
};
use crate::{Error, Real, Vec3};
use bytemuck::{Pod, Zeroable};
use core::mem::size_of;

/// Alignment of the buffer and of every column, bytes (a cache line; enough for any SIMD width).
pub const ALIGN: usize = 64;
/// Columns are padded to a multiple of this many entries so chunked loops need no remainder.
pub const CHUNK: usize = 32;
// Whole reach groups keep chunks whole (`REACH_GROUP`): a multiple of every chunk width.
const _: () = assert!(REACH_GROUP.is_multiple_of(CHUNK));

pub(crate) const MAGIC: u64 = u64::from_le_bytes(*b"MPMGIMP\0");
/// Layout version: bumped whenever the buffer format changes.
const VERSION: u64 = 20;

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
    // The method switch added with the effects, and the effects (`Effects`).
    pub transfer: u64,
    pub damping_declared: u64,
    pub damping_grid: ScheduleRecord,
    pub damping_particle: ScheduleRecord,
    pub feedback_declared: u64,
    pub feedback_gain: f64,
    pub feedback_target: ScheduleRecord,
    pub feedback_max_alpha: f64,
    pub per_particle_damping: u64,
    pub particle_forces: u64,
    pub traction_capacity: u64,
    pub body_force: [f64; 3],
    pub body_force_scale: ScheduleRecord,
    pub heat: TransportRecord,
    pub diffusion: TransportRecord,
    // Effect state.
    pub traction_count: u64,
    /// The thermostat's current alpha, 1/s.
    pub feedback_alpha: f64,
    // The definition's limits (`WorldDef::max_substeps`, `max_volume_ratio`).
    pub max_substeps: u64,
    pub max_volume_ratio: f64,
    /// `WorldDef::workers`.
    pub workers: u64,
    // Nodal damping (`Damping::grid_on_force`, `Damping::zones`).
    pub damping_on_force: u64,
    pub damping_zone_count: u64,
    pub damping_zones: [ZoneRecord; DAMPING_ZONES],
    pub traction_schedules: [ScheduleRecord; TRACTION_SCHEDULES],
    /// `Effects::plasticity`.
    pub plasticity: u64,
    /// `Effects::collider_capacity`, and the colliders added.
    pub collider_capacity: u64,
    pub collider_count: u64,
    /// `WorldDef::wall_friction`, `WorldDef::wall_velocity`.
    pub wall_friction: [f64; 6],
    pub wall_velocity: [[f64; 3]; 6],
    /// `WorldDef::pic_rate`.
    pub pic_rate: f64,
    /// `Effects::sdf_capacity`, and the distance samples added.
    pub sdf_capacity: u64,
    pub sdf_count: u64,
    /// `Effects::body_force_gradient`, by rows.
    pub body_force_gradient: [[f64; 3]; 3],
}

/// A [`DampingZone`] widened to 8-byte fields; `ramp` is 0 for none, else the face's number
/// plus one.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct ZoneRecord {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub rate: f64,
    pub ramp: u64,
}

// SAFETY: repr(C), only u64 and f64 fields: no padding, every bit pattern valid.
unsafe impl Zeroable for ZoneRecord {}
// SAFETY: as above; Copy and 'static.
unsafe impl Pod for ZoneRecord {}

impl ZoneRecord {
    fn of(z: &DampingZone) -> Self {
        let w = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        ZoneRecord {
            min: w(z.min),
            max: w(z.max),
            rate: z.rate as f64,
            ramp: z.ramp.map_or(0, |f| f as u64 + 1),
        }
    }

    fn zone(&self) -> Result<DampingZone, Error> {
        let v = |a: [f64; 3]| Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
        let ramp = match self.ramp {
            0 => None,
            f => Some(
                u32::try_from(f - 1)
                    .ok()
                    .and_then(Face::from_code)
                    .ok_or(Error::NotAWorld)?,
            ),
        };
        Ok(DampingZone {
            min: v(self.min),
            max: v(self.max),
            rate: self.rate as Real,
            ramp,
        })
    }
}

/// An optional [`Transport`] widened to 8-byte fields: declared flag, each face's condition
/// (0 insulated, 1 fixed, 2 flux) and value, sources flag.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct TransportRecord {
    pub declared: u64,
    pub kinds: [u64; 6],
    pub values: [f64; 6],
    pub sources: u64,
}

// SAFETY: repr(C), only u64 and f64 fields: no padding, every bit pattern valid.
unsafe impl Zeroable for TransportRecord {}
// SAFETY: as above; Copy and 'static.
unsafe impl Pod for TransportRecord {}

impl TransportRecord {
    fn of(t: &Option<Transport>) -> Self {
        let mut r = TransportRecord::zeroed();
        if let Some(t) = t {
            r.declared = 1;
            r.sources = t.sources as u64;
            for (k, f) in t.faces.iter().enumerate() {
                (r.kinds[k], r.values[k]) = match *f {
                    ScalarBoundary::Insulated => (0, 0.0),
                    ScalarBoundary::Fixed(v) => (1, v as f64),
                    ScalarBoundary::Flux(v) => (2, v as f64),
                };
            }
        }
        r
    }

    fn transport(&self) -> Result<Option<Transport>, Error> {
        if self.declared == 0 {
            return Ok(None);
        }
        if self.declared != 1 || self.sources > 1 {
            return Err(Error::NotAWorld);
        }
        let mut faces = [ScalarBoundary::Insulated; 6];
        for k in 0..6 {
            let v = self.values[k] as Real;
            faces[k] = match self.kinds[k] {
                0 => ScalarBoundary::Insulated,
                1 => ScalarBoundary::Fixed(v),
                2 => ScalarBoundary::Flux(v),
                _ => return Err(Error::NotAWorld),
            };
        }
        Ok(Some(Transport {
            faces,
            sources: self.sources == 1,
        }))
    }
}

/// A [`Schedule`] widened to 8-byte fields.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct ScheduleRecord {
    pub points: u64,
    pub times: [f64; SCHEDULE_POINTS],
    pub values: [f64; SCHEDULE_POINTS],
}

// SAFETY: repr(C), only u64 and f64 arrays: no padding, every bit pattern valid.
unsafe impl Zeroable for ScheduleRecord {}
// SAFETY: as above; Copy and 'static.
unsafe impl Pod for ScheduleRecord {}

impl ScheduleRecord {
    fn of(s: &Schedule) -> Self {
        ScheduleRecord {
            points: s.points as u64,
            times: s.times.map(|t| t as f64),
            values: s.values.map(|v| v as f64),
        }
    }

    fn schedule(&self) -> Result<Schedule, Error> {
        let points = u32::try_from(self.points).map_err(|_| Error::NotAWorld)?;
        Ok(Schedule {
            points,
            times: self.times.map(|t| t as Real),
            values: self.values.map(|v| v as Real),
        })
    }
}

// SAFETY: Header is repr(C), every field is a u64, f64 or an array of them (8-byte size and
// alignment), so there is no padding; all bit patterns are valid for these types.
unsafe impl Zeroable for Header {}
// SAFETY: as above; Header is Copy and 'static.
unsafe impl Pod for Header {}

const _: () = assert!(
    size_of::<Header>()
        == 8 * (37
            + 14
            + (4 + TRACTION_SCHEDULES) * (1 + 2 * SCHEDULE_POINTS)
            + 2 * 14
            + 4
            + 6 * 4
            + 3
            + 8 * DAMPING_ZONES
            + 9)
);

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
    pub heat_capacity: Real,
    pub conductivity: Real,
    pub diffusivity: Real,
    pub thermal_expansion: Real,
    pub reference_temperature: Real,
    pub swelling: Real,
    pub reference_concentration: Real,
    pub viscosity: Real,
    pub bulk_viscosity: Real,
    pub volume_relaxation: Real,
    pub bulk_modulus: Real,
    pub pressure_exponent: Real,
    pub yield_stress: Real,
    pub hardening_modulus: Real,
    pub friction_angle: Real,
    /// [`crate::FrictionFit`] as a number.
    pub friction_fit: Real,
    pub cohesion: Real,
    pub critical_compression: Real,
    pub critical_stretch: Real,
    pub hardening_coefficient: Real,
    /// Derived once when the material is added (each model's `Model::params` copies them): the
    /// Drucker-Prager `alpha` and apex tension `c cot(phi)` (Pa), and snow's `ln(1 - theta_c)`
    /// and `ln(1 + theta_s)`.
    pub friction_coefficient: Real,
    pub apex_tension: Real,
    pub log_compression: Real,
    pub log_stretch: Real,
}

// SAFETY: MaterialRecord is repr(C) with thirty-one values of one float type: no padding, and every
// bit pattern is a valid float.
unsafe impl Zeroable for MaterialRecord {}
// SAFETY: as above; it is Copy and 'static.
unsafe impl Pod for MaterialRecord {}

/// One traction in the buffer's table: the particle id, the schedule it follows (an index of
/// [`crate::Effects::traction_schedules`]), the traction
/// vector (Pa) with the loaded face's area in the reference configuration (m^2, m per unit
/// thickness in 2D) as fourth entry, and the face's outward unit normal in the reference
/// configuration (fourth entry zero). Two u32 then floats: no implicit padding in either
/// precision.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub(crate) struct TractionRecord {
    pub particle: u32,
    pub schedule: u32,
    /// The traction (Pa) in the world's axes, or for a load that follows the face
    /// ([`TractionRecord::follows`]) along the deformed face's normal and tangents; then the
    /// face's reference area.
    pub traction: [Real; 4],
    /// The face's reference unit normal (its first `d` entries; 0 past them), then
    /// [`TractionRecord::FOLLOWS`] or 0 (a traction in the world's axes).
    pub normal: [Real; 4],
}

impl TractionRecord {
    /// Whether the record is one [`crate::World::add_tractions`] or
    /// [`crate::World::add_surface_tractions`] could have written for a world of `count`
    /// particles in `d` dimensions: finite, a positive area, a unit normal in the plane of the
    /// first `d` axes, a known frame; or a removed one ([`TractionRecord::REMOVED`]).
    pub fn is_valid(&self, count: usize, d: usize) -> bool {
        if *self == Self::REMOVED {
            return true;
        }
        let finite = self
            .traction
            .iter()
            .chain(&self.normal)
            .all(|c| c.is_finite());
        let norm2: Real = self.normal[..d].iter().map(|c| c * c).sum();
        let off_plane = self.normal[d..3].iter().any(|&c| c != 0.0);
        (self.particle as usize) < count
            && (self.schedule as usize) < TRACTION_SCHEDULES
            && finite
            && self.traction[3] > 0.0
            && (norm2 - 1.0).abs() < 1.0e-3
            && !off_plane
            && (self.normal[3] == 0.0 || self.follows())
    }

    /// A removed traction's record ([`crate::World::remove_tractions`]): its id names no
    /// load until an adder takes its room; the other ids stay.
    pub const REMOVED: TractionRecord = TractionRecord {
        particle: u32::MAX,
        schedule: 0,
        traction: [0.0; 4],
        normal: [0.0; 4],
    };

    /// Whether the record is [`TractionRecord::REMOVED`]'s id (a removed traction).
    pub fn is_removed(&self) -> bool {
        self.particle == u32::MAX
    }

    /// How long a table of `records` is without the removed ones at its end.
    pub fn end_of(records: &[TractionRecord]) -> usize {
        records
            .iter()
            .rposition(|r| !r.is_removed())
            .map_or(0, |last| last + 1)
    }

    /// The value of `normal[3]` that marks a load following its face
    /// ([`crate::World::add_follower_tractions`]).
    pub const FOLLOWS: Real = 1.0;

    /// Whether the traction's components are along the deformed face's normal and tangents.
    pub fn follows(&self) -> bool {
        self.normal[3] == Self::FOLLOWS
    }
}

// SAFETY: repr(C): two u32 then eight floats; 8 bytes before a 4- or 8-byte aligned float
// array, 40 or 72 bytes in all, so there is no padding; every bit pattern is valid.
unsafe impl Zeroable for TractionRecord {}
// SAFETY: as above; Copy and 'static.
unsafe impl Pod for TractionRecord {}

/// One collider in the buffer's table ([`crate::ColliderDef`]), widened to f64: its pose at
/// `pose_time` (world time, s), which the step moves on with its velocities. `shape` and
/// `contact` are the enums' numbers; `size` the shape's lengths (radius; half-extents;
/// half-length then radius, and a cylinder's inner radius). What it holds and whether a
/// record is one the API writes: `boundary/colliders.rs` (`ColliderRecord::def`,
/// `ColliderRecord::is_valid`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub(crate) struct ColliderRecord {
    pub shape: u64,
    pub contact: u64,
    pub friction: f64,
    pub size: [f64; 3],
    pub position: [f64; 3],
    pub rotation: [f64; 4],
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub pose_time: f64,
    /// A distance field's first sample and its samples along x, y, z (zeros otherwise).
    pub grid: [u64; 4],
    /// A dynamic solid's mass and principal moments of inertia (zeros: kinematic).
    pub mass: f64,
    pub inertia: [f64; 3],
}

// SAFETY: repr(C), 8-byte fields only: no padding; every bit pattern is valid.
unsafe impl Zeroable for ColliderRecord {}
// SAFETY: as above; Copy and 'static.
unsafe impl Pod for ColliderRecord {}

/// What the material put on one collider over the last step: the impulse (N s; per unit
/// thickness in plane strain, per radian axisymmetric) and the angular impulse about the
/// collider's position where each substep began (N m s), summed node by node in node order,
/// the step's length, and what of those sums a dynamic collider has taken into its velocity
/// (E96).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub(crate) struct ColliderImpulse {
    pub linear: [f64; 3],
    pub angular: [f64; 3],
    pub duration: f64,
    pub taken: [f64; 6],
}

// SAFETY: repr(C), 8-byte fields only: no padding; every bit pattern is valid.
unsafe impl Zeroable for ColliderImpulse {}
// SAFETY: as above; Copy and 'static.
unsafe impl Pod for ColliderImpulse {}

/// (row, column) of each stored symmetric stress component; in 2D the fourth stored
/// component is the out-of-plane `zz`.
pub(crate) const fn sym_pairs(d: usize) -> &'static [(usize, usize)] {
    if d == 2 {
        &[(0, 0), (1, 1), (0, 1)]
    } else {
        &[(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    }
}

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
    pub tractions_offset: usize,
    pub traction_capacity: usize,
    /// The collider table and, after it, the colliders' impulses (the step writes them), then
    /// the distance samples (the end of the head).
    pub colliders_offset: usize,
    pub impulses_offset: usize,
    pub sdf_offset: usize,
    pub particle_offset: usize,
    pub real_column_bytes: usize,
    pub u32_column_bytes: usize,
    /// Particle Real columns: x[D], v[D], mass, vol0, H[D*D], tau[NS], x_low[D], then
    /// x_start[D] (MUSL), then the effect columns (see [`EffectColumns`]).
    pub particle_real_columns: usize,
    /// First column and count of each optional group of particle Real columns.
    pub x_start: ColumnGroup,
    pub force: ColumnGroup,
    pub damping: ColumnGroup,
    pub affine: ColumnGroup,
    /// Transported scalars: value, grid value, then source if declared; heat then diffusion.
    pub scalar: [ColumnGroup; 2],
    /// Axisymmetric: the hoop stretch `F_thetatheta - 1`.
    pub hoop: ColumnGroup,
    /// cpGIMP: each particle's domain stretch per axis, frozen for a substep.
    pub stretch: ColumnGroup,
    /// `Effects::plasticity`: the plastic models' history value.
    pub plastic: ColumnGroup,
    /// Whether each transported scalar (heat, diffusion) has its 4 grid columns.
    pub scalar_grid: [bool; 2],
    /// Whether the grid has the colliders' contact column (a collider capacity).
    pub contact_grid: bool,
    /// Whether the grid has the stress-update velocity columns (USF, MUSL, and XPIC's or
    /// FMPM's series from order 2, whose projections they take).
    pub remap_grid: bool,
    /// Whether the grid has XPIC's or FMPM's series columns (order 2 and up).
    pub series_grid: bool,
    pub grid_offset: usize,
    pub node_column_bytes: usize,
    /// Grid columns: mass, velocity[D], acceleration[D], then the stress-update velocity[D]
    /// ([`Layout::remap_grid`]), XPIC's series[D] ([`Layout::series_grid`]), the transported
    /// scalars' and the colliders' contact column.
    pub grid_columns: usize,
    /// The parallel step's scratch after the grid: one [`Partial`] per item of a pass,
    /// [`SLOTS_PER_WORKER`] per worker of [`WorldDef::workers`] (none for one worker).
    pub scratch_offset: usize,
    pub scratch_slots: usize,
    /// After the slots: per [`REACH_GROUP`] particles, the first and last grid line along the
    /// slowest axis their stencils may reach (the scatter's tiles take the chunks that reach
    /// them).
    pub reach_groups: usize,
    pub total: usize,
}

/// A run of consecutive particle Real columns: the first column's index and how many there are
/// (0 when the group is not reserved).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ColumnGroup {
    pub first: usize,
    pub count: usize,
}

/// The optional column groups, reserved in this order after the always-present columns.
pub(crate) struct EffectColumns;

impl EffectColumns {
    /// Groups `(x_start, force, damping, affine, heat, diffusion, hoop, stretch, plastic)` for a
    /// definition, starting at column `first`; returns them and the column after the last.
    fn of(def: &WorldDef, d: usize, first: usize) -> ([ColumnGroup; 9], usize) {
        let musl = def.update_order == UpdateOrder::Musl;
        let fx = &def.effects;
        let per_particle_damping = fx.damping.is_some_and(|dm| dm.per_particle);
        let counts = [
            if musl { d } else { 0 },
            if fx.particle_forces { d } else { 0 },
            if per_particle_damping { 2 } else { 0 },
            if def.transfer.is_affine() { d * d } else { 0 },
            fx.heat.map_or(0, |t| 2 + t.sources as usize),
            fx.diffusion.map_or(0, |t| 2 + t.sources as usize),
            (def.dimension == Dimension::Axisymmetric2D) as usize,
            if def.shape == ShapeFunction::CpGimp {
                d
            } else {
                0
            },
            fx.plasticity as usize,
        ];
        let mut next = first;
        let groups = counts.map(|count| {
            let g = ColumnGroup { first: next, count };
            next += count;
            g
        });
        (groups, next)
    }
}

const fn round_up(x: usize, to: usize) -> usize {
    x.div_ceil(to) * to
}

/// Bytes between the starts of two columns of `bytes` each: rounded up to [`ALIGN`], and, for
/// columns of a page or more, to a stride of 5 cache lines past a multiple of 4 KiB. Columns
/// whose starts are a multiple of 4 KiB apart put a chunk's entries of every column at the same
/// low 12 address bits, where a load after a store to another column can be taken as dependent
/// on it until the full addresses compare (4K aliasing; the likely reason the default 3D step
/// took about 10 % longer with such strides, ARCHITECTURE.md); with the stride of 5 lines, the
/// chunks of up to 64 columns fall on distinct lines of the page.
const fn column_stride(bytes: usize) -> usize {
    const LINES_PER_PAGE: usize = 4096 / ALIGN;
    let lines = bytes.div_ceil(ALIGN);
    if lines < LINES_PER_PAGE {
        return lines * ALIGN;
    }
    let past = lines % LINES_PER_PAGE;
    (lines + (5 + LINES_PER_PAGE - past) % LINES_PER_PAGE) * ALIGN
}

impl Layout {
    /// Layout of a validated definition.
    pub fn of(def: &WorldDef) -> Layout {
        let d = def.axes();
        let cap = round_up(def.particle_capacity as usize, CHUNK);
        let nodes: usize = (0..d).map(|a| def.cells[a] as usize + 1).product();
        let real_column_bytes = column_stride(cap * size_of::<Real>());
        let u32_column_bytes = column_stride(cap * 4);
        let (
            [x_start, force, damping, affine, heat, diffusion, hoop, stretch, plastic],
            particle_real_columns,
        ) = EffectColumns::of(def, d, col::x_low(d, d));
        // Stencil rows may reach past the last node: see `crate::shape::ROW`.
        let node_column_bytes =
            column_stride(round_up(nodes + crate::shape::ROW, CHUNK) * size_of::<Real>());
        let series_grid = def.transfer.series().is_some_and(|(k, _)| k >= 2);
        let remap_grid = def.update_order != UpdateOrder::Usl || series_grid;
        let scalar_grid = [def.effects.heat.is_some(), def.effects.diffusion.is_some()];
        let contact_grid = def.effects.collider_capacity > 0;
        let grid_columns = 1
            + 2 * d
            + if remap_grid { d } else { 0 }
            + if series_grid { d } else { 0 }
            + 4 * scalar_grid.iter().filter(|&&b| b).count()
            + contact_grid as usize;
        let traction_capacity = def.effects.traction_capacity as usize;
        let tables = Tables::of(
            def.material_capacity as usize,
            traction_capacity,
            def.effects.collider_capacity as usize,
            def.effects.sdf_capacity as usize,
        );
        let particle_offset = tables.end;
        let grid_offset = particle_offset
            + particle_real_columns * real_column_bytes
            + col::U32_COLUMNS * u32_column_bytes;
        let scratch_offset = grid_offset + grid_columns * node_column_bytes;
        let scratch_slots = if def.workers > 1 {
            SLOTS_PER_WORKER * def.workers as usize
        } else {
            0
        };
        // And the grid lines each REACH_GROUP particles' stencils reach along the slowest
        // axis, for the scatter's tiles.
        let reach_groups = if scratch_slots > 0 {
            cap.div_ceil(REACH_GROUP)
        } else {
            0
        };
        let total = scratch_offset
            + scratch_slots * size_of::<Partial>()
            + reach_groups * size_of::<[u32; 2]>();
        Layout {
            d,
            padded_capacity: cap,
            nodes,
            materials_offset: tables.materials,
            tractions_offset: tables.tractions,
            traction_capacity,
            colliders_offset: tables.colliders,
            impulses_offset: tables.impulses,
            sdf_offset: tables.sdf,
            particle_offset,
            real_column_bytes,
            u32_column_bytes,
            particle_real_columns,
            x_start,
            force,
            damping,
            affine,
            scalar: [heat, diffusion],
            hoop,
            stretch,
            plastic,
            scalar_grid,
            contact_grid,
            remap_grid,
            series_grid,
            grid_offset,
            node_column_bytes,
            grid_columns,
            scratch_offset,
            scratch_slots,
            reach_groups,
            total,
        }
    }
}

/// Where the tables at the head of a buffer start, bytes (items 2 and 3 of the module's
/// list): a function of four capacities alone, which the header holds, so that a query of one
/// record finds it from the header's fields without the definition ([`Header::tables`]);
/// [`Layout::of`] takes its offsets from here too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Tables {
    pub materials: usize,
    pub tractions: usize,
    pub colliders: usize,
    pub impulses: usize,
    pub sdf: usize,
    /// The first byte after them: where the particle columns start.
    pub end: usize,
}

impl Tables {
    /// The tables of `materials` material records, `tractions` traction records, `colliders`
    /// collider records and impulses and `samples` distance samples.
    pub const fn of(materials: usize, tractions: usize, colliders: usize, samples: usize) -> Self {
        let material_table = round_up(size_of::<Header>(), ALIGN);
        let traction_table = round_up(
            material_table + materials * size_of::<MaterialRecord>(),
            ALIGN,
        );
        let collider_table = round_up(
            traction_table + tractions * size_of::<TractionRecord>(),
            ALIGN,
        );
        let impulses = collider_table + colliders * size_of::<ColliderRecord>();
        let sdf = impulses + colliders * size_of::<ColliderImpulse>();
        Tables {
            materials: material_table,
            tractions: traction_table,
            colliders: collider_table,
            impulses,
            sdf,
            end: round_up(sdf + samples * size_of::<Real>(), ALIGN),
        }
    }
}

impl Header {
    /// The tables of the world this header heads ([`Tables`]), from its capacities alone: for
    /// a header that [`World::reopen`](crate::World::reopen)'s checks passed (its capacities
    /// are its definition's), the offsets [`Layout::of`] gives, in a few additions.
    pub fn tables(&self) -> Tables {
        Tables::of(
            self.material_capacity as usize,
            self.traction_capacity as usize,
            self.collider_capacity as usize,
            self.sdf_capacity as usize,
        )
    }

    /// Whether the world's motion is in a plane (2D, plane strain or axisymmetric): read from
    /// the stored dimension's number.
    pub fn planar(&self) -> bool {
        self.dimension != Dimension::ThreeD as u64
    }
}

/// Largest count of particles or nodes a world may index (u32 ids, and room for padding).
const MAX_ITEMS: u64 = 1 << 30;

/// Checks every field of a definition; the error names the first one that is wrong.
pub(crate) fn validate(def: &WorldDef) -> Result<(), Error> {
    if !(def.cell_size.is_finite() && def.cell_size > 0.0) {
        return Err(Error::InvalidCellSize);
    }
    let used_finite = |v: Vec3| (0..def.axes()).all(|a| v[a].is_finite());
    if !used_finite(def.origin)
        || !used_finite(def.gravity)
        || !def.wall_velocity.iter().all(|&v| used_finite(v))
        || !def.wall_friction.iter().all(|f| f.is_finite())
    {
        return Err(Error::NonFiniteDefinition);
    }
    if def.wall_friction.iter().any(|&f| f < 0.0) {
        return Err(Error::InvalidEffect);
    }
    if def.dimension == Dimension::Axisymmetric2D {
        // The axis r = 0 is the lower r face's wall plane, `margin` cells in from the grid's
        // face (to round-off of the cell size).
        let axis = def.origin.x + def.shape.margin_cells() as Real * def.cell_size;
        if def.faces[0] == Boundary::Open || axis.abs() > 1.0e-4 * def.cell_size {
            return Err(Error::InvalidAxis);
        }
    }
    // Periodic faces come in pairs, on an axis with walls at neither end (E95).
    for a in 0..def.axes() {
        let periodic = [2 * a, 2 * a + 1].map(|f| def.faces[f] == Boundary::Periodic);
        if !periodic[0] && !periodic[1] {
            continue;
        }
        let scalar = |t: Option<Transport>| {
            t.is_some_and(|t| {
                [2 * a, 2 * a + 1]
                    .iter()
                    .any(|&f| t.faces[f] != ScalarBoundary::Insulated)
            })
        };
        let wall = [2 * a, 2 * a + 1]
            .iter()
            .any(|&f| def.wall_friction[f] != 0.0 || def.wall_velocity[f] != Vec3::ZERO);
        if periodic[0] != periodic[1]
            || (a == 0 && def.dimension == Dimension::Axisymmetric2D)
            || wall
            || scalar(def.effects.heat)
            || scalar(def.effects.diffusion)
        {
            return Err(Error::InvalidBoundary);
        }
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
    let rate_ok = def.pic_rate >= 0.0 && def.pic_rate.is_finite();
    if !((0.0..=1.0).contains(&def.flip_beta) && rate_ok) {
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
    // NaN-safe: a NaN ratio is not greater than 1.
    let ratio_ok = def.max_volume_ratio.partial_cmp(&1.0) == Some(core::cmp::Ordering::Greater);
    let workers_ok = (1..=crate::MAX_WORKERS).contains(&def.workers);
    if !(1..=crate::MAX_SUBSTEPS).contains(&def.max_substeps) || !ratio_ok || !workers_ok {
        return Err(Error::InvalidLimit);
    }
    // MLS-MPM's gradient is the shape function's only where D_p is constant: the B-splines.
    if def.transfer == Transfer::Mls
        && (!matches!(
            def.shape,
            ShapeFunction::QuadraticBspline | ShapeFunction::CubicBspline
        ) || def.dimension == Dimension::Axisymmetric2D)
    {
        return Err(Error::InvalidTransfer);
    }
    // XPIC's and FMPM's order.
    if let Some((k, fmpm)) = def.transfer.series() {
        let most = if fmpm {
            crate::MAX_FMPM_ORDER
        } else {
            crate::MAX_TRANSFER_ORDER
        };
        // FMPM's stress from its own v* under USL: the bar's energy grew 18-fold in 5 periods.
        let usl_series = fmpm && k >= 2 && def.update_order == UpdateOrder::Usl;
        if !(1..=most).contains(&k) || usl_series {
            return Err(Error::InvalidTransfer);
        }
    }
    // The momentum approach's gradient has no hoop term of its own yet.
    if def.transfer == Transfer::FlipMomentum && def.dimension == Dimension::Axisymmetric2D {
        return Err(Error::InvalidTransfer);
    }
    def.effects.validate(def.axes())?;
    // Damping is explicit (`v (1 - alpha dt)`): a rate the step resolves only below
    // MIN_STABLE_DT is refused here rather than clamped in every step.
    if let Some(damping) = def.effects.damping {
        // A sum of finite rates: never NaN.
        if damping.definition_rate() > def.resolvable().rate {
            return Err(Error::StableStepTooShort);
        }
    }
    // A build without the effect instances cannot step a world that declares one.
    if !cfg!(feature = "effects")
        && (def.effects != crate::Effects::NONE
            || def.transfer.is_affine()
            || def.dimension == Dimension::Axisymmetric2D)
    {
        return Err(Error::Unsupported);
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
        let fx = &def.effects;
        let damping = fx.damping.unwrap_or(Damping::NONE);
        let feedback = damping.feedback.unwrap_or(Feedback {
            gain: 0.0,
            target: Schedule::ZERO,
            max_alpha: 0.0,
        });
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
            transfer: def.transfer.code() as u64,
            damping_declared: fx.damping.is_some() as u64,
            damping_grid: ScheduleRecord::of(&damping.grid),
            damping_particle: ScheduleRecord::of(&damping.particle),
            feedback_declared: damping.feedback.is_some() as u64,
            feedback_gain: feedback.gain as f64,
            feedback_target: ScheduleRecord::of(&feedback.target),
            feedback_max_alpha: feedback.max_alpha as f64,
            per_particle_damping: damping.per_particle as u64,
            particle_forces: fx.particle_forces as u64,
            traction_capacity: fx.traction_capacity as u64,
            body_force: w(fx.body_force),
            body_force_scale: ScheduleRecord::of(&fx.body_force_scale),
            body_force_gradient: fx.body_force_gradient.map(w),
            heat: TransportRecord::of(&fx.heat),
            diffusion: TransportRecord::of(&fx.diffusion),
            traction_count: 0,
            feedback_alpha: 0.0,
            max_substeps: def.max_substeps as u64,
            max_volume_ratio: def.max_volume_ratio as f64,
            workers: def.workers as u64,
            damping_on_force: damping.grid_on_force as u64,
            damping_zone_count: damping.zone_count as u64,
            damping_zones: damping.zones.each_ref().map(ZoneRecord::of),
            traction_schedules: fx.traction_schedules.each_ref().map(ScheduleRecord::of),
            plasticity: fx.plasticity as u64,
            collider_capacity: fx.collider_capacity as u64,
            collider_count: 0,
            wall_friction: def.wall_friction.map(|f| f as f64),
            wall_velocity: def.wall_velocity.map(w),
            pic_rate: def.pic_rate as f64,
            sdf_capacity: fx.sdf_capacity as u64,
            sdf_count: 0,
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
        let transfer = code(self.transfer)
            .and_then(Transfer::from_code)
            .ok_or(not_a_world)?;
        let flag = |v: u64| match v {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(Error::NotAWorld),
        };
        let v = |a: [f64; 3]| Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
        let feedback = if flag(self.feedback_declared)? {
            Some(Feedback {
                gain: self.feedback_gain as Real,
                target: self.feedback_target.schedule()?,
                max_alpha: self.feedback_max_alpha as Real,
            })
        } else {
            None
        };
        let damping = if flag(self.damping_declared)? {
            Some(Damping {
                grid: self.damping_grid.schedule()?,
                particle: self.damping_particle.schedule()?,
                feedback,
                per_particle: flag(self.per_particle_damping)?,
                grid_on_force: flag(self.damping_on_force)?,
                zones: {
                    let mut zones = [DampingZone::NONE; DAMPING_ZONES];
                    for (z, r) in zones.iter_mut().zip(&self.damping_zones) {
                        *z = r.zone()?;
                    }
                    zones
                },
                zone_count: u32::try_from(self.damping_zone_count).map_err(|_| Error::NotAWorld)?,
            })
        } else {
            None
        };
        let effects = Effects {
            damping,
            particle_forces: flag(self.particle_forces)?,
            traction_capacity: small(self.traction_capacity)?,
            body_force: v(self.body_force),
            body_force_scale: self.body_force_scale.schedule()?,
            body_force_gradient: self.body_force_gradient.map(v),
            traction_schedules: {
                let mut s = [Schedule::ZERO; TRACTION_SCHEDULES];
                for (s, r) in s.iter_mut().zip(&self.traction_schedules) {
                    *s = r.schedule()?;
                }
                s
            },
            heat: self.heat.transport()?,
            diffusion: self.diffusion.transport()?,
            plasticity: flag(self.plasticity)?,
            collider_capacity: small(self.collider_capacity)?,
            sdf_capacity: small(self.sdf_capacity)?,
        };
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
            transfer,
            update_order,
            gravity: v(self.gravity),
            faces,
            wall_friction: self.wall_friction.map(|f| f as Real),
            wall_velocity: self.wall_velocity.map(v),
            pic_rate: self.pic_rate as Real,
            exp_terms: small(self.exp_terms)?,
            cfl: self.cfl as Real,
            max_substeps: small(self.max_substeps)?,
            max_volume_ratio: self.max_volume_ratio as Real,
            workers: small(self.workers)?,
            effects,
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
    /// The low part of the position along axis `a`: what rounding `x` to `Real` left out
    /// (see [`crate::particles::ParticleCols::x_low`]).
    pub const fn x_low(d: usize, a: usize) -> usize {
        tau(d, super::stress_components(d)) + a
    }
    /// u32 columns.
    pub const MATERIAL: usize = 0;
    pub const STATUS: usize = 1;
    /// How many u32 columns a particle has.
    pub const U32_COLUMNS: usize = 2;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Property of `column_stride` over column sizes from one byte to 64 MiB: it holds the
    /// column, is a whole number of cache lines, adds less than a page, and, for columns of a
    /// page or more, puts the starts of 64 consecutive columns on 64 distinct lines of the page
    /// (so no two of them alias modulo 4 KiB).
    #[test]
    fn column_strides_hold_the_column_and_spread_over_the_page() {
        let mut bytes = 1usize;
        while bytes <= 64 << 20 {
            for b in [bytes, bytes + 4, bytes + 60, bytes * 3] {
                let s = column_stride(b);
                assert!(
                    s >= b && s.is_multiple_of(ALIGN) && s < b + 4096 + ALIGN,
                    "{b}: {s}"
                );
                if b >= 4096 {
                    let mut lines = [false; 64];
                    for j in 0..64 {
                        let line = (j * s) % 4096 / ALIGN;
                        assert!(!lines[line], "{b}: columns alias at line {line}");
                        lines[line] = true;
                    }
                }
            }
            bytes *= 2;
        }
    }
}
