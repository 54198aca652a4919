//! The setters of the declared effects' per-particle data and state: particle forces and
//! tractions, per-particle damping rates and the thermostat's update, transported scalars and
//! their sources. The effects' declarations are [`crate::Effects`]; their terms in the step
//! [`crate::effects`].

use super::World;
use crate::boundary::colliders;
use crate::def::ScalarField;
use crate::def::{ColliderDef, Feedback};
use crate::layout::{ColliderImpulse, ColliderRecord, Layout, TractionRecord};
use crate::{Error, Real, Vec3};
use core::mem::size_of;
use core::ops::Range;

impl World<'_> {
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
            |_| Ok(()),
        )
    }
    /// Adds one traction per particle of `particles`, each loading the `face` of that
    /// particle's domain with the traction `traction` (Pa: force per area of the deformed face,
    /// per unit thickness in plane strain, per radian axisymmetric); returns the range of their
    /// traction ids. The face is the side of the undeformed square (cube) of side
    /// `2 l_p = h / n` around the particle, carried along by its deformation: what
    /// [`World::add_surface_tractions`] loads with the face's normal and area `(2 l_p)^(D-1)`.
    /// All or nothing. Needs [`crate::Effects::traction_capacity`]. The tractions are
    /// integrated each substep into `f_iT` (E15, E16) while their particle is active.
    pub fn add_tractions(
        &mut self,
        particles: Range<u32>,
        face: crate::Face,
        traction: Vec3,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let d = def.axes();
        if face as usize / 2 >= d {
            return Err(Error::InvalidEffect);
        }
        let mut normal = Vec3::ZERO;
        normal[face as usize / 2] = if (face as usize).is_multiple_of(2) {
            -1.0
        } else {
            1.0
        };
        let side = def.cell_size / def.particles_per_cell as Real;
        let area = (1..d).fold(1.0, |a, _| a * side);
        self.add_surface_tractions(particles, normal, area, traction)
    }

    /// Adds one traction per particle of `particles`, each loading a plane face of outward
    /// normal `normal` and area `area` (m^2; m per unit thickness in plane strain and
    /// axisymmetric, the length of the face's trace in the (r, z) plane), both in the
    /// reference configuration, with the traction `traction` (Pa, per area of the deformed
    /// face; per radian axisymmetric); returns the range of their traction ids. Any normal in
    /// the plane (2D; its z is ignored) or in space: a curved surface is loaded by giving each
    /// particle at it the local normal and its share of the surface's area.
    ///
    /// The face is centred where the normal leaves the particle's undeformed domain (the
    /// square of half-width `l_p` around it), is a segment (2D) or square (3D) across the
    /// normal, and moves and deforms with the particle's `F`. All or nothing;
    /// `InvalidEffect` for a normal of zero length or not finite, an area not positive and
    /// finite, or a traction not finite. Needs [`crate::Effects::traction_capacity`].
    pub fn add_surface_tractions(
        &mut self,
        particles: Range<u32>,
        normal: Vec3,
        area: Real,
        traction: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.add_face_loads(particles, normal, area, traction, false)
    }

    /// Adds one load per particle of `particles` on a face given as for
    /// [`World::add_surface_tractions`] (reference normal and area), that turns and stretches
    /// with the face: `load` is the traction (Pa, per area of the deformed face) along the
    /// face's current outward normal, then along its current tangents, so that a pressure `p`
    /// is `Vec3::new(-p, 0.0, 0.0)`: the force on an element `dA` of the reference face is
    /// `load_n n da + load_1 t1 da + load_2 t2 da` with `n da = J F^-T N dA` (Nanson). The
    /// tangents are the reference ones carried by `F`: in 2D `t1 = F (-N_y, N_x) / |..|`; in
    /// 3D `t1 = F T1 / |F T1|`, `T1 = N x e / |N x e|` with `e` the axis of `N`'s smallest
    /// component, and `t2 = n x t1`. Its id, schedule and removal are a traction's; the same
    /// errors as [`World::add_surface_tractions`].
    pub fn add_follower_tractions(
        &mut self,
        particles: Range<u32>,
        normal: Vec3,
        area: Real,
        load: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.add_face_loads(particles, normal, area, load, true)
    }

    /// The two adders' one path: `load` in the world's axes, or along the face (`follows`).
    fn add_face_loads(
        &mut self,
        particles: Range<u32>,
        normal: Vec3,
        area: Real,
        traction: Vec3,
        follows: bool,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        if layout.traction_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let d = layout.d;
        let finite = (0..d).all(|a| traction[a].is_finite() && normal[a].is_finite());
        let length = crate::math::sqrt((0..d).map(|a| normal[a] * normal[a]).sum());
        // A normal must have a length whose square is a normal float and that is finite.
        let normal_ok = length > 1.0e-15 && length.is_finite();
        if !(finite && normal_ok && area > 0.0 && area.is_finite()) {
            return Err(Error::InvalidEffect);
        }
        if particles.start > particles.end {
            return Err(Error::UnknownParticle);
        }
        let n = (particles.end - particles.start) as usize;
        self.particle_range(particles.start, n)?;
        let used = self.header().traction_count as usize;
        // The first run of `n` removed records, else the table's end.
        let records = self.read().traction_records();
        let start = used
            .checked_sub(n)
            .filter(|_| n > 0)
            .and_then(|last| {
                (0..=last).find(|&s| records[s..s + n].iter().all(TractionRecord::is_removed))
            })
            .unwrap_or(used);
        if start == used && n > layout.traction_capacity - used {
            return Err(Error::TractionCapacityExceeded);
        }
        let in_plane = |v: Vec3, a: usize| if a < d { v[a] } else { 0.0 };
        let record = TractionRecord {
            particle: 0,
            schedule: 0,
            traction: core::array::from_fn(|a| if a == 3 { area } else { in_plane(traction, a) }),
            normal: core::array::from_fn(|a| match a {
                3 if follows => TractionRecord::FOLLOWS,
                _ => in_plane(normal, a) / length,
            }),
        };
        let table = self.traction_records_mut(&layout, start, n);
        for (rec, particle) in table.iter_mut().zip(particles) {
            *rec = TractionRecord { particle, ..record };
        }
        let h = self.header_mut();
        h.traction_count = h.traction_count.max((start + n) as u64);
        Ok(start as u32..(start + n) as u32)
    }

    /// Makes the tractions `ids` (a range [`World::add_tractions`] returned, or any part of the
    /// table) follow the schedule `schedule` of [`crate::Effects::traction_schedules`] (new
    /// tractions follow the first). All or nothing: `UnknownTraction` if the range is not
    /// within the table or holds a removed id, `InvalidEffect` for a schedule past the list (nothing changes);
    /// `EffectNotDeclared` without [`crate::Effects::traction_capacity`].
    pub fn set_traction_schedule(&mut self, ids: Range<u32>, schedule: u32) -> Result<(), Error> {
        let (start, end, used) = self.traction_range(ids)?;
        if schedule as usize >= crate::TRACTION_SCHEDULES {
            return Err(Error::InvalidEffect);
        }
        let layout = Layout::of(&self.def());
        for rec in &mut self.traction_records_mut(&layout, 0, used)[start..end] {
            rec.schedule = schedule;
        }
        Ok(())
    }

    /// Removes every traction (the capacity stays).
    pub fn clear_tractions(&mut self) {
        self.header_mut().traction_count = 0;
    }

    /// Removes the tractions `ids` (a range [`World::add_tractions`] returned, or any part of
    /// the table), so that loads applied together can be taken off together. Every other id
    /// stays the traction it was; the removed ids' room is free again, for a later adder that
    /// fits it (or the capacity's end). `UnknownTraction` if the range is not within the
    /// table or holds an id already removed (nothing is removed); `EffectNotDeclared` without
    /// [`crate::Effects::traction_capacity`].
    pub fn remove_tractions(&mut self, ids: Range<u32>) -> Result<(), Error> {
        let (start, end, used) = self.traction_range(ids)?;
        let layout = Layout::of(&self.def());
        let records = self.traction_records_mut(&layout, 0, used);
        records[start..end].fill(TractionRecord::REMOVED);
        self.header_mut().traction_count = TractionRecord::end_of(records) as u64;
        Ok(())
    }

    /// `ids` as indices of the traction table, `(start, end, used)`, if it lies within the
    /// `used` entries and names no removed traction: `EffectNotDeclared` without
    /// [`crate::Effects::traction_capacity`], else `UnknownTraction`.
    fn traction_range(&self, ids: Range<u32>) -> Result<(usize, usize, usize), Error> {
        if self.def().effects.traction_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let records = self.read().traction_records();
        let (start, end) = (ids.start as usize, ids.end as usize);
        if start > end || end > records.len() {
            return Err(Error::UnknownTraction);
        }
        if records[start..end].iter().any(TractionRecord::is_removed) {
            return Err(Error::UnknownTraction);
        }
        Ok((start, end, records.len()))
    }
}

impl World<'_> {
    /// The thermostat (NairnMPM's feedback damping, E52): `alpha += 2 gain (KE - target) dt / M`,
    /// clamped to `[0, min(max_alpha, room)]`, from the active particles' kinetic energy and
    /// mass; `room` is the largest alpha the substep integrates stably. The stored alpha stays
    /// finite: a rate that is not a number (no finite energy to compare) leaves it as it was.
    pub(crate) fn update_feedback(&mut self, f: &Feedback, time: f64, dt: Real, room: f64) {
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

    /// Sets the local grid and particle damping `alpha_g(x_p)`, `alpha_p(x_p)` (1/s, >= 0) of
    /// particles `first..first + n`, added to the global damping for those particles (E53).
    /// Needs [`crate::Damping::per_particle`]. A rate the step cannot resolve (above half of
    /// what the definition's rates leave of [`crate::Resolvable::rate`]) is
    /// [`Error::StableStepTooShort`].
    pub fn set_particle_damping(
        &mut self,
        first: u32,
        alpha_g: &[Real],
        alpha_p: &[Real],
    ) -> Result<(), Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        let group = (layout.damping.count > 0).then_some(layout.damping.first);
        let limit = def
            .effects
            .damping
            .map_or(0.0, |d| d.particle_rate_limit(&def));
        let columns = &[alpha_g, alpha_p];
        self.write_particle_columns(&layout, group, first, columns, Error::InvalidEffect, |v| {
            if v < 0.0 {
                Err(Error::InvalidEffect)
            } else if v as f64 > limit {
                Err(Error::StableStepTooShort)
            } else {
                Ok(())
            }
        })
    }
}

impl World<'_> {
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
            |_| Ok(()),
        )
    }
}

/// Colliders (E90-E93).
impl World<'_> {
    /// Adds a collider ([`ColliderDef`]) and returns its id; its pose is the definition's
    /// now ([`World::time`]). Needs [`crate::Effects::collider_capacity`] (else
    /// [`Error::EffectNotDeclared`]); [`Error::InvalidEffect`] for a value not finite or out
    /// of range, [`Error::ColliderCapacityExceeded`] past the capacity. Nothing changes on
    /// failure. In 2D the position's and velocity's z and the angular velocity's x and y are
    /// not read (not checked, stored as 0), as no z of a 2D call is. [`World::open`] checks
    /// a stored collider as this checks a definition.
    pub fn add_collider(&mut self, c: &ColliderDef) -> Result<u32, Error> {
        let def = self.def();
        if def.effects.collider_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let id = self.header().collider_count as u32;
        if id >= def.effects.collider_capacity {
            return Err(Error::ColliderCapacityExceeded);
        }
        let record = self.collider_record(c)?;
        *self.collider_mut(id) = record;
        self.header_mut().collider_count += 1;
        Ok(id)
    }

    /// Adds the samples of a signed distance field (m, negative inside) to the world's and
    /// returns the index of the first: what a [`crate::ColliderShape::Sdf`] collider names.
    /// Needs [`crate::Effects::sdf_capacity`] (else [`Error::EffectNotDeclared`]);
    /// [`Error::NonFiniteInput`] for a sample not finite, [`Error::InvalidCapacity`] past the
    /// capacity (nothing is added).
    pub fn add_distance_field(&mut self, samples: &[Real]) -> Result<u32, Error> {
        let def = self.def();
        if def.effects.sdf_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let first = self.header().sdf_count as usize;
        let end = first
            .checked_add(samples.len())
            .filter(|&e| e <= def.effects.sdf_capacity as usize)
            .ok_or(Error::InvalidCapacity)?;
        if !samples.iter().all(|d| d.is_finite()) {
            return Err(Error::NonFiniteInput);
        }
        let at = Layout::of(&def).sdf_offset;
        let field: &mut [Real] = bytemuck::cast_slice_mut(
            &mut self.buf[at + first * size_of::<Real>()..at + end * size_of::<Real>()],
        );
        field.copy_from_slice(samples);
        self.header_mut().sdf_count = end as u64;
        Ok(first as u32)
    }

    /// Replaces collider `id`'s definition (its pose, velocities, shape, contact): a host
    /// that moves it sets it between steps, as [`World::add_collider`] checks it.
    /// [`Error::UnknownCollider`] for an id not added. The impulse of the last step stays.
    pub fn set_collider(&mut self, id: u32, c: &ColliderDef) -> Result<(), Error> {
        if id as u64 >= self.header().collider_count {
            return Err(Error::UnknownCollider);
        }
        let record = self.collider_record(c)?;
        *self.collider_mut(id) = record;
        Ok(())
    }

    /// Number of colliders added.
    pub fn collider_count(&self) -> usize {
        self.read().collider_count()
    }

    /// Collider `id` as it is now and what the material put on it over the last step
    /// ([`crate::WorldRef::collider`]).
    pub fn collider(&self, id: u32) -> Result<crate::ColliderState, Error> {
        self.read().collider(id)
    }

    /// The signed distance from collider `id`'s surface at `x`
    /// ([`crate::WorldRef::collider_distance`]).
    pub fn collider_distance(&self, id: u32, x: Vec3) -> Result<Real, Error> {
        self.read().collider_distance(id, x)
    }

    /// The box that holds collider `id`'s solid now ([`crate::WorldRef::collider_bounds`]).
    pub fn collider_bounds(&self, id: u32) -> Result<Option<(Vec3, Vec3)>, Error> {
        self.read().collider_bounds(id)
    }

    /// The record of `c`, posed now; in 2D the components a 2D world does not read stored as
    /// 0 ([`ColliderDef::read_components`]). The record is checked as [`World::open`] checks
    /// a stored one ([`ColliderRecord::is_valid`]: one check for both; here it adds that a
    /// distance field lies within the samples added).
    fn collider_record(&self, c: &ColliderDef) -> Result<ColliderRecord, Error> {
        let h = self.header();
        if !c.is_valid(h.planar()) {
            return Err(Error::InvalidEffect);
        }
        let record = c.record(h.planar(), h.time);
        if record.is_valid(h.sdf_count, h.planar(), h.time) {
            Ok(record)
        } else {
            Err(Error::InvalidEffect)
        }
    }

    fn collider_mut(&mut self, id: u32) -> &mut ColliderRecord {
        let at = self.header().tables().colliders + id as usize * size_of::<ColliderRecord>();
        bytemuck::from_bytes_mut(&mut self.buf[at..at + size_of::<ColliderRecord>()])
    }

    fn impulses_mut(&mut self) -> &mut [ColliderImpulse] {
        let n = self.header().collider_count as usize;
        let at = self.header().tables().impulses;
        bytemuck::cast_slice_mut(&mut self.buf[at..at + n * size_of::<ColliderImpulse>()])
    }

    /// At the start of a step of `dt`: the colliders' impulses back to zero.
    pub(super) fn start_collider_impulses(&mut self, dt: Real) {
        for i in self.impulses_mut() {
            *i = ColliderImpulse {
                duration: dt as f64,
                ..ColliderImpulse::default()
            };
        }
    }

    /// After a substep that ends at world time `end`, the colliders posed there: each active
    /// particle whose centre lies inside a solid is put back out, moved along the surface's
    /// normal to a thousandth of a cell outside it, its velocity kept (E91). The contact holds
    /// the nodes, not the particles: a particle that the grid's interpolation carried a little
    /// into the solid (its stencil reaches nodes inside, which carry no mass and no velocity)
    /// would otherwise stay there and build up. A move that would leave the admissible region
    /// is not made. Positions only: no momentum changes hands.
    pub(super) fn put_out_of_colliders(&mut self, end: f64) {
        let count = self.header().collider_count as u32;
        if count == 0 {
            return;
        }
        let def = self.def();
        let (layout, geom) = (Layout::of(&def), super::GeomAny::new(&def));
        let (d, n, margin) = (layout.d, self.particle_count(), def.cell_size / 1024.0);
        for id in 0..count {
            // 64 particles at a time: where to move them, read from the world, then written.
            for from in (0..n).step_by(64) {
                let to = (from + 64).min(n);
                let mut moves = [(0usize, [0.0 as Real; 3]); 64];
                let mut k = 0;
                {
                    let w = self.read();
                    let Ok(c) = w.collider_at(id, end) else {
                        break;
                    };
                    let p = w.particles();
                    for i in from..to {
                        if p.status[i] != crate::particles::ACTIVE {
                            continue;
                        }
                        let x: [Real; 3] =
                            core::array::from_fn(|a| if a < d { p.position[a][i] } else { 0.0 });
                        if c.farther_than(x, 0.0) {
                            continue;
                        }
                        let (phi, normal) = c.distance(x);
                        if phi >= 0.0 || phi.is_nan() {
                            continue;
                        }
                        let out: [Real; 3] = core::array::from_fn(|a| {
                            if a < d {
                                x[a] + (margin - phi) * normal[a]
                            } else {
                                0.0
                            }
                        });
                        if geom.admits(out) {
                            moves[k] = (i, out);
                            k += 1;
                        }
                    }
                }
                for &(i, out) in &moves[..k] {
                    for (a, &x) in out.iter().enumerate().take(d) {
                        self.real_col_mut(&layout, crate::layout::col::x(a), n)[i] = x;
                        self.real_col_mut(&layout, crate::layout::col::x_low(d, a), n)[i] = 0.0;
                    }
                }
            }
        }
    }

    /// After a substep of `dt` that ends at world time `end`: each dynamic collider moved by
    /// what the material put on it and by `gravity` (E96, [`colliders::drive`]).
    pub(super) fn drive_colliders(&mut self, end: f64, dt: Real, gravity: Vec3) {
        let h = self.header();
        let (n, planar, tables) = (h.collider_count as usize, h.planar(), h.tables());
        let (head, rest) = self.buf.split_at_mut(tables.impulses);
        let records: &mut [ColliderRecord] = bytemuck::cast_slice_mut(
            &mut head[tables.colliders..tables.colliders + n * size_of::<ColliderRecord>()],
        );
        let sums: &mut [ColliderImpulse] =
            bytemuck::cast_slice_mut(&mut rest[..n * size_of::<ColliderImpulse>()]);
        let g = glam::DVec3::new(gravity.x as f64, gravity.y as f64, gravity.z as f64);
        for (r, sum) in records.iter_mut().zip(sums) {
            colliders::drive(r, sum, end, dt as f64, g, planar);
        }
    }

    /// At the end of a step, at world time `end`: each collider's pose moved on to then (E90).
    pub(super) fn move_colliders(&mut self, end: f64) {
        for id in 0..self.header().collider_count as u32 {
            let r = self.collider_mut(id);
            let (position, rotation) = colliders::pose_at(r, end);
            r.position = position.to_array();
            r.rotation = rotation.to_array();
            r.pose_time = end;
        }
    }
}
