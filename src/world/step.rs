//! Stepping: [`World::step`], the dispatch to the compiled instance of the dimension and
//! shape function, and `Substep`, the only place the phase order of a substep is written.

use super::parallel::{Columns, GridPasses};
use super::passes::{Passes, Scan};
use super::{StepReport, World};
use crate::def::{Transfer, UpdateOrder, WorldDef};
use crate::effects::damping::NodalDamping;
use crate::grid::Geom;
use crate::layout::{ColliderImpulse, ColliderRecord, Layout, MaterialRecord, TractionRecord};
use crate::math::{ceil, exp_m1};
use crate::particles::FROZEN;
use crate::phases::p2g::{Adds, Mode};
use crate::phases::{grid_update, xpic, Ctx};
use crate::shape::Shape1D;
use crate::simd::lanes::width;
use crate::simd::Simd;
use crate::tasks::{Serial, TaskSystem};
use crate::{Error, Real};
use core::mem::size_of;

/// Nodes lighter than this fraction of the lightest particle are treated as empty: epsilon^2,
/// which only keeps the division `p_i / m_i` away from denormals. A larger cutoff does harm: a
/// node that carries a sliver of a particle still has a well-defined velocity (its `p_i / m_i`
/// is the particle's velocity), and zeroing it puts a spurious jump next to its neighbours
/// (seen as stress in a rigidly translating block with linear shapes in f64).
const NODAL_MASS_CUTOFF: Real = Real::EPSILON * Real::EPSILON;

impl<'a> World<'a> {
    /// Advances the world by `dt` seconds. A `dt` above [`World::stable_dt`] (evaluated at the
    /// start of the call) is taken in equal substeps that are each stable (E89). In a world whose
    /// material hardens (snow, with plasticity declared) the stable step is evaluated again
    /// before each substep, and where the hardening has outgrown the substep the rest of the
    /// step is split again into shorter equal substeps, within
    /// [`WorldDef::max_substeps`] in all; a particle whose hardened wave speed even the
    /// shortest substep the limit allows cannot resolve (a Courant number above 1) freezes
    /// and is reported as runaway.
    pub fn step(&mut self, dt: Real) -> Result<StepReport, Error> {
        self.step_on(dt, Simd::Detect, &Serial)
    }

    /// [`World::step`] on the host's task system (see [`crate::tasks`]): every pass of the
    /// step is cut into items the workers share. The state after the step is bit-identical
    /// to [`World::step`]'s, for any number of workers and however the system spreads the
    /// items. A world of fewer than [`crate::PARALLEL_FROM`] particles steps on the calling
    /// thread, as [`World::step`] does, handing the system nothing. Fails with
    /// [`Error::InvalidLimit`] (changing nothing) where the system has more workers than the
    /// definition's [`WorldDef::workers`].
    pub fn step_with_tasks(
        &mut self,
        dt: Real,
        tasks: &dyn TaskSystem,
    ) -> Result<StepReport, Error> {
        let shares = self.particle_count() >= crate::PARALLEL_FROM;
        self.step_sharing(dt, Simd::Detect, tasks, shares)
    }

    /// [`World::step`] with a chosen instruction set (see [`crate::simd`]). Not part of the
    /// stable API: tests use it to show that both paths give bit-identical state.
    #[doc(hidden)]
    pub fn step_with_simd(&mut self, dt: Real, simd: Simd) -> Result<StepReport, Error> {
        self.step_on(dt, simd, &Serial)
    }

    /// [`World::step_with_tasks`] with a chosen instruction set, on `tasks` at any particle
    /// count. Not part of the stable API.
    #[doc(hidden)]
    pub fn step_on(
        &mut self,
        dt: Real,
        simd: Simd,
        tasks: &dyn TaskSystem,
    ) -> Result<StepReport, Error> {
        self.step_sharing(dt, simd, tasks, true)
    }

    /// The step on `tasks`, which must fit the definition's workers, and on the calling thread
    /// unless `shares`.
    fn step_sharing(
        &mut self,
        dt: Real,
        simd: Simd,
        tasks: &dyn TaskSystem,
        shares: bool,
    ) -> Result<StepReport, Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::InvalidTimeStep);
        }
        let def = self.def();
        if !(1..=def.workers as usize).contains(&tasks.worker_count()) {
            return Err(Error::InvalidLimit);
        }
        let tasks: &dyn TaskSystem = if shares { tasks } else { &Serial };
        let scan = Scan {
            tasks,
            workers: tasks.worker_count(),
        };
        let limits = self.limits(dt, simd, &scan);
        let ratio = dt / limits.stable_dt;
        let substeps = if ratio <= 1.0 { 1.0 } else { ceil(ratio) };
        // NaN-safe: a NaN ratio fails `<=`.
        let within = substeps <= def.max_substeps as Real;
        if !within {
            return Err(Error::SubstepLimit);
        }
        let mut plan = Plan {
            count: substeps as u32,
            dt: dt / substeps,
            first: 0,
            start: 0.0,
            other_damping: limits.other_damping,
        };
        let mut report = StepReport::default();
        let fx = def.effects;
        self.start_collider_impulses(dt);
        let hardening = fx.plasticity && self.read().materials_harden();
        let time0 = self.time();
        let mut k = 0;
        while k < plan.count {
            if hardening && k > 0 {
                self.replan(&mut plan, k, dt, (simd, &scan), &mut report);
            }
            let time = time0 + plan.start + (k - plan.first) as f64 * plan.dt as f64;
            if let Some(feedback) = fx.damping.and_then(|d| d.feedback) {
                // The thermostat's alpha is kept to what a substep of this length integrates
                // stably besides the other damping (`alpha dt <= cfl`, as `stable_dt` keeps
                // the other damping): it adapts to the substep and never sets its length,
                // whatever its gain.
                let room = (def.cfl as f64 / plan.dt as f64 - plan.other_damping).max(0.0);
                self.update_feedback(&feedback, time, plan.dt, room);
            }
            let mut substep = Substep {
                report: &mut report,
            };
            self.dispatch((plan.dt, time), &mut substep, simd, tasks);
            if fx.collider_capacity > 0 {
                self.drive_colliders(time + plan.dt as f64, plan.dt, def.gravity);
                self.put_out_of_colliders(time + plan.dt as f64);
            }
            k += 1;
        }
        report.substeps = plan.count;
        report.substep_dt = plan.dt;
        let end = self.time() + dt as f64;
        self.move_colliders(end);
        let h = self.header_mut();
        h.time = end;
        h.step_count = h.step_count.saturating_add(1);
        Ok(report)
    }

    /// The stable step's limits for a step of `dt`, the colliders' speed among them (E88).
    fn limits(&self, dt: Real, simd: Simd, scan: &Scan<'_>) -> super::query::TimeStepLimits {
        let w = self.read();
        let mut limits = w.time_step_limits(simd, scan);
        limits.stable_dt = limits.stable_dt.min(w.collider_substep(dt));
        limits
    }

    /// Before substep `k` of a step of `dt` in a world whose material hardens: where the stable
    /// step has fallen below the planned substep, splits the rest of the step into equal
    /// substeps again, at most what [`WorldDef::max_substeps`] leaves; if even those are
    /// longer than the stable step, freezes the particles whose hardened wave speed they do
    /// not resolve (a Courant number above 1), as runaway.
    fn replan(
        &mut self,
        plan: &mut Plan,
        k: u32,
        dt: Real,
        (simd, scan): (Simd, &Scan<'_>),
        report: &mut StepReport,
    ) {
        let limits = self.limits(dt, simd, scan);
        if limits.stable_dt >= plan.dt {
            return;
        }
        let start = plan.start + (k - plan.first) as f64 * plan.dt as f64;
        let rest = dt as f64 - start;
        let room = self.def().max_substeps - k;
        // NaN-safe: a stable step of 0 asks for infinitely many, clamped to the room.
        let need = libm::ceil(rest / limits.stable_dt as f64).clamp(1.0, room as f64) as u32;
        *plan = Plan {
            count: k + need,
            dt: (rest / need as f64) as Real,
            first: k,
            start,
            other_damping: limits.other_damping,
        };
        if limits.stable_dt < plan.dt {
            let limit = self.def().cell_size as f64 / plan.dt as f64;
            self.freeze_hardened(limit, report);
        }
    }

    /// Freezes every active particle whose material hardens and whose hardened wave speed is
    /// above `limit` (m/s), as the step freezes a runaway particle: its velocity zeroed, its
    /// other state kept, and reported.
    fn freeze_hardened(&mut self, limit: f64, report: &mut StepReport) {
        let def = self.def();
        let layout = Layout::of(&def);
        let n = self.particle_count();
        // 64 particles at a time: which to freeze, read from the world, then written.
        for from in (0..n).step_by(64) {
            let to = (from + 64).min(n);
            let w = self.read();
            let freeze = (from..to).fold(0u64, |bits, i| {
                bits | ((w.hardened_past(&layout, i, limit) as u64) << (i - from))
            });
            for i in (from..to).filter(|i| freeze >> (i - from) & 1 == 1) {
                self.u32_col_mut(&layout, crate::layout::col::STATUS, n)[i] = FROZEN;
                for a in 0..layout.d {
                    self.real_col_mut(&layout, crate::layout::col::v(layout.d, a), n)[i] = 0.0;
                }
                report.note_frozen(i as u32, true);
            }
        }
    }

    /// Runs `kernel` once on the world's columns, dispatching once on (dimension, shape
    /// function) to the monomorphised instance, with the instruction set `simd` picks.
    fn dispatch(
        &mut self,
        (dt, time): (Real, f64),
        kernel: &mut impl Kernel,
        simd: Simd,
        tasks: &dyn TaskSystem,
    ) {
        let def = self.def();
        let layout = Layout::of(&def);
        let run = (dt, time, tasks);
        crate::shape::with_form!(&def, shape => {
            self.run::<D, K, _, { width(D) }>(shape, run, &def, &layout, kernel, simd)
        })
    }

    /// Carves the columns and the step context of a substep of length `dt` starting at `time`,
    /// then runs `kernel` on them.
    fn run<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: S,
        (dt, time, tasks): (Real, f64, &dyn TaskSystem),
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
        let n_colliders = self.header().collider_count as usize;
        let n_samples = self.header().sdf_count as usize;
        let (head, rest) = self.buf.split_at_mut(layout.particle_offset);
        let (head, impulses) = head.split_at_mut(layout.impulses_offset);
        let (impulses, sdf) = impulses.split_at_mut(layout.sdf_offset - layout.impulses_offset);
        let impulses: &mut [ColliderImpulse] =
            bytemuck::cast_slice_mut(&mut impulses[..n_colliders * size_of::<ColliderImpulse>()]);
        let sdf: &[Real] = bytemuck::cast_slice(&sdf[..n_samples * size_of::<Real>()]);
        let (pbytes, rest) = rest.split_at_mut(layout.grid_offset - layout.particle_offset);
        let (gbytes, scratch) = rest.split_at_mut(layout.scratch_offset - layout.grid_offset);
        let mat_start = layout.materials_offset;
        let materials: &[MaterialRecord] = bytemuck::cast_slice(
            &head[mat_start..mat_start + n_materials * size_of::<MaterialRecord>()],
        );
        let trac_start = layout.tractions_offset;
        let tractions: &[TractionRecord] = bytemuck::cast_slice(
            &head[trac_start..trac_start + n_tractions * size_of::<TractionRecord>()],
        );
        let col_start = layout.colliders_offset;
        let colliders: &[ColliderRecord] = bytemuck::cast_slice(
            &head[col_start..col_start + n_colliders * size_of::<ColliderRecord>()],
        );
        let mut cols = Columns::<D>::new(pbytes, gbytes, scratch, impulses, layout, tasks);
        let fx = &def.effects;
        let body_scale = fx.body_force_scale.at(time);
        let body = fx.body_force * body_scale;
        let gradient = fx.body_force_gradient;
        // The grid rate (thermostat included) acts in the particle update or on the force.
        let (alpha_g, alpha_p, nodal_damping) = match fx.damping {
            Some(d) => {
                let grid = d.grid.at(time) + feedback_alpha;
                let nodal = d.on_nodes().then_some(NodalDamping {
                    alpha: if d.grid_on_force { grid } else { 0.0 },
                    zones: d.zones,
                    zone_count: d.zone_count as usize,
                });
                let on_particles = if d.grid_on_force { 0.0 } else { grid };
                (on_particles, d.particle.at(time), nodal)
            }
            None => (0.0, 0.0, None),
        };
        let geom = Geom::<D>::new(def);
        let active = cols.node_box::<K, S>(simd, &geom, count);
        let ctx = Ctx {
            geom,
            active,
            dt,
            order: def.update_order,
            apic: def.transfer.is_affine(),
            mls: def.transfer == Transfer::Mls,
            particle_velocity: def.transfer == Transfer::FlipParticleVelocity,
            momentum: def.transfer == Transfer::FlipMomentum,
            series: def.transfer.series(),
            forces: fx.particle_forces,
            damp: fx.damping.is_some_and(|d| d.on_particles()),
            gravity: core::array::from_fn(|a| def.gravity[a] + body[a]),
            body_gradient: (0..D)
                .any(|a| (0..D).any(|b| gradient[a][b] != 0.0))
                .then(|| {
                    core::array::from_fn(|a| core::array::from_fn(|b| gradient[a][b] * body_scale))
                }),
            beta: def.flip_beta * (1.0 + exp_m1(-def.pic_rate * dt)),
            alpha_g,
            alpha_p,
            nodal_damping,
            half_width: def.cell_size / (2 * def.particles_per_cell) as Real,
            contact_band: def.shape.grid_function_reach() as Real * def.cell_size,
            particles: count,
            exp_terms: def.exp_terms,
            jm1_band: [1.0 / def.max_volume_ratio - 1.0, def.max_volume_ratio - 1.0],
            speed_scale: (Real::MAX as f64 / def.resolvable().speed) as Real,
            mass_cutoff: (NODAL_MASS_CUTOFF as f64 * min_mass) as Real,
            materials,
            tractions,
            colliders,
            sdf,
            time,
            traction_scales: fx.traction_schedules.each_ref().map(|s| s.at(time)),
            transport: [fx.heat, fx.diffusion],
            eigenstrain: [
                fx.heat.is_some() && materials.iter().any(|m| m.thermal_expansion != 0.0),
                fx.diffusion.is_some() && materials.iter().any(|m| m.swelling != 0.0),
            ],
            plastic: fx.plasticity,
            viscous: materials
                .iter()
                .any(|m| m.viscosity != 0.0 || m.bulk_viscosity != 0.0),
            fluid: materials.iter().any(crate::phases::volume::relaxes),
        };
        run_kernel::<D, K, S, W>(kernel, simd, &shape, &ctx, &mut cols, count);
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
        self.dispatch((dt, time), &mut run, Simd::Detect, &Serial);
        Ok(run.report)
    }
}

/// The substeps of a step: `count` in all, those from `first` on of length `dt`, the first of
/// them starting `start` seconds into the step; the damping rates besides the thermostat's
/// that the last stable step allowed for.
struct Plan {
    count: u32,
    dt: Real,
    first: u32,
    start: f64,
    other_damping: f64,
}

/// A computation on the world's columns with the dimension and shape function fixed at compile
/// time; `World::dispatch` picks the form once per call. `I` is the instruction set each
/// pass runs in: a body calls every pass through it ([`Passes`]).
trait Kernel {
    fn body<I: Passes, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        shape: &S,
        ctx: &Ctx<'_, D>,
        cols: &mut Columns<'_, D>,
        count: usize,
    );
}

/// Runs `kernel` with its passes in the instance `simd` picks on this CPU (see
/// [`crate::simd`]).
fn run_kernel<const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
    kernel: &mut impl Kernel,
    simd: Simd,
    shape: &S,
    ctx: &Ctx<'_, D>,
    cols: &mut Columns<'_, D>,
    count: usize,
) {
    crate::simd::with_instance!(simd, form (D, K), I => {
        kernel.body::<I, D, K, S, W>(shape, ctx, cols, count)
    });
}

/// One substep: the phase order of E12-E32 for the chosen update order, the momentum approach
/// (E73-E77, [`crate::phases::momentum`]) a branch of it. This is the only place the order of
/// the phases is written down:
///
/// ```text
/// USL : scatter(m, p, f) -> v -> tractions -> a -> particles(x, v, stress)
/// MUSL: scatter(m, p, f) -> v -> tractions -> a -> particles(x, v; remap p) -> v' -> stress
/// XPIC(k), FMPM(k): after a, k - 1 times project(gather v*, scatter m v) -> v*
/// USF : scatter(m, p) -> v -> v with walls -> stress -> scatter(f) -> tractions -> a -> particles
/// momentum approach: m and p first, masses mirrored at the walls, then its own scatter(f)
/// ```
///
/// The update order, the transfer and the declared effects are values of the context
/// ([`Ctx`]): one compiled substep serves them all, and the passes skip an undeclared effect's
/// work once per chunk of lanes.
struct Substep<'r> {
    report: &'r mut StepReport,
}

impl Kernel for Substep<'_> {
    fn body<I: Passes, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        s: &S,
        ctx: &Ctx<'_, D>,
        cols: &mut Columns<'_, D>,
        count: usize,
    ) {
        let report = &mut *self.report;
        cols.full().0.freeze_domain_stretch(count);
        // Heat and diffusion first, with the particles where the substep starts.
        for (f, t) in ctx.transport.iter().enumerate() {
            if let Some(t) = t {
                cols.transport::<I, K, S, W>(s, ctx, count, f, t);
            }
        }
        // The fluids' volumes toward the space they fill, with the grid as scratch (E97).
        if ctx.fluid {
            cols.relax_volumes::<I, K, S, W>(s, ctx, count);
        }
        grid_update::reset(ctx, &mut GridPasses { cols, ctx });
        let (usf, musl) = (
            ctx.order == UpdateOrder::Usf,
            ctx.order == UpdateOrder::Musl,
        );
        // The masses and momenta, and with them the force unless USF's stress or the momentum
        // approach's weights need the nodal velocities (or masses) first.
        let with_force = !(usf || ctx.momentum);
        let first = if with_force {
            Mode::All
        } else {
            Mode::MassMomentum
        };
        cols.scatter::<I, K, S, W>(s, ctx, count, Adds::of(first, ctx));
        grid_update::velocity(ctx, &mut GridPasses { cols, ctx });
        if ctx.momentum {
            // The momentum approach's weights read the masses past the walls as mirrored.
            crate::phases::momentum::mirror_masses(ctx, &mut cols.grid());
        }
        if usf {
            // USF: the stress from the velocities the walls leave, before the force.
            grid_update::constrained_velocity(ctx, &mut GridPasses { cols, ctx });
            cols.stress::<I, K, S, W>(s, ctx, count, report);
        }
        if !with_force {
            // The momentum approach's force scatter is its own (E75, `phases::momentum`).
            cols.scatter::<I, K, S, W>(s, ctx, count, Adds::of(Mode::Force, ctx));
        }
        {
            let (p, mut g) = cols.full();
            crate::phases::tractions::tractions(s, ctx, &p, count, &mut g);
        }
        grid_update::acceleration(ctx, &mut GridPasses { cols, ctx });
        // XPIC(k) and FMPM(k): the series of k - 1 projections (E98-E101).
        if let Some((k, _)) = ctx.series.filter(|&(k, fmpm)| fmpm || k >= 2) {
            xpic::start(ctx, &mut GridPasses { cols, ctx });
            for r in 2..=k {
                cols.project::<I, K, S, W>(s, ctx, count, false);
                xpic::absorb(ctx, &mut GridPasses { cols, ctx }, r);
            }
            xpic::finish(ctx, &mut GridPasses { cols, ctx });
        }
        // USL also updates the stress here, MUSL scatters the new momenta to the remap
        // columns (see g2p::particles).
        cols.particles::<I, K, S, W>(s, ctx, count, report);
        if musl {
            // MUSL: the stress from the re-mapped velocities (FMPM(k): through its series).
            match ctx.series {
                Some((k, true)) if k >= 2 => {
                    xpic::restart(ctx, &mut GridPasses { cols, ctx });
                    for r in 2..=k {
                        cols.project::<I, K, S, W>(s, ctx, count, true);
                        xpic::absorb(ctx, &mut GridPasses { cols, ctx }, r);
                    }
                    xpic::into_remap(ctx, &mut GridPasses { cols, ctx });
                    grid_update::constrain_remapped(ctx, &mut GridPasses { cols, ctx });
                }
                _ => grid_update::remap_velocity(ctx, &mut GridPasses { cols, ctx }),
            }
            cols.stress::<I, K, S, W>(s, ctx, count, report);
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
    fn body<I: Passes, const D: usize, const K: usize, S: Shape1D<K>, const W: usize>(
        &mut self,
        s: &S,
        ctx: &Ctx<'_, D>,
        cols: &mut Columns<'_, D>,
        count: usize,
    ) {
        // A plain USL substep: FLIP, no damping, no particle forces.
        let ctx = &Ctx {
            order: UpdateOrder::Usl,
            apic: false,
            mls: false,
            particle_velocity: false,
            momentum: false,
            series: None,
            forces: false,
            damp: false,
            nodal_damping: None,
            ..*ctx
        };
        match self.phase {
            Phase::ResetGrid => grid_update::reset(ctx, &mut GridPasses { cols, ctx }),
            Phase::ParticleToGrid => {
                cols.full().0.freeze_domain_stretch(count);
                grid_update::reset(ctx, &mut GridPasses { cols, ctx });
                cols.scatter::<I, K, S, W>(s, ctx, count, Adds::of(Mode::All, ctx));
            }
            Phase::GridUpdate => {
                grid_update::velocity(ctx, &mut GridPasses { cols, ctx });
                grid_update::acceleration(ctx, &mut GridPasses { cols, ctx });
            }
            Phase::GridToParticle => cols.particles::<I, K, S, W>(s, ctx, count, &mut self.report),
        }
    }
}
