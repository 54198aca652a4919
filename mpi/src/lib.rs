//! One mpm-gimp scene split over MPI ranks by slabs along one axis, stepping bit for bit as
//! one world does.
//!
//! The scene is defined once, as a [`World`] of the whole domain that every rank builds
//! alike. [`Split::new`] cuts the grid's cell lines along the split axis into one slab per
//! rank, balanced on the particle counts of the scene as given, and cuts them again when a
//! rank comes to own a quarter more than the mean ([`Split::rebalance`]). A particle is owned
//! by the rank whose slab holds its cell along the axis.
//!
//! **Why the bits stay.** Within one world a node's sum is added in particle order, in
//! chunks of lanes counted from particle 0, with the lanes of a chunk that share a stencil's
//! first node summed in registers first ([`mpm_gimp::REACH_GROUP`]). A rank therefore holds
//! a full [`World`] (same definition, the whole grid) whose particles are whole groups of
//! [`REACH_GROUP`] consecutive ids of the scene, in the scene's order: the groups that hold
//! a particle it owns or a particle within the halo of its slab. Its chunks and blocks are
//! the scene's, and every node all of whose particles it holds gets the scene's sums, bit for
//! bit: the nodes its owned particles read, when the halo is wide enough
//! ([`halo_cells`]). Ghost nodes are never summed across ranks; ghost particles are.
//!
//! **Each substep** ([`Split::step`]): every rank steps its world by the same `dt` (at most
//! the scene's stable step, the minimum over ranks: exact); then each owner sends the whole
//! state of its particles (every column, history, stress, low part of the position, status)
//! to every other rank that holds their groups. A rank whose groups stay overwrites its
//! ghosts in place; one whose groups changed rebuilds its list in id order from what it
//! receives, its own particles included: particles that crossed a slab boundary migrate,
//! groups it no longer needs leave it. Ownership follows the positions after each substep;
//! ids stay the scene's. The
//! report ([`SplitReport`]) counts the owned particles that froze or escaped, summed over
//! the ranks (integers: exact); walls' stops and runaways are not counted yet.
//!
//! **A rank that dies or stalls** does not hang the others: every collective is started
//! immediate and polled; past [`Split::time_out`] (default [`DEFAULT_TIME_OUT`]) each rank
//! still running prints which exchange it waited for and aborts the job (`MPI_Abort`, exit
//! code [`TIME_OUT_EXIT_CODE`]). A started collective cannot be withdrawn, so the call does
//! not return an error instead. A message of the wrong size or content is
//! [`SplitError::Message`] on every rank.
//!
//! **Not supported** (refused by [`Split::new`] with [`SplitError::Unsupported`]):
//! colliders (their force and torque are float sums across ranks), tractions, damping (the
//! thermostat's feedback is a float sum; the rest is untested), heat and diffusion (their
//! grid solves reach further), fluids (the volume relaxation is a further scatter), periodic
//! faces on the split axis, and a least particle mass that differs between a rank's
//! particles and the scene's (the nodal mass cutoff follows it). A rank's grid is the whole
//! domain's (a box with ghost lines is a later step).

use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::request::{Request, Scope};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;
use mpm_gimp::{
    memory_requirements, Boundary, HeapBuffer, MaterialModel, ParticleState, Real, Removal,
    ShapeFunction, Transfer, UpdateOrder, World, WorldDef, WorldRef, REACH_GROUP,
};
use std::fmt;
use std::time::{Duration, Instant};

/// Real columns a [`ParticleState`] may give (3D with every effect), in the order of
/// [`ParticleState::real_columns`].
pub const REAL_COLUMNS: usize = ParticleState::REAL_COLUMNS;

/// Why a split could not be made or stepped. Every rank returns the same error.
#[derive(Debug, Clone, PartialEq)]
pub enum SplitError {
    /// The kernel refused a call (on some rank).
    Kernel(mpm_gimp::Error),
    /// The scene declares something a split does not keep bit for bit (named).
    Unsupported(&'static str),
    /// More ranks than cell lines along the split axis, or an axis the scene does not have.
    RanksDoNotFit {
        /// Ranks in the communicator.
        ranks: usize,
        /// Cell lines along the axis.
        lines: u32,
    },
    /// The ranks were not given the same scene (particle counts differ).
    SceneDiffers,
    /// `dt` is above the scene's stable step: take it in substeps of at most
    /// [`Split::stable_dt`].
    TimeStepAboveStable {
        /// The step asked for, s.
        dt: Real,
        /// The scene's stable step, s.
        stable: Real,
    },
    /// A message received was not what the sender had to send (wrong size, ids missing,
    /// repeated or out of place).
    Message(String),
}

impl fmt::Display for SplitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SplitError::Kernel(e) => write!(f, "the kernel refused a call: {e:?}"),
            SplitError::Unsupported(what) => {
                write!(f, "a split over ranks does not support {what}")
            }
            SplitError::RanksDoNotFit { ranks, lines } => write!(
                f,
                "{ranks} ranks do not fit {lines} cell lines along the split axis"
            ),
            SplitError::SceneDiffers => write!(f, "the ranks were given different scenes"),
            SplitError::TimeStepAboveStable { dt, stable } => write!(
                f,
                "dt {dt} s is above the scene's stable step {stable} s: take substeps"
            ),
            SplitError::Message(what) => write!(f, "a message received is wrong: {what}"),
        }
    }
}

impl std::error::Error for SplitError {}

impl From<mpm_gimp::Error> for SplitError {
    fn from(e: mpm_gimp::Error) -> Self {
        SplitError::Kernel(e)
    }
}

/// What one [`Split::step`] did, over the whole scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SplitReport {
    /// Particles frozen in this step (their status turned frozen), over every rank.
    pub frozen: u32,
    /// Particles that left through an open face in this step, over every rank.
    pub escaped: u32,
    /// Bytes this rank sent to other ranks in the exchange after the step.
    pub bytes_sent: u64,
    /// Messages (non-empty sends) this rank sent to other ranks.
    pub messages_sent: u32,
    /// Whether this rank's groups changed, so that it rebuilt its list (else it overwrote
    /// its ghosts in place).
    pub rebuilt: bool,
    /// Whether the slabs were cut again after this step ([`Split::rebalance`]).
    pub rebalanced: bool,
}

/// The default of [`Split::rebalance`]: a rank owning a quarter more than the mean.
pub const DEFAULT_REBALANCE: f64 = 1.25;

/// The default of [`Split::time_out`]: far above any exchange of a substep (milliseconds
/// here), below a batch job's patience.
pub const DEFAULT_TIME_OUT: Duration = Duration::from_secs(60);

/// The exit code of a job a time-out aborts.
pub const TIME_OUT_EXIT_CODE: i32 = 75;

/// Waits for `request`, a collective this rank started on `comm`, polling; past `limit`
/// prints what it waited for (`what`) and aborts the job.
fn wait<'a, D: ?Sized, S: Scope<'a>>(
    comm: &SimpleCommunicator,
    limit: Duration,
    request: Request<'a, D, S>,
    what: &str,
) {
    let start = Instant::now();
    let mut request = request;
    loop {
        match request.test() {
            Ok(_) => return,
            Err(pending) => request = pending,
        }
        if start.elapsed() > limit {
            eprintln!(
                "mpm-gimp-mpi: rank {} of {}: no answer in {:.1} s ({what}): a rank died or \
                 stalled; aborting the job",
                comm.rank(),
                comm.size(),
                limit.as_secs_f64()
            );
            comm.abort(TIME_OUT_EXIT_CODE);
        }
        std::thread::yield_now();
    }
}

/// `recv` = `send` reduced by `op` over the ranks of `comm` ([`wait`]'s time-out).
fn all_reduce<T: Equivalence>(
    comm: &SimpleCommunicator,
    limit: Duration,
    send: &[T],
    recv: &mut [T],
    op: SystemOperation,
    what: &str,
) {
    mpi::request::scope(|scope| {
        let request = comm.immediate_all_reduce_into(scope, send, recv, op);
        wait(comm, limit, request, what);
    });
}

/// The particle columns of the whole scene gathered on rank 0, in id order.
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    /// Number of particles.
    pub count: usize,
    /// Each Real column in the order of [`ParticleState::real_columns`]; empty where the scene
    /// keeps none.
    pub reals: Vec<Vec<Real>>,
    /// Material ids.
    pub material: Vec<u32>,
    /// Status codes.
    pub status: Vec<u32>,
}

impl Gathered {
    /// The columns as a [`ParticleState`].
    pub fn state(&self) -> ParticleState<'_> {
        state_of(self.count, &self.reals, &self.material, &self.status)
    }
}

/// The state whose Real columns are `c` (in the order of [`ParticleState::real_columns`]).
fn state_of<'s>(
    count: usize,
    c: &'s [Vec<Real>],
    material: &'s [u32],
    status: &'s [u32],
) -> ParticleState<'s> {
    let columns = core::array::from_fn(|k| c[k].as_slice());
    ParticleState::from_real_columns(count, columns, material, status)
}

/// The halo, in cell lines on each side of a slab, that a rank holds particles of, for a
/// scene of definition `def`. A particle in cell line `c` reads and adds to the nodes of
/// lines `c - 1 ..= c + 2` (linear shapes: `c ..= c + 1`), which other particles reach from
/// lines up to 3 away (linear: 1). A round, a scatter whose sums a particle reads, so spans 3
/// lines (1); a substep has one for USL and two for MUSL (the re-map), USF (the force
/// scatter after the stress) and the momentum approach (the force scatter after the
/// masses). Every stencil of a substep is taken where its particles start it, and the owners
/// and groups are found again from the positions after each substep, so motion needs no
/// room; one line more is kept all the same. `split_check` finds differences with a halo of
/// 2 lines in each of its USL scenes, and of 4 in some of its MUSL and USF ones.
pub fn halo_cells(def: &WorldDef) -> u32 {
    let span = match def.shape {
        ShapeFunction::Linear => 1,
        _ => 3,
    };
    let rounds = match (def.update_order, def.transfer) {
        (UpdateOrder::Usl, t) if t != Transfer::FlipMomentum => 1,
        _ => 2,
    };
    rounds * span + 1
}

/// Checks that a split keeps the bits of scene `scene`: [`SplitError::Unsupported`] naming
/// what does not.
fn check_supported(scene: &World<'_>, axis: usize) -> Result<(), SplitError> {
    let def = scene.def();
    let fx = &def.effects;
    let refuse = [
        (
            fx.collider_capacity > 0,
            "colliders (force and torque summed across ranks)",
        ),
        (fx.traction_capacity > 0, "tractions"),
        (
            fx.damping.is_some(),
            "damping (the thermostat's feedback is a sum across ranks)",
        ),
        (fx.heat.is_some(), "heat conduction"),
        (fx.diffusion.is_some(), "diffusion"),
        (
            def.faces[2 * axis] == Boundary::Periodic
                || def.faces[2 * axis + 1] == Boundary::Periodic,
            "periodic faces on the split axis",
        ),
    ];
    if let Some((_, what)) = refuse.iter().find(|(bad, _)| *bad) {
        return Err(SplitError::Unsupported(what));
    }
    let fluid = (0..scene.material_count() as u32)
        .filter_map(|id| scene.material(id))
        .any(|m| m.model == MaterialModel::Fluid);
    if fluid {
        return Err(SplitError::Unsupported("fluids (their volume relaxation)"));
    }
    Ok(())
}

/// Slab bounds: `ranks + 1` cell lines, slab `r` the lines `bounds[r]..bounds[r + 1]`, cut
/// so that each slab holds about as many of the particles whose cells are `cells` (at least
/// one line each).
fn cut_slabs(cells: &[u32], lines: u32, ranks: usize) -> Vec<u32> {
    let mut per_line = vec![0u64; lines as usize];
    for &c in cells {
        per_line[c as usize] += 1;
    }
    cut_lines(&per_line, ranks)
}

/// [`cut_slabs`] from the particle count of each cell line.
fn cut_lines(per_line: &[u64], ranks: usize) -> Vec<u32> {
    let lines = per_line.len() as u32;
    let n: u64 = per_line.iter().sum();
    let mut bounds = vec![0u32; ranks + 1];
    bounds[ranks] = lines;
    let (mut line, mut below) = (0u32, 0u64);
    for r in 1..ranks {
        let target = r as u64 * n / ranks as u64;
        while line < lines && below + per_line[line as usize] <= target {
            below += per_line[line as usize];
            line += 1;
        }
        let cut = line.max(bounds[r - 1] + 1).min(lines - (ranks - r) as u32);
        while line < cut {
            below += per_line[line as usize];
            line += 1;
        }
        bounds[r] = cut;
    }
    bounds
}

/// A rank's part of a scene split over the ranks of a communicator (see the crate's docs).
pub struct Split {
    comm: SimpleCommunicator,
    rank: usize,
    size: usize,
    def: WorldDef,
    axis: usize,
    bounds: Vec<u32>,
    halo: u32,
    total: usize,
    present: Vec<usize>,
    min_mass: Real,
    buf: HeapBuffer,
    /// The scene id of each particle this rank holds, ascending: whole groups.
    ids: Vec<u32>,
    /// The local indices of the particles this rank owns, ascending.
    owned: Vec<u32>,
    /// Re-cut the slabs when a rank owns more than this times the mean ([`Split::rebalance`]).
    rebalance: Option<f64>,
    /// How long a collective may wait ([`Split::time_out`]).
    time_out: Duration,
}

impl Split {
    /// Splits `scene` (the whole domain's world, built alike on every rank) over the ranks of
    /// `comm` along `axis` (0 = x), with the halo of [`halo_cells`]. Collective.
    pub fn new(
        comm: SimpleCommunicator,
        scene: &World<'_>,
        axis: usize,
    ) -> Result<Split, SplitError> {
        let halo = halo_cells(&scene.def());
        Split::with_halo(comm, scene, axis, halo)
    }

    /// [`Split::new`] with a halo of `halo` cell lines; thinner than [`halo_cells`] loses the
    /// bits (the tests show it). Not part of the stable API.
    #[doc(hidden)]
    pub fn with_halo(
        comm: SimpleCommunicator,
        scene: &World<'_>,
        axis: usize,
        halo: u32,
    ) -> Result<Split, SplitError> {
        let def = scene.def();
        let (rank, size) = (comm.rank() as usize, comm.size() as usize);
        let dims = if def.dimension == mpm_gimp::Dimension::ThreeD {
            3
        } else {
            2
        };
        let lines = if axis < dims { def.cells[axis] } else { 0 };
        if size as u64 > lines as u64 {
            return Err(SplitError::RanksDoNotFit { ranks: size, lines });
        }
        check_supported(scene, axis)?;
        let total = scene.particle_count();
        let (mut low, mut high) = ([0u64], [0u64]);
        let (limit, what) = (DEFAULT_TIME_OUT, "the scene's particle count");
        let count = [total as u64];
        all_reduce(&comm, limit, &count, &mut low, SystemOperation::min(), what);
        all_reduce(
            &comm,
            limit,
            &count,
            &mut high,
            SystemOperation::max(),
            what,
        );
        if low != high {
            return Err(SplitError::SceneDiffers);
        }
        let view = scene.particles();
        if total == 0 {
            return Err(SplitError::Unsupported("a scene without particles"));
        }
        let present = view
            .state()
            .real_columns()
            .iter()
            .enumerate()
            .filter(|(_, c)| c.len() == total)
            .map(|(k, _)| k)
            .collect();
        let min_mass = view.mass.iter().copied().fold(Real::INFINITY, Real::min);
        let mut buf = HeapBuffer::new(memory_requirements(&def)?.bytes);
        let bytes = scene.as_bytes();
        buf.as_mut_bytes()[..bytes.len()].copy_from_slice(bytes);
        let mut split = Split {
            comm,
            rank,
            size,
            def,
            axis,
            bounds: Vec::new(),
            halo,
            total,
            present,
            min_mass,
            buf,
            ids: (0..total as u32).collect(),
            owned: Vec::new(),
            rebalance: Some(DEFAULT_REBALANCE),
            time_out: DEFAULT_TIME_OUT,
        };
        let cells: Vec<u32> = view.position[axis].iter().map(|&x| split.cell(x)).collect();
        split.bounds = cut_slabs(&cells, lines, size);
        // Every rank holds the whole scene: the groups' reach needs no message.
        let (mut lo, mut hi) = (vec![u32::MAX; split.groups()], vec![0u32; split.groups()]);
        for (i, &c) in cells.iter().enumerate() {
            let g = i / REACH_GROUP;
            lo[g] = lo[g].min(c);
            hi[g] = hi[g].max(c);
        }
        let keep: Vec<bool> = (0..split.groups())
            .map(|g| split.needs(rank, lo[g], hi[g]))
            .collect();
        let gone: Vec<u32> = (0..total as u32)
            .filter(|&i| !keep[i as usize / REACH_GROUP])
            .collect();
        split.world().remove_particles(Removal::List(&gone))?;
        split.ids = (0..total as u32)
            .filter(|&i| keep[i as usize / REACH_GROUP])
            .collect();
        split.find_owned();
        split.check_min_mass()?;
        Ok(split)
    }

    /// This rank's world: the whole grid, the particles of the groups it holds.
    pub fn world(&mut self) -> World<'_> {
        World::reopen(self.buf.as_mut_bytes()).expect("the rank's world stays a world")
    }

    /// This rank's world, to read.
    pub fn view(&self) -> WorldRef<'_> {
        WorldRef::reopen(self.buf.as_bytes()).expect("the rank's world stays a world")
    }

    /// The scene ids of the particles this rank holds, ascending (local index to id).
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// The local indices of the particles this rank owns, ascending.
    pub fn owned(&self) -> &[u32] {
        &self.owned
    }

    /// Particles in the whole scene.
    pub fn total(&self) -> usize {
        self.total
    }

    /// The slabs: rank `r` owns the cell lines `bounds()[r]..bounds()[r + 1]` along the axis.
    pub fn bounds(&self) -> &[u32] {
        &self.bounds
    }

    /// When the slabs are cut again: after a substep in which some rank owns more than
    /// `limit` times the mean particle count (`None`: never; default
    /// [`DEFAULT_REBALANCE`]). The test rides on the exchange's reduction (no extra message);
    /// past the limit, one reduction of a count per cell line balances the slabs on the
    /// particles' positions as [`Split::new`] does; where that moves a bound, the ranks whose
    /// groups change rebuild their lists ([`SplitReport::rebalanced`]). The bits do not depend on the slabs. Collective: call
    /// it alike on every rank.
    pub fn rebalance(&mut self, limit: Option<f64>) {
        self.rebalance = limit;
    }

    /// How long this rank waits for the others in an exchange before it aborts the job (see
    /// the crate's docs; default [`DEFAULT_TIME_OUT`]).
    pub fn time_out(&mut self, limit: Duration) {
        self.time_out = limit;
    }

    /// The halo, in cell lines on each side of a slab.
    pub fn halo(&self) -> u32 {
        self.halo
    }

    /// This rank and the number of ranks.
    pub fn rank(&self) -> (usize, usize) {
        (self.rank, self.size)
    }

    /// The communicator the split runs on.
    pub fn comm(&self) -> &SimpleCommunicator {
        &self.comm
    }

    /// The scene's stable step, s: the least over the ranks' worlds (exact). Collective.
    pub fn stable_dt(&mut self) -> Real {
        let local = [self.world().stable_dt()];
        let mut stable = local;
        let op = SystemOperation::min();
        all_reduce(
            &self.comm,
            self.time_out,
            &local,
            &mut stable,
            op,
            "the stable step",
        );
        stable[0]
    }

    /// Advances the scene by `dt` (at most [`Split::stable_dt`]: one substep, as one world's
    /// step then takes), then exchanges the owned particles' states and migrates. Collective;
    /// every rank returns the same result.
    pub fn step(&mut self, dt: Real) -> Result<SplitReport, SplitError> {
        self.step_with_tasks(dt, &mpm_gimp::tasks::Serial)
    }

    /// [`Split::step`] with each rank's world stepped on `tasks`
    /// ([`World::step_with_tasks`]: the same bits for any worker count, so ranks times
    /// workers give one world's bits too). The scene's [`WorldDef::workers`] must be at
    /// least its worker count.
    pub fn step_with_tasks(
        &mut self,
        dt: Real,
        tasks: &dyn mpm_gimp::TaskSystem,
    ) -> Result<SplitReport, SplitError> {
        let stable = self.stable_dt();
        // NaN-safe: a NaN dt is not at most the stable step.
        if dt.partial_cmp(&stable).is_none_or(|o| o.is_gt()) {
            return Err(SplitError::TimeStepAboveStable { dt, stable });
        }
        let before: Vec<u32> = {
            let status = self.view().particles().status;
            self.owned.iter().map(|&i| status[i as usize]).collect()
        };
        let stepped = self.world().step_with_tasks(dt, tasks);
        let ok = self.agree(stepped.is_ok());
        let stepped = stepped?;
        if !ok || stepped.substeps != 1 {
            return Err(SplitError::Message(
                "a rank's step failed or took more than one substep".into(),
            ));
        }
        let (mut frozen, mut escaped) = (0u32, 0u32);
        {
            let status = self.view().particles().status;
            for (k, &i) in self.owned.iter().enumerate() {
                let (was, now) = (before[k], status[i as usize]);
                if was != now {
                    frozen += (now == mpm_gimp::ParticleStatus::Frozen as u32) as u32;
                    escaped += (now == mpm_gimp::ParticleStatus::Escaped as u32) as u32;
                }
            }
        }
        let mut counts = [0u32; 2];
        all_reduce(
            &self.comm,
            self.time_out,
            &[frozen, escaped],
            &mut counts,
            SystemOperation::sum(),
            "the step's report",
        );
        let (bytes_sent, messages_sent, rebuilt, rebalanced) = self.exchange()?;
        Ok(SplitReport {
            frozen: counts[0],
            escaped: counts[1],
            bytes_sent,
            messages_sent,
            rebuilt,
            rebalanced,
        })
    }

    /// Gathers every particle's columns on rank 0, in id order (`None` on the other ranks).
    /// Collective.
    pub fn gather_to_root(&mut self) -> Result<Option<Gathered>, SplitError> {
        let send = self.encode(&self.owned);
        let root = self.comm.process_at_rank(0);
        let n = send.len() as Count;
        let (comm, limit, what) = (&self.comm, self.time_out, "the gather");
        if self.rank != 0 {
            mpi::request::scope(|scope| {
                wait(comm, limit, root.immediate_gather_into(scope, &n), what);
                let request = root.immediate_gather_varcount_into(scope, &send[..]);
                wait(comm, limit, request, what);
            });
            return Ok(None);
        }
        let mut counts = vec![0 as Count; self.size];
        mpi::request::scope(|scope| {
            let request = root.immediate_gather_into_root(scope, &n, &mut counts[..]);
            wait(comm, limit, request, what);
        });
        let displs = displacements(&counts);
        let mut recv = vec![0u8; counts.iter().map(|&c| c as usize).sum()];
        {
            let mut part = PartitionMut::new(&mut recv[..], &counts[..], &displs[..]);
            mpi::request::scope(|scope| {
                let request = root.immediate_gather_varcount_into_root(scope, &send[..], &mut part);
                wait(comm, limit, request, what);
            });
        }
        let all: Vec<u32> = (0..self.total as u32).collect();
        let (reals, material, status) = decode(&self.present, &recv, &all)?;
        Ok(Some(Gathered {
            count: self.total,
            reals,
            material,
            status,
        }))
    }

    /// Whether every rank's `ok` is true. Collective.
    fn agree(&self, ok: bool) -> bool {
        let mut all = [0u8];
        let op = SystemOperation::min();
        all_reduce(
            &self.comm,
            self.time_out,
            &[ok as u8],
            &mut all,
            op,
            "the ranks' agreement",
        );
        all[0] == 1
    }

    fn groups(&self) -> usize {
        self.total.div_ceil(REACH_GROUP)
    }

    /// The cell line along the axis of a particle at `x` along it (clamped to the grid).
    fn cell(&self, x: Real) -> u32 {
        let a = self.axis;
        let s = (x as f64 - self.def.origin[a] as f64) / self.def.cell_size as f64;
        let last = self.def.cells[a] as f64 - 1.0;
        s.floor().clamp(0.0, last) as u32
    }

    fn owner(&self, cell: u32) -> usize {
        self.bounds[1..].partition_point(|&b| b <= cell)
    }

    /// Whether rank `r` needs a group whose particles lie in the cell lines `lo..=hi`.
    fn needs(&self, r: usize, lo: u32, hi: u32) -> bool {
        let from = self.bounds[r] as i64 - self.halo as i64;
        let to = self.bounds[r + 1] as i64 - 1 + self.halo as i64;
        lo as i64 <= to && hi as i64 >= from
    }

    fn find_owned(&mut self) {
        let axis = self.axis;
        let view = self.view();
        let x = view.particles().position[axis];
        let owned = (0..x.len() as u32)
            .filter(|&i| self.owner(self.cell(x[i as usize])) == self.rank)
            .collect();
        self.owned = owned;
    }

    fn check_min_mass(&mut self) -> Result<(), SplitError> {
        let least = self
            .view()
            .particles()
            .mass
            .iter()
            .copied()
            .fold(Real::INFINITY, Real::min);
        let ok = self.ids.is_empty() || least.to_bits() == self.min_mass.to_bits();
        if !self.agree(ok) {
            return Err(SplitError::Unsupported(
                "a rank's least particle mass differs from the scene's (the nodal mass cutoff)",
            ));
        }
        Ok(())
    }

    /// Bytes of one particle's record.
    fn record_bytes(&self) -> usize {
        record_bytes(&self.present)
    }

    /// The records of the local particles `local` (ascending).
    fn encode(&self, local: &[u32]) -> Vec<u8> {
        let (present, ids) = (&self.present, &self.ids);
        let mut out = Vec::with_capacity(local.len() * self.record_bytes());
        let w = self.view();
        let view = w.particles();
        let state = view.state();
        let cols = state.real_columns();
        for &i in local {
            let i = i as usize;
            out.extend_from_slice(&ids[i].to_ne_bytes());
            for &k in present {
                out.extend_from_slice(&cols[k][i].to_ne_bytes());
            }
            out.extend_from_slice(&view.material[i].to_ne_bytes());
            out.extend_from_slice(&view.status[i].to_ne_bytes());
        }
        out
    }

    /// After a step: the groups each rank now needs (from the owners' positions), the owned
    /// states sent to every rank that holds their groups. A rank that holds the same groups
    /// as before keeps its own particles as stepped and overwrites its ghosts in place, run
    /// by run ([`World::set_particle_state`]); one whose groups changed (migration) rebuilds
    /// its list, in id order, from what it receives, its own particles included. Returns the
    /// bytes and messages this rank sent to others, and whether it rebuilt.
    fn exchange(&mut self) -> Result<(u64, u32, bool, bool), SplitError> {
        let groups = self.groups();
        let axis = self.axis;
        let view = self.view();
        let x = view.particles().position[axis];
        let (mut lo, mut hi) = (vec![u32::MAX; groups], vec![0u32; groups + 1]);
        for &i in &self.owned {
            let g = self.ids[i as usize] as usize / REACH_GROUP;
            let c = self.cell(x[i as usize]);
            lo[g] = lo[g].min(c);
            hi[g] = hi[g].max(c);
        }
        // With the groups' highest lines, the most particles a rank owns.
        hi[groups] = self.owned.len() as u32;
        let (mut glo, mut ghi) = (vec![0u32; groups], vec![0u32; groups + 1]);
        let (comm, limit, what) = (&self.comm, self.time_out, "the groups' lines");
        all_reduce(comm, limit, &lo, &mut glo, SystemOperation::min(), what);
        all_reduce(comm, limit, &hi, &mut ghi, SystemOperation::max(), what);
        let most = ghi.pop().unwrap_or(0) as f64;
        let mean = self.total as f64 / self.size as f64;
        let mut rebalanced = false;
        if self.rebalance.is_some_and(|limit| most > limit * mean) {
            // The slabs cut again on where the particles are now; the owners found before
            // the step send to the ranks that need their groups under the new slabs.
            let mut per_line = vec![0u64; self.def.cells[axis] as usize];
            for &i in &self.owned {
                per_line[self.cell(x[i as usize]) as usize] += 1;
            }
            let mut all = vec![0u64; per_line.len()];
            let op = SystemOperation::sum();
            all_reduce(
                &self.comm,
                self.time_out,
                &per_line,
                &mut all,
                op,
                "the slabs' counts",
            );
            // Slabs as good as the lines allow already are left alone (no rebuild).
            let bounds = cut_lines(&all, self.size);
            rebalanced = bounds != self.bounds;
            self.bounds = bounds;
        }
        // A group no rank owns a particle of means an owner lost track of it.
        let owned_all = glo.iter().zip(&ghi).all(|(l, h)| l <= h);
        let needs = |r: usize, g: usize| owned_all && self.needs(r, glo[g], ghi[g]);
        let held: Vec<u32> = (0..self.total as u32)
            .filter(|&i| needs(self.rank, i as usize / REACH_GROUP))
            .collect();
        // The same groups as before: this rank's own particles stay as stepped.
        let in_place = held == self.ids;
        let mut send = Vec::new();
        let mut counts = vec![0 as Count; self.size];
        for (r, count) in counts.iter_mut().enumerate() {
            if r == self.rank && in_place {
                continue;
            }
            let to: Vec<u32> = self
                .owned
                .iter()
                .copied()
                .filter(|&i| needs(r, self.ids[i as usize] as usize / REACH_GROUP))
                .collect();
            let bytes = self.encode(&to);
            *count = bytes.len() as Count;
            send.extend_from_slice(&bytes);
        }
        let mut rcounts = vec![0 as Count; self.size];
        let (comm, limit, what) = (&self.comm, self.time_out, "the particles' exchange");
        mpi::request::scope(|scope| {
            let request = comm.immediate_all_to_all_into(scope, &counts[..], &mut rcounts[..]);
            wait(comm, limit, request, what);
        });
        let received: usize = rcounts.iter().map(|&c| c as usize).sum();
        // Buffers of one byte at least: Open MPI refuses two empty ones (the same dangling
        // address for sending and receiving reads as an exchange in place).
        send.push(0);
        let mut recv = vec![0u8; received + 1];
        {
            let sdispls = displacements(&counts);
            let rdispls = displacements(&rcounts);
            let part = Partition::new(&send[..], &counts[..], &sdispls[..]);
            let mut rpart = PartitionMut::new(&mut recv[..], &rcounts[..], &rdispls[..]);
            mpi::request::scope(|scope| {
                let request = comm.immediate_all_to_all_varcount_into(scope, &part, &mut rpart);
                wait(comm, limit, request, what);
            });
        }
        // What this rank must receive: every particle it holds, or only its ghosts.
        let (expect, local): (Vec<u32>, Vec<u32>) = if in_place {
            let mut own = vec![false; held.len()];
            self.owned.iter().for_each(|&i| own[i as usize] = true);
            (0..held.len() as u32)
                .filter(|&i| !own[i as usize])
                .map(|i| (held[i as usize], i))
                .unzip()
        } else {
            (held.clone(), (0..held.len() as u32).collect())
        };
        let decoded = decode(&self.present, &recv[..received], &expect);
        if !self.agree(owned_all && decoded.is_ok()) {
            return Err(match decoded {
                Err(e) => e,
                Ok(_) if !owned_all => {
                    SplitError::Message("a group of particles has no owner".into())
                }
                Ok(_) => SplitError::Message("another rank received a wrong message".into()),
            });
        }
        let (reals, material, status) = decoded?;
        let state = state_of(expect.len(), &reals, &material, &status);
        let mut w = self.world();
        let written = if in_place {
            // Runs of consecutive local indices, each set as one.
            let mut result = Ok(());
            let mut k = 0;
            while k < local.len() && result.is_ok() {
                let mut end = k + 1;
                while end < local.len() && local[end] == local[end - 1] + 1 {
                    end += 1;
                }
                let rows = state.rows(k..end).expect("the run lies within the state");
                result = w.set_particle_state(local[k], &rows);
                k = end;
            }
            result
        } else {
            let n = w.particle_count() as u32;
            w.remove_particles(Removal::Range(0..n))
                .and_then(|_| w.add_particles_with_state(&state).map(drop))
        };
        if !self.agree(written.is_ok()) {
            written?;
            return Err(SplitError::Message(
                "another rank could not write what it received".into(),
            ));
        }
        self.ids = held;
        self.find_owned();
        self.check_min_mass()?;
        let others = counts
            .iter()
            .enumerate()
            .filter(|&(r, &c)| r != self.rank && c > 0);
        let (bytes, messages) = others.fold((0u64, 0u32), |(b, m), (_, &c)| (b + c as u64, m + 1));
        Ok((bytes, messages, !in_place, rebalanced))
    }
}

/// Bytes of one particle's record of the Real columns `present`: id, those columns, material,
/// status.
fn record_bytes(present: &[usize]) -> usize {
    4 + present.len() * size_of::<Real>() + 8
}

/// The columns of the records in `bytes` (of the Real columns `present`), in id order: a
/// [`SplitError::Message`] unless they are exactly the particles `expect` (ascending).
#[allow(clippy::type_complexity)]
fn decode(
    present: &[usize],
    bytes: &[u8],
    expect: &[u32],
) -> Result<(Vec<Vec<Real>>, Vec<u32>, Vec<u32>), SplitError> {
    let rb = record_bytes(present);
    if bytes.len() != expect.len() * rb {
        return Err(SplitError::Message(format!(
            "{} bytes received, {} expected ({} particles of {} bytes)",
            bytes.len(),
            expect.len() * rb,
            expect.len(),
            rb
        )));
    }
    let u32_at = |at: usize| u32::from_ne_bytes(bytes[at..at + 4].try_into().unwrap());
    let mut order: Vec<(u32, usize)> = (0..expect.len())
        .map(|k| (u32_at(k * rb), k * rb))
        .collect();
    order.sort_unstable();
    if order.iter().map(|&(id, _)| id).ne(expect.iter().copied()) {
        return Err(SplitError::Message(
            "the particle ids received are not the groups this rank holds".into(),
        ));
    }
    let n = expect.len();
    let mut reals = vec![Vec::new(); REAL_COLUMNS];
    for &k in present {
        reals[k] = Vec::with_capacity(n);
    }
    let (mut material, mut status) = (Vec::with_capacity(n), Vec::with_capacity(n));
    const R: usize = size_of::<Real>();
    for &(_, at) in &order {
        let mut p = at + 4;
        for &k in present {
            reals[k].push(Real::from_ne_bytes(bytes[p..p + R].try_into().unwrap()));
            p += R;
        }
        material.push(u32_at(p));
        status.push(u32_at(p + 4));
    }
    Ok((reals, material, status))
}

/// The offsets of consecutive blocks of `counts` bytes.
fn displacements(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0, |at, &c| {
            let here = *at;
            *at += c;
            Some(here)
        })
        .collect()
}

use core::mem::size_of;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_balance_counts_and_keep_a_line_each() {
        // 100 particles on lines 0..10 of 10, 4 ranks: 25 each.
        let cells: Vec<u32> = (0..100).map(|i| i / 10).collect();
        assert_eq!(cut_slabs(&cells, 10, 4), vec![0, 2, 5, 7, 10]);
        // Every particle on one line: the other ranks still get a line each.
        assert_eq!(cut_slabs(&[5; 40], 10, 3), vec![0, 5, 6, 10]);
        assert_eq!(cut_slabs(&[0; 4], 3, 3), vec![0, 1, 2, 3]);
    }

    /// Records of particles `ids` with Real columns 0 and 9 (value: the id), material 1,
    /// status 0.
    fn records(ids: &[u32]) -> Vec<u8> {
        let mut out = Vec::new();
        for &id in ids {
            out.extend_from_slice(&id.to_ne_bytes());
            for _ in 0..2 {
                out.extend_from_slice(&(id as Real).to_ne_bytes());
            }
            out.extend_from_slice(&1u32.to_ne_bytes());
            out.extend_from_slice(&0u32.to_ne_bytes());
        }
        out
    }

    #[test]
    fn decode_sorts_by_id_and_refuses_a_wrong_message() {
        let present = [0, 9];
        let (reals, material, status) = decode(&present, &records(&[7, 5, 6]), &[5, 6, 7]).unwrap();
        assert_eq!(reals[0], vec![5.0, 6.0, 7.0]);
        assert_eq!(reals[9], vec![5.0, 6.0, 7.0]);
        assert!(reals[1].is_empty());
        assert_eq!((material, status), (vec![1; 3], vec![0; 3]));
        // A byte short, a particle missing, one repeated, one not expected.
        let mut short = records(&[5, 6, 7]);
        short.pop();
        for (bytes, expect) in [
            (short, &[5u32, 6, 7][..]),
            (records(&[5, 6]), &[5, 6, 7][..]),
            (records(&[5, 5, 7]), &[5, 6, 7][..]),
            (records(&[5, 6, 8]), &[5, 6, 7][..]),
        ] {
            assert!(matches!(
                decode(&present, &bytes, expect),
                Err(SplitError::Message(_))
            ));
        }
    }

    #[test]
    fn columns_round_trip() {
        let reals: Vec<Vec<Real>> = (0..REAL_COLUMNS).map(|k| vec![k as Real]).collect();
        let s = state_of(1, &reals, &[0], &[0]);
        let back = s.real_columns();
        for (k, c) in back.iter().enumerate() {
            assert_eq!(c[0], k as Real);
        }
    }
}
