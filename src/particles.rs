//! Particle columns: one contiguous column per scalar component (structure of arrays).
//!
//! Always present: position x[D], velocity v[D], mass, initial volume V0, displacement
//! gradient `H = F - I` [D][D] (row-major, one column per entry; storing `F - I` rather than F
//! keeps small strains at full precision in f32), stress tau/rho0 (symmetric components, see
//! [`crate::layout::stress_components`]), the low part of the position x_low[D], material id,
//! status. With MUSL the step also reserves
//! D scratch columns for the positions of the start of the step.
//!
//! Per effect, only when declared: external force `F_p` [D] (particle forces), local damping
//! `alpha_g`, `alpha_p` (per-particle damping), moment matrix `B_p` [D][D] (APIC, see
//! [`crate::ParticlesView::affine`]), transported scalars (heat, diffusion), hoop stretch
//! `F_thetatheta - 1` (axisymmetric). An
//! undeclared group is a set of empty slices, which the passes that would read it never
//! instantiate.

use crate::layout::{stress_components, Layout};
use crate::tasks::Shared;
use crate::Real;
use core::ops::Range;

/// Life state of a particle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum ParticleStatus {
    /// Takes part in every step.
    Active = 0,
    /// Its state turned non-finite (or F inverted) in a step: it keeps its last finite position,
    /// its velocity is zeroed, and it no longer contributes to the grid.
    Frozen = 1,
    /// It crossed an open face: it stays at the point where it crossed and no longer takes part.
    Escaped = 2,
}

impl ParticleStatus {
    /// The status stored as `code` in the status column.
    pub const fn from_code(code: u32) -> Option<ParticleStatus> {
        match code {
            0 => Some(ParticleStatus::Active),
            1 => Some(ParticleStatus::Frozen),
            2 => Some(ParticleStatus::Escaped),
            _ => None,
        }
    }
}

/// Status code of an active particle.
pub(crate) const ACTIVE: u32 = ParticleStatus::Active as u32;
/// Status code of a frozen particle.
pub(crate) const FROZEN: u32 = ParticleStatus::Frozen as u32;
/// Status code of an escaped particle.
pub(crate) const ESCAPED: u32 = ParticleStatus::Escaped as u32;

/// Mutable views of every particle column, each `padded_capacity` long.
pub(crate) struct ParticleCols<'a, const D: usize> {
    pub x: [&'a mut [Real]; D],
    pub v: [&'a mut [Real]; D],
    pub mass: &'a mut [Real],
    /// Initial volume V0.
    pub vol0: &'a mut [Real],
    /// Displacement gradient `H = F - I`.
    pub h: [[&'a mut [Real]; D]; D],
    /// First `stress_components(D)` used; the rest are empty.
    pub tau: [&'a mut [Real]; 6],
    /// The low part of the position, m: `x + x_low` is the position to twice `Real`'s
    /// precision, `|x_low| <= ulp(x)` (`ulp(x) / 2` once a step moved it less than `|x|`). The particle update adds each step's displacement
    /// to the pair without rounding error ([`crate::phases::update::advance`]), so that an
    /// increment smaller than the last bit of `x` still moves the particle (in f32, a
    /// coordinate of 10 m has a last bit of 1 um: a slow particle far from the origin would
    /// otherwise never move).
    pub x_low: [&'a mut [Real]; D],
    /// MUSL scratch: the positions of the start of the step, kept by the particle update for the
    /// stress update's stencils. Empty slices otherwise.
    pub x_start: [&'a mut [Real]; D],
    /// External force `F_p`, N (particle forces).
    pub force: [&'a mut [Real]; D],
    /// Local grid and particle damping, 1/s (per-particle damping).
    pub damping: [&'a mut [Real]; 2],
    /// APIC moment matrix `B_p`, entry (a, b), m^2/s (`C_p = B_p D_p^-1`).
    pub affine: [[&'a mut [Real]; D]; D],
    /// Transported scalars (heat: temperature, K; diffusion: concentration potential), each
    /// value, grid value at the particle, then source (empty when not declared).
    pub scalar: [[&'a mut [Real]; 3]; 2],
    /// Axisymmetric only: the hoop stretch `F_thetatheta - 1 = r / r_0 - 1`.
    pub hoop: &'a mut [Real],
    /// cpGIMP only: each particle's domain stretch per axis for the current substep.
    pub stretch: [&'a mut [Real]; D],
    /// Declared plasticity only: the plastic models' history value (see
    /// [`crate::ParticlesView::plastic`]).
    pub plastic: &'a mut [Real],
    pub material: &'a mut [u32],
    pub status: &'a mut [u32],
}

/// The columns MUSL's re-map reads of a window of particles, read only: what a tile of the
/// parallel particle pass reads of the particles another item updated (`world::parallel`,
/// [`crate::phases::g2p::remap`]). Optional columns not reserved are empty.
pub(crate) struct RemapCols<'a, const D: usize> {
    pub x_start: [&'a [Real]; D],
    pub v: [&'a [Real]; D],
    pub mass: &'a [Real],
    pub affine: [[&'a [Real]; D]; D],
    pub stretch: [&'a [Real]; D],
    pub status: &'a [u32],
}

impl<'a, const D: usize> RemapCols<'a, D> {
    /// The columns of `p` with its current positions as `x_start`: what XPIC's projection
    /// reads before the particle update ([`crate::phases::xpic`]).
    pub fn at_current(p: &'a ParticleCols<'_, D>) -> Self {
        RemapCols {
            x_start: p.x.each_ref().map(|c| &**c),
            v: p.v.each_ref().map(|c| &**c),
            mass: p.mass,
            affine: p.affine.each_ref().map(|r| r.each_ref().map(|c| &**c)),
            stretch: p.stretch.each_ref().map(|c| &**c),
            status: p.status,
        }
    }

    /// The particles `window` of the shared particle region, particle `window.start` their
    /// first value (the columns where [`ParticleCols::carve_window`] finds them: the layout's
    /// column order).
    ///
    /// # Safety
    /// No view that may change these particles is alive while this one is.
    pub unsafe fn read(region: &Shared<'a, u8>, layout: &Layout, window: Range<usize>) -> Self {
        let (rb, ub, n) = (
            layout.real_column_bytes,
            layout.u32_column_bytes,
            layout.padded_capacity,
        );
        let (start, end) = (window.start.min(n), window.end.min(n));
        let size = size_of::<Real>();
        let real = |column: usize| -> &'a [Real] {
            let at = column * rb;
            // SAFETY: column `column`'s bytes, cut to the window; the caller keeps writers
            // away.
            bytemuck::cast_slice(unsafe { region.read(at + start * size..at + end * size) })
        };
        let group = |g: crate::layout::ColumnGroup, k: usize| -> &'a [Real] {
            if k < g.count {
                real(g.first + k)
            } else {
                &[]
            }
        };
        // The u32 columns follow the Real ones: material, then status.
        let at = layout.particle_real_columns * rb + ub;
        // SAFETY: as for `real`.
        let status = unsafe { region.read(at + start * 4..at + end * 4) };
        RemapCols {
            x_start: core::array::from_fn(|a| group(layout.x_start, a)),
            v: core::array::from_fn(|a| real(D + a)),
            mass: real(2 * D),
            affine: core::array::from_fn(|a| {
                core::array::from_fn(|b| group(layout.affine, a * D + b))
            }),
            stretch: core::array::from_fn(|a| group(layout.stretch, a)),
            status: bytemuck::cast_slice(status),
        }
    }
}

/// Hands out consecutive column slices of a byte region, each cut to a window of its values
/// (all of them, or the part of each column one item of a parallel pass works on).
pub(crate) struct Carver<'a> {
    region: Shared<'a, u8>,
    at: usize,
    window: Range<usize>,
}

impl<'a> Carver<'a> {
    /// A carver of the values `window` of each column of `region`.
    ///
    /// # Safety
    /// No other slice of `region` that overlaps these windows is alive while the columns
    /// carved are (the items of a parallel pass take disjoint windows).
    pub unsafe fn window(region: &Shared<'a, u8>, window: Range<usize>) -> Self {
        Carver {
            region: region.clone(),
            at: 0,
            window,
        }
    }

    /// Passes over the next `bytes` bytes (a column the view leaves out).
    pub fn skip(&mut self, bytes: usize) {
        self.at += bytes;
    }

    /// The next `bytes` bytes viewed as `len` values of `T` (`bytes` >= len * size_of T), cut
    /// to the carver's window.
    pub fn take<T: bytemuck::Pod>(&mut self, bytes: usize, len: usize) -> &'a mut [T] {
        let (at, size) = (self.at, core::mem::size_of::<T>());
        self.at += bytes;
        let (start, end) = (self.window.start.min(len), self.window.end.min(len));
        // SAFETY: every column is its own `bytes` of the region, so the windows of distinct
        // columns are disjoint; `Carver::window`'s caller keeps the windows of concurrent
        // carvers apart.
        let col = unsafe { self.region.window(at + start * size..at + end * size) };
        // Columns start on 64-byte boundaries of a 64-byte aligned buffer (checked at init and
        // open) and windows on a value's boundary, so this cast never fails.
        bytemuck::cast_slice_mut(col)
    }
}

impl<const D: usize> ParticleCols<'_, D> {
    /// Whether the particles carry their domains' stretch (cpGIMP, whose domains stretch
    /// with the deformation; every other family's domain keeps its size).
    #[inline(always)]
    pub fn stretches(&self) -> bool {
        !self.stretch[0].is_empty()
    }

    /// The domain stretch columns to read (empty but for cpGIMP): what the stencils take.
    #[inline(always)]
    pub fn stretch_columns(&self) -> [&[Real]; D] {
        self.stretch.each_ref().map(|c| &**c)
    }

    /// The stretch of particle `i`'s domain per axis (cpGIMP); 1 for every other family.
    #[inline(always)]
    pub fn domain_stretch(&self, i: usize) -> [Real; D] {
        core::array::from_fn(|a| self.stretch[a].get(i).copied().unwrap_or(1.0))
    }

    /// cpGIMP: freezes each particle's domain stretch for the substep, from its deformation
    /// at the substep's start, so that every pass of the substep weighs a particle with the
    /// same domain (the scatter of mass and the gather of accelerations must agree, or
    /// momentum is not conserved; USF updates F between them). Nothing for other families.
    pub fn freeze_domain_stretch(&mut self, count: usize) {
        if !self.stretches() {
            return;
        }
        for i in 0..count {
            let h = &self.h;
            let e =
                crate::shape::domain_stretch::<D>(|a, b| h[a][b].get(i).copied().unwrap_or(0.0));
            for a in 0..D {
                if let Some(v) = self.stretch[a].get_mut(i) {
                    *v = e[a];
                }
            }
        }
    }
}

impl<'a, const D: usize> ParticleCols<'a, D> {
    /// The particles `window` of the shared particle region: the columns one item of a
    /// parallel pass works on, particle `window.start` their first value.
    ///
    /// # Safety
    /// No other view of the region that overlaps these particles is alive while this one is.
    pub unsafe fn carve_window(
        region: &Shared<'a, u8>,
        layout: &Layout,
        window: Range<usize>,
    ) -> Self {
        // SAFETY: as required of the caller.
        let mut c = unsafe { Carver::window(region, window) };
        let (rb, ub, n) = (
            layout.real_column_bytes,
            layout.u32_column_bytes,
            layout.padded_capacity,
        );
        let ns = stress_components(D);
        // An optional group's columns, or empty slices when it is not reserved.
        let group = |c: &mut Carver<'a>, reserved: bool| -> &'a mut [Real] {
            if reserved {
                c.take(rb, n)
            } else {
                &mut [][..]
            }
        };
        let x = core::array::from_fn(|_| c.take(rb, n));
        let v = core::array::from_fn(|_| c.take(rb, n));
        let mass = c.take(rb, n);
        // V0 is read only by the transported scalars (current volume `J V0`); the mechanics
        // stores stress as tau/rho0 (E3) and does not need it.
        let vol0 = c.take(rb, n);
        let h = core::array::from_fn(|_| core::array::from_fn(|_| c.take(rb, n)));
        let tau = core::array::from_fn(|i| if i < ns { c.take(rb, n) } else { &mut [][..] });
        let x_low = core::array::from_fn(|_| c.take(rb, n));
        let x_start = core::array::from_fn(|_| group(&mut c, layout.x_start.count > 0));
        let force = core::array::from_fn(|_| group(&mut c, layout.force.count > 0));
        let damping = core::array::from_fn(|_| group(&mut c, layout.damping.count > 0));
        let affine = core::array::from_fn(|_| {
            core::array::from_fn(|_| group(&mut c, layout.affine.count > 0))
        });
        let scalar = core::array::from_fn(|f| {
            let g = layout.scalar[f];
            core::array::from_fn(|k| group(&mut c, k < g.count))
        });
        let hoop = group(&mut c, layout.hoop.count > 0);
        let stretch = core::array::from_fn(|_| group(&mut c, layout.stretch.count > 0));
        let plastic = group(&mut c, layout.plastic.count > 0);
        let material = c.take(ub, n);
        let status = c.take(ub, n);
        ParticleCols {
            x,
            v,
            mass,
            vol0,
            h,
            tau,
            x_low,
            x_start,
            force,
            damping,
            affine,
            scalar,
            hoop,
            stretch,
            plastic,
            material,
            status,
        }
    }
}

/// What one call of [`crate::World::step`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Substeps taken (>= 1).
    pub substeps: u32,
    /// Length of the last substep, s: every substep's, unless a hardening material made the
    /// step split its rest again into shorter ones ([`crate::World::step`]).
    pub substep_dt: Real,
    /// Particle-substeps in which a particle reached a stick or slip wall and was stopped there.
    pub stopped: u32,
    /// Particles that crossed an open face and left the simulation.
    pub escaped: u32,
    /// Particles frozen in this call: their state turned non-finite, their F inverted, or
    /// they ran away (see `runaway`). Nonzero means the step went bad somewhere
    /// ([`StepReport::went_bad`]).
    pub frozen: u32,
    /// Of the frozen, those that ran away: their volume ratio `J` left
    /// `[1 / max_volume_ratio, max_volume_ratio]` ([`crate::WorldDef::max_volume_ratio`]), their
    /// speed (the sum of its components' magnitudes) passed
    /// [`crate::Resolvable::speed`], or their hardening (snow) took their wave
    /// speed past what the substep resolves (a Courant number above 1). The sign of an
    /// unstable scheme or a time step too long for the scene.
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

    /// This report as a parallel item's part of one ([`crate::cut::Partial`]).
    pub(crate) fn to_partial(&self) -> crate::cut::Partial {
        let mut first_frozen = [0; 8];
        first_frozen[..self.first_frozen.len()].copy_from_slice(&self.first_frozen);
        crate::cut::Partial {
            stopped: self.stopped,
            escaped: self.escaped,
            frozen: self.frozen,
            runaway: self.runaway,
            first_count: self.first_frozen.len() as u32,
            first_frozen,
            _pad: [0; 3],
        }
    }

    /// Adds what one parallel pass did, its items' parts absorbed into one
    /// ([`crate::cut::Partial::absorb`], the one merge of parts): the counts, and the pass's
    /// frozen ids after those of the passes before, as one worker notes them.
    pub(crate) fn merge(&mut self, pass: &crate::cut::Partial) {
        self.stopped += pass.stopped;
        self.escaped += pass.escaped;
        self.frozen += pass.frozen;
        self.runaway += pass.runaway;
        let n = (pass.first_count as usize).min(pass.first_frozen.len());
        for &id in &pass.first_frozen[..n] {
            // A full list only means more than 8 froze; the count says how many.
            let _ = self.first_frozen.push(id);
        }
    }

    /// Whether a particle froze in this call (non-finite state, inverted F or runaway volume):
    /// the flag a host checks after each step. Frozen particles leave the simulation; the
    /// rest of the world goes on.
    pub fn went_bad(&self) -> bool {
        self.frozen > 0
    }
}

/// The least plastic history of the active particles of material `m` (`status`'s length;
/// `material` and `plastic` at least as long), `Real::INFINITY` where it has none: the
/// material's fastest particle where its wave speed falls as the history grows
/// ([`crate::material::Model::wave_speed`]). A NaN history is passed over, as `max` passes over
/// a NaN speed. Lane-wise minima over chunks of 16 particles (loops the compiler vectorises),
/// then the tail: the same minimum as a particle-by-particle scan. Run in the step's
/// instruction set (`world::passes`).
#[inline(always)]
pub(crate) fn least_plastic(plastic: &[Real], material: &[u32], status: &[u32], m: u32) -> Real {
    let n = status.len();
    const L: usize = 16;
    let mut lanes = [Real::INFINITY; L];
    let full = n - n % L;
    for from in (0..full).step_by(L) {
        let p: &[Real; L] = plastic[from..from + L].try_into().unwrap_or(&[0.0; L]);
        let id: &[u32; L] = material[from..from + L].try_into().unwrap_or(&[0; L]);
        let st: &[u32; L] = status[from..from + L].try_into().unwrap_or(&[0; L]);
        for l in 0..L {
            lanes[l] = if st[l] == ACTIVE && id[l] == m && p[l] < lanes[l] {
                p[l]
            } else {
                lanes[l]
            };
        }
    }
    let mut least = lanes
        .iter()
        .fold(Real::INFINITY, |a, &p| if p < a { p } else { a });
    for i in full..n {
        if status[i] == ACTIVE && material[i] == m && plastic[i] < least {
            least = plastic[i];
        }
    }
    least
}

/// The largest `|v|^2` of the active particles (`status`'s length; `v[a]` at least as long for
/// `a < d`), in f64: a speed near f32's range (1e19 m/s and up) would overflow `v^2` in f32 and
/// make the stable step 0, which no step could take, although the true step is representable.
/// Lane-wise maxima over chunks of 8 particles (loops the compiler vectorises), then the tail:
/// the same maximum as a particle-by-particle scan. Run in the step's instruction set
/// (`world::passes`).
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Parts absorbed in any order keep the least 8 frozen ids in order and every count: the
    /// report one worker notes, updating the particles in order.
    #[test]
    fn absorbed_parts_keep_the_least_frozen_ids_in_order() {
        use crate::cut::Partial;
        // Parts of particles 0..100, 100..200, ..: part k froze ids (3 j + k) % 40 + j of
        // its own, in order.
        let ids = |k: u32| (0..(k % 5 + 3)).map(move |j| ((3 * j + k) % 40 + j, j % 2 == 0));
        let part = |k: u32| {
            let mut r = StepReport::default();
            for (id, runaway) in ids(k) {
                r.note_frozen(id, runaway);
            }
            r.stopped = k;
            r.to_partial()
        };
        let mut one_worker = StepReport::default();
        for k in 0..6 {
            for (id, runaway) in ids(k) {
                one_worker.note_frozen(k * 100 + id, runaway);
            }
            one_worker.stopped += k;
        }
        for order in [[5, 4, 3, 2, 1, 0], [2, 0, 5, 1, 4, 3], [0, 1, 2, 3, 4, 5]] {
            let mut acc = Partial::default();
            for k in order {
                acc.absorb(&part(k), k * 100);
            }
            let mut merged = StepReport::default();
            merged.merge(&acc);
            assert_eq!(merged, one_worker, "{order:?}");
        }
    }

    /// [`RemapCols::read`] finds each column where [`ParticleCols::carve_window`] does, for
    /// every optional group a definition may reserve.
    #[test]
    fn remap_columns_are_the_views_columns() {
        use crate::{ShapeFunction, Transfer, UpdateOrder, WorldDef};
        for (shape, transfer) in [
            (ShapeFunction::Gimp, Transfer::Flip),
            (ShapeFunction::CpGimp, Transfer::Apic),
            (ShapeFunction::CubicBspline, Transfer::Apic),
        ] {
            let def = WorldDef {
                particle_capacity: 100,
                update_order: UpdateOrder::Musl,
                shape,
                transfer,
                ..WorldDef::DEFAULT
            };
            let layout = Layout::of(&def);
            // 8-byte aligned, as the columns' casts need.
            let mut words = [0u64; 1 << 13];
            let region = Shared::new(bytemuck::cast_slice_mut::<u64, u8>(&mut words));
            for window in [0..32, 32..96, 64..128] {
                // SAFETY: one view at a time, both only compared.
                let cols =
                    unsafe { ParticleCols::<2>::carve_window(&region, &layout, window.clone()) };
                let (x_start, v, mass) = (
                    cols.x_start[1].as_ptr(),
                    cols.v[1].as_ptr(),
                    cols.mass.as_ptr(),
                );
                let (affine, stretch) = (cols.affine[1][0].as_ptr(), cols.stretch[1].as_ptr());
                let (status, len) = (cols.status.as_ptr(), cols.status.len());
                let reserved = (!cols.affine[1][0].is_empty(), !cols.stretch[1].is_empty());
                // SAFETY: as above.
                let r = unsafe { RemapCols::<2>::read(&region, &layout, window) };
                assert_eq!(
                    (r.x_start[1].as_ptr(), r.v[1].as_ptr(), r.mass.as_ptr()),
                    (x_start, v, mass)
                );
                assert_eq!((r.status.as_ptr(), r.status.len()), (status, len));
                assert_eq!(
                    (!r.affine[1][0].is_empty(), !r.stretch[1].is_empty()),
                    reserved
                );
                if reserved.0 {
                    assert_eq!(r.affine[1][0].as_ptr(), affine);
                }
                if reserved.1 {
                    assert_eq!(r.stretch[1].as_ptr(), stretch);
                }
            }
        }
    }

    /// [`least_plastic`] finds what a particle-by-particle scan finds, over every length to 48
    /// (full chunks and tails), with three materials, inactive particles and NaN histories.
    #[test]
    fn least_plastic_is_the_least_of_a_scan() {
        let mut state = 5u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as u32
        };
        let mut plastic = [0.0 as Real; 48];
        let (mut material, mut status) = ([0u32; 48], [ACTIVE; 48]);
        for i in 0..48 {
            plastic[i] = match next() % 8 {
                0 => Real::NAN,
                k => (next() % 1000) as Real * 1.0e-3 - 0.5 + k as Real * 1.0e-4,
            };
            material[i] = next() % 3;
            status[i] = if next() % 4 == 0 { FROZEN } else { ACTIVE };
        }
        for n in 0..=48 {
            for m in 0..4 {
                let mut want = Real::INFINITY;
                for i in 0..n {
                    if status[i] == ACTIVE && material[i] == m && plastic[i] < want {
                        want = plastic[i];
                    }
                }
                let got = least_plastic(&plastic, &material, &status[..n], m);
                assert_eq!(got.to_bits(), want.to_bits(), "{n} {m}");
            }
        }
    }
}
