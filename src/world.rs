//! The world: a view of the caller's buffer with add, step, stable_dt and read access.
//! The phase order of a step lives here and only here ([`World::step`]).

use crate::def::{Dimension, MaterialDef, ShapeFunction, Transfer, UpdateOrder, WorldDef};
use crate::effects::Feedback;
use crate::grid::{Geom, GridCols};
use crate::layout::{col, validate, Header, Layout, MaterialRecord, TractionRecord, ALIGN};
use crate::material::{eigenstrain_part, elastic_part, Deformation};
use crate::material::{energy_density, model_of, Params};
use crate::math::{ceil, Mat};
use crate::particles::{ParticleCols, ParticleStatus, ACTIVE};
use crate::phases::lanes::width;
use crate::phases::p2g::{Adds, Mode};
use crate::phases::{grid_update, p2g, Ctx, Isa};
use crate::shape::{CpGimp, CubicBspline, Gimp, Linear, QuadraticBspline, Shape1D};
use crate::simd::Simd;
use crate::{Error, Real, Vec3};
use core::cmp::Ordering;
use core::mem::size_of;
use core::ops::Range;

/// The largest [`WorldDef::max_substeps`] a definition may set.
pub const MAX_SUBSTEPS: u32 = 1 << 20;

/// Nodes lighter than this fraction of the lightest particle are treated as empty: epsilon^2,
/// which only keeps the division `p_i / m_i` away from denormals. A larger cutoff does harm: a
/// node that carries a sliver of a particle still has a well-defined velocity (its `p_i / m_i`
/// is the particle's velocity), and zeroing it puts a spurious jump next to its neighbours
/// (seen as stress in a rigidly translating block with linear shapes in f64).
const NODAL_MASS_CUTOFF: Real = Real::EPSILON * Real::EPSILON;

/// What one call of [`World::step`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Substeps taken (>= 1).
    pub substeps: u32,
    /// Length of each substep, s.
    pub substep_dt: Real,
    /// Particle-substeps in which a particle reached a stick or slip wall and was stopped there.
    pub stopped: u32,
    /// Particles that crossed an open face and left the simulation.
    pub escaped: u32,
    /// Particles frozen in this call: their state turned non-finite, their F inverted, or
    /// their volume ran away. Nonzero means the step went bad somewhere
    /// ([`StepReport::went_bad`]).
    pub frozen: u32,
    /// Of the frozen, those frozen because their volume ratio `J` left
    /// `[1 / max_volume_ratio, max_volume_ratio]` ([`WorldDef::max_volume_ratio`]): the sign
    /// of an unstable scheme or a time step too long for the scene.
    pub runaway: u32,
    /// The ids of the first frozen particles (up to 8), for diagnosis.
    pub first_frozen: heapless::Vec<u32, 8>,
}

impl StepReport {
    pub(crate) fn note_frozen(&mut self, id: u32, runaway: bool) {
        self.frozen += 1;
        self.runaway += runaway as u32;
        // A full list only means more than 8 froze; the count says how many.
        let _ = self.first_frozen.push(id);
    }

    /// Whether a particle froze in this call (non-finite state, inverted F or runaway volume):
    /// the flag a host checks after each step. Frozen particles leave the simulation; the
    /// rest of the world goes on.
    pub fn went_bad(&self) -> bool {
        self.frozen > 0
    }
}

/// A transported scalar field.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum ScalarField {
    /// Temperature, K (heat conduction).
    Temperature = 0,
    /// Concentration potential `c / c_sat` (diffusion).
    Concentration = 1,
}

/// One particle for [`World::add_particle`]. In 2D the z components are ignored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleDef {
    /// Position, m.
    pub position: Vec3,
    /// Velocity, m/s.
    pub velocity: Vec3,
    /// Mass, kg (per unit thickness in plane strain), > 0.
    pub mass: Real,
    /// Initial volume V0, m^3 (m^2 per unit thickness in plane strain), > 0.
    pub volume: Real,
    /// Material id returned by [`World::add_material`].
    pub material: u32,
}

/// Particles as structure-of-arrays slices, all of one length, for [`World::add_particles`].
/// In 2D the z slices may be empty.
#[derive(Clone, Copy, Debug)]
pub struct ParticleBatch<'b> {
    /// Positions x, y, z, m.
    pub position: [&'b [Real]; 3],
    /// Velocities x, y, z, m/s.
    pub velocity: [&'b [Real]; 3],
    /// Masses, kg, > 0.
    pub mass: &'b [Real],
    /// Initial volumes, m^3, > 0.
    pub volume: &'b [Real],
    /// Material ids.
    pub material: &'b [u32],
}

/// Sums over the active particles, in f64.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// Total mass of the active particles, kg.
    pub mass: f64,
    /// Linear momentum, kg m/s.
    pub momentum: [f64; 3],
    /// Angular momentum about the coordinate origin, kg m^2/s (2D: the z component only).
    /// With APIC it includes each particle's affine part `m_p eps : B_p^T` (see
    /// [`ParticlesView::affine`]), which the transfer conserves together with `x_p x m_p v_p`
    /// (seeds/001).
    pub angular_momentum: [f64; 3],
    /// Centre of mass, m.
    pub center_of_mass: [f64; 3],
    /// Kinetic energy `sum m v^2 / 2`, J.
    pub kinetic: f64,
    /// Strain energy `sum V0 W(F)`, J.
    pub strain: f64,
    /// Gravitational potential energy `-sum m g . x`, J (zero at the origin).
    pub potential: f64,
}

impl Diagnostics {
    /// Kinetic + strain + gravitational potential energy, J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic + self.strain + self.potential
    }
}

/// Borrowed view of the particle columns, valid while the world is not mutated.
/// Columns of axes the dimension lacks (z in 2D) are empty slices.
#[derive(Clone, Copy, Debug)]
pub struct ParticlesView<'w> {
    /// Number of particles (every column has this length).
    pub count: usize,
    /// The world's dimension.
    pub dimension: Dimension,
    /// Positions per axis, m.
    pub position: [&'w [Real]; 3],
    /// Velocities per axis, m/s.
    pub velocity: [&'w [Real]; 3],
    /// Masses, kg.
    pub mass: &'w [Real],
    /// Initial volumes, m^3.
    pub volume0: &'w [Real],
    /// Displacement gradient `H = F - I`, entry `[a][b]` (row a, column b) with F the
    /// deformation gradient; 2D uses a, b < 2 (F_zz = 1). Stored as `F - I` so that small
    /// strains keep full precision in f32.
    pub displacement_gradient: [[&'w [Real]; 3]; 3],
    /// Kirchhoff stress over initial density, m^2/s^2: 2D xx, yy, xy, zz; 3D xx, yy, zz, xy,
    /// xz, yz. Cauchy stress is `rho0 / J` times it.
    pub stress: [&'w [Real]; 6],
    /// Material ids.
    pub material: &'w [u32],
    /// Status codes ([`crate::ParticleStatus`]).
    pub status: &'w [u32],
    /// External forces per axis, N (empty unless particle forces are declared).
    pub force: [&'w [Real]; 3],
    /// Local grid and particle damping, 1/s (empty unless per-particle damping is declared).
    pub damping: [&'w [Real]; 2],
    /// Temperature, K (empty unless heat conduction is declared).
    pub temperature: &'w [Real],
    /// Concentration potential (empty unless diffusion is declared).
    pub concentration: &'w [Real],
    /// The grid's temperature at each particle after the last step, `T_g->p = sum S_ip T_i`,
    /// K: what a feature that depends on temperature should read (seeds/000 section 8.2), since
    /// the particles' own values keep any variation within a cell (the FLIP update never
    /// smooths them). Empty unless heat conduction is declared.
    pub grid_temperature: &'w [Real],
    /// The grid's concentration potential at each particle after the last step, as
    /// [`ParticlesView::grid_temperature`]. Empty unless diffusion is declared.
    pub grid_concentration: &'w [Real],
    /// Axisymmetric only (else empty): the hoop stretch `F_thetatheta - 1 = r / r_0 - 1`, the
    /// out-of-plane part of the deformation gradient.
    pub hoop: &'w [Real],
    /// APIC moment matrix `B_p = sum_i S_ip v_i (x_i - x_p)^T`, entry `[a][b]`, m^2/s (empty
    /// unless the transfer is APIC); with linear shape functions, the affine velocity matrix
    /// `C_p` itself, 1/s, in its gradient form (see [`crate::shape::Shape1D::GRADIENT_AFFINE`]). The affine velocity field is `C_p = B_p D_p^-1`, with
    /// `D_p` the particle's second moment of the weights, evaluated where the particle is when
    /// it next scatters (storing `B_p` rather than `C_p` is what makes the transfer conserve
    /// angular momentum when `D_p` depends on position, as with uGIMP).
    pub affine: [[&'w [Real]; 3]; 3],
}

impl ParticlesView<'_> {
    /// `J - 1 = det F - 1` of particle `i` (with `F_thetatheta` when axisymmetric), computed
    /// from H without cancellation.
    pub fn jacobian_minus_one(&self, i: usize) -> Real {
        if self.dimension == Dimension::ThreeD {
            self.deformation::<3>(i).jm1
        } else {
            self.deformation::<2>(i).jm1
        }
    }

    /// The deformation of particle `i` as the materials see it (`D` the world's axes).
    pub(crate) fn deformation<const D: usize>(&self, i: usize) -> Deformation<D> {
        let h = &self.displacement_gradient;
        let m: Mat<D> = core::array::from_fn(|a| core::array::from_fn(|b| h[a][b][i]));
        Deformation::new(m, self.hoop.get(i).copied().unwrap_or(0.0))
    }

    /// `J = det F` of particle `i` (current volume over initial volume).
    pub fn jacobian(&self, i: usize) -> Real {
        1.0 + self.jacobian_minus_one(i)
    }
}

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

    fn header(&self) -> &Header {
        self.read().header()
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

    /// Number of `step` calls that succeeded.
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

    /// The thermostat's current alpha, 1/s ([`WorldRef::feedback_alpha`]).
    pub fn feedback_alpha(&self) -> f64 {
        self.read().feedback_alpha()
    }

    /// Number of tractions added ([`WorldRef::traction_count`]).
    pub fn traction_count(&self) -> usize {
        self.read().traction_count()
    }

    fn header_mut(&mut self) -> &mut Header {
        bytemuck::from_bytes_mut(&mut self.buf[..size_of::<Header>()])
    }

    fn real_col_mut(&mut self, layout: &Layout, j: usize, count: usize) -> &mut [Real] {
        bytemuck::cast_slice_mut(&mut self.buf[layout.real_col(j, count)])
    }

    fn u32_col_mut(&mut self, layout: &Layout, j: usize, count: usize) -> &mut [u32] {
        bytemuck::cast_slice_mut(&mut self.buf[layout.u32_col(j, count)])
    }

    /// Adds a material; returns its id.
    pub fn add_material(&mut self, m: &MaterialDef) -> Result<u32, Error> {
        let record = material_record(m)?;
        let def = self.def();
        let id = self.material_count();
        if id >= def.material_capacity as usize {
            return Err(Error::MaterialCapacityExceeded);
        }
        let layout = Layout::of(&def);
        let start = layout.materials_offset + id * size_of::<MaterialRecord>();
        let rec: &mut MaterialRecord =
            bytemuck::from_bytes_mut(&mut self.buf[start..start + size_of::<MaterialRecord>()]);
        *rec = record;
        self.header_mut().material_count += 1;
        Ok(id as u32)
    }

    /// Adds one particle; returns its id.
    pub fn add_particle(&mut self, p: &ParticleDef) -> Result<u32, Error> {
        fn one(v: &Real) -> &[Real] {
            core::slice::from_ref(v)
        }
        let batch = ParticleBatch {
            position: [one(&p.position.x), one(&p.position.y), one(&p.position.z)],
            velocity: [one(&p.velocity.x), one(&p.velocity.y), one(&p.velocity.z)],
            mass: one(&p.mass),
            volume: one(&p.volume),
            material: core::slice::from_ref(&p.material),
        };
        self.add_particles(&batch).map(|r| r.start)
    }

    /// Adds a batch of particles; all or nothing. Returns the range of their ids.
    pub fn add_particles(&mut self, b: &ParticleBatch<'_>) -> Result<Range<u32>, Error> {
        let def = self.def();
        let d = def.axes();
        let n = b.mass.len();
        let lengths_ok = (0..d).all(|a| b.position[a].len() == n && b.velocity[a].len() == n)
            && b.volume.len() == n
            && b.material.len() == n;
        if !lengths_ok {
            return Err(Error::LengthMismatch);
        }
        self.check_room(&def, n)?;
        let materials = self.material_count() as u32;
        let geom = GeomAny::new(&def);
        for i in 0..n {
            let x: [Real; 3] = core::array::from_fn(|a| if a < d { b.position[a][i] } else { 0.0 });
            let v: [Real; 3] = core::array::from_fn(|a| if a < d { b.velocity[a][i] } else { 0.0 });
            let (m, vol) = (b.mass[i], b.volume[i]);
            if !(x.iter().chain(v.iter()).all(|c| c.is_finite())
                && m.is_finite()
                && vol.is_finite())
            {
                return Err(Error::NonFiniteInput);
            }
            if m <= 0.0 || vol <= 0.0 {
                return Err(Error::NonPositiveMassOrVolume);
            }
            if b.material[i] >= materials {
                return Err(Error::UnknownMaterial);
            }
            if !geom.admits(x) {
                return Err(Error::PositionOutsideDomain);
            }
        }
        // Validated: write.
        let items = (0..n).map(|i| {
            (
                core::array::from_fn(|a| if a < d { b.position[a][i] } else { 0.0 }),
                core::array::from_fn(|a| if a < d { b.velocity[a][i] } else { 0.0 }),
                b.mass[i],
                b.volume[i],
                b.material[i],
            )
        });
        Ok(self.append(&def, items))
    }

    /// Sets the external force `F_p` (N; per unit thickness in plane strain) of particles
    /// `first..first + n`, `n` the length of the slices (z may be empty in 2D). Needs
    /// [`crate::Effects::particle_forces`]. The force stays until set again.
    pub fn set_particle_forces(&mut self, first: u32, force: [&[Real]; 3]) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        let group = (layout.force.count > 0).then_some(layout.force.first);
        let columns = &force[..layout.d];
        self.write_particle_columns(
            &layout,
            group,
            first,
            columns,
            Error::NonFiniteInput,
            |_| true,
        )
    }

    /// Sets the value of a transported scalar (temperature, K, or concentration potential) of
    /// particles `first..first + n`, `n = values.len()`. Needs the field declared
    /// ([`crate::Effects::heat`], [`crate::Effects::diffusion`]). Values start at 0.
    pub fn set_particle_scalar(
        &mut self,
        field: ScalarField,
        first: u32,
        values: &[Real],
    ) -> Result<(), Error> {
        self.set_scalar_column(field, 0, first, values)
    }

    /// Sets the source of a transported scalar (heat: W/m^3; diffusion: 1/s) of particles
    /// `first..first + n`. Needs the field declared with [`crate::Transport::sources`].
    pub fn set_particle_sources(
        &mut self,
        field: ScalarField,
        first: u32,
        values: &[Real],
    ) -> Result<(), Error> {
        self.set_scalar_column(field, 2, first, values)
    }

    fn set_scalar_column(
        &mut self,
        field: ScalarField,
        k: usize,
        first: u32,
        values: &[Real],
    ) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        let g = layout.scalar[field as usize];
        let group = (k < g.count).then_some(g.first + k);
        self.write_particle_columns(
            &layout,
            group,
            first,
            &[values],
            Error::NonFiniteInput,
            |_| true,
        )
    }

    /// Sets the local grid and particle damping `alpha_g(x_p)`, `alpha_p(x_p)` (1/s, >= 0) of
    /// particles `first..first + n`, added to the global damping for those particles (eq 107).
    /// Needs [`crate::Damping::per_particle`].
    pub fn set_particle_damping(
        &mut self,
        first: u32,
        alpha_g: &[Real],
        alpha_p: &[Real],
    ) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        let group = (layout.damping.count > 0).then_some(layout.damping.first);
        let columns = &[alpha_g, alpha_p];
        self.write_particle_columns(&layout, group, first, columns, Error::InvalidEffect, |v| {
            v >= 0.0
        })
    }

    /// The per-particle setters' one path: writes `columns` (one slice per column, all of one
    /// length n) into the consecutive particle Real columns from `group` for particles
    /// `first..first + n`, after checking, in this order, that the group is reserved
    /// (`EffectNotDeclared`), that the lengths agree (`LengthMismatch`), that the particles
    /// exist (`UnknownParticle`) and that every value is finite and passes `valid` (else
    /// `invalid`). Nothing is written unless every check passes.
    fn write_particle_columns(
        &mut self,
        layout: &Layout,
        group: Option<usize>,
        first: u32,
        columns: &[&[Real]],
        invalid: Error,
        valid: fn(Real) -> bool,
    ) -> Result<(), Error> {
        let group = group.ok_or(Error::EffectNotDeclared)?;
        let n = columns.first().map_or(0, |c| c.len());
        if columns.iter().any(|c| c.len() != n) {
            return Err(Error::LengthMismatch);
        }
        let range = self.particle_range(first, n)?;
        if columns
            .iter()
            .any(|c| c.iter().any(|&v| !v.is_finite() || !valid(v)))
        {
            return Err(invalid);
        }
        for (k, values) in columns.iter().enumerate() {
            let col = self.real_col_mut(layout, group + k, range.end);
            col[range.clone()].copy_from_slice(values);
        }
        Ok(())
    }

    /// Adds one traction per particle of `particles`, each loading the `face` of that
    /// particle's domain with the traction `traction` (Pa: force per area of the face, whose
    /// area is per unit thickness in plane strain); returns the range of their traction ids.
    /// All or nothing. Needs [`crate::Effects::traction_capacity`]. The tractions are
    /// integrated each substep into `f_iT` (eq 21) while their particle is active.
    pub fn add_tractions(
        &mut self,
        particles: Range<u32>,
        face: crate::Face,
        traction: Vec3,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        if layout.traction_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let d = layout.d;
        if face as usize / 2 >= d || (0..d).any(|a| !traction[a].is_finite()) {
            return Err(Error::InvalidEffect);
        }
        if particles.start > particles.end {
            return Err(Error::UnknownParticle);
        }
        let n = (particles.end - particles.start) as usize;
        self.particle_range(particles.start, n)?;
        let used = self.header().traction_count as usize;
        if n > layout.traction_capacity - used {
            return Err(Error::TractionCapacityExceeded);
        }
        let start = layout.tractions_offset + used * size_of::<TractionRecord>();
        let table: &mut [TractionRecord] =
            bytemuck::cast_slice_mut(&mut self.buf[start..start + n * size_of::<TractionRecord>()]);
        for (rec, id) in table.iter_mut().zip(particles) {
            *rec = TractionRecord {
                particle: id,
                face: face as u32,
                traction: core::array::from_fn(|a| if a < d { traction[a] } else { 0.0 }),
            };
        }
        self.header_mut().traction_count += n as u64;
        Ok(used as u32..(used + n) as u32)
    }

    /// Removes every traction (the capacity stays).
    pub fn clear_tractions(&mut self) {
        self.header_mut().traction_count = 0;
    }

    /// `first..first + n` if those particles exist.
    fn particle_range(&self, first: u32, n: usize) -> Result<Range<usize>, Error> {
        let first = first as usize;
        match first.checked_add(n) {
            Some(end) if end <= self.particle_count() => Ok(first..end),
            _ => Err(Error::UnknownParticle),
        }
    }

    /// The thermostat (NairnMPM's feedback damping): `alpha += 2 gain (KE - target) dt / M`,
    /// clamped to `[0, min(max_alpha, room)]`, from the active particles' kinetic energy and
    /// mass; `room` is the largest alpha the substep integrates stably. The stored alpha stays
    /// finite: a rate that is not a number (no finite energy to compare) leaves it as it was.
    fn update_feedback(&mut self, f: &Feedback, time: f64, dt: Real, room: f64) {
        let (kinetic, mass) = self.read().kinetic_energy_and_mass();
        let h = self.header_mut();
        if mass > 0.0 {
            let target = f.target.at(time) as f64;
            let rate = 2.0 * f.gain as f64 * (kinetic - target) / mass;
            let alpha = h.feedback_alpha + rate * dt as f64;
            if !alpha.is_nan() {
                h.feedback_alpha = alpha.clamp(0.0, (f.max_alpha as f64).min(room));
            }
        }
    }

    fn check_room(&self, def: &WorldDef, n: usize) -> Result<(), Error> {
        if n > def.particle_capacity as usize - self.particle_count() {
            return Err(Error::ParticleCapacityExceeded);
        }
        Ok(())
    }

    /// Appends validated particles `(x, v, mass, volume, material)`; returns their ids.
    fn append(&mut self, def: &WorldDef, items: impl Iterator<Item = NewParticle>) -> Range<u32> {
        let layout = Layout::of(def);
        let d = layout.d;
        let start = self.particle_count();
        let cap = layout.padded_capacity;
        let mut min_mass = self.header().min_particle_mass;
        let mut i = start;
        for (x, v, m, vol, mat) in items {
            for a in 0..d {
                self.real_col_mut(&layout, col::x(a), cap)[i] = x[a];
                self.real_col_mut(&layout, col::v(d, a), cap)[i] = v[a];
                for b in 0..d {
                    self.real_col_mut(&layout, col::h(d, a, b), cap)[i] = 0.0;
                }
            }
            self.real_col_mut(&layout, col::mass(d), cap)[i] = m;
            self.real_col_mut(&layout, col::vol0(d), cap)[i] = vol;
            for k in 0..crate::layout::stress_components(d) {
                self.real_col_mut(&layout, col::tau(d, k), cap)[i] = 0.0;
            }
            self.u32_col_mut(&layout, col::MATERIAL, cap)[i] = mat;
            self.u32_col_mut(&layout, col::STATUS, cap)[i] = ACTIVE;
            min_mass = min_mass.min(m as f64);
            i += 1;
        }
        let h = self.header_mut();
        h.particle_count = i as u64;
        h.min_particle_mass = min_mass;
        start as u32..i as u32
    }

    /// Fills the axis-aligned box `[min, max]` with particles of `material` on the lattice of
    /// `particles_per_cell` sites per cell per axis (sites at the centres of the sub-cells), each
    /// with the volume of its sub-cell and the mass of that volume at the material's density
    /// (axisymmetric: per radian, the sub-cell's area times the site's radius).
    /// All or nothing; the box must lie inside the admissible region.
    ///
    /// The particles are written in stencil-bin order, not x fastest: the sites whose stencils
    /// start at the same node come together (one run per node), which lets the step's scatter
    /// sum a run in registers before it touches the grid and its gathers read a stencil row
    /// once for four particles; the runs of a multiple of 4 particles come first, those at the
    /// box's edges last. Find a face's particles by position.
    pub fn fill_box(
        &mut self,
        min: Vec3,
        max: Vec3,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.fill(
            min,
            max,
            material,
            velocity,
            |_| true,
            |_, _| Some([min.x, max.x]),
        )
    }

    /// Fills the disk (2D) of `center` and `radius` like [`World::fill_box`]. In 3D the disk is
    /// not defined: use [`World::fill_sphere`].
    pub fn fill_disk(
        &mut self,
        center: Vec3,
        radius: Real,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.fill_ball(2, center, radius, material, velocity)
    }

    /// Fills the sphere (3D) of `center` and `radius` like [`World::fill_box`].
    pub fn fill_sphere(
        &mut self,
        center: Vec3,
        radius: Real,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.fill_ball(3, center, radius, material, velocity)
    }

    /// A disk (`axes` = 2) or sphere (`axes` = 3); a world of the other dimension rejects it.
    fn fill_ball(
        &mut self,
        axes: usize,
        center: Vec3,
        radius: Real,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        if self.def().axes() != axes {
            return Err(Error::InvalidRegion);
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::InvalidRegion);
        }
        let r = Vec3::splat(radius);
        let d = self.def().axes();
        let inside = |x: [Real; 3]| {
            let mut q = 0.0;
            for a in 0..d {
                q += (x[a] - center[a]) * (x[a] - center[a]);
            }
            q <= radius * radius
        };
        // The ball's chord along x through the sites of `y` and `z` (ranges of coordinates;
        // z is [0, 0] in 2D): `c_x -+ sqrt(r^2 - dy^2 - dz^2)`, with dy, dz the distances
        // from the centre to those ranges; none where the ball does not reach them.
        let chord = |y: [Real; 2], z: [Real; 2]| {
            let gap = |c: Real, [lo, hi]: [Real; 2]| (lo - c).max(c - hi).max(0.0);
            let (dy, dz) = (
                gap(center.y, y),
                if d == 3 { gap(center.z, z) } else { 0.0 },
            );
            let q = radius * radius - dy * dy - dz * dz;
            (q >= 0.0).then(|| {
                let half = crate::math::sqrt(q);
                [center.x - half, center.x + half]
            })
        };
        self.fill(center - r, center + r, material, velocity, inside, chord)
    }

    /// Lattice sites of the bounding box `[min, max]` for which `inside` holds. `chord(y, z)`
    /// bounds the region's x extent over the sites whose y and z coordinates lie in the
    /// ranges `y` and `z` (`None`: the region misses them), so that the sites visited are
    /// those of the region's rows, not of its whole bounding box: a call costs in proportion
    /// to the particles it seeds, plus one test per row of bins of the bounding box within
    /// the grid.
    fn fill(
        &mut self,
        min: Vec3,
        max: Vec3,
        material: u32,
        velocity: Vec3,
        inside: impl Fn([Real; 3]) -> bool,
        chord: impl Fn([Real; 2], [Real; 2]) -> Option<[Real; 2]>,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let d = def.axes();
        // The axes the dimension uses (z is ignored in 2D, as `add_particles` ignores it).
        let finite =
            (0..d).all(|a| min[a].is_finite() && max[a].is_finite() && velocity[a].is_finite());
        if !finite || (0..d).any(|a| min[a] > max[a]) {
            return Err(if finite {
                Error::InvalidRegion
            } else {
                Error::NonFiniteInput
            });
        }
        let rec = self.material(material).ok_or(Error::UnknownMaterial)?;
        let geom = GeomAny::new(&def);
        let spacing = def.cell_size / def.particles_per_cell as Real;
        let mut volume = 1.0;
        for _ in 0..d {
            volume *= spacing;
        }
        // Axisymmetric: the volume per radian of a site's sub-cell, its area times its radius.
        let axisymmetric = def.dimension == Dimension::Axisymmetric2D;
        let per_site = move |x: [Real; 3]| {
            let v = if axisymmetric { volume * x[0] } else { volume };
            (v * rec.density, v)
        };
        // Lattice index range per axis: sites at origin + (k + 1/2) spacing inside [lo, hi],
        // clipped to the admissible region widened by one site, so that a huge region costs
        // no more than the grid while a region reaching out of the grid still meets a site
        // outside it (and is rejected). The sites, not the region's corners, are checked.
        let margin = def.shape.margin_cells() as Real * def.particles_per_cell as Real;
        let sites_in = |a: usize, lo: Real, hi: Real| -> [i64; 2] {
            let sites_per_axis = (def.cells[a] * def.particles_per_cell) as Real;
            let (adm_lo, adm_hi) = (margin - 1.5, sites_per_axis - margin + 0.5);
            let lattice = |x: Real| ((x - def.origin[a]) / spacing - 0.5).clamp(adm_lo, adm_hi);
            [ceil(lattice(lo)) as i64, libm_floor(lattice(hi)) as i64]
        };
        let mut k_lo = [0i64; 3];
        let mut k_hi = [0i64; 3];
        for a in 0..d {
            [k_lo[a], k_hi[a]] = sites_in(a, min[a], max[a]);
        }
        let coordinate = |a: usize, k: i64| def.origin[a] + (k as Real + 0.5) * spacing;
        let site = |k: [i64; 3]| -> [Real; 3] {
            core::array::from_fn(|a| if a < d { coordinate(a, k[a]) } else { 0.0 })
        };
        let bins = Bins {
            n: def.particles_per_cell as i64,
            shift_halves: def.shape.first_node_shift_halves(),
        };
        // The x sites of the region's chord through the sites `y`, `z` (inclusive index
        // ranges), widened by a site on each side against the chord's round-off (the sites
        // themselves are tested with `inside`).
        let row = |y: [i64; 2], z: [i64; 2]| -> [i64; 2] {
            let at = |a: usize, k: [i64; 2]| {
                if a < d {
                    [coordinate(a, k[0]), coordinate(a, k[1])]
                } else {
                    [0.0; 2]
                }
            };
            match chord(at(1, y), at(2, z)) {
                Some([lo, hi]) => {
                    let [l, h] = sites_in(0, lo, hi);
                    [l - 1, h + 1]
                }
                None => [1, 0],
            }
        };
        let sites = || {
            BinnedSites::new(k_lo, k_hi, bins, &row)
                .map(site)
                .filter(|x| inside(*x))
        };
        // Pass 1: count and validate as `add_particles` does (nothing is written on failure).
        // Stops at the first problem, so a region far larger than the capacity costs no more
        // than the capacity.
        let room = def.particle_capacity as usize - self.particle_count();
        let mut n = 0usize;
        for x in sites() {
            // The position first: a site's mass follows from it (axisymmetric: its radius).
            if !geom.admits(x) {
                return Err(Error::PositionOutsideDomain);
            }
            let (mass, volume) = per_site(x);
            if !(mass.is_finite() && volume.is_finite()) {
                return Err(Error::NonFiniteInput);
            }
            if !(mass > 0.0 && volume > 0.0) {
                return Err(Error::NonPositiveMassOrVolume);
            }
            n += 1;
            if n > room {
                return Err(Error::ParticleCapacityExceeded);
            }
        }
        // Pass 2: write the same sites in the same order.
        let v3 = core::array::from_fn(|a| if a < d { velocity[a] } else { 0.0 });
        Ok(self.append(
            &def,
            sites().map(|x| {
                let (mass, volume) = per_site(x);
                (x, v3, mass, volume, material)
            }),
        ))
    }

    /// Advances the world by `dt` seconds. A `dt` above [`World::stable_dt`] (evaluated once at
    /// the start of the call) is taken in equal substeps that are each stable.
    pub fn step(&mut self, dt: Real) -> Result<StepReport, Error> {
        self.step_with_simd(dt, Simd::Detect)
    }

    /// [`World::step`] with a chosen instruction set (see [`crate::simd`]). Not part of the
    /// stable API: tests use it to show that both paths give bit-identical state.
    #[doc(hidden)]
    pub fn step_with_simd(&mut self, dt: Real, simd: Simd) -> Result<StepReport, Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::InvalidTimeStep);
        }
        let def = self.def();
        let limits = self.read().time_step_limits(simd);
        let ratio = dt / limits.stable_dt;
        let substeps = if ratio <= 1.0 { 1.0 } else { ceil(ratio) };
        // NaN-safe: a NaN ratio fails `<=`.
        let within = substeps <= def.max_substeps as Real;
        if !within {
            return Err(Error::SubstepLimit);
        }
        let substeps = substeps as u32;
        let sub_dt = dt / substeps as Real;
        // The thermostat's alpha is kept to what a substep of this length integrates stably
        // besides the other damping (`alpha dt <= cfl`, as `stable_dt` keeps the other
        // damping): it adapts to the substep and never sets its length, whatever its gain.
        let feedback_room = (def.cfl as f64 / sub_dt as f64 - limits.other_damping).max(0.0);
        let mut report = StepReport {
            substeps,
            substep_dt: sub_dt,
            ..StepReport::default()
        };
        let fx = def.effects;
        let time0 = self.time();
        for k in 0..substeps {
            let time = time0 + k as f64 * sub_dt as f64;
            if let Some(feedback) = fx.damping.and_then(|d| d.feedback) {
                self.update_feedback(&feedback, time, sub_dt, feedback_room);
            }
            let mut substep = Substep {
                report: &mut report,
            };
            self.dispatch(sub_dt, time, &mut substep, simd);
        }
        let h = self.header_mut();
        h.time += dt as f64;
        h.step_count += 1;
        Ok(report)
    }

    /// Runs `kernel` once on the world's columns, dispatching once on (dimension, shape
    /// function) to the monomorphised instance, with the instruction set `simd` picks.
    fn dispatch(&mut self, dt: Real, time: f64, kernel: &mut impl Kernel, simd: Simd) {
        let def = self.def();
        let layout = Layout::of(&def);
        let ppc = def.particles_per_cell;
        let run = (dt, time);
        // One run of the family `$family` in dimension `$d`, its stencil width `$k` fixed with
        // it and the chunk width with the dimension; `$wrap` turns the family into the shape
        // the step uses.
        macro_rules! run_family {
            ($d:literal, $k:literal, $family:expr, $wrap:expr) => {
                self.run::<$d, $k, _, { width($d) }>(
                    $wrap($family, &def),
                    run,
                    &def,
                    &layout,
                    kernel,
                    simd,
                )
            };
        }
        macro_rules! by_shape {
            ($d:literal, $wrap:expr) => {
                match def.shape {
                    ShapeFunction::Linear => run_family!($d, 2, Linear, $wrap),
                    ShapeFunction::Gimp => run_family!($d, 3, Gimp::new(ppc), $wrap),
                    ShapeFunction::QuadraticBspline => {
                        run_family!($d, 3, QuadraticBspline, $wrap)
                    }
                    ShapeFunction::CubicBspline => run_family!($d, 4, CubicBspline, $wrap),
                    ShapeFunction::CpGimp => run_family!($d, 3, CpGimp::new(ppc), $wrap),
                }
            };
        }
        // The family as it is, or wrapped in the axisymmetric form.
        fn plain<S>(shape: S, _: &WorldDef) -> S {
            shape
        }
        #[cfg(feature = "effects")]
        if def.dimension == Dimension::Axisymmetric2D {
            fn axi<S>(inner: S, def: &WorldDef) -> crate::shape::Axisymmetric<S> {
                let half_width = def.cell_size / (2 * def.particles_per_cell) as Real;
                crate::shape::Axisymmetric::new(inner, def.origin.x, def.cell_size, half_width)
            }
            return by_shape!(2, axi);
        }
        if def.axes() == 2 {
            by_shape!(2, plain)
        } else {
            by_shape!(3, plain)
        }
    }

    /// Carves the columns and the step context of a substep of length `dt` starting at `time`,
    /// then runs `kernel` on them.
    fn run<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: S,
        (dt, time): (Real, f64),
        def: &WorldDef,
        layout: &Layout,
        kernel: &mut impl Kernel,
        simd: Simd,
    ) {
        let count = self.particle_count();
        let min_mass = self.header().min_particle_mass;
        let n_materials = self.material_count();
        let n_tractions = self.header().traction_count as usize;
        let feedback_alpha = self.header().feedback_alpha as Real;
        let (head, rest) = self.buf.split_at_mut(layout.particle_offset);
        let (pbytes, gbytes) = rest.split_at_mut(layout.grid_offset - layout.particle_offset);
        let mat_start = layout.materials_offset;
        let materials: &[MaterialRecord] = bytemuck::cast_slice(
            &head[mat_start..mat_start + n_materials * size_of::<MaterialRecord>()],
        );
        let trac_start = layout.tractions_offset;
        let tractions: &[TractionRecord] = bytemuck::cast_slice(
            &head[trac_start..trac_start + n_tractions * size_of::<TractionRecord>()],
        );
        let mut p = ParticleCols::<D>::carve(pbytes, layout);
        let mut g = GridCols::<D>::carve(gbytes, layout);
        let fx = &def.effects;
        let body = fx.body_force * fx.body_force_scale.at(time);
        let (alpha_g, alpha_p) = match fx.damping {
            Some(d) => (d.grid.at(time) + feedback_alpha, d.particle.at(time)),
            None => (0.0, 0.0),
        };
        let geom = Geom::<D>::new(def);
        let active = crate::phases::node_box::<D, K, S>(
            simd,
            &geom,
            &p.x.each_ref().map(|c| &**c),
            p.status,
            count,
        );
        let ctx = Ctx {
            geom,
            active,
            dt,
            order: def.update_order,
            apic: def.transfer == Transfer::Apic,
            forces: fx.particle_forces,
            damp: fx.damping.is_some(),
            gravity: core::array::from_fn(|a| def.gravity[a] + body[a]),
            beta: def.flip_beta,
            alpha_g,
            alpha_p,
            half_width: def.cell_size / (2 * def.particles_per_cell) as Real,
            exp_terms: def.exp_terms,
            jm1_band: [1.0 / def.max_volume_ratio - 1.0, def.max_volume_ratio - 1.0],
            mass_cutoff: (NODAL_MASS_CUTOFF as f64 * min_mass) as Real,
            materials,
            tractions,
            transport: [fx.heat, fx.diffusion],
            eigenstrain: [
                fx.heat.is_some() && materials.iter().any(|m| m.thermal_expansion != 0.0),
                fx.diffusion.is_some() && materials.iter().any(|m| m.swelling != 0.0),
            ],
        };
        run_kernel::<D, K, S, W>(kernel, simd, &shape, &ctx, &mut p, count, &mut g);
    }

    /// Runs one phase of a USL step on the current state, for benchmarks that time the phases
    /// one at a time. Not part of the stable API.
    #[doc(hidden)]
    pub fn run_phase(&mut self, phase: Phase, dt: Real) -> Result<StepReport, Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::InvalidTimeStep);
        }
        let mut run = PhaseRun {
            phase,
            report: StepReport::default(),
        };
        let time = self.time();
        self.dispatch(dt, time, &mut run, Simd::Detect);
        Ok(run.report)
    }
}

/// A world read in place: every query of [`World`] that changes nothing, on a shared borrow
/// of its bytes (from [`World::read`], or [`WorldRef::open`] on memory only lent for reading,
/// such as a snapshot or a world other threads read at the same time).
#[derive(Clone, Copy)]
pub struct WorldRef<'a> {
    buf: &'a [u8],
}

impl<'a> WorldRef<'a> {
    /// Reads the world that `buf` holds, with the checks of [`World::open`] (the state
    /// included).
    pub fn open(buf: &'a [u8]) -> Result<WorldRef<'a>, Error> {
        let w = WorldRef::reopen(buf)?;
        w.check_state()?;
        Ok(w)
    }

    /// Reads the world that `buf` holds, with the constant-time checks of [`World::reopen`].
    pub fn reopen(buf: &'a [u8]) -> Result<WorldRef<'a>, Error> {
        let total = World::stored_bytes(buf)?;
        check_buffer(buf, total)?;
        Ok(WorldRef { buf })
    }

    /// Checks the state of a world whose header is sound, as [`World::open`] does; the first
    /// problem found is [`Error::InvalidState`]. What holds in every world this API produced:
    /// - the time is finite and >= 0; the thermostat's alpha finite, in `[0, max_alpha]`
    ///   (0 without one); the smallest particle mass is the smallest of the particles' masses
    ///   (infinite before the first particle);
    /// - each material record is what [`World::add_material`] makes of a valid definition;
    ///   each traction names an existing particle and a face of the dimension, with a finite
    ///   traction;
    /// - every particle has a known status and material, a finite mass and volume > 0, a
    ///   position in the admissible region (the grid less the shape function's margin; on
    ///   its wall planes, where the step puts a particle that reaches them), and every value
    ///   it carries is finite (velocity, `H` with `J > 0`, stress, and the columns of its
    ///   declared effects: forces, damping >= 0, moment matrix, transported values and
    ///   sources, hoop stretch > -1): a particle frozen or escaped in a step keeps its last
    ///   finite state.
    pub fn check_state(&self) -> Result<(), Error> {
        let invalid = Err(Error::InvalidState);
        let h = self.header();
        let def = self.def();
        let layout = self.layout();
        let d = layout.d;
        let n = self.particle_count();
        let max_alpha = def
            .effects
            .damping
            .and_then(|dm| dm.feedback)
            .map_or(0.0, |f| f.max_alpha as f64);
        let alpha_ok = (0.0..=max_alpha).contains(&h.feedback_alpha);
        if !(h.time.is_finite() && h.time >= 0.0 && alpha_ok) {
            return invalid;
        }
        for (id, rec) in self.materials(&layout).iter().enumerate() {
            let again = self.material(id as u32).map(|m| material_record(&m));
            if !matches!(again, Some(Ok(r)) if bytemuck::bytes_of(&r) == bytemuck::bytes_of(rec)) {
                return invalid;
            }
        }
        let trac_start = layout.tractions_offset;
        let trac_bytes = self.traction_count() * size_of::<TractionRecord>();
        let tractions: &[TractionRecord] =
            bytemuck::cast_slice(&self.buf[trac_start..trac_start + trac_bytes]);
        for t in tractions {
            let finite = t.traction.iter().all(|c| c.is_finite());
            if t.particle as usize >= n || t.face as usize >= 2 * d || !finite {
                return invalid;
            }
        }
        let v = self.particles();
        let materials = self.material_count();
        let geom = GeomAny::new(&def);
        // Every particle Real column a particle's state lives in: those of `H`, the stress,
        // the declared effects (the MUSL start positions and the cpGIMP stretches are scratch).
        let real = |j: usize| self.real_col(&layout, j, n);
        let groups = [
            layout.force,
            layout.damping,
            layout.affine,
            layout.scalar[0],
            layout.scalar[1],
            layout.hoop,
        ];
        let columns = (0..d * d)
            .map(|k| col::h(d, k / d, k % d))
            .chain((0..crate::layout::stress_components(d)).map(|k| col::tau(d, k)))
            .chain(groups.iter().flat_map(|g| g.first..g.first + g.count))
            .map(real);
        let mut min_mass = f64::INFINITY;
        for i in 0..n {
            let (m, vol) = (v.mass[i], v.volume0[i]);
            min_mass = min_mass.min(m as f64);
            let x: [Real; 3] = core::array::from_fn(|a| if a < d { v.position[a][i] } else { 0.0 });
            let sound = ParticleStatus::from_code(v.status[i]).is_some()
                && (v.material[i] as usize) < materials
                && m.is_finite()
                && m > 0.0
                && vol.is_finite()
                && vol > 0.0
                && (0..d).all(|a| v.velocity[a][i].is_finite())
                && columns.clone().all(|c| c[i].is_finite())
                && v.damping.iter().all(|c| c.get(i).is_none_or(|&x| x >= 0.0))
                && v.hoop.get(i).is_none_or(|&x| x > -1.0)
                && v.jacobian_minus_one(i).partial_cmp(&-1.0) == Some(Ordering::Greater)
                && geom.holds(x);
            if !sound {
                return invalid;
            }
        }
        if h.min_particle_mass != min_mass {
            return invalid;
        }
        Ok(())
    }

    fn header(&self) -> &'a Header {
        bytemuck::from_bytes(&self.buf[..size_of::<Header>()])
    }

    /// The world's definition.
    pub fn def(&self) -> WorldDef {
        // The header was written by init or checked by open, so it always decodes.
        self.header().def().unwrap_or(WorldDef::DEFAULT)
    }

    fn layout(&self) -> Layout {
        Layout::of(&self.def())
    }

    /// Number of particles added.
    pub fn particle_count(&self) -> usize {
        self.header().particle_count as usize
    }

    /// Number of materials added.
    pub fn material_count(&self) -> usize {
        self.header().material_count as usize
    }

    /// Simulated time, s (sum of the `dt` of every step).
    pub fn time(&self) -> f64 {
        self.header().time
    }

    /// Number of `step` calls that succeeded.
    pub fn step_count(&self) -> u64 {
        self.header().step_count
    }

    /// The bytes the world occupies (a prefix of the buffer). A copy is a snapshot.
    pub fn as_bytes(&self) -> &'a [u8] {
        let total = self.header().total_bytes as usize;
        &self.buf[..total]
    }

    /// The world's state: [`as_bytes`](Self::as_bytes) without the grid columns at its end.
    /// The grid is scratch: every substep resets each node value before it reads it, so
    /// whatever those bytes hold cannot change a step (tested). A snapshot therefore needs
    /// only these bytes: copied to the start of a buffer of
    /// [`memory_requirements`](crate::memory_requirements) bytes, they open
    /// ([`World::open`]) as a world that steps as this one does.
    pub fn state_bytes(&self) -> &'a [u8] {
        &self.buf[..self.layout().grid_offset]
    }

    fn materials(&self, layout: &Layout) -> &'a [MaterialRecord] {
        let n = self.material_count();
        let start = layout.materials_offset;
        bytemuck::cast_slice(&self.buf[start..start + n * size_of::<MaterialRecord>()])
    }

    fn real_col(&self, layout: &Layout, j: usize, count: usize) -> &'a [Real] {
        bytemuck::cast_slice(&self.buf[layout.real_col(j, count)])
    }

    fn u32_col(&self, layout: &Layout, j: usize, count: usize) -> &'a [u32] {
        bytemuck::cast_slice(&self.buf[layout.u32_col(j, count)])
    }

    /// The definition of material `id`.
    pub fn material(&self, id: u32) -> Option<MaterialDef> {
        let layout = self.layout();
        self.materials(&layout)
            .get(id as usize)
            .map(|r| MaterialDef {
                model: model_of(r),
                youngs_modulus: r.youngs_modulus,
                poisson_ratio: r.poisson_ratio,
                density: r.density,
                heat_capacity: r.heat_capacity,
                conductivity: r.conductivity,
                diffusivity: r.diffusivity,
                thermal_expansion: r.thermal_expansion,
                reference_temperature: r.reference_temperature,
                swelling: r.swelling,
                reference_concentration: r.reference_concentration,
            })
    }

    /// Largest stable time step `cfl h / (c_max + |v|_max)`, s: `c_max` is the fastest
    /// dilatational wave speed of the materials, `|v|_max` the fastest active particle; shorter
    /// where damping (`alpha dt <= cfl`, the thermostat's alpha excepted: it is clamped to what
    /// the substep allows), conduction or diffusion (`dt <= h^2 / (2 d kappa)`) need it.
    /// Infinite when nothing moves and there is no material.
    pub fn stable_dt(&self) -> Real {
        self.stable_dt_with_simd(Simd::Detect)
    }

    /// [`WorldRef::stable_dt`], its scan of the particles run in the instruction set `simd`.
    pub(crate) fn stable_dt_with_simd(&self, simd: Simd) -> Real {
        self.time_step_limits(simd).stable_dt
    }

    /// The stable time step and the damping besides the thermostat that it allows for.
    fn time_step_limits(&self, simd: Simd) -> TimeStepLimits {
        let layout = self.layout();
        let def = self.def();
        let c_max = self
            .materials(&layout)
            .iter()
            .fold(0.0 as Real, |c, r| c.max(r.wave_speed));
        let n = self.particle_count();
        let d = layout.d;
        let status = self.u32_col(&layout, col::STATUS, n);
        let v: [&[Real]; 3] = core::array::from_fn(|a| {
            if a < d {
                self.real_col(&layout, col::v(d, a), n)
            } else {
                &[]
            }
        });
        let v2_max = crate::phases::fastest_squared(simd, &v, &status[..n], d);
        let speed = c_max as f64 + libm::sqrt(v2_max);
        // Damping is integrated explicitly, `v (1 - alpha dt)`: the step keeps `alpha dt` at
        // most the Courant number, with alpha the largest damping any particle can see (the
        // schedules' maxima, the largest local values). The thermostat's alpha is not among
        // them: the step clamps it to the room this leaves (`World::update_feedback`).
        let other_damping = def.effects.damping.map_or(0.0, |dm| {
            let local = |k: usize| view_max(self.particles().damping[k], status);
            dm.grid.max_value() as f64 + dm.particle.max_value() as f64 + local(0) + local(1)
        });
        // Conduction and diffusion are explicit too: `dt <= h^2 / (2 d kappa)` with kappa the
        // largest thermal diffusivity `k / (rho C_p)` or diffusivity D of a declared field.
        let fx = &def.effects;
        let kappa = self.materials(&layout).iter().fold(0.0f64, |m, r| {
            let thermal = if fx.heat.is_some() {
                r.conductivity as f64 / (r.density as f64 * r.heat_capacity as f64)
            } else {
                0.0
            };
            let solvent = if fx.diffusion.is_some() {
                r.diffusivity as f64
            } else {
                0.0
            };
            m.max(thermal).max(solvent)
        });
        let h = def.cell_size as f64;
        let conduction = h * h / (2.0 * d as f64 * kappa);
        // Never 0: a step below the smallest positive Real is not a step.
        let dt = def.cfl as f64 * (h / speed).min(1.0 / other_damping).min(conduction);
        let stable_dt = if dt.is_finite() {
            (dt as Real).max(Real::MIN_POSITIVE)
        } else {
            Real::INFINITY
        };
        TimeStepLimits {
            stable_dt,
            other_damping,
        }
    }

    /// Borrowed view of every particle column.
    pub fn particles(&self) -> ParticlesView<'a> {
        let layout = self.layout();
        let d = layout.d;
        let n = self.particle_count();
        let empty: &[Real] = &[];
        let r = |j: usize| self.real_col(&layout, j, n);
        let ns = crate::layout::stress_components(d);
        // Column k of an optional group, or empty when the group is not reserved.
        let group = |g: crate::layout::ColumnGroup, k: usize| {
            if k < g.count {
                r(g.first + k)
            } else {
                empty
            }
        };
        ParticlesView {
            count: n,
            dimension: self.def().dimension,
            position: core::array::from_fn(|a| if a < d { r(col::x(a)) } else { empty }),
            velocity: core::array::from_fn(|a| if a < d { r(col::v(d, a)) } else { empty }),
            mass: r(col::mass(d)),
            volume0: r(col::vol0(d)),
            displacement_gradient: core::array::from_fn(|a| {
                core::array::from_fn(|b| {
                    if a < d && b < d {
                        r(col::h(d, a, b))
                    } else {
                        empty
                    }
                })
            }),
            stress: core::array::from_fn(|k| if k < ns { r(col::tau(d, k)) } else { empty }),
            material: self.u32_col(&layout, col::MATERIAL, n),
            status: self.u32_col(&layout, col::STATUS, n),
            force: core::array::from_fn(|a| group(layout.force, a)),
            temperature: group(layout.scalar[0], 0),
            concentration: group(layout.scalar[1], 0),
            grid_temperature: group(layout.scalar[0], 1),
            grid_concentration: group(layout.scalar[1], 1),
            hoop: group(layout.hoop, 0),
            damping: core::array::from_fn(|k| group(layout.damping, k)),
            affine: core::array::from_fn(|a| {
                core::array::from_fn(|b| {
                    if a < d && b < d {
                        group(layout.affine, a * d + b)
                    } else {
                        empty
                    }
                })
            }),
        }
    }

    /// Kinetic energy (J) and mass (kg) of the active particles, in f64.
    fn kinetic_energy_and_mass(&self) -> (f64, f64) {
        let view = self.particles();
        let d = self.layout().d;
        let (mut kinetic, mut mass) = (0.0f64, 0.0f64);
        for i in 0..view.count {
            if view.status[i] == ACTIVE {
                let m = view.mass[i] as f64;
                let v2: f64 = (0..d)
                    .map(|a| view.velocity[a][i] as f64 * view.velocity[a][i] as f64)
                    .sum();
                kinetic += 0.5 * m * v2;
                mass += m;
            }
        }
        (kinetic, mass)
    }

    /// The thermostat's current alpha, 1/s (0 without one).
    pub fn feedback_alpha(&self) -> f64 {
        self.header().feedback_alpha
    }

    /// Number of tractions added.
    pub fn traction_count(&self) -> usize {
        self.header().traction_count as usize
    }

    /// Mass, momentum, centre of mass and energies of the active particles.
    pub fn diagnostics(&self) -> Diagnostics {
        let def = self.def();
        let layout = Layout::of(&def);
        let materials = self.materials(&layout);
        let view = self.particles();
        let d = layout.d;
        let mut out = Diagnostics::default();
        let mut first_moment = [0.0f64; 3];
        for i in 0..view.count {
            if view.status[i] != ACTIVE {
                continue;
            }
            let m = view.mass[i] as f64;
            out.mass += m;
            let mut x = [0.0f64; 3];
            let mut v = [0.0f64; 3];
            for a in 0..d {
                v[a] = view.velocity[a][i] as f64;
                x[a] = view.position[a][i] as f64;
                out.momentum[a] += m * v[a];
                out.kinetic += 0.5 * m * v[a] * v[a];
                first_moment[a] += m * x[a];
                out.potential -= m * def.gravity[a] as f64 * x[a];
            }
            // L = x x m v, plus m eps_abc B_cb with APIC.
            let mut l = [
                m * (x[1] * v[2] - x[2] * v[1]),
                m * (x[2] * v[0] - x[0] * v[2]),
                m * (x[0] * v[1] - x[1] * v[0]),
            ];
            if def.transfer == Transfer::Apic {
                // B_p itself, or C_p D_p for linear weights, whose column holds C_p (the
                // gradient form; D_p = f (1 - f) h^2 per axis, f the offset in the cell).
                let linear = def.shape == ShapeFunction::Linear;
                let dm: [f64; 3] = core::array::from_fn(|a| {
                    if linear && a < d {
                        let h = def.cell_size as f64;
                        let s = (x[a] - def.origin[a] as f64) / h;
                        let f = s - libm::floor(s);
                        f * (1.0 - f) * h * h
                    } else {
                        1.0
                    }
                });
                let b = |a: usize, c: usize| {
                    if a < d && c < d {
                        view.affine[a][c][i] as f64 * dm[c]
                    } else {
                        0.0
                    }
                };
                l[0] += m * (b(2, 1) - b(1, 2));
                l[1] += m * (b(0, 2) - b(2, 0));
                l[2] += m * (b(1, 0) - b(0, 1));
            }
            let axes = if d == 3 { 0..3 } else { 2..3 };
            for a in axes {
                out.angular_momentum[a] += l[a];
            }
            if let Some(rec) = materials.get(view.material[i] as usize) {
                // The elastic part's energy, per volume of the eigenstrained (stress-free)
                // configuration, (1 + d)^3 V0.
                let (model, params) = (model_of(rec), Params::of(rec));
                let eig = eigenstrain_of(rec, &view, i);
                let (w, scale) = if d == 3 {
                    let (f, k) = elastic_part(&view.deformation::<3>(i), eig);
                    (energy_density(model, &params, &f), k)
                } else {
                    let (f, k) = elastic_part(&view.deformation::<2>(i), eig);
                    (energy_density(model, &params, &f), k)
                };
                out.strain += view.volume0[i] as f64 * (scale * w) as f64;
            }
        }
        if out.mass > 0.0 {
            for a in 0..3 {
                out.center_of_mass[a] = first_moment[a] / out.mass;
            }
        }
        out
    }
}

/// The record of a valid material definition, with what the step derives from it (Lame
/// parameters, wave speed), or `InvalidMaterial`.
fn material_record(m: &MaterialDef) -> Result<MaterialRecord, Error> {
    let ok = m.youngs_modulus.is_finite()
        && m.youngs_modulus > 0.0
        && m.poisson_ratio > -1.0
        && m.poisson_ratio < 0.5
        && m.density.is_finite()
        && m.density > 0.0
        && m.heat_capacity.is_finite()
        && m.heat_capacity > 0.0
        && m.conductivity.is_finite()
        && m.conductivity >= 0.0
        && m.diffusivity.is_finite()
        && m.diffusivity >= 0.0
        && m.thermal_expansion.is_finite()
        && m.reference_temperature.is_finite()
        && m.swelling.is_finite()
        && m.reference_concentration.is_finite();
    if !ok {
        return Err(Error::InvalidMaterial);
    }
    let (lambda, mu) = m.lame();
    let c = m.wave_speed();
    if !(lambda.is_finite() && mu.is_finite() && c.is_finite()) {
        return Err(Error::InvalidMaterial);
    }
    Ok(MaterialRecord {
        model: m.model as u32 as Real,
        youngs_modulus: m.youngs_modulus,
        poisson_ratio: m.poisson_ratio,
        density: m.density,
        lambda,
        mu,
        wave_speed: c,
        heat_capacity: m.heat_capacity,
        conductivity: m.conductivity,
        diffusivity: m.diffusivity,
        thermal_expansion: m.thermal_expansion,
        reference_temperature: m.reference_temperature,
        swelling: m.swelling,
        reference_concentration: m.reference_concentration,
        reserved: [0.0; 2],
    })
}

/// The isotropic eigenstrain `d` of particle `i` of material `rec` (thermal expansion and
/// swelling, from the grid values at the particle; 0 for a field not declared), as the stress
/// update takes it out.
fn eigenstrain_of(rec: &MaterialRecord, view: &ParticlesView<'_>, i: usize) -> Real {
    [view.grid_temperature, view.grid_concentration]
        .iter()
        .enumerate()
        .filter_map(|(f, col)| col.get(i).map(|&v| eigenstrain_part(rec, f, v)))
        .sum()
}

/// What bounds a substep: [`WorldRef::stable_dt`], and the largest damping rate besides the
/// thermostat's that any particle can see (1/s), whose room the thermostat's alpha must stay
/// within.
struct TimeStepLimits {
    stable_dt: Real,
    other_damping: f64,
}

/// Largest value of `col` over active particles (0 for an empty column).
fn view_max(col: &[Real], status: &[u32]) -> f64 {
    col.iter()
        .zip(status)
        .filter(|(_, &s)| s == ACTIVE)
        .fold(0.0f64, |m, (&v, _)| m.max(v as f64))
}

/// A computation on the world's columns with the dimension and shape function fixed at compile
/// time; [`World::dispatch`] picks the instance once per call. `I` is the instruction set each
/// pass runs in: a body calls every pass as `I::run(|| pass(..))`.
trait Kernel {
    fn body<I: Isa, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &mut GridCols<'_, D>,
    );
}

/// Runs `kernel` with its passes in the instance `simd` picks on this CPU (see
/// [`crate::simd`]).
fn run_kernel<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    kernel: &mut impl Kernel,
    simd: Simd,
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &mut ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    crate::phases::with_instance!(simd, I => kernel.body::<I, D, K, S, W>(shape, ctx, p, count, g));
}

/// One substep: the phase order of seeds/000 section 5.1 for the chosen update order. This is
/// the only place the order of the phases is written down. The update order, the transfer and
/// the declared effects are values of the context ([`Ctx`]): one compiled substep serves them
/// all, and the passes skip an undeclared effect's work once per chunk of lanes.
struct Substep<'r> {
    report: &'r mut StepReport,
}

impl Kernel for Substep<'_> {
    fn body<I: Isa, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        s: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &mut GridCols<'_, D>,
    ) {
        let report = &mut *self.report;
        p.freeze_domain_stretch::<K, S>(count);
        // Heat and diffusion first, with the particles where the substep starts.
        for (f, t) in ctx.transport.iter().enumerate() {
            if let Some(t) = t {
                I::transport::<D, K, S, W>(s, ctx, p, count, g, f, t);
            }
        }
        grid_update::reset(ctx, g);
        let adds = |mode| Adds::of(mode, ctx);
        match ctx.order {
            UpdateOrder::Usf => {
                I::scatter::<D, K, S, W>(s, ctx, p, count, g, adds(Mode::MassMomentum));
                grid_update::velocity(ctx, g);
                grid_update::constrained_velocity(ctx, g);
                I::stress::<D, K, S, W>(s, ctx, p, count, g, report);
                I::scatter::<D, K, S, W>(s, ctx, p, count, g, adds(Mode::Force));
                p2g::tractions(s, ctx, p, count, g);
                grid_update::acceleration(ctx, g);
                I::particles::<D, K, S, W>(s, ctx, p, count, g, report);
            }
            UpdateOrder::Usl => {
                I::scatter::<D, K, S, W>(s, ctx, p, count, g, adds(Mode::All));
                p2g::tractions(s, ctx, p, count, g);
                grid_update::velocity(ctx, g);
                grid_update::acceleration(ctx, g);
                // Also updates the stress (see g2p::particles).
                I::particles::<D, K, S, W>(s, ctx, p, count, g, report);
            }
            UpdateOrder::Musl => {
                I::scatter::<D, K, S, W>(s, ctx, p, count, g, adds(Mode::All));
                p2g::tractions(s, ctx, p, count, g);
                grid_update::velocity(ctx, g);
                grid_update::acceleration(ctx, g);
                // Also scatters the new momenta to the remap columns (see g2p::particles).
                I::particles::<D, K, S, W>(s, ctx, p, count, g, report);
                grid_update::remap_velocity(ctx, g);
                I::stress::<D, K, S, W>(s, ctx, p, count, g, report);
            }
        }
    }
}

/// The phases of a USL step, for [`World::run_phase`] (benchmarks).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Zero the grid columns on the nodes the particles reach.
    ResetGrid,
    /// Reset, then scatter mass, momentum and force to the grid.
    ParticleToGrid,
    /// Nodal velocity and acceleration, with the walls.
    GridUpdate,
    /// Particle update with the fused stress update.
    GridToParticle,
}

struct PhaseRun {
    phase: Phase,
    report: StepReport,
}

impl Kernel for PhaseRun {
    fn body<I: Isa, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        s: &S,
        ctx: &Ctx<'_, D>,
        p: &mut ParticleCols<'_, D>,
        count: usize,
        g: &mut GridCols<'_, D>,
    ) {
        // A plain USL substep: FLIP, no damping, no particle forces.
        let ctx = &Ctx {
            order: UpdateOrder::Usl,
            apic: false,
            forces: false,
            damp: false,
            ..*ctx
        };
        match self.phase {
            Phase::ResetGrid => grid_update::reset(ctx, g),
            Phase::ParticleToGrid => {
                p.freeze_domain_stretch::<K, S>(count);
                grid_update::reset(ctx, g);
                I::scatter::<D, K, S, W>(s, ctx, p, count, g, Adds::of(Mode::All, ctx));
            }
            Phase::GridUpdate => {
                grid_update::velocity(ctx, g);
                grid_update::acceleration(ctx, g);
            }
            Phase::GridToParticle => {
                let report = &mut self.report;
                I::particles::<D, K, S, W>(s, ctx, p, count, g, report)
            }
        }
    }
}

fn libm_floor(x: Real) -> Real {
    -ceil(-x)
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

/// A particle to append: position, velocity, mass, volume, material id.
type NewParticle = ([Real; 3], [Real; 3], Real, Real, u32);

/// Lattice indices in `[lo, hi]` (inclusive per axis, x fastest).
struct Sites {
    lo: [i64; 3],
    hi: [i64; 3],
    next: Option<[i64; 3]>,
}

impl Sites {
    fn new(lo: [i64; 3], hi: [i64; 3]) -> Self {
        let empty = (0..3).any(|a| lo[a] > hi[a]);
        Sites {
            lo,
            hi,
            next: if empty { None } else { Some(lo) },
        }
    }
}

impl Iterator for Sites {
    type Item = [i64; 3];
    fn next(&mut self) -> Option<[i64; 3]> {
        let cur = self.next?;
        let mut k = cur;
        let mut a = 0;
        self.next = loop {
            if a == 3 {
                break None;
            }
            if k[a] < self.hi[a] {
                k[a] += 1;
                break Some(k);
            }
            k[a] = self.lo[a];
            a += 1;
        };
        Some(cur)
    }
}

/// How lattice sites fall into stencil bins along an axis: site `k` sits at `s = (k + 1/2) / n`
/// cells from the grid origin, and its stencil's first node is `floor(s + shift) - lead`, so
/// the sites of bin `b = floor((2k + 1 + 2 n shift) / 2n)` share their first node.
#[derive(Clone, Copy)]
struct Bins {
    /// Sites per cell per axis.
    n: i64,
    /// `2 shift` ([`crate::ShapeFunction::first_node_shift_halves`]).
    shift_halves: i64,
}

impl Bins {
    /// The bin of site `k`.
    fn of(self, k: i64) -> i64 {
        (2 * k + 1 + self.shift_halves * self.n).div_euclid(2 * self.n)
    }

    /// The first site of bin `b` (the least `k` whose bin is at least `b`).
    fn first(self, b: i64) -> i64 {
        -((1 + self.shift_halves * self.n - 2 * self.n * b).div_euclid(2))
    }
}

/// The x sites of a row of a region: given the row's y and z site ranges (inclusive), the
/// inclusive x range that holds every site of the region in those rows (empty if lo > hi).
type RowSpan<'r> = &'r dyn Fn([i64; 2], [i64; 2]) -> [i64; 2];

/// Lattice indices in `[lo, hi]` (inclusive per axis) in stencil-bin order: the bins x
/// fastest, and within a bin its sites x fastest. The sites of a bin share their stencil's
/// first node, so they come one after another and the scatter sums them before it adds to the
/// grid ([`crate::phases::p2g`]'s runs): one load and store per node row for the bin rather
/// than one per particle. In each row of bins (y and z fixed) only the bins that meet the
/// region's x span for that row ([`RowSpan`]) are visited.
///
/// The bins whose number of sites is a multiple of 4 come first, the others (the partial bins
/// at the box's edges) after them: a run of the first kind then starts where a 4-lane block
/// of the passes' chunks starts (when the fill itself starts there), so that the gathers read
/// one stencil row for the block's four particles ([`crate::phases::rows::blocks_share`]).
/// At 2 sites per cell per axis that is every bin inside the box (4 sites in 2D, 8 in 3D) and,
/// in 3D, those on its faces (4).
struct BinnedSites<'r> {
    lo: [i64; 3],
    hi: [i64; 3],
    bins: Bins,
    span: RowSpan<'r>,
    /// The rows of bins (x index 0; y and z the row's).
    rows: Sites,
    /// The bins of the current row still to visit.
    row: Sites,
    inner: Sites,
    /// Visiting the bins whose site count is a multiple of 4 (else the others).
    whole: bool,
}

impl<'r> BinnedSites<'r> {
    fn new(lo: [i64; 3], hi: [i64; 3], bins: Bins, span: RowSpan<'r>) -> Self {
        BinnedSites {
            lo,
            hi,
            bins,
            span,
            rows: Self::rows(lo, hi, bins),
            row: Sites::new([0; 3], [-1; 3]),
            inner: Sites::new([0; 3], [-1; 3]),
            whole: true,
        }
    }

    /// The rows of the bins the sites `[lo, hi]` fall into.
    fn rows(lo: [i64; 3], hi: [i64; 3], bins: Bins) -> Sites {
        Sites::new(
            [0, bins.of(lo[1]), bins.of(lo[2])],
            [0, bins.of(hi[1]), bins.of(hi[2])],
        )
    }

    /// The sites of bin `b` inside `[lo, hi]` (inclusive; empty on an axis where lo > hi).
    fn sites_of(&self, b: [i64; 3]) -> ([i64; 3], [i64; 3]) {
        let bins = self.bins;
        let from = core::array::from_fn(|a| self.lo[a].max(bins.first(b[a])));
        let to = core::array::from_fn(|a| self.hi[a].min(bins.first(b[a] + 1) - 1));
        (from, to)
    }
}

impl Iterator for BinnedSites<'_> {
    type Item = [i64; 3];
    fn next(&mut self) -> Option<[i64; 3]> {
        loop {
            if let Some(k) = self.inner.next() {
                return Some(k);
            }
            if let Some(b) = self.row.next() {
                let (from, to) = self.sites_of(b);
                let count: i64 = (0..3).map(|a| (to[a] - from[a] + 1).max(0)).product();
                if (count % 4 == 0) == self.whole {
                    self.inner = Sites::new(from, to);
                }
                continue;
            }
            let Some(r) = self.rows.next() else {
                if !self.whole {
                    return None;
                }
                // Then the bins of the other kind.
                self.whole = false;
                self.rows = Self::rows(self.lo, self.hi, self.bins);
                continue;
            };
            // The row's sites in y and z, and the region's x span over them, in bins.
            let (from, to) = self.sites_of(r);
            let [x0, x1] = (self.span)([from[1], to[1]], [from[2], to[2]]);
            let (x0, x1) = (x0.max(self.lo[0]), x1.min(self.hi[0]));
            self.row = if x0 > x1 {
                Sites::new([0; 3], [-1; 3])
            } else {
                Sites::new(
                    [self.bins.of(x0), r[1], r[2]],
                    [self.bins.of(x1), r[1], r[2]],
                )
            };
        }
    }
}

/// The largest `|v|^2` of the active particles (`status`'s length; `v[a]` at least as long for
/// `a < d`), in f64: a speed near f32's range (1e19 m/s and up) would overflow `v^2` in f32 and
/// make the stable step 0, which no step could take, although the true step is representable.
/// Lane-wise maxima over chunks of 8 particles (loops the compiler vectorises), then the tail:
/// the same maximum as a particle-by-particle scan. Run in the step's instruction set
/// (`phases::isa`).
#[inline(always)]
pub(crate) fn fastest_squared(v: &[&[Real]; 3], status: &[u32], d: usize) -> f64 {
    let n = status.len();
    const L: usize = 8;
    let mut lanes = [0.0f64; L];
    let full = n - n % L;
    for from in (0..full).step_by(L) {
        let mut v2 = [0.0f64; L];
        for va in v.iter().take(d) {
            let va: &[Real; L] = va[from..from + L].try_into().unwrap_or(&[0.0; L]);
            for l in 0..L {
                v2[l] += va[l] as f64 * va[l] as f64;
            }
        }
        let st: &[u32; L] = status[from..from + L].try_into().unwrap_or(&[0; L]);
        for l in 0..L {
            lanes[l] = if st[l] == ACTIVE && v2[l] > lanes[l] {
                v2[l]
            } else {
                lanes[l]
            };
        }
    }
    let mut v2_max = lanes.iter().fold(0.0f64, |m, &x| m.max(x));
    for i in full..n {
        let v2: f64 = v.iter().take(d).map(|va| va[i] as f64 * va[i] as f64).sum();
        if status[i] == ACTIVE && v2 > v2_max {
            v2_max = v2;
        }
    }
    v2_max
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::shape::{first_node, CpGimp, CubicBspline, Gimp, Linear, QuadraticBspline, Shape1D};
    use crate::{HeapBuffer, MaterialDef};
    use std::vec::Vec;

    /// A small deterministic generator in `[0, 1)`.
    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// `open` checks the header's state and the tables as well as the particles: each edit
    /// of a snapshot that no call produces is `InvalidState` (a particle count raised over
    /// empty slots, a time, minimum mass or thermostat alpha out of range, a material record
    /// that is not what `add_material` makes of its definition, a traction naming no particle
    /// or face, or not finite), and the bytes stay as they were; the intact snapshot opens.
    #[cfg(feature = "effects")]
    #[test]
    fn open_refuses_damaged_header_state_and_tables() {
        use crate::{Damping, Effects, Face, Feedback, Schedule};
        let def = WorldDef {
            cells: [16, 16, 1],
            cell_size: 0.1,
            particle_capacity: 512,
            effects: Effects {
                damping: Some(Damping {
                    feedback: Some(Feedback {
                        gain: 1.0,
                        target: Schedule::ZERO,
                        max_alpha: 10.0,
                    }),
                    ..Damping::NONE
                }),
                traction_capacity: 8,
                ..Effects::NONE
            },
            ..WorldDef::DEFAULT
        };
        let layout = Layout::of(&def);
        let mut buf = HeapBuffer::new(crate::memory_requirements(&def).unwrap().bytes);
        let mut w = World::init(&def, buf.as_mut_bytes()).unwrap();
        let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
        w.fill_box(
            Vec3::new(0.4, 0.4, 0.0),
            Vec3::new(0.8, 0.8, 0.0),
            m,
            Vec3::ZERO,
        )
        .unwrap();
        w.add_tractions(0..2, Face::XMax, Vec3::new(1.0, 0.0, 0.0))
            .unwrap();
        let snapshot = w.as_bytes().to_vec();
        type Edit = fn(&mut Header, &mut MaterialRecord, &mut TractionRecord);
        let edits: [(&str, Edit); 15] = [
            ("count over empty slots", |h, _, _| h.particle_count += 30),
            ("time NaN", |h, _, _| h.time = f64::NAN),
            ("time negative", |h, _, _| h.time = -1.0),
            ("min mass NaN", |h, _, _| h.min_particle_mass = f64::NAN),
            ("min mass negative", |h, _, _| h.min_particle_mass = -1.0),
            ("min mass not the least", |h, _, _| {
                h.min_particle_mass *= 0.5
            }),
            ("alpha NaN", |h, _, _| h.feedback_alpha = f64::NAN),
            ("alpha negative", |h, _, _| h.feedback_alpha = -1.0),
            ("alpha over its bound", |h, _, _| h.feedback_alpha = 11.0),
            ("modulus NaN", |_, r, _| r.youngs_modulus = Real::NAN),
            ("Lame parameter edited", |_, r, _| r.lambda *= 2.0),
            ("unknown model", |_, r, _| r.model = 7.0),
            ("traction of no particle", |_, _, t| t.particle = 999),
            ("traction on a 3D face", |_, _, t| {
                t.face = Face::ZMax as u32
            }),
            ("traction NaN", |_, _, t| t.traction[1] = Real::NAN),
        ];
        let mut copy = HeapBuffer::new(snapshot.len());
        for (what, edit) in edits {
            let mem = copy.as_mut_bytes();
            mem.copy_from_slice(&snapshot);
            let (head, rest) = mem.split_at_mut(layout.materials_offset);
            let h: &mut Header = bytemuck::from_bytes_mut(&mut head[..size_of::<Header>()]);
            let (mat, rest) = rest.split_at_mut(size_of::<MaterialRecord>());
            let r: &mut MaterialRecord = bytemuck::from_bytes_mut(mat);
            let at =
                layout.tractions_offset - layout.materials_offset - size_of::<MaterialRecord>();
            let t: &mut TractionRecord =
                bytemuck::from_bytes_mut(&mut rest[at..at + size_of::<TractionRecord>()]);
            edit(h, r, t);
            let before = mem.to_vec();
            assert_eq!(World::open(mem).err(), Some(Error::InvalidState), "{what}");
            assert!(
                *mem == before[..],
                "{what}: the refused open changed the bytes"
            );
        }
        copy.as_mut_bytes().copy_from_slice(&snapshot);
        assert!(World::open(copy.as_mut_bytes()).is_ok());
    }

    /// The bin order visits exactly the sites of the plain lattice order, each once, for boxes
    /// anywhere (negative indices included), every bin width and shift.
    #[test]
    fn binned_sites_are_a_permutation_of_the_lattice() {
        let mut state = 7;
        for n in 1..=4 {
            for shift_halves in [0, 1] {
                let bins = Bins { n, shift_halves };
                for _ in 0..200 {
                    let mut lo = [0i64; 3];
                    let mut hi = [0i64; 3];
                    for a in 0..3 {
                        lo[a] = (lcg(&mut state) * 30.0) as i64 - 15;
                        hi[a] = lo[a] + (lcg(&mut state) * 9.0) as i64 - 1;
                    }
                    let mut plain: Vec<[i64; 3]> = Sites::new(lo, hi).collect();
                    let mut binned: Vec<[i64; 3]> =
                        BinnedSites::new(lo, hi, bins, &|_, _| [i64::MIN, i64::MAX]).collect();
                    plain.sort_unstable();
                    binned.sort_unstable();
                    assert_eq!(plain, binned, "n {n}, shift {shift_halves}, {lo:?}..{hi:?}");
                }
            }
        }
    }

    /// The particles a fill seeds come in runs that share their stencil's first node, one run
    /// per first node (what the scatter's run sums rely on), the runs of a multiple of 4
    /// first and each on a 4-lane block (what the gathers' shared row reads rely on), for
    /// every shape, 2D and 3D, 1 to 4 particles per cell per axis and boxes at random places.
    /// The first node is the one the step computes ([`first_node`] with the shape's own shift
    /// and lead).
    #[test]
    fn filled_particles_come_in_one_run_per_first_node() {
        fn check<const K: usize, S: Shape1D<K>>(shape: ShapeFunction) {
            let mut state = 11;
            for dim in [Dimension::Plane2D, Dimension::ThreeD] {
                for ppc in 1..=4u32 {
                    let cells = 12u32;
                    let def = WorldDef {
                        dimension: dim,
                        cells: if dim == Dimension::ThreeD {
                            [cells; 3]
                        } else {
                            [cells, cells, 1]
                        },
                        cell_size: 0.5,
                        origin: Vec3::new(-1.25, 0.75, -2.0),
                        shape,
                        particles_per_cell: ppc,
                        particle_capacity: 20_000,
                        ..WorldDef::DEFAULT
                    };
                    let d = def.axes();
                    let h = def.cell_size;
                    let mut buf = HeapBuffer::new(crate::memory_requirements(&def).unwrap().bytes);
                    for _ in 0..6 {
                        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
                        let mat = world.add_material(&MaterialDef::DEFAULT).unwrap();
                        // A box within the cells 2..10 of each axis (inside every margin).
                        let corner = |t: f64| 2.0 + 8.0 * t;
                        let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
                        for a in 0..3 {
                            let (p, q) = (corner(lcg(&mut state)), corner(lcg(&mut state)));
                            lo[a] = def.origin[a] + h * p.min(q) as Real;
                            hi[a] = def.origin[a] + h * p.max(q) as Real;
                        }
                        let filled = world
                            .fill_box(Vec3::from(lo), Vec3::from(hi), mat, Vec3::ZERO)
                            .unwrap();
                        let v = world.particles();
                        let key = |i: usize| -> [i32; 3] {
                            core::array::from_fn(|a| {
                                if a < d {
                                    let s = (v.position[a][i] - def.origin[a]) / h;
                                    first_node::<K, S>(s, cells as usize + 1)
                                } else {
                                    0
                                }
                            })
                        };
                        let keys: Vec<[i32; 3]> = (filled.start as usize..filled.end as usize)
                            .map(key)
                            .collect();
                        let runs = 1 + keys.windows(2).filter(|w| w[0] != w[1]).count();
                        let mut distinct = keys.clone();
                        distinct.sort_unstable();
                        distinct.dedup();
                        if !keys.is_empty() {
                            assert_eq!(
                                runs,
                                distinct.len(),
                                "{shape:?} {dim:?} ppc {ppc}: a first node in two runs"
                            );
                        }
                        // The runs of a multiple of 4 particles come first, each starting a
                        // multiple of 4 particles after the fill's first.
                        let mut start = 0;
                        let mut others = false;
                        for (i, w) in keys.iter().enumerate() {
                            if i + 1 == keys.len() || keys[i + 1] != *w {
                                let len = i + 1 - start;
                                if len % 4 == 0 {
                                    assert!(
                                        !others && start % 4 == 0,
                                        "{shape:?} {dim:?} ppc {ppc}: a run of {len} at {start}"
                                    );
                                } else {
                                    others = true;
                                }
                                start = i + 1;
                            }
                        }
                    }
                }
            }
        }
        check::<2, Linear>(ShapeFunction::Linear);
        check::<3, Gimp>(ShapeFunction::Gimp);
        check::<3, QuadraticBspline>(ShapeFunction::QuadraticBspline);
        check::<4, CubicBspline>(ShapeFunction::CubicBspline);
        check::<3, CpGimp>(ShapeFunction::CpGimp);
    }
}
