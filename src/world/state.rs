//! The check of one particle's values that [`WorldRef::check_state`] (what [`World::open`]
//! runs on untrusted bytes) applies to every particle, with the error each bound answers.

use super::add::speed_resolvable;
#[cfg(doc)]
use super::World;
use super::{GeomAny, WorldRef};
use crate::layout::{col, stress_components, ColumnGroup, Layout, MaterialRecord};
use crate::material::{history_in_range, wave_speed, Deformation};
use crate::particles::{ParticleStatus, ACTIVE};
use crate::{Error, Real};

/// More particle Real columns than any definition reserves (53 at most: 3D with MUSL,
/// cpGIMP, APIC and every effect), for the tables of columns a check reads.
pub(super) const MAX_COLUMNS: usize = 64;

/// The bounds every particle of a world keeps, checked one particle at a time (by
/// [`WorldRef::check_state`] on a world's particles).
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
