//! Particle forces, tractions and a body force (seeds/000 eqs 13, 20-22): the per-particle
//! forces and the tractions a host sets, and the traction pass. The particle forces enter the
//! nodal force in the scatter's rows (`S_ip F_p`, [`crate::phases::p2g`]); the body force is
//! added to gravity for the substep ([`crate::Effects::body_force`]).

use crate::grid::GridCols;
use crate::layout::{Layout, TractionRecord};
use crate::particles::{ParticleCols, ACTIVE};
use crate::phases::Ctx;
use crate::shape::{Shape1D, Stencil};
use crate::world::World;
use crate::{Error, Real, Vec3};
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
            |_| true,
        )
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
        let table = self.traction_records_mut(&layout, used, n);
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

    /// Removes the tractions `ids` (a range [`World::add_tractions`] returned, or any part of
    /// the table), so that loads applied together can be taken off together; the tractions
    /// after them move down by `ids.len()`, in their order, and their room is free again.
    /// `UnknownTraction` if the range is not within the table (nothing is removed);
    /// `EffectNotDeclared` without [`crate::Effects::traction_capacity`].
    pub fn remove_tractions(&mut self, ids: Range<u32>) -> Result<(), Error> {
        if self.def().effects.traction_capacity == 0 {
            return Err(Error::EffectNotDeclared);
        }
        let used = self.header().traction_count as usize;
        let (start, end) = (ids.start as usize, ids.end as usize);
        if start > end || end > used {
            return Err(Error::UnknownTraction);
        }
        let layout = Layout::of(&self.def());
        self.traction_records_mut(&layout, 0, used)
            .copy_within(end..used, start);
        self.header_mut().traction_count = (used - (end - start)) as u64;
        Ok(())
    }
}

/// Adds the tractions of the table to the nodal force (eq 21): each loads one face of one
/// active particle's domain, a square (segment in 2D) of side `2 l_p`, `l_p = h / (2 n)` for
/// `n` particles per cell per axis (the undeformed domain uGIMP uses), so its resultant is
/// `T A` with `A = (2 l_p)^(D-1)` (per unit thickness in 2D). The resultant is spread over the
/// nodes with the particle's own weights, `f_iT = S_ip T A`.
///
/// Why not the face integral `sum_q N_i(x_q) T A / q` at Gauss points `x_q` on the face: it
/// gives the nodes just past the material's surface a force out of proportion to the sliver of
/// mass they carry (`N_i` at the face against `S_ip` at the particle), an acceleration that
/// grows without bound as that mass vanishes; USL differentiates it into the velocity
/// gradient, and a 3D quadratic B-spline block under USL froze (f64 hard case). With `S_ip`
/// the acceleration a traction gives any node is at most `T A / m_p`. The cost is the point of
/// application, moved by `l_p` from the face to the particle: the resultant is exact, its
/// moment is off by `T A l_p` per particle.
///
/// Axisymmetric, the force is per radian: `A = 2 l_p (r_p -+ l_p)` for the faces of constant
/// r at `r_p -+ l_p`, `2 l_p r_p` for those of constant z. There the point of application
/// matters more: a radial load `F` applied at radius `r` balances a uniform stress `F / r`,
/// so a load on the outer face of a pressurised solid cylinder of radius `R` stresses its
/// interior `~l_p / R` too much (measured: 1.3 % for `l_p / R = 1/40`).
pub(crate) fn tractions<const D: usize, const K: usize, S: Shape1D<K>>(
    shape: &S,
    ctx: &Ctx<'_, D>,
    p: &ParticleCols<'_, D>,
    count: usize,
    g: &mut GridCols<'_, D>,
) {
    let geom = &ctx.geom;
    let area = (1..D).fold(1.0 as Real, |a, _| a * 2.0 * ctx.half_width);
    for rec in ctx.tractions {
        let i = rec.particle as usize;
        if i >= count || (rec.face / 2) as usize >= D || p.status.get(i) != Some(&ACTIVE) {
            continue;
        }
        let s: [Real; D] = core::array::from_fn(|a| (p.x[a][i] - geom.origin[a]) * geom.inv_h);
        let stretch = p.domain_stretch(i);
        let st = Stencil::<D, K>::new(shape, s, stretch, geom.nodes, geom.stride, geom.inv_h);
        let area = if S::AXISYMMETRIC {
            let (r, l) = (p.x[0][i], ctx.half_width);
            area * match rec.face {
                0 => (r - l).max(0.0),
                1 => r + l,
                _ => r,
            }
        } else {
            area
        };
        st.for_each_node(geom.stride, |node, w, _| {
            for a in 0..D {
                if let Some(f) = g.acc[a].get_mut(node) {
                    *f += w * rec.traction[a] * area * ctx.traction_scale;
                }
            }
        });
    }
}
