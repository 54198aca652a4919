//! A particle's whole state in and out: [`World::add_particles_with_state`] and
//! [`World::set_particle_state`] write every column a world keeps of a particle, as given,
//! after the check of one particle's values that [`WorldRef::check_state`] (what
//! [`World::open`] runs on untrusted bytes) applies too: a state read from a world goes back
//! into it, or into another world with the same materials and declared effects, bit for bit.

use super::add::speed_resolvable;
use super::{GeomAny, ParticleState, World, WorldRef};
use crate::layout::{col, stress_components, ColumnGroup, Layout, MaterialRecord};
use crate::material::{history_in_range, wave_speed, Deformation};
use crate::particles::{ParticleStatus, ACTIVE};
use crate::{Error, Real};
use core::ops::Range;

/// More particle Real columns than any definition reserves (53 at most: 3D with MUSL,
/// cpGIMP, APIC and every effect), for the tables of columns a check reads.
pub(super) const MAX_COLUMNS: usize = 64;

/// The bounds every particle of a world keeps, checked one particle at a time: by
/// [`WorldRef::check_state`] on a world's particles, by the state setters on the values a
/// particle would have after them.
pub(super) struct ParticleRules<'w> {
    layout: Layout,
    geom: GeomAny,
    def: crate::WorldDef,
    records: &'w [MaterialRecord],
    /// The largest per-particle damping rate, 1/s ([`crate::Damping::particle_rate_limit`]).
    rate_limit: f64,
    /// The largest wave speed a step resolves, m/s ([`crate::Resolvable::speed`]).
    speed_limit: f64,
}

impl<'w> ParticleRules<'w> {
    pub(super) fn new(world: &WorldRef<'w>) -> Self {
        let def = world.def();
        ParticleRules {
            layout: Layout::of(&def),
            geom: GeomAny::new(&def),
            records: world.material_records(),
            rate_limit: def
                .effects
                .damping
                .map_or(0.0, |dm| dm.particle_rate_limit(&def)),
            speed_limit: def.resolvable().speed,
            def,
        }
    }

    /// Checks one particle whose value in particle Real column `j` is `value(j)`, of material
    /// `material` and status `status`: in this order, a finite position, velocity, mass and
    /// volume (`NonFiniteInput`), mass and volume > 0 (`NonPositiveMassOrVolume`), a speed a
    /// step resolves (`StableStepTooShort`), a known material (`UnknownMaterial`), a position
    /// the world holds: the grid less the shape's margin, or on a wall plane
    /// (`PositionOutsideDomain`); a known status, a finite low part of the position within
    /// one unit in the last place of the position (`InvalidState`, `NonFiniteInput`); a
    /// finite `H` with `J > 0`, a finite hoop stretch > -1, a finite stress, a finite plastic
    /// history in its model's range (`InvalidDeformation`) that, active, leaves a wave speed
    /// a step resolves (`StableStepTooShort`); finite forces, moment matrix, transported
    /// values and sources (`NonFiniteInput`); damping rates >= 0 (`InvalidEffect`) and
    /// within their bound (`StableStepTooShort`).
    pub(super) fn check(
        &self,
        value: impl Fn(usize) -> Real,
        material: u32,
        status: u32,
    ) -> Result<(), Error> {
        let l = &self.layout;
        let d = l.d;
        let axis = |j: fn(usize, usize) -> usize| -> [Real; 3] {
            core::array::from_fn(|a| if a < d { value(j(d, a)) } else { 0.0 })
        };
        let (x, v) = (axis(|_, a| col::x(a)), axis(col::v));
        let (mass, vol) = (value(col::mass(d)), value(col::vol0(d)));
        let finite = |c: &[Real]| c.iter().all(|v| v.is_finite());
        if !(finite(&x) && finite(&v) && mass.is_finite() && vol.is_finite()) {
            return Err(Error::NonFiniteInput);
        }
        if mass <= 0.0 || vol <= 0.0 {
            return Err(Error::NonPositiveMassOrVolume);
        }
        if !speed_resolvable(&self.def, v) {
            return Err(Error::StableStepTooShort);
        }
        let rec = self
            .records
            .get(material as usize)
            .ok_or(Error::UnknownMaterial)?;
        if !self.geom.holds(x) {
            return Err(Error::PositionOutsideDomain);
        }
        if ParticleStatus::from_code(status).is_none() {
            return Err(Error::InvalidState);
        }
        // The low part of the position is what the last rounding of `x` left out: at most one
        // unit in its last place (half of one where the step moved it less than its distance
        // from the origin).
        for (a, &xa) in x.iter().enumerate().take(d) {
            let (xa, low) = (xa.abs(), value(col::x_low(d, a)));
            if !low.is_finite() {
                return Err(Error::NonFiniteInput);
            }
            if low.abs() > xa.next_up() - xa {
                return Err(Error::InvalidState);
            }
        }
        let one = |g: ColumnGroup| (g.count > 0).then(|| value(g.first));
        let hoop = one(l.hoop);
        let h_finite = (0..d * d).all(|k| value(col::h(d, k / d, k % d)).is_finite());
        let hoop_ok = hoop.is_none_or(|z| z.is_finite() && z > -1.0);
        let jm1 = if d == 3 {
            Deformation::<3>::new(crate::num::matrix(|a, b| value(col::h(3, a, b))), 0.0).jm1
        } else {
            let h = crate::num::matrix(|a, b| value(col::h(2, a, b)));
            Deformation::<2>::new(h, hoop.unwrap_or(0.0)).jm1
        };
        let stress_ok = (0..stress_components(d)).all(|k| value(col::tau(d, k)).is_finite());
        if !(h_finite && hoop_ok && jm1 > -1.0 && stress_ok) {
            return Err(Error::InvalidDeformation);
        }
        if let Some(p) = one(l.plastic) {
            if !(p.is_finite() && history_in_range(rec, p)) {
                return Err(Error::InvalidDeformation);
            }
            if status == ACTIVE && wave_speed(rec, p) > self.speed_limit {
                return Err(Error::StableStepTooShort);
            }
        }
        let effects = [l.force, l.affine, l.scalar[0], l.scalar[1]];
        if !effects
            .iter()
            .flat_map(|g| g.first..g.first + g.count)
            .all(|j| value(j).is_finite())
        {
            return Err(Error::NonFiniteInput);
        }
        for j in l.damping.first..l.damping.first + l.damping.count {
            let rate = value(j);
            if !(rate.is_finite() && rate >= 0.0) {
                return Err(Error::InvalidEffect);
            }
            if rate as f64 > self.rate_limit {
                return Err(Error::StableStepTooShort);
            }
        }
        Ok(())
    }
}

/// A group of particle Real columns a [`ParticleState`] may give: the world's first column of
/// it (`None` when the definition does not reserve it), whether the world's dimension has it
/// at all, and the state's slices of it (the first `len` of `cols`), given whole or not at
/// all.
struct Group<'s> {
    first: Option<usize>,
    read: bool,
    cols: [&'s [Real]; 9],
    len: usize,
}

impl<'s> Group<'s> {
    fn new(first: Option<usize>, cols: &[&'s [Real]]) -> Self {
        let mut all: [&'s [Real]; 9] = [&[]; 9];
        all[..cols.len()].copy_from_slice(cols);
        Group {
            first,
            read: true,
            cols: all,
            len: cols.len(),
        }
    }

    fn given(&self) -> bool {
        self.read && self.cols[..self.len].iter().any(|c| !c.is_empty())
    }
}

/// The index in [`groups`] of the groups every particle added needs: its position, mass and
/// volume.
const POSITION: usize = 0;
const MASS: usize = 3;
const VOLUME: usize = 4;

/// The groups of Real columns of `s` in a world of layout `l` (position first, then mass and
/// volume at [`MASS`] and [`VOLUME`]).
fn groups<'s>(s: &ParticleState<'s>, l: &Layout) -> [Group<'s>; 18] {
    let d = l.d;
    let reserved = |g: ColumnGroup| (g.count > 0).then_some(g.first);
    let scalar = |f: usize, k: usize| (k < l.scalar[f].count).then_some(l.scalar[f].first + k);
    let matrix = |m: &[[&'s [Real]; 3]; 3]| -> [&'s [Real]; 9] {
        core::array::from_fn(|k| if k < d * d { m[k / d][k % d] } else { &[] })
    };
    let (h, affine) = (matrix(&s.displacement_gradient), matrix(&s.affine));
    let mut hoop = Group::new(reserved(l.hoop), &[s.hoop]);
    hoop.read = l.hoop.count > 0;
    [
        Group::new(Some(col::x(0)), &s.position[..d]),
        Group::new(Some(col::x_low(d, 0)), &s.position_low[..d]),
        Group::new(Some(col::v(d, 0)), &s.velocity[..d]),
        Group::new(Some(col::mass(d)), &[s.mass]),
        Group::new(Some(col::vol0(d)), &[s.volume0]),
        Group::new(Some(col::h(d, 0, 0)), &h[..d * d]),
        Group::new(Some(col::tau(d, 0)), &s.stress[..stress_components(d)]),
        hoop,
        Group::new(reserved(l.plastic), &[s.plastic]),
        Group::new(reserved(l.affine), &affine[..d * d]),
        Group::new(reserved(l.force), &s.force[..d]),
        Group::new(reserved(l.damping), &s.damping),
        Group::new(scalar(0, 0), &[s.temperature]),
        Group::new(scalar(1, 0), &[s.concentration]),
        Group::new(scalar(0, 1), &[s.grid_temperature]),
        Group::new(scalar(1, 1), &[s.grid_concentration]),
        Group::new(scalar(0, 2), &[s.temperature_source]),
        Group::new(scalar(1, 2), &[s.concentration_source]),
    ]
}

/// Whether a state is added (columns not given take a new particle's values) or set on
/// particles that exist (columns not given stay).
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Add,
    Set(u32),
}

impl World<'_> {
    /// Adds `state.count` particles with the state `state` ([`ParticleState`]); all or
    /// nothing. Returns the range of their ids. Their position, mass, initial volume and
    /// material must be given; every other column not given takes a new particle's value
    /// (0; status active), so that a particle read from a world with every column its view
    /// shows and added here, in this world or another with the same materials and declared
    /// effects, is that particle to the bit.
    ///
    /// Checked in this order, nothing written unless everything passes: `EffectNotDeclared`
    /// for a column of an effect not declared; `LengthMismatch` for a column given that is
    /// not `count` long, a group given in part, or a position, mass, volume or material not
    /// given; `ParticleCapacityExceeded`; then each particle as [`World::open`] checks a
    /// snapshot's (the errors of [`World::set_particle_state`]).
    pub fn add_particles_with_state(
        &mut self,
        state: &ParticleState<'_>,
    ) -> Result<Range<u32>, Error> {
        let range = self.write_state(Mode::Add, state)?;
        Ok(range.start as u32..range.end as u32)
    }

    /// Sets the columns `state` gives ([`ParticleState`]) of particles
    /// `first..first + state.count`, as given, bit for bit; the columns it does not give stay.
    /// Nothing is derived: the stress is what is given, however the deformation changes
    /// ([`World::set_displacement_gradient`] derives it), and the low part of the position
    /// stays unless given (it must stay within one unit in the last place of the position).
    ///
    /// Checked in this order, nothing written unless everything passes: `EffectNotDeclared`,
    /// `LengthMismatch` (as [`World::add_particles_with_state`]); `UnknownParticle` unless the
    /// particles exist; then each particle with its values after the call, as [`World::open`]
    /// checks a snapshot's: `NonFiniteInput` for a position, velocity, mass, volume, low part
    /// of the position, force, moment matrix, transported value or source that is not
    /// finite; `NonPositiveMassOrVolume`; `StableStepTooShort` for a speed, a snow's hardening
    /// (active particles) or a damping rate no step above [`crate::MIN_STABLE_DT`] resolves;
    /// `UnknownMaterial`; `PositionOutsideDomain` for a position outside the grid less the
    /// shape's margin and its wall planes; `InvalidState` for an unknown status or a low part
    /// past one unit in the last place of the position; `InvalidDeformation` for an `H`, hoop
    /// stretch or stress that is not finite, `J <= 0`, a hoop stretch <= -1 or a plastic
    /// history out of its model's range ([`crate::ParticlesView::plastic`]: < 0 for von Mises
    /// and Drucker-Prager, `J_p <= 0` for snow, not 0 for a model without one);
    /// `InvalidEffect` for a damping rate < 0 or not finite.
    pub fn set_particle_state(
        &mut self,
        first: u32,
        state: &ParticleState<'_>,
    ) -> Result<(), Error> {
        self.write_state(Mode::Set(first), state).map(drop)
    }

    /// The state setters' one path: checks `s` for `mode`, then writes it; returns the
    /// particles written.
    fn write_state(&mut self, mode: Mode, s: &ParticleState<'_>) -> Result<Range<usize>, Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        let n = s.count;
        let groups = groups(s, &layout);
        if groups.iter().any(|g| g.given() && g.first.is_none()) {
            return Err(Error::EffectNotDeclared);
        }
        let whole = |c: &[Real]| c.len() == n;
        let ids_ok = |c: &[u32]| c.is_empty() || c.len() == n;
        let lengths_ok = groups
            .iter()
            .all(|g| !g.given() || g.cols[..g.len].iter().all(|c| whole(c)))
            && ids_ok(s.material)
            && ids_ok(s.status);
        // What every particle added needs: its position, mass, volume and material.
        let required = [&groups[POSITION], &groups[MASS], &groups[VOLUME]];
        let complete = (required.iter().all(|g| g.given()) && s.material.len() == n) || n == 0;
        if !lengths_ok || (mode == Mode::Add && !complete) {
            return Err(Error::LengthMismatch);
        }
        let range = match mode {
            Mode::Add => {
                let start = self.particle_count();
                if n > def.particle_capacity as usize - start {
                    return Err(Error::ParticleCapacityExceeded);
                }
                start..start + n
            }
            Mode::Set(first) => self.particle_range(first, n)?,
        };
        {
            // Each particle with the values it would have: given, kept (set) or new (add: 0,
            // an empty column).
            let world = self.read();
            let rules = ParticleRules::new(&world);
            let mut values: [&[Real]; MAX_COLUMNS] = [&[]; MAX_COLUMNS];
            if mode != Mode::Add {
                let cols = layout.particle_real_columns.min(MAX_COLUMNS);
                for (j, v) in values.iter_mut().enumerate().take(cols) {
                    *v = &world.real_col(&layout, j, range.end)[range.clone()];
                }
            }
            for g in groups.iter().filter(|g| g.given()) {
                let first = g.first.unwrap_or(0);
                for (k, &c) in g.cols[..g.len].iter().enumerate() {
                    if let Some(v) = values.get_mut(first + k) {
                        *v = c;
                    }
                }
            }
            let view = world.particles();
            for i in 0..n {
                let p = range.start + i;
                let kept = |c: &[u32], new: u32| c.get(p).copied().unwrap_or(new);
                let material = s.material.get(i).copied();
                let material = material.unwrap_or_else(|| kept(view.material, 0));
                let status = s.status.get(i).copied();
                let status = status.unwrap_or_else(|| kept(view.status, ACTIVE));
                let value = |j: usize| values[j].get(i).copied().unwrap_or(0.0);
                rules.check(value, material, status)?;
            }
        }
        // Validated: write.
        let cap = layout.padded_capacity;
        if mode == Mode::Add {
            for j in 0..layout.particle_real_columns {
                self.real_col_mut(&layout, j, cap)[range.clone()].fill(0.0);
            }
            self.u32_col_mut(&layout, col::STATUS, cap)[range.clone()].fill(ACTIVE);
        }
        for g in groups.iter().filter(|g| g.given()) {
            let first = g.first.unwrap_or(0);
            for (k, c) in g.cols[..g.len].iter().enumerate() {
                self.real_col_mut(&layout, first + k, cap)[range.clone()].copy_from_slice(c);
            }
        }
        for (j, c) in [(col::MATERIAL, s.material), (col::STATUS, s.status)] {
            if !c.is_empty() {
                self.u32_col_mut(&layout, j, cap)[range.clone()].copy_from_slice(c);
            }
        }
        let count = self.particle_count().max(range.end);
        let mut min_mass = self.header().min_particle_mass;
        if groups[MASS].given() {
            // Masses set may raise the least: take it again over every particle.
            if mode != Mode::Add {
                min_mass = f64::INFINITY;
            }
            let masses = self.read().real_col(&layout, col::mass(layout.d), count);
            min_mass = masses.iter().fold(min_mass, |m, &v| m.min(v as f64));
        }
        let h = self.header_mut();
        h.particle_count = count as u64;
        h.min_particle_mass = min_mass;
        Ok(range)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Damping, Dimension, Effects, ShapeFunction, Transfer, Transport, WorldDef};

    /// [`MAX_COLUMNS`] holds the particle Real columns of every definition: those that reserve
    /// the most (MUSL, cpGIMP, APIC, every per-particle effect, sources and plasticity), in
    /// each dimension form.
    #[test]
    fn the_column_tables_hold_every_definitions_columns() {
        let sources = Transport {
            sources: true,
            ..Transport::INSULATED
        };
        for dimension in [
            Dimension::Plane2D,
            Dimension::Axisymmetric2D,
            Dimension::ThreeD,
        ] {
            let def = WorldDef {
                dimension,
                shape: ShapeFunction::CpGimp,
                transfer: Transfer::Apic,
                effects: Effects {
                    damping: Some(Damping {
                        per_particle: true,
                        ..Damping::NONE
                    }),
                    particle_forces: true,
                    heat: Some(sources),
                    diffusion: Some(sources),
                    plasticity: true,
                    ..Effects::NONE
                },
                ..WorldDef::DEFAULT
            };
            let columns = Layout::of(&def).particle_real_columns;
            assert!(columns <= MAX_COLUMNS, "{dimension:?}: {columns}");
        }
    }
}
