//! The world: the [`World`] struct over the caller's buffer, its opening, header and simple
//! accessors; the submodules hold its value types, adding, seeding, stepping and reading. The
//! phase order of a step lives in `step.rs` and only there ([`World::step`]).

mod add;
mod edit;
mod effects;
mod open;
mod parallel;
mod passes;
mod query;
mod seed;
mod state;
mod step;
mod types;

pub use crate::particles::StepReport;
pub use query::WorldRef;
pub use step::Phase;
pub use types::{
    ColliderState, Diagnostics, ParticleBatch, ParticleDef, ParticleState, ParticlesView, Removal,
};

use crate::def::{MaterialDef, WorldDef};
use crate::layout::{validate, Header, Layout, TractionRecord, ALIGN};
use crate::{Error, Real};
use core::mem::size_of;

/// A world living in a caller-provided buffer. Holds no pointers into it but the borrow, so a
/// byte copy of [`World::as_bytes`] opened with [`World::open`] is an independent world.
pub struct World<'a> {
    buf: &'a mut [u8],
}

fn check_buffer(buf: &[u8], bytes: usize) -> Result<(), Error> {
    if buf.len() < bytes {
        return Err(Error::BufferTooSmall);
    }
    if !(buf.as_ptr() as usize).is_multiple_of(ALIGN) {
        return Err(Error::BufferMisaligned);
    }
    Ok(())
}

impl<'a> World<'a> {
    /// Lays out an empty world in `buf`, which must be at least
    /// [`crate::memory_requirements`] bytes long and aligned to its `align`.
    pub fn init(def: &WorldDef, buf: &'a mut [u8]) -> Result<World<'a>, Error> {
        validate(def)?;
        let layout = Layout::of(def);
        check_buffer(buf, layout.total)?;
        let used = &mut buf[..layout.total];
        used.fill(0);
        *bytemuck::from_bytes_mut::<Header>(&mut used[..size_of::<Header>()]) =
            Header::new(def, layout.total);
        Ok(World { buf })
    }

    /// Opens a world that `buf` already holds, such as a byte copy of another world's
    /// [`World::as_bytes`] read from disk or a network: untrusted bytes. Checks the header, the
    /// size and the alignment (else [`Error::NotAWorld`], [`Error::BufferTooSmall`],
    /// [`Error::BufferMisaligned`]) and then the whole state, every particle included
    /// ([`WorldRef::check_state`], else [`Error::InvalidState`]): a world that opens steps
    /// with meaningful results. Costs one pass over the particles.
    pub fn open(buf: &'a mut [u8]) -> Result<World<'a>, Error> {
        WorldRef::open(buf)?;
        Ok(World { buf })
    }

    /// Opens a world that this program laid out ([`World::init`]) or opened ([`World::open`])
    /// before and has changed since only through this API: the header, size and alignment
    /// checks of [`World::open`], in constant time, without the state check. Whatever the
    /// buffer holds, no call on the world reads or writes outside it; a state changed
    /// behind the API's back may give meaningless results. For hosts that hold a world by its
    /// address between calls (the C interface opens the world this way on every call).
    pub fn reopen(buf: &'a mut [u8]) -> Result<World<'a>, Error> {
        WorldRef::reopen(buf)?;
        Ok(World { buf })
    }

    /// Bytes of the world whose header starts `buf` (at least [`World::HEADER_BYTES`] long and
    /// aligned to [`crate::ALIGN`]): what a byte copy must hold, and what [`World::open`] needs.
    /// Checks the header as [`World::reopen`] does. For hosts that hold a world by its address
    /// alone (the C interface) and must learn its extent before they can open it; such a host
    /// first checks [`World::has_magic`] on the first [`World::MAGIC_BYTES`] bytes, so that a
    /// pointer to something else is not read any further.
    pub fn stored_bytes(buf: &[u8]) -> Result<usize, Error> {
        check_buffer(buf, size_of::<Header>())?;
        let h = *bytemuck::from_bytes::<Header>(&buf[..size_of::<Header>()]);
        let def = h.def()?;
        validate(&def).map_err(|_| Error::NotAWorld)?;
        let layout = Layout::of(&def);
        if h.total_bytes != layout.total as u64
            || h.particle_count > def.particle_capacity as u64
            || h.material_count > def.material_capacity as u64
            || h.traction_count > def.effects.traction_capacity as u64
            || h.collider_count > def.effects.collider_capacity as u64
            || h.sdf_count > def.effects.sdf_capacity as u64
        {
            return Err(Error::NotAWorld);
        }
        Ok(layout.total)
    }

    /// Bytes at the start of a world that identify it (its magic number).
    pub const MAGIC_BYTES: usize = 8;

    /// Whether `prefix` (at least [`World::MAGIC_BYTES`] long) starts like a world of this
    /// library: the first check, before anything else of a buffer is read.
    pub fn has_magic(prefix: &[u8]) -> bool {
        prefix.get(..Self::MAGIC_BYTES) == Some(&crate::layout::MAGIC.to_le_bytes()[..])
    }

    /// Size of the header at the start of every world buffer, bytes.
    pub const HEADER_BYTES: usize = size_of::<Header>();

    /// The world's read-only queries ([`WorldRef`]), borrowing it shared.
    pub fn read(&self) -> WorldRef<'_> {
        WorldRef { buf: self.buf }
    }

    /// The world's definition.
    pub fn def(&self) -> WorldDef {
        self.read().def()
    }

    pub(crate) fn header(&self) -> &Header {
        self.read().header()
    }

    /// The `n` records of the traction table from `first` on (the caller checked them against
    /// the capacity).
    pub(crate) fn traction_records_mut(
        &mut self,
        layout: &Layout,
        first: usize,
        n: usize,
    ) -> &mut [TractionRecord] {
        let start = layout.tractions_offset + first * size_of::<TractionRecord>();
        bytemuck::cast_slice_mut(&mut self.buf[start..start + n * size_of::<TractionRecord>()])
    }

    /// Number of particles added.
    pub fn particle_count(&self) -> usize {
        self.read().particle_count()
    }

    /// Number of materials added.
    pub fn material_count(&self) -> usize {
        self.read().material_count()
    }

    /// Simulated time, s (sum of the `dt` of every step).
    pub fn time(&self) -> f64 {
        self.read().time()
    }

    /// Number of `step` calls that succeeded (saturates at `u64::MAX`).
    pub fn step_count(&self) -> u64 {
        self.read().step_count()
    }

    /// The bytes the world occupies (a prefix of the buffer). A copy is a snapshot.
    pub fn as_bytes(&self) -> &[u8] {
        self.read().as_bytes()
    }

    /// The world's state: [`as_bytes`](Self::as_bytes) without the grid at its end
    /// ([`WorldRef::state_bytes`]).
    pub fn state_bytes(&self) -> &[u8] {
        self.read().state_bytes()
    }

    /// The definition of material `id`.
    pub fn material(&self, id: u32) -> Option<MaterialDef> {
        self.read().material(id)
    }

    /// The largest stable time step, s ([`WorldRef::stable_dt`]).
    pub fn stable_dt(&self) -> Real {
        self.read().stable_dt()
    }

    /// Borrowed view of every particle column.
    pub fn particles(&self) -> ParticlesView<'_> {
        self.read().particles()
    }

    /// Mass, momentum, centre of mass and energies of the active particles.
    pub fn diagnostics(&self) -> Diagnostics {
        self.read().diagnostics()
    }

    /// [`World::diagnostics`] on a task system ([`WorldRef::diagnostics_with_tasks`]).
    pub fn diagnostics_with_tasks(&self, tasks: &dyn crate::TaskSystem) -> Diagnostics {
        self.read().diagnostics_with_tasks(tasks)
    }

    /// The thermostat's current alpha, 1/s ([`WorldRef::feedback_alpha`]).
    pub fn feedback_alpha(&self) -> f64 {
        self.read().feedback_alpha()
    }

    /// Number of tractions added ([`WorldRef::traction_count`]).
    pub fn traction_count(&self) -> usize {
        self.read().traction_count()
    }

    pub(crate) fn header_mut(&mut self) -> &mut Header {
        bytemuck::from_bytes_mut(&mut self.buf[..size_of::<Header>()])
    }

    fn real_col_mut(&mut self, layout: &Layout, j: usize, count: usize) -> &mut [Real] {
        bytemuck::cast_slice_mut(&mut self.buf[layout.real_col(j, count)])
    }

    fn u32_col_mut(&mut self, layout: &Layout, j: usize, count: usize) -> &mut [u32] {
        bytemuck::cast_slice_mut(&mut self.buf[layout.u32_col(j, count)])
    }
}

/// The admissible-region check in 3-component form, for the (non-generic) add functions.
struct GeomAny {
    d: usize,
    origin: [Real; 3],
    h: Real,
    inv_h: Real,
    lo: [Real; 3],
    hi: [Real; 3],
}

impl GeomAny {
    fn new(def: &WorldDef) -> Self {
        let m = def.shape.margin_cells() as Real;
        GeomAny {
            d: def.axes(),
            origin: [def.origin.x, def.origin.y, def.origin.z],
            h: def.cell_size,
            inv_h: 1.0 / def.cell_size,
            lo: [m; 3],
            hi: core::array::from_fn(|a| def.cells[a] as Real - m),
        }
    }

    fn admits(&self, x: [Real; 3]) -> bool {
        (0..self.d).all(|a| self.admits_on(a, x[a]))
    }

    fn admits_on(&self, a: usize, x: Real) -> bool {
        let s = (x - self.origin[a]) * self.inv_h;
        s >= self.lo[a] && s <= self.hi[a]
    }

    /// Whether a step can leave a particle at `x`: admitted, or on a wall plane where the
    /// step puts a particle that reached it (`origin + lo h`, `origin + hi h`, which may lie a
    /// rounding outside the admitted range).
    fn holds(&self, x: [Real; 3]) -> bool {
        (0..self.d).all(|a| {
            let (lo, hi) = (
                self.origin[a] + self.lo[a] * self.h,
                self.origin[a] + self.hi[a] * self.h,
            );
            self.admits_on(a, x[a]) || (x[a] >= lo && x[a] <= hi)
        })
    }
}
