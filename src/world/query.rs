//! Reading a world in place: [`WorldRef`] and its queries (the stable time step, the particle
//! view, the diagnostics), on a shared borrow of the bytes; the checks that open one are in
//! `open.rs`.

use super::{Diagnostics, ParticlesView};
use crate::def::{MaterialDef, ShapeFunction, WorldDef};
use crate::grid::Geom;
use crate::layout::{
    col, ColliderImpulse, ColliderRecord, Header, Layout, MaterialRecord, TractionRecord,
};
use crate::material::{
    eigenstrain_at, elastic_part, energy_density, explicit_diffusivity, hardens, model_of,
    particle_stress, wave_speed, Deformation,
};
use crate::particles::ACTIVE;
use crate::shape::{domain_stretch, Shape1D, Stencils};
use crate::simd::Simd;
use crate::{Error, Real};
use core::mem::size_of;

/// A world read in place: every query of [`World`](super::World) that changes nothing, on a
/// shared borrow of its bytes (from [`World::read`](super::World::read), or
/// [`WorldRef::open`] on memory only lent for reading,
/// such as a snapshot or a world other threads read at the same time).
#[derive(Clone, Copy)]
pub struct WorldRef<'a> {
    pub(super) buf: &'a [u8],
}

impl<'a> WorldRef<'a> {
    pub(super) fn header(&self) -> &'a Header {
        bytemuck::from_bytes(&self.buf[..size_of::<Header>()])
    }

    /// The world's definition.
    pub fn def(&self) -> WorldDef {
        // The header was written by init or checked by open, so it always decodes.
        self.header().def().unwrap_or(WorldDef::DEFAULT)
    }

    pub(super) fn layout(&self) -> Layout {
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

    /// Number of `step` calls that succeeded (it stays at `u64::MAX` once there: it does not
    /// wrap).
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
    /// ([`World::open`](super::World::open)) as a world that steps as this one does.
    pub fn state_bytes(&self) -> &'a [u8] {
        &self.buf[..self.layout().grid_offset]
    }

    /// The material table's records of the materials added, found from the header alone.
    pub(super) fn materials(&self) -> &'a [MaterialRecord] {
        let n = self.material_count();
        let start = self.header().tables().materials;
        bytemuck::cast_slice(&self.buf[start..start + n * size_of::<MaterialRecord>()])
    }

    /// The material records of the materials added.
    pub(super) fn material_records(&self) -> &'a [MaterialRecord] {
        self.materials()
    }

    pub(super) fn real_col(&self, layout: &Layout, j: usize, count: usize) -> &'a [Real] {
        bytemuck::cast_slice(&self.buf[layout.real_col(j, count)])
    }

    pub(super) fn u32_col(&self, layout: &Layout, j: usize, count: usize) -> &'a [u32] {
        bytemuck::cast_slice(&self.buf[layout.u32_col(j, count)])
    }

    /// Number of colliders added ([`World::add_collider`](super::World::add_collider)).
    pub fn collider_count(&self) -> usize {
        self.header().collider_count as usize
    }

    /// Collider `id`'s record and impulse, found from the header alone (a per-item query
    /// costs what it reads: no definition decoded, no layout computed);
    /// [`Error::UnknownCollider`] for an id not added.
    fn collider_record(&self, id: u32) -> Result<(&'a ColliderRecord, &'a ColliderImpulse), Error> {
        let h = self.header();
        if id as u64 >= h.collider_count {
            return Err(Error::UnknownCollider);
        }
        let (tables, id) = (h.tables(), id as usize);
        let at = tables.colliders + id * size_of::<ColliderRecord>();
        let record = bytemuck::from_bytes(&self.buf[at..at + size_of::<ColliderRecord>()]);
        let at = tables.impulses + id * size_of::<ColliderImpulse>();
        let impulse = bytemuck::from_bytes(&self.buf[at..at + size_of::<ColliderImpulse>()]);
        Ok((record, impulse))
    }

    /// Collider `id` as it is now and what the material put on it over the last step
    /// ([`crate::ColliderState`]); [`Error::UnknownCollider`] for an id not added. In 2D its
    /// position's and velocity's z and its angular velocity's x and y are 0 (they are not
    /// read: [`crate::ColliderDef::position`]).
    pub fn collider(&self, id: u32) -> Result<crate::ColliderState, Error> {
        let (r, i) = self.collider_record(id)?;
        let v = |a: [f64; 3]| crate::Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
        Ok(crate::ColliderState {
            def: r.def().ok_or(Error::InvalidState)?,
            impulse: v(i.linear),
            angular_impulse: v(i.angular),
            duration: i.duration as Real,
        })
    }

    /// The signed distance from collider `id`'s surface at `x` (negative inside), m, in its
    /// pose of now: what the step tests each node with (E91), distance fields too
    /// ([`crate::ColliderDef::distance`] needs no world but cannot read a field's samples).
    /// In 2D `x`'s z is not read: the distance is the one in the plane z = 0, where the
    /// step's nodes lie. Costs the distance and the collider's pose, read from the header and
    /// the record alone.
    pub fn collider_distance(&self, id: u32, x: crate::Vec3) -> Result<Real, Error> {
        let c = self.collider_now(id)?;
        let z = if self.header().planar() { 0.0 } else { x.z };
        Ok(c.distance([x.x, x.y, z]).0)
    }

    /// Collider `id` in its pose of now, as the step meets it, found from the header alone.
    pub(super) fn collider_now(
        &self,
        id: u32,
    ) -> Result<crate::boundary::colliders::Collider<'a>, Error> {
        let (r, _) = self.collider_record(id)?;
        self.collider_at(id, r.pose_time)
    }

    /// Collider `id` posed at world time `t` (E90).
    pub(crate) fn collider_at(
        &self,
        id: u32,
        t: f64,
    ) -> Result<crate::boundary::colliders::Collider<'a>, Error> {
        let (r, _) = self.collider_record(id)?;
        let h = self.header();
        let at = h.tables().sdf;
        let samples: &[Real] =
            bytemuck::cast_slice(&self.buf[at..at + h.sdf_count as usize * size_of::<Real>()]);
        crate::boundary::colliders::Collider::at(r, t, samples).ok_or(Error::InvalidState)
    }

    /// The box `(min, max)` (world axes, m) that holds collider `id`'s solid in its pose of
    /// now, as the step bounds the nodes it tests (E91); `None` for an unbounded solid (a
    /// half-space). For a host that draws the collider or seeds around it: the distance
    /// ([`WorldRef::collider_distance`]) is positive everywhere outside. In 2D the box's z is
    /// the plane's, 0. [`Error::UnknownCollider`] for an id not added.
    pub fn collider_bounds(&self, id: u32) -> Result<Option<(crate::Vec3, crate::Vec3)>, Error> {
        let c = self.collider_now(id)?;
        let planar = self.header().planar();
        let v = |a: [Real; 3]| crate::Vec3::new(a[0], a[1], if planar { 0.0 } else { a[2] });
        Ok(c.bounds().map(|(lo, hi)| (v(lo), v(hi))))
    }

    /// The definition of material `id` (its record found from the header alone).
    pub fn material(&self, id: u32) -> Option<MaterialDef> {
        self.materials().get(id as usize).map(|r| MaterialDef {
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
            viscosity: r.viscosity,
            bulk_viscosity: r.bulk_viscosity,
            volume_relaxation: r.volume_relaxation,
            bulk_modulus: r.bulk_modulus,
            pressure_exponent: r.pressure_exponent,
            yield_stress: r.yield_stress,
            hardening_modulus: r.hardening_modulus,
            friction_angle: r.friction_angle,
            friction_fit: crate::FrictionFit::from_code(r.friction_fit as u32)
                .unwrap_or(crate::FrictionFit::Compression),
            cohesion: r.cohesion,
            critical_compression: r.critical_compression,
            critical_stretch: r.critical_stretch,
            hardening_coefficient: r.hardening_coefficient,
        })
    }

    /// Largest stable time step `cfl h / (c_max + |v|_max)` (E88), s: `c_max` is the fastest
    /// dilatational wave speed of the materials, `|v|_max` the fastest active particle; shorter
    /// where damping (`alpha dt <= cfl`, the thermostat's alpha excepted: it is clamped to what
    /// the substep allows), conduction or diffusion (`dt <= h^2 / (2 d kappa)`) need it.
    /// Infinite when nothing moves and there is no material. Never raised to a floor: what a
    /// world accepts keeps it at least [`crate::MIN_STABLE_DT`] / 2 (see
    /// [`crate::Resolvable`]).
    pub fn stable_dt(&self) -> Real {
        self.stable_dt_with_simd(Simd::Detect)
    }

    /// [`WorldRef::stable_dt`], its scan of the particles run in the instruction set `simd`.
    pub(crate) fn stable_dt_with_simd(&self, simd: Simd) -> Real {
        let scan = super::passes::Scan {
            tasks: &crate::tasks::Serial,
            workers: 1,
        };
        self.time_step_limits(simd, &scan).stable_dt
    }

    /// The stable time step and the damping besides the thermostat that it allows for, the
    /// particles scanned on `scan`'s task system.
    pub(super) fn time_step_limits(
        &self,
        simd: Simd,
        scan: &super::passes::Scan<'_>,
    ) -> TimeStepLimits {
        let layout = self.layout();
        let def = self.def();
        let n = self.particle_count();
        let d = layout.d;
        let status = self.u32_col(&layout, col::STATUS, n);
        let materials = self.materials();
        let mut c_max = materials
            .iter()
            .fold(0.0 as Real, |c, r| c.max(r.wave_speed));
        // A model that hardens (snow) stiffens with its plastic history: the most hardened
        // active particle may be the fastest. Its wave speed falls as the history grows
        // (`Model::wave_speed`), so a material's fastest particle is the one with the least
        // history: one vectorised scan per material that hardens, one wave speed each.
        if layout.plastic.count > 0 {
            let plastic = self.real_col(&layout, layout.plastic.first, n);
            let material = self.u32_col(&layout, col::MATERIAL, n);
            for (m, r) in materials.iter().enumerate() {
                if hardens(r) {
                    let least = super::passes::least_plastic(
                        simd,
                        scan,
                        plastic,
                        material,
                        &status[..n],
                        m as u32,
                    );
                    // None active: an infinite history, a wave speed of 0.
                    c_max = c_max.max(wave_speed(r, least) as Real);
                }
            }
        }
        let v: [&[Real]; 3] = core::array::from_fn(|a| {
            if a < d {
                self.real_col(&layout, col::v(d, a), n)
            } else {
                &[]
            }
        });
        let v2_max = super::passes::fastest_squared(simd, scan, &v, &status[..n], d);
        let speed = c_max as f64 + libm::sqrt(v2_max);
        // Damping is integrated explicitly, `v (1 - alpha dt)`: the step keeps `alpha dt` at
        // most the Courant number, with alpha the largest damping any particle can see (the
        // schedules' maxima, the largest local values). The thermostat's alpha is not among
        // them: the step clamps it to the room this leaves (`World::update_feedback`).
        let other_damping = def.effects.damping.map_or(0.0, |dm| {
            let local = |k: usize| view_max(self.particles().damping[k], status);
            dm.definition_rate() + local(0) + local(1)
        });
        // Conduction, diffusion and viscosity are explicit too: `dt <= h^2 / (2 d kappa)`.
        let kappa = materials
            .iter()
            .fold(0.0f64, |m, r| m.max(explicit_diffusivity(r, &def)));
        let h = def.cell_size as f64;
        let conduction = h * h / (2.0 * d as f64 * kappa);
        // Not clamped: a longer step than this would not be stable. What a world accepts
        // (materials, rates, particle speeds, each within `Resolvable`) keeps it at least
        // MIN_STABLE_DT / 2; only a particle speed no stable step produces takes it lower,
        // to 0 past the smallest Real (a step that `step` refuses).
        let dt = def.cfl as f64 * (h / speed).min(1.0 / other_damping).min(conduction);
        let stable_dt = if dt.is_finite() {
            dt as Real
        } else {
            Real::INFINITY
        };
        TimeStepLimits {
            stable_dt,
            other_damping,
        }
    }

    /// The longest substep of a step of `dt` in which no collider that may touch the material
    /// moves its surface more than `cfl` cells (E88): `cfl h / s`, `s = |v| + |omega| r` its
    /// fastest surface speed, `r` the farthest its solid lies from its origin within reach of
    /// the particles (their box, widened by the two cells a stencil reaches and by how far
    /// the solid travels in the step); infinite where none may touch. A solid moved faster
    /// than the grid resolves would tear through the material without a word.
    pub(super) fn collider_substep(&self, dt: Real) -> Real {
        use crate::boundary::colliders::Collider;
        let count = self.header().collider_count as usize;
        if count == 0 {
            return Real::INFINITY;
        }
        let (layout, def) = (self.layout(), self.def());
        let at = layout.colliders_offset;
        let colliders: &[ColliderRecord] =
            bytemuck::cast_slice(&self.buf[at..at + count * size_of::<ColliderRecord>()]);
        let at = layout.sdf_offset;
        let samples: &[Real] = bytemuck::cast_slice(
            &self.buf[at..at + self.header().sdf_count as usize * size_of::<Real>()],
        );
        let (n, d, h) = (self.particle_count(), layout.d, def.cell_size as f64);
        let status = self.u32_col(&layout, col::STATUS, n);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for a in 0..d {
            let x = self.real_col(&layout, col::x(a), n);
            for (&x, _) in x.iter().zip(status).filter(|(_, &s)| s == ACTIVE) {
                lo[a] = lo[a].min(x as f64);
                hi[a] = hi[a].max(x as f64);
            }
        }
        let mut speed = 0.0f64;
        for r in colliders {
            let Some(c) = Collider::at(r, self.time(), samples) else {
                continue;
            };
            let norm = |v: [f64; 3]| libm::sqrt(v.iter().map(|c| c * c).sum::<f64>());
            let (v, omega) = (norm(r.velocity), norm(r.angular_velocity));
            let reach = 2.0 * h + (v + omega * norm(r.size)) * dt as f64;
            // The part of the particles' box the solid may reach, and its farthest corner.
            let (mut near_lo, mut near_hi) = ([0.0; 3], [0.0; 3]);
            let mut touches = true;
            for a in 0..d {
                let (mut l, mut u) = (lo[a] - reach, hi[a] + reach);
                if let Some((min, max)) = c.bounds() {
                    l = l.max(min[a] as f64 - reach);
                    u = u.min(max[a] as f64 + reach);
                }
                touches &= l <= u;
                (near_lo[a], near_hi[a]) = (l, u);
            }
            if !touches {
                continue;
            }
            let far: [f64; 3] = core::array::from_fn(|a| {
                let centre = c.centre[a] as f64;
                (near_lo[a] - centre).abs().max((near_hi[a] - centre).abs())
            });
            speed = speed.max(v + omega * norm(far));
        }
        let dt = def.cfl as f64 * h / speed;
        if dt.is_finite() {
            dt as Real
        } else {
            Real::INFINITY
        }
    }

    /// Whether some material stiffens with its plastic history (snow with `xi > 0`), so that
    /// its wave speed can outgrow a substep chosen before.
    pub(super) fn materials_harden(&self) -> bool {
        self.materials().iter().any(hardens)
    }

    /// Whether particle `i` is active, of a material that hardens, with a hardened wave speed
    /// above `limit` (m/s).
    pub(super) fn hardened_past(&self, layout: &Layout, i: usize, limit: f64) -> bool {
        let n = self.particle_count();
        if layout.plastic.count == 0 || self.u32_col(layout, col::STATUS, n)[i] != ACTIVE {
            return false;
        }
        let id = self.u32_col(layout, col::MATERIAL, n)[i] as usize;
        let plastic = self.real_col(layout, layout.plastic.first, n)[i];
        self.materials().get(id).is_some_and(|r| {
            let c = wave_speed(r, plastic);
            hardens(r) && (c.is_nan() || c > limit)
        })
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
            position_low: core::array::from_fn(|a| if a < d { r(col::x_low(d, a)) } else { empty }),
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
            temperature_source: group(layout.scalar[0], 2),
            concentration_source: group(layout.scalar[1], 2),
            hoop: group(layout.hoop, 0),
            plastic: group(layout.plastic, 0),
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

    /// Kinetic energy (J) and mass (kg) of the active particles, in f64; with APIC and MLS-MPM
    /// the energy includes the particles' affine velocity fields, as
    /// [`Diagnostics::kinetic`] does.
    pub(crate) fn kinetic_energy_and_mass(&self) -> (f64, f64) {
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
        let def = self.def();
        if def.transfer.is_affine() {
            kinetic += self.affine_kinetic(&def);
        }
        (kinetic, mass)
    }

    /// The thermostat's current alpha, 1/s (0 without one).
    pub fn feedback_alpha(&self) -> f64 {
        self.header().feedback_alpha
    }

    /// Number of tractions the world holds (added and not removed). Their ids run below
    /// the table's length, the removed ones' ids among them ([`crate::World::remove_tractions`]).
    pub fn traction_count(&self) -> usize {
        self.traction_records()
            .iter()
            .filter(|r| !r.is_removed())
            .count()
    }

    /// The traction table's entries in use, removed ones among them.
    pub(crate) fn traction_records(&self) -> &'a [TractionRecord] {
        let layout = Layout::of(&self.def());
        let start = layout.tractions_offset;
        let bytes = self.header().traction_count as usize * size_of::<TractionRecord>();
        bytemuck::cast_slice(&self.buf[start..start + bytes])
    }

    /// Mass, momentum, centre of mass and energies of the active particles.
    pub fn diagnostics(&self) -> Diagnostics {
        self.diagnostics_with_tasks(&crate::tasks::Serial)
    }

    /// [`WorldRef::diagnostics`] on a task system: the sums over fixed blocks of particles
    /// (none more than 64, each a multiple of 4096 particles, whatever the workers), added in
    /// block order, so the result is the same for any task system.
    pub fn diagnostics_with_tasks(&self, tasks: &dyn crate::tasks::TaskSystem) -> Diagnostics {
        let def = self.def();
        let n = self.particles().count;
        let zero = Sums::default();
        let block = |r: core::ops::Range<usize>| self.sums(&def, r);
        let cut = (n, crate::tasks::MAX_PARTS, 4096);
        let sums = crate::tasks::reduce(tasks, cut, zero, &block, Sums::add);
        let mut out = sums.d;
        if out.mass > 0.0 {
            for a in 0..3 {
                out.center_of_mass[a] = sums.first_moment[a] / out.mass;
            }
        }
        if def.transfer.is_affine() {
            out.kinetic += self.affine_kinetic(&def);
        }
        out
    }

    /// The sums of [`WorldRef::diagnostics`] over the particles `range`.
    fn sums(&self, def: &WorldDef, range: core::ops::Range<usize>) -> Sums {
        let materials = self.materials();
        let view = self.particles();
        let d = def.axes();
        let mut out = Sums::default();
        for i in range {
            if view.status[i] != ACTIVE {
                continue;
            }
            let m = view.mass[i] as f64;
            out.d.mass += m;
            let mut x = [0.0f64; 3];
            let mut v = [0.0f64; 3];
            for a in 0..d {
                v[a] = view.velocity[a][i] as f64;
                x[a] = view.position[a][i] as f64;
                out.d.momentum[a] += m * v[a];
                out.d.kinetic += 0.5 * m * v[a] * v[a];
                out.first_moment[a] += m * x[a];
                out.d.potential -= m * def.gravity[a] as f64 * x[a];
            }
            // L = x x m v, plus m eps_abc B_cb with APIC.
            let mut l = [
                m * (x[1] * v[2] - x[2] * v[1]),
                m * (x[2] * v[0] - x[0] * v[2]),
                m * (x[0] * v[1] - x[1] * v[0]),
            ];
            if def.transfer.is_affine() {
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
                out.d.angular_momentum[a] += l[a];
            }
            if let Some(rec) = materials.get(view.material[i] as usize) {
                // The elastic part's energy, per volume of the eigenstrained (stress-free)
                // configuration, (1 + d)^3 V0.
                let eig = eigenstrain_of(rec, &view, i);
                let (w, scale) = if d == 3 {
                    let (f, k) = elastic_part(&view.deformation::<3>(i), eig);
                    (energy_density(rec, &f), k)
                } else {
                    let (f, k) = elastic_part(&view.deformation::<2>(i), eig);
                    (energy_density(rec, &f), k)
                };
                // An energy density past the largest Real (the step keeps stresses finite, not
                // energies: an eigenstrain near -1 leaves an elastic part whose energy
                // overflows in f32 though its scaled stress does not) counts as the largest
                // Real, so that the sum stays finite.
                let e = scale as f64 * w as f64;
                let e = if e.is_finite() { e } else { Real::MAX as f64 };
                out.d.strain += view.volume0[i] as f64 * e;
            }
        }
        out
    }

    /// The kinetic energy of the APIC (and MLS-MPM) particles' affine velocity fields:
    /// `sum_p m_p tr(C_p D_p C_p^T) / 2 = sum_p m_p tr(B_p D_p^-1 B_p^T) / 2`, with `D_p` (diagonal
    /// for tensor-product weights) from the stencil the next transfer takes, at the particle's
    /// position and (cpGIMP) with the domain its deformation gives. It is what the transfer
    /// carries to the grid beside `m_p v_p^2 / 2`: `sum_i S_ip m_p |v_p + C_p (x_i - x_p)|^2 /
    /// 2`, the moments summing to zero. Linear weights keep `C_p` itself (the gradient form).
    fn affine_kinetic(&self, def: &WorldDef) -> f64 {
        crate::shape::with_form!(def, shape => self.affine_kinetic_in::<D, K, _>(shape, def))
    }

    /// [`WorldRef::affine_kinetic`] with the dimension and shape function fixed.
    fn affine_kinetic_in<const D: usize, const K: usize, S: Shape1D<K>>(
        &self,
        shape: S,
        def: &WorldDef,
    ) -> f64 {
        let view = self.particles();
        let geom = Geom::<D>::new(def);
        let mut st = Stencils::<D, K, 4>::default();
        let mut kinetic = 0.0f64;
        for i in 0..view.count {
            if view.status[i] != ACTIVE {
                continue;
            }
            // One particle in every lane of a four-lane stencil set.
            let s: [[Real; 4]; D] =
                core::array::from_fn(|a| [(view.position[a][i] - geom.origin[a]) * geom.inv_h; 4]);
            let h = &view.displacement_gradient;
            let stretch = domain_stretch::<D>(|a, b| h[a][b][i]).map(|e| [e; 4]);
            let (nodes, stride) = (geom.nodes, geom.stride);
            st.compute(&shape, &s, Some(&stretch), nodes, stride, geom.inv_h, true);
            let m = view.mass[i] as f64;
            for c in 0..D {
                let inv_d = st.inverse_moments(c)[0] as f64;
                // C_p D_p with linear weights (D_p = 1 / inv_d, 0 on a node); B_p D_p^-1.
                let weight = match (S::GRADIENT_AFFINE, inv_d > 0.0) {
                    (true, true) => 1.0 / inv_d,
                    (true, false) => 0.0,
                    (false, _) => inv_d,
                };
                for a in 0..D {
                    let b = view.affine[a][c][i] as f64;
                    kinetic += 0.5 * m * b * b * weight;
                }
            }
        }
        kinetic
    }
}

/// The isotropic eigenstrain `d` of particle `i` of material `rec` (thermal expansion and
/// swelling, from the grid values at the particle; 0 for a field not declared), as the stress
/// update takes it out.
impl WorldRef<'_> {
    /// `tau / rho0` of particle `i` at the deformation `f`, with its material and the
    /// eigenstrain of its current temperature and concentration ([`particle_stress`]); `None`
    /// if its material is unknown or it would invert.
    pub(super) fn particle_stress<const D: usize>(
        &self,
        view: &ParticlesView<'_>,
        i: usize,
        f: &Deformation<D>,
    ) -> Option<[Real; 6]> {
        self.particle_stress_of(view, i, view.material[i], f)
    }

    /// [`WorldRef::particle_stress`] with material `material` in place of the particle's own.
    pub(super) fn particle_stress_of<const D: usize>(
        &self,
        view: &ParticlesView<'_>,
        i: usize,
        material: u32,
        f: &Deformation<D>,
    ) -> Option<[Real; 6]> {
        let rec = self.materials().get(material as usize)?;
        particle_stress(rec, f, eigenstrain_of(rec, view, i))
    }
}

fn eigenstrain_of(rec: &MaterialRecord, view: &ParticlesView<'_>, i: usize) -> Real {
    let at = |col: &[Real]| col.get(i).copied();
    eigenstrain_at(
        rec,
        [at(view.grid_temperature), at(view.grid_concentration)],
    )
}

/// What bounds a substep: [`WorldRef::stable_dt`], and the largest damping rate besides the
/// thermostat's that any particle can see (1/s), whose room the thermostat's alpha must stay
/// within.
pub(super) struct TimeStepLimits {
    pub(super) stable_dt: Real,
    pub(super) other_damping: f64,
}

/// Largest value of `col` over active particles (0 for an empty column).
fn view_max(col: &[Real], status: &[u32]) -> f64 {
    col.iter()
        .zip(status)
        .filter(|(_, &s)| s == ACTIVE)
        .fold(0.0f64, |m, (&v, _)| m.max(v as f64))
}

/// The sums a block of particles adds to [`Diagnostics`] (its centre of mass as the first
/// moment).
#[derive(Clone, Copy, Default)]
struct Sums {
    d: Diagnostics,
    first_moment: [f64; 3],
}

impl Sums {
    /// The sums of two blocks, `self`'s first.
    fn add(self, b: Sums) -> Sums {
        let (x, y) = (self.d, b.d);
        let v = |a: [f64; 3], b: [f64; 3]| core::array::from_fn(|k| a[k] + b[k]);
        Sums {
            d: Diagnostics {
                mass: x.mass + y.mass,
                momentum: v(x.momentum, y.momentum),
                angular_momentum: v(x.angular_momentum, y.angular_momentum),
                center_of_mass: [0.0; 3],
                kinetic: x.kinetic + y.kinetic,
                strain: x.strain + y.strain,
                potential: x.potential + y.potential,
            },
            first_moment: v(self.first_moment, b.first_moment),
        }
    }
}
