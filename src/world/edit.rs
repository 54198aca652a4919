//! Changing particles after they are in: their position, velocity, affine matrix and material
//! (each validated as [`World::add_particles`] validates, all or nothing), and removing them,
//! which frees their room for later additions; and reordering them by cell
//! ([`World::sort_particles`]).

use super::add::speed_resolvable;
use super::{GeomAny, Removal, World};
use crate::grid::Geom;
use crate::layout::{col, Layout, TractionRecord};
use crate::material::Deformation;
use crate::particles::ACTIVE;
use crate::shape::{first_node, Shape1D};
use crate::{Error, Real, WorldDef};
use core::mem::{size_of, size_of_val};

/// The status a particle the removal takes out carries during the call (no stored status has
/// it: [`crate::ParticleStatus`] uses 0 to 2).
const REMOVED: u32 = 3;

/// The top bit of an entry of the sort's permutation, flipped when the entry's particle is put
/// in place (no index has it: the capacity is at most 2^30).
const MOVED: u32 = 1 << 31;

impl World<'_> {
    /// Moves particles `first..first + n` to `position` (one slice per axis, `n` values each;
    /// in 2D the z slice is not read): a teleport. The part of each position that rounding
    /// left out (`position_low`) is cleared; the deformation and velocity stay.
    /// `LengthMismatch`, `UnknownParticle`, `NonFiniteInput`, `PositionOutsideDomain` as
    /// [`World::add_particles`] checks them; nothing is changed unless every value passes.
    pub fn set_particle_positions(
        &mut self,
        first: u32,
        position: [&[Real]; 3],
    ) -> Result<(), Error> {
        let def = self.def();
        let (d, geom) = (def.axes(), GeomAny::new(&def));
        let range = self.vectors_range(first, &position[..d])?;
        for i in 0..range.len() {
            let x: [Real; 3] = core::array::from_fn(|a| if a < d { position[a][i] } else { 0.0 });
            if !x.iter().all(|c| c.is_finite()) {
                return Err(Error::NonFiniteInput);
            }
            if !geom.admits(x) {
                return Err(Error::PositionOutsideDomain);
            }
        }
        let layout = Layout::of(&def);
        for (a, values) in position.iter().enumerate().take(d) {
            self.real_col_mut(&layout, col::x(a), range.end)[range.clone()].copy_from_slice(values);
            self.real_col_mut(&layout, col::x_low(d, a), range.end)[range.clone()].fill(0.0);
        }
        Ok(())
    }

    /// Gives particles `first..first + n` the velocity `velocity` (m/s, one slice per axis,
    /// `n` values each; in 2D the z slice is not read): an impulse, or a kinematic particle
    /// set before every step. `LengthMismatch`, `UnknownParticle`, `NonFiniteInput`, and
    /// `StableStepTooShort` for a speed no stable step resolves, as [`World::add_particles`];
    /// nothing is changed unless every value passes.
    pub fn set_particle_velocities(
        &mut self,
        first: u32,
        velocity: [&[Real]; 3],
    ) -> Result<(), Error> {
        let def = self.def();
        let d = def.axes();
        let range = self.vectors_range(first, &velocity[..d])?;
        for i in 0..range.len() {
            let v: [Real; 3] = core::array::from_fn(|a| if a < d { velocity[a][i] } else { 0.0 });
            if !v.iter().all(|c| c.is_finite()) {
                return Err(Error::NonFiniteInput);
            }
            if !speed_resolvable(&def, v) {
                return Err(Error::StableStepTooShort);
            }
        }
        let layout = Layout::of(&def);
        for (a, values) in velocity.iter().enumerate().take(d) {
            self.real_col_mut(&layout, col::v(d, a), range.end)[range.clone()]
                .copy_from_slice(values);
        }
        Ok(())
    }

    /// Sets the affine matrix of particles `first..first + n` as [`crate::ParticlesView::affine`]
    /// holds it (APIC's `B_p`, m^2/s; `C_p`, 1/s, with linear shapes and MLS-MPM's gradient
    /// form): `affine[a][b]` holds `n` values of entry `(a, b)`, the first `D` rows and columns
    /// read. Zero is no affine motion; a copy of the view's values restores them.
    /// `EffectNotDeclared` unless the transfer is APIC or MLS-MPM; `LengthMismatch`,
    /// `UnknownParticle`, `NonFiniteInput`; nothing is changed unless every value passes.
    pub fn set_particle_affine(
        &mut self,
        first: u32,
        affine: [[&[Real]; 3]; 3],
    ) -> Result<(), Error> {
        let def = self.def();
        let (d, layout) = (def.axes(), Layout::of(&def));
        let group = (layout.affine.count > 0).then_some(layout.affine.first);
        let mut columns: [&[Real]; 9] = [&[]; 9];
        for a in 0..d {
            for b in 0..d {
                columns[a * d + b] = affine[a][b];
            }
        }
        let columns = &columns[..d * d];
        self.write_particle_columns(
            &layout,
            group,
            first,
            columns,
            Error::NonFiniteInput,
            |_| Ok(()),
        )
    }

    /// Gives particles `first..first + n` the materials `material` as adding them would: the
    /// plastic history restarts at 0 and the stress is the new material's at the particle's
    /// current deformation (with the eigenstrain of its temperature and concentration).
    /// `UnknownParticle`; `UnknownMaterial` for an id not added; `InvalidDeformation` where the
    /// new material gives a stress that is not finite; nothing is changed unless every
    /// particle passes.
    pub fn set_particle_materials(&mut self, first: u32, material: &[u32]) -> Result<(), Error> {
        if self.def().axes() == 3 {
            self.set_materials::<3>(first, material)
        } else {
            self.set_materials::<2>(first, material)
        }
    }

    fn set_materials<const D: usize>(&mut self, first: u32, material: &[u32]) -> Result<(), Error> {
        let def = self.def();
        let layout = Layout::of(&def);
        let range = self.particle_range(first, material.len())?;
        let known = self.material_count() as u32;
        if material.iter().any(|&m| m >= known) {
            return Err(Error::UnknownMaterial);
        }
        self.set_with_stress::<D>(
            range,
            |world, view, i, p| {
                let h = crate::num::matrix(|a, b| view.displacement_gradient[a][b][p]);
                let hoop = view.hoop.get(p).copied().unwrap_or(0.0);
                let f = Deformation::<D>::new(h, hoop);
                world.particle_stress_of(view, p, material[i], &f)
            },
            |w, i, p| {
                let cap = layout.padded_capacity;
                w.u32_col_mut(&layout, col::MATERIAL, cap)[p] = material[i];
                if layout.plastic.count > 0 {
                    w.real_col_mut(&layout, layout.plastic.first, cap)[p] = 0.0;
                }
            },
        )
    }

    /// `first..first + n` for the `D` slices of a vector setter: `LengthMismatch` unless they
    /// have one length `n`, `UnknownParticle` unless those particles exist.
    fn vectors_range(
        &self,
        first: u32,
        slices: &[&[Real]],
    ) -> Result<core::ops::Range<usize>, Error> {
        let n = slices.first().map_or(0, |s| s.len());
        if slices.iter().any(|s| s.len() != n) {
            return Err(Error::LengthMismatch);
        }
        self.particle_range(first, n)
    }

    /// Removes the particles `which` selects and returns how many it removed. The others keep
    /// their order and every column of theirs (so the step that follows is the step of a
    /// world built with them alone, to the bit): a particle moves down by the number removed
    /// before it, which is how a host follows its ids. The room they held is free for later
    /// additions. Tractions on removed particles are removed too (as by
    /// [`World::remove_tractions`]: the other tractions keep their ids); the others follow
    /// their particle.
    ///
    /// O(n) for n particles: one pass over each particle column. `UnknownParticle` for a
    /// range or an id not in the world, `NonFiniteInput` for a box corner that is not finite,
    /// `InvalidRegion` for a box with `min > max` on an axis, `UnknownCollider` for a collider
    /// id past the colliders; nothing is removed then.
    pub fn remove_particles(&mut self, which: Removal<'_>) -> Result<usize, Error> {
        let def = self.def();
        let (d, count) = (def.axes(), self.particle_count());
        match which {
            Removal::Range(ref r) if r.start > r.end || r.end as usize > count => {
                return Err(Error::UnknownParticle)
            }
            Removal::List(ids) if ids.iter().any(|&i| i as usize >= count) => {
                return Err(Error::UnknownParticle)
            }
            Removal::Box { min, max } => {
                if !(0..d).all(|a| min[a].is_finite() && max[a].is_finite()) {
                    return Err(Error::NonFiniteInput);
                }
                if (0..d).any(|a| min[a] > max[a]) {
                    return Err(Error::InvalidRegion);
                }
            }
            Removal::Collider(id) => {
                self.read().collider_now(id)?;
            }
            _ => {}
        }
        let layout = Layout::of(&def);
        match which {
            Removal::Collider(id) => self.mark_in_collider(&def, &layout, count, id),
            _ => self.mark_removed(&layout, count, &which),
        }
        Ok(self.compact(&layout, count))
    }

    /// Gives the particles `which` selects the status [`REMOVED`].
    fn mark_removed(&mut self, layout: &Layout, count: usize, which: &Removal<'_>) {
        let d = layout.d;
        let (_, particles) = self.buf[..layout.grid_offset].split_at_mut(layout.particle_offset);
        let (reals, u32s) =
            particles.split_at_mut(layout.particle_real_columns * layout.real_column_bytes);
        let status = col::STATUS * layout.u32_column_bytes;
        let status: &mut [u32] = bytemuck::cast_slice_mut(&mut u32s[status..status + 4 * count]);
        match *which {
            Removal::Range(ref r) => status[r.start as usize..r.end as usize].fill(REMOVED),
            Removal::List(ids) => ids.iter().for_each(|&i| status[i as usize] = REMOVED),
            Removal::Box { min, max } => {
                let x: [&[Real]; 3] = core::array::from_fn(|a| {
                    let start = col::x(a.min(d - 1)) * layout.real_column_bytes;
                    bytemuck::cast_slice(&reals[start..start + count * size_of::<Real>()])
                });
                for (i, s) in status.iter_mut().enumerate() {
                    if (0..d).all(|a| x[a][i] >= min[a] && x[a][i] <= max[a]) {
                        *s = REMOVED;
                    }
                }
            }
            Removal::Inactive => status
                .iter_mut()
                .filter(|s| **s != ACTIVE)
                .for_each(|s| *s = REMOVED),
            Removal::Collider(_) => {} // `mark_in_collider`
        }
    }

    /// Gives the particles whose domains reach collider `id`'s solid ([`Removal::Collider`])
    /// the status [`REMOVED`]: 64 at a time, found from the world, then marked.
    fn mark_in_collider(&mut self, def: &WorldDef, layout: &Layout, count: usize, id: u32) {
        let d = layout.d;
        let l = def.cell_size / (2 * def.particles_per_cell) as Real;
        let touch = def.cell_size / 1024.0;
        for from in (0..count).step_by(64) {
            let to = (from + 64).min(count);
            let mut reached = 0u64;
            {
                let w = self.read();
                let Ok(c) = w.collider_now(id) else {
                    return; // Unreachable: `remove_particles` found the collider.
                };
                let p = w.particles();
                for i in from..to {
                    let x: [Real; 3] =
                        core::array::from_fn(|a| if a < d { p.position[a][i] } else { 0.0 });
                    // The farthest a domain reaches, `l` along each axis's diagonal.
                    if c.farther_than(x, l * d as Real + touch) {
                        continue;
                    }
                    let (phi, n) = c.distance(x);
                    let reach = l * n[..d].iter().map(|v| v.abs()).sum::<Real>();
                    if phi <= reach + touch {
                        reached |= 1 << (i - from);
                    }
                }
            }
            let status = self.u32_col_mut(layout, col::STATUS, count);
            for (k, s) in status[from..to].iter_mut().enumerate() {
                if reached >> k & 1 == 1 {
                    *s = REMOVED;
                }
            }
        }
    }

    /// Removes the particles marked [`REMOVED`] from every particle column (the others moved
    /// down in their order, the freed entries zeroed as a new world's are) and from the
    /// traction table; returns how many.
    fn compact(&mut self, layout: &Layout, count: usize) -> usize {
        let used = self.header().traction_count as usize;
        let (head, particles) = self.buf[..layout.grid_offset].split_at_mut(layout.particle_offset);
        let (reals, u32s) =
            particles.split_at_mut(layout.particle_real_columns * layout.real_column_bytes);
        // The u32 columns: the material, then the status.
        const _: () = assert!(col::MATERIAL == 0 && col::STATUS == 1);
        let (material, status) = u32s.split_at_mut(layout.u32_column_bytes);
        let material: &mut [u32] = bytemuck::cast_slice_mut(&mut material[..4 * count]);
        let status: &mut [u32] = bytemuck::cast_slice_mut(&mut status[..4 * count]);
        let mut tractions = used;
        if used > 0 {
            // Each kept particle's status carries, above its two bits, how many particles
            // before it go (its id moves down by that much; below 2^30 particles, it fits):
            // the tractions read their particle's new id there.
            let mut before = 0u32;
            for s in status.iter_mut() {
                if *s == REMOVED {
                    before += 1;
                } else {
                    *s |= before << 2;
                }
            }
            let start = layout.tractions_offset;
            let records: &mut [TractionRecord] = bytemuck::cast_slice_mut(
                &mut head[start..start + used * size_of::<TractionRecord>()],
            );
            for r in records.iter_mut().filter(|r| !r.is_removed()) {
                let s = status[r.particle as usize];
                if s & 3 == REMOVED {
                    *r = TractionRecord::REMOVED;
                } else {
                    r.particle -= s >> 2;
                }
            }
            tractions = TractionRecord::end_of(records);
        }
        let column_bytes = count * size_of::<Real>();
        let d = layout.d;
        let mut min_mass = f64::INFINITY;
        for j in 0..layout.particle_real_columns {
            let start = j * layout.real_column_bytes;
            let column: &mut [Real] =
                bytemuck::cast_slice_mut(&mut reals[start..start + column_bytes]);
            let kept = compact_column(column, status);
            if j == col::mass(d) {
                min_mass = column[..kept]
                    .iter()
                    .fold(min_mass, |m, &v| m.min(v as f64));
            }
        }
        compact_column(material, status);
        // The status last: it says which entries go.
        let mut kept = 0;
        for i in 0..count {
            let s = status[i] & 3;
            if s != REMOVED {
                status[kept] = s;
                kept += 1;
            }
        }
        status[kept..].fill(0);
        let h = self.header_mut();
        h.particle_count = kept as u64;
        h.min_particle_mass = min_mass;
        h.traction_count = tractions as u64;
        count - kept
    }
}

/// Moves the entries of `column` whose particle stays (`status`, as long, not [`REMOVED`] in
/// its two low bits) down, in their order, and zeroes the rest; returns how many stay.
fn compact_column<T: Copy + Default>(column: &mut [T], status: &[u32]) -> usize {
    let mut kept = 0;
    for (i, &s) in status.iter().enumerate().take(column.len()) {
        if s & 3 != REMOVED {
            column[kept] = column[i];
            kept += 1;
        }
    }
    column[kept..].fill(T::default());
    kept
}

impl World<'_> {
    /// Reorders the particles by cell, in place: by the node their stencil starts at, in the
    /// grid's node order (x fastest), each cell's whole groups of four first and the rest of
    /// every cell after them, those of one cell keeping their order (a stable counting sort,
    /// so the result is a function of the state alone). A step reads and adds a particle's
    /// stencil rows four lanes at a time, summed in registers where the lanes start at one
    /// node: particles that lost that order (a scene that stirs, a host adding them in its own
    /// order) step slower, shuffled 2 (2D) to 3.6 (3D) times as long; a host calls this between
    /// frames, every so many steps (benches/PERFORMANCE.md, "Reordering particles"), at the
    /// cost of one or two steps.
    ///
    /// `order` receives, for each new index, the particle's index before the call
    /// (`order[new] = old`), which is how a host follows its ids. Every particle column
    /// (statuses, materials and every effect's columns included) moves with its particle, and
    /// tractions follow theirs: right after the call the state is the state before, permuted,
    /// bit for bit. Later steps add the particles' shares to the nodes in the new order, so they
    /// agree with the unsorted world's to round-off, not to the bit.
    ///
    /// O(n + nodes) for n particles, no memory but the grid's (scratch between steps, so a
    /// snapshot, [`World::state_bytes`], is unaffected):
    /// `LengthMismatch` if `order` is shorter than [`World::particle_count`]; nothing is
    /// changed then (entries of `order` past the count are never written).
    pub fn sort_particles(&mut self, order: &mut [u32]) -> Result<(), Error> {
        let def = self.def();
        let order = order
            .get_mut(..self.particle_count())
            .ok_or(Error::LengthMismatch)?;
        let layout = Layout::of(&def);
        crate::shape::with_form!(&def, shape => self.order_by_cell::<D, K, _>(&shape, &layout, order));
        self.renumber_tractions(&layout, order);
        self.permute_columns(&layout, order);
        Ok(())
    }

    /// Fills `order` (`particle_count` long) with the particles' indices sorted, stably, by the
    /// flat index of their stencil's first node, in two parts: first the whole groups of four
    /// of each cell (the first `4 * floor(count / 4)` of its particles), then each cell's rest.
    /// So every group of four starts a 4-lane block: the blocks of the step's chunks share their
    /// stencil rows (as `fill_box` writes its particles), which a plain sort by cell would
    /// break at the first cell whose count is not a multiple of 4. Counts in the grid.
    fn order_by_cell<const D: usize, const K: usize, S: Shape1D<K>>(
        &mut self,
        _shape: &S,
        layout: &Layout,
        order: &mut [u32],
    ) {
        let geom = Geom::<D>::new(&self.def());
        let (n, nodes) = (order.len(), layout.nodes);
        let (particles, grid) = self.buf.split_at_mut(layout.grid_offset);
        let x: [&[Real]; D] = core::array::from_fn(|a| {
            bytemuck::cast_slice(&particles[layout.real_col(col::x(a), n)])
        });
        let cell = |i: usize| -> usize {
            (0..D)
                .map(|a| {
                    let s = (x[a][i] - geom.origin[a]) * geom.inv_h;
                    first_node::<K, S>(s, geom.nodes[a]) as usize * geom.stride[a]
                })
                .sum()
        };
        // The grid is scratch between steps ("Memory layout"); its first columns (at least
        // 5 of `nodes` Reals each) hold per cell: how many of its particles still go to the
        // whole groups, and where its next particle goes in each part.
        let scratch: &mut [u32] = bytemuck::cast_slice_mut(&mut grid[..12 * nodes]);
        let (quota, next) = scratch.split_at_mut(nodes);
        let (whole, rest) = next.split_at_mut(nodes);
        quota.fill(0);
        for i in 0..n {
            quota[cell(i)] += 1;
        }
        let (mut w, mut r) = (0, quota.iter().map(|&c| c & !3).sum::<u32>());
        for c in 0..nodes {
            (whole[c], rest[c]) = (w, r);
            (w, r) = (w + (quota[c] & !3), r + (quota[c] & 3));
            quota[c] &= !3;
        }
        for i in 0..n {
            let c = cell(i);
            let next = if quota[c] > 0 {
                quota[c] -= 1;
                &mut whole[c]
            } else {
                &mut rest[c]
            };
            order[*next as usize] = i as u32;
            *next += 1;
        }
    }

    /// Points each traction at its particle's new index (`order[new] = old`), which each
    /// particle's status carries above its two bits meanwhile (as in [`World::remove_particles`]).
    fn renumber_tractions(&mut self, layout: &Layout, order: &[u32]) {
        let used = self.header().traction_count as usize;
        if used == 0 {
            return;
        }
        let (head, particles) = self.buf[..layout.grid_offset].split_at_mut(layout.particle_offset);
        let status = layout.u32_col(col::STATUS, order.len());
        let status: &mut [u32] = bytemuck::cast_slice_mut(
            &mut particles
                [status.start - layout.particle_offset..status.end - layout.particle_offset],
        );
        for (new, &old) in order.iter().enumerate() {
            status[old as usize] |= (new as u32) << 2;
        }
        let start = layout.tractions_offset;
        let records: &mut [TractionRecord] =
            bytemuck::cast_slice_mut(&mut head[start..start + used * size_of::<TractionRecord>()]);
        for r in records.iter_mut().filter(|r| !r.is_removed()) {
            r.particle = status[r.particle as usize] >> 2;
        }
        status.iter_mut().for_each(|s| *s &= 3);
    }

    /// Applies the permutation `order` (`order[new] = old`) to every particle column the layout
    /// holds, Real then u32, one column at a time; `order` is as it came when this returns.
    /// Where the grid (scratch between steps) holds a column, each column is gathered into it
    /// and copied back (reads that do not wait on each other: on a shuffled scene a seventh of
    /// the cost of the cycles); else each column follows the permutation's cycles in place.
    fn permute_columns(&mut self, layout: &Layout, order: &mut [u32]) {
        let n = order.len();
        let (particles, grid) = self.buf[..layout.scratch_offset].split_at_mut(layout.grid_offset);
        let mut copy = (n * size_of::<Real>() <= grid.len()).then_some(grid);
        let mut marked = false;
        for j in 0..layout.particle_real_columns {
            let column: &mut [Real] =
                bytemuck::cast_slice_mut(&mut particles[layout.real_col(j, n)]);
            marked = permute(column, order, marked, copy.as_deref_mut());
        }
        for j in 0..col::U32_COLUMNS {
            let column: &mut [u32] = bytemuck::cast_slice_mut(&mut particles[layout.u32_col(j, n)]);
            marked = permute(column, order, marked, copy.as_deref_mut());
        }
        if marked {
            order.iter_mut().for_each(|o| *o &= !MOVED);
        }
    }
}

/// Puts `column[order[i]]` at `i` for every `i` (`order`, as long, a permutation of its indices
/// whose [`MOVED`] bits are all `marked`), and returns how the [`MOVED`] bits are left. With
/// `copy` (room for the column): gathered there and copied back, the bits left alone. Without:
/// following the permutation's cycles, each entry moved once, the cycle's first held aside,
/// every bit flipped.
fn permute<T: bytemuck::Pod>(
    column: &mut [T],
    order: &mut [u32],
    marked: bool,
    copy: Option<&mut [u8]>,
) -> bool {
    if let Some(bytes) = copy {
        let copy: &mut [T] = bytemuck::cast_slice_mut(&mut bytes[..size_of_val(column)]);
        for (c, &o) in copy.iter_mut().zip(order.iter()) {
            *c = column[o as usize];
        }
        column.copy_from_slice(copy);
        return marked;
    }
    let done = if marked { 0 } else { MOVED };
    for start in 0..column.len() {
        if order[start] & MOVED == done {
            continue;
        }
        let held = column[start];
        let mut j = start;
        loop {
            let k = (order[j] & !MOVED) as usize;
            order[j] ^= MOVED;
            if k == start {
                column[j] = held;
                break;
            }
            column[j] = column[k];
            j = k;
        }
    }
    !marked
}
