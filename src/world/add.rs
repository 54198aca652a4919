//! Adding to a world: materials and particles, and the append path every particle goes
//! through. The setters of the effects' per-particle data live with their effect
//! ([`crate::effects`]).

use super::{ParticleBatch, ParticleDef, ParticleState, World};
use crate::def::{MaterialDef, WorldDef};
use crate::layout::{col, Layout, MaterialRecord};
use crate::material::{material_record, material_resolvable, Deformation};
use crate::particles::ACTIVE;
use crate::{Error, Real};
use core::mem::size_of;
use core::ops::Range;

impl<'a> World<'a> {
    /// Adds a material; returns its id.
    pub fn add_material(&mut self, m: &MaterialDef) -> Result<u32, Error> {
        let record = material_record(m)?;
        let def = self.def();
        if m.model.plastic() && !def.effects.plasticity {
            return Err(Error::EffectNotDeclared);
        }
        if !material_resolvable(&record, &def) {
            return Err(Error::StableStepTooShort);
        }
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

    /// Adds a batch of particles; all or nothing. Returns the range of their ids. Every slice
    /// the dimension reads holds one value per particle (`LengthMismatch`); each particle is
    /// checked as [`World::add_particles_with_state`] checks it, the path this call takes: a
    /// batch is a state with the position, velocity, mass, volume and material given.
    pub fn add_particles(&mut self, b: &ParticleBatch<'_>) -> Result<Range<u32>, Error> {
        let (d, n) = (self.def().axes(), b.mass.len());
        if b.velocity[..d].iter().any(|v| v.len() != n) {
            return Err(Error::LengthMismatch);
        }
        self.add_particles_with_state(&ParticleState {
            count: n,
            position: b.position,
            velocity: b.velocity,
            mass: b.mass,
            volume0: b.volume,
            material: b.material,
            ..ParticleState::NONE
        })
    }

    /// Gives particles `first..first + n` the displacement gradient `H = F - I` (so the
    /// deformation gradient `F = I + H`), and the Kirchhoff stress their material gives it
    /// (with the eigenstrain of their current temperature and concentration, when declared):
    /// a scene that starts deformed or prestressed, or a restart from another code. `h[a][b]`
    /// holds `n` values of `H_ab`; in 2D only the in-plane entries are read, and `h[2][2]`
    /// (the hoop stretch `F_thetatheta - 1`) in the axisymmetric form; the others may be
    /// empty. Written as `H` rather than `F` so that small strains keep their digits in f32.
    ///
    /// The particles' volume given when adding them is their reference volume `V0`; their
    /// current volume is `J V0` with `J = det F`. Positions and velocities are not changed.
    /// All or nothing: `LengthMismatch` if the read entries differ in length,
    /// `UnknownParticle` if the particles do not exist, `InvalidDeformation` if any `H` is
    /// not finite, inverts (`J <= 0`), has `J` outside the definition's
    /// [`max_volume_ratio`](crate::WorldDef::max_volume_ratio) band, or gives a stress that
    /// is not finite.
    pub fn set_displacement_gradient(
        &mut self,
        first: u32,
        h: [[&[Real]; 3]; 3],
    ) -> Result<(), Error> {
        if self.def().axes() == 3 {
            self.set_h::<3>(first, h)
        } else {
            self.set_h::<2>(first, h)
        }
    }

    fn set_h<const D: usize>(&mut self, first: u32, h: [[&[Real]; 3]; 3]) -> Result<(), Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        let axisymmetric = layout.hoop.count > 0;
        let n = h[0][0].len();
        let read = |a: usize, b: usize| (a < D && b < D) || (axisymmetric && a == 2 && b == 2);
        if (0..3).any(|a| (0..3).any(|b| read(a, b) && h[a][b].len() != n)) {
            return Err(Error::LengthMismatch);
        }
        let range = self.particle_range(first, n)?;
        let band = [1.0 / def.max_volume_ratio - 1.0, def.max_volume_ratio - 1.0];
        let deformation = |i: usize| {
            let m = crate::num::matrix(|a, b| h[a][b][i]);
            Deformation::<D>::new(m, if axisymmetric { h[2][2][i] } else { 0.0 })
        };
        self.set_with_stress::<D>(
            range,
            |world, view, i, p| {
                let f = deformation(i);
                let finite = f.h.iter().flatten().all(|v| v.is_finite())
                    && f.hzz.is_finite()
                    && f.jm1 >= band[0]
                    && f.jm1 <= band[1];
                world.particle_stress(view, p, &f).filter(|_| finite)
            },
            |w, i, p| {
                let cap = layout.padded_capacity;
                for a in 0..D {
                    for b in 0..D {
                        w.real_col_mut(&layout, col::h(D, a, b), cap)[p] = h[a][b][i];
                    }
                }
                if axisymmetric {
                    w.real_col_mut(&layout, layout.hoop.first, cap)[p] = h[2][2][i];
                }
            },
        )
    }

    /// The stress setters' one path, for particles `range`: `stress(world, view, i, p)` gives
    /// the new `tau / rho0` of particle `p`, entry `i` of the input (`None` or a value that is
    /// not finite: `InvalidDeformation`, nothing written). Computed in blocks from the world
    /// read-only; when every particle passes, the blocks are computed again and written:
    /// `write(world, i, p)` writes the particle's inputs, then its stress is stored (no
    /// allocation).
    pub(super) fn set_with_stress<const D: usize>(
        &mut self,
        range: Range<usize>,
        stress: impl Fn(
            &super::WorldRef<'_>,
            &super::ParticlesView<'_>,
            usize,
            usize,
        ) -> Option<[Real; 6]>,
        mut write: impl FnMut(&mut Self, usize, usize),
    ) -> Result<(), Error> {
        let layout = Layout::of(&self.def());
        const BLOCK: usize = 64;
        let mut tau = [[0.0; 6]; BLOCK];
        for pass in [false, true] {
            for start in (0..range.len()).step_by(BLOCK) {
                let len = BLOCK.min(range.len() - start);
                {
                    let world = self.read();
                    let view = world.particles();
                    for (k, tau) in tau.iter_mut().enumerate().take(len) {
                        let (i, p) = (start + k, range.start + start + k);
                        match stress(&world, &view, i, p) {
                            Some(s) if s.iter().all(|v| v.is_finite()) => *tau = s,
                            _ => return Err(Error::InvalidDeformation),
                        }
                    }
                }
                if !pass {
                    continue;
                }
                let cap = layout.padded_capacity;
                for (k, tau) in tau.iter().enumerate().take(len) {
                    let (i, p) = (start + k, range.start + start + k);
                    write(self, i, p);
                    for (c, &v) in tau
                        .iter()
                        .enumerate()
                        .take(crate::layout::stress_components(D))
                    {
                        self.real_col_mut(&layout, col::tau(D, c), cap)[p] = v;
                    }
                }
            }
        }
        Ok(())
    }

    /// The per-particle setters' one path: writes `columns` (one slice per column, all of one
    /// length n) into the consecutive particle Real columns from `group` for particles
    /// `first..first + n`, after checking, in this order, that the group is reserved
    /// (`EffectNotDeclared`), that the lengths agree (`LengthMismatch`), that the particles
    /// exist (`UnknownParticle`), that every value is finite (else `invalid`) and that `check`
    /// accepts it (else its error). Nothing is written unless every check passes.
    pub(crate) fn write_particle_columns(
        &mut self,
        layout: &Layout,
        group: Option<usize>,
        first: u32,
        columns: &[&[Real]],
        invalid: Error,
        check: impl Fn(Real) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let group = group.ok_or(Error::EffectNotDeclared)?;
        let n = columns.first().map_or(0, |c| c.len());
        if columns.iter().any(|c| c.len() != n) {
            return Err(Error::LengthMismatch);
        }
        let range = self.particle_range(first, n)?;
        for &v in columns.iter().flat_map(|c| c.iter()) {
            if !v.is_finite() {
                return Err(invalid);
            }
            check(v)?;
        }
        for (k, values) in columns.iter().enumerate() {
            let col = self.real_col_mut(layout, group + k, range.end);
            col[range.clone()].copy_from_slice(values);
        }
        Ok(())
    }

    /// `first..first + n` if those particles exist.
    pub(crate) fn particle_range(&self, first: u32, n: usize) -> Result<Range<usize>, Error> {
        let first = first as usize;
        match first.checked_add(n) {
            Some(end) if end <= self.particle_count() => Ok(first..end),
            _ => Err(Error::UnknownParticle),
        }
    }

    /// Appends validated particles `(x, v, mass, volume, material)`; returns their ids.
    pub(super) fn append(
        &mut self,
        def: &WorldDef,
        items: impl Iterator<Item = NewParticle>,
    ) -> Range<u32> {
        let layout = Layout::of(def);
        let d = layout.d;
        let start = self.particle_count();
        let cap = layout.padded_capacity;
        let mut min_mass = self.header().min_particle_mass;
        let mut i = start;
        for (x, v, m, vol, mat) in items {
            for a in 0..d {
                self.real_col_mut(&layout, col::x(a), cap)[i] = x[a];
                self.real_col_mut(&layout, col::x_low(d, a), cap)[i] = 0.0;
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
            if layout.plastic.count > 0 {
                self.real_col_mut(&layout, layout.plastic.first, cap)[i] = 0.0;
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
}

/// A particle to append: position, velocity, mass, volume, material id.
type NewParticle = ([Real; 3], [Real; 3], Real, Real, u32);

/// Whether a world of `def` resolves a particle moving at `v` (m/s, the axes it has) in a
/// stable step of at least [`crate::MIN_STABLE_DT`] ([`crate::Resolvable::speed`]).
pub(crate) fn speed_resolvable(def: &WorldDef, v: [Real; 3]) -> bool {
    let v2: f64 = v[..def.axes()].iter().map(|&c| c as f64 * c as f64).sum();
    let limit = def.resolvable().speed;
    v2 <= limit * limit
}
