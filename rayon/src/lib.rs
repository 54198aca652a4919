//! A [rayon] task system for the mpm-gimp kernel: [`RayonTasks`] steps a world on the
//! threads of a rayon pool through [`World::step_with_tasks`](mpm_gimp::World::step_with_tasks).
//!
//! The kernel is `no_std` and owns no thread; it hands each parallel pass of its step to the
//! host's [`TaskSystem`] as a range of items. [`RayonTasks`] cuts that range into a few
//! ranges per worker ([`RANGES_PER_WORKER`], never shorter than the pass asks), splits them
//! with [`rayon::join`] on the pool's threads and passes each range the index of the pool
//! thread that runs it as the worker. The step's results do not depend on the cut nor on the
//! workers: they are bit-identical to [`World::step`](mpm_gimp::World::step)'s for any thread
//! count.
//!
//! ```
//! use mpm_gimp::{memory_requirements, HeapBuffer, MaterialDef, TaskSystem, Vec3, World, WorldDef};
//! use mpm_gimp_rayon::RayonTasks;
//!
//! let tasks = RayonTasks::new(2).expect("a pool of two threads");
//! // The world's buffer holds the parallel step's scratch for `workers` workers.
//! let def = WorldDef {
//!     cells: [16, 16, 1],
//!     cell_size: 0.05,
//!     particle_capacity: 1024,
//!     workers: tasks.worker_count() as u32,
//!     ..WorldDef::DEFAULT
//! };
//! let mut storage = HeapBuffer::new(memory_requirements(&def).unwrap().bytes);
//! let mut world = World::init(&def, storage.as_mut_bytes()).unwrap();
//! let rubber = world.add_material(&MaterialDef::DEFAULT).unwrap();
//! world
//!     .fill_box(Vec3::new(0.2, 0.2, 0.0), Vec3::new(0.5, 0.5, 0.0), rubber, Vec3::ZERO)
//!     .unwrap();
//! world.step_with_tasks(1.0 / 240.0, &tasks).unwrap();
//! ```

#![deny(missing_docs)]

use mpm_gimp::tasks::Task;
use mpm_gimp::TaskSystem;
use rayon::{ThreadPool, ThreadPoolBuildError, ThreadPoolBuilder, Yield};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// The most ranges [`RayonTasks::parallel_for`](TaskSystem::parallel_for) cuts a pass into per
/// worker (fewer when the pass's `min_range` allows fewer): more than one, so that a worker
/// that finishes early steals a range of a slower one (a shared machine's cores do not run at
/// one speed), and few, since each range costs the pass a task and whatever per-range work the
/// kernel does.
pub const RANGES_PER_WORKER: usize = 4;

/// A [`TaskSystem`] on a rayon thread pool: a pool of its own ([`RayonTasks::new`]) or rayon's
/// global pool ([`RayonTasks::global`]).
///
/// Its workers are the pool's threads, and the worker a range runs on is the index of the
/// pool thread that runs it ([`rayon::current_thread_index`]): every range runs inside the
/// pool, also when the step is called from a thread outside it (the calling thread then waits,
/// as [`ThreadPool::install`] does), so the index is always below
/// [`worker_count`](TaskSystem::worker_count). A world stepped on it needs
/// [`WorldDef::workers`](mpm_gimp::WorldDef::workers) at least that count.
///
/// A panic in a range is carried to the caller of `parallel_for` once the other ranges are
/// done, as [`rayon::join`] does.
#[derive(Debug)]
pub struct RayonTasks {
    /// The pool of its own; `None` for rayon's global pool.
    pool: Option<ThreadPool>,
    /// Held by [`RayonTasks::install`] while it occupies the pool from outside: a second
    /// caller's broadcast would run, on the spinning threads, on top of the first one's
    /// stolen ranges and wait for a thread 0 that waits for those ranges (a deadlock two
    /// viewer tests stepping on one pool met).
    outside: Mutex<()>,
}

impl RayonTasks {
    /// A task system on a new pool of `threads` threads (named `mpm-gimp-0`, `mpm-gimp-1`, ...);
    /// `threads == 0` lets rayon choose, as its global pool does (the `RAYON_NUM_THREADS`
    /// environment variable, else the cores available). The pool's threads end when it is
    /// dropped.
    ///
    /// # Errors
    /// rayon's, when the operating system refuses a thread.
    pub fn new(threads: usize) -> Result<RayonTasks, ThreadPoolBuildError> {
        let pool = ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("mpm-gimp-{i}"))
            .build()?;
        Ok(RayonTasks {
            pool: Some(pool),
            outside: Mutex::new(()),
        })
    }

    /// A task system on rayon's global pool, shared with the host's other rayon work (its
    /// size: `RAYON_NUM_THREADS`, else the cores available, unless the host built the global
    /// pool itself). As rayon's own [`rayon::join`] does, a step called from a thread of
    /// another rayon pool runs on that pool instead: [`worker_count`](TaskSystem::worker_count)
    /// is then that pool's thread count, so size [`WorldDef::workers`](mpm_gimp::WorldDef::workers)
    /// from the thread that steps.
    pub fn global() -> RayonTasks {
        RayonTasks {
            pool: None,
            outside: Mutex::new(()),
        }
    }

    /// Runs `f` on a thread of the pool and returns its result: a host that steps inside it
    /// (`tasks.install(|| world.step_with_tasks(dt, &tasks))`) hands the pool the whole step
    /// once, and each pass's ranges then start on the pool's own threads (rayon's join, a few
    /// hundred nanoseconds), instead of handing every pass over from the calling thread and
    /// waiting for it (tens of microseconds each, a dozen passes a substep: the 2D default
    /// step on 2 workers took 1.25 times as long; benches/PERFORMANCE.md).
    ///
    /// Meanwhile the pool's other threads do not sleep between the passes: they spin, taking
    /// whatever rayon work the pool has (the passes' ranges, and any rayon work of `f`'s
    /// own), until `f` returns or unwinds. A thread woken for each pass made the 2D default
    /// step on 2 workers about 3 % longer. So `f` should be the step, not the host's whole
    /// frame. Called from a thread of the pool, or on a pool of one thread, it is
    /// [`ThreadPool::install`]. A panic of `f` reaches the caller once the threads stop.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        let Some(pool) = &self.pool else {
            return f();
        };
        if pool.current_num_threads() < 2 || pool.current_thread_index().is_some() {
            return pool.install(f);
        }
        // One caller from outside at a time (a poisoned lock only says another caller's `f`
        // panicked: the pool is free again).
        let _outside = self.outside.lock().unwrap_or_else(|e| e.into_inner());
        // Thread 0 runs `f`; the others take the passes' ranges as rayon's threads do
        // (`yield_now` steals them), spinning in between rather than sleeping, until `f`
        // returns or unwinds.
        struct Release<'a>(&'a AtomicBool);
        impl Drop for Release<'_> {
            fn drop(&mut self) {
                self.0.store(true, Ordering::Release);
            }
        }
        let (f, out, done) = (
            Mutex::new(Some(f)),
            Mutex::new(None),
            AtomicBool::new(false),
        );
        pool.broadcast(|ctx| {
            if ctx.index() == 0 {
                let _release = Release(&done);
                let f = f.lock().ok().and_then(|mut f| f.take());
                if let (Some(f), Ok(mut out)) = (f, out.lock()) {
                    *out = Some(f());
                }
            } else {
                while !done.load(Ordering::Acquire) {
                    if pool.yield_now() != Some(Yield::Executed) {
                        std::hint::spin_loop();
                    }
                }
            }
        });
        match out.into_inner() {
            Ok(Some(r)) => r,
            // Thread 0 ran `f` once and stored its result, or unwound (which `broadcast`
            // carries here before this point).
            _ => unreachable!("install: the closure ran on thread 0"),
        }
    }

    /// The index of the calling thread in the pool the ranges run on, if it is one of its
    /// threads.
    fn thread_index(&self) -> Option<usize> {
        match &self.pool {
            Some(pool) => pool.current_thread_index(),
            None => rayon::current_thread_index(),
        }
    }
}

// SAFETY: the ranges `bound(k)..bound(k + 1)` partition `0..items`; each runs once, on a
// thread of the pool (whose index is its worker index, below the pool's thread count), or on
// the calling thread when there is one range; `split` returns when every range has.
unsafe impl TaskSystem for RayonTasks {
    /// The pool's threads.
    fn worker_count(&self) -> usize {
        match &self.pool {
            Some(pool) => pool.current_num_threads(),
            None => rayon::current_num_threads(),
        }
    }

    fn parallel_for(&self, items: usize, min_range: usize, task: &Task<'_>) {
        if items == 0 {
            return;
        }
        let ranges = range_count(items, min_range, self.worker_count());
        if ranges == 1 {
            // One range: no thread to wake. It runs on the calling thread, as worker 0 unless
            // that thread is one of the pool's (nothing else of this pass runs meanwhile).
            task(0, items, self.thread_index().unwrap_or(0));
            return;
        }
        let run = || {
            split(0, ranges, &|k| {
                let (start, end) = (bound(items, ranges, k), bound(items, ranges, k + 1));
                // Inside the pool (`install`, or `join` on the global pool), so the index is
                // there; 0 only if rayon ever ran a job elsewhere.
                task(start, end, self.thread_index().unwrap_or(0));
            })
        };
        match &self.pool {
            Some(pool) => pool.install(run),
            // Outside any pool, `rayon::join` moves the whole split onto the global pool and
            // waits for it; inside one it runs there.
            None => run(),
        }
    }
}

/// How many ranges `items` items are cut into for `workers` workers: one for a single worker
/// or a pass shorter than two ranges of `min_range`; else as many as fit at `min_range` items
/// each, at most [`RANGES_PER_WORKER`] per worker.
fn range_count(items: usize, min_range: usize, workers: usize) -> usize {
    if workers <= 1 {
        return 1;
    }
    (items / min_range.max(1))
        .min(workers.saturating_mul(RANGES_PER_WORKER))
        .max(1)
}

/// Where range `k` of `0..items` cut into `ranges` even ranges starts: each range has
/// `items / ranges` items rounded down or up, so at least `min_range` when
/// `ranges <= items / min_range` ([`range_count`]).
fn bound(items: usize, ranges: usize, k: usize) -> usize {
    (items as u128 * k as u128 / ranges as u128) as usize
}

/// Runs `range(k)` for every `k` in `first..last`, halving the span with [`rayon::join`]
/// until one range is left (no allocation: rayon's join keeps its jobs on the stack).
fn split(first: usize, last: usize, range: &(dyn Fn(usize) + Sync)) {
    if last - first == 1 {
        range(first);
    } else {
        let mid = first + (last - first) / 2;
        rayon::join(|| split(first, mid, range), || split(mid, last, range));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_long_enough_and_cover_the_items() {
        for items in [1, 2, 7, 63, 64, 65, 1000, 4097] {
            for min_range in [1, 3, 32, 64, 5000] {
                for workers in [1, 2, 3, 8] {
                    let n = range_count(items, min_range, workers);
                    assert!(n >= 1 && n <= workers * RANGES_PER_WORKER);
                    assert_eq!((bound(items, n, 0), bound(items, n, n)), (0, items));
                    for k in 0..n {
                        let len = bound(items, n, k + 1) - bound(items, n, k);
                        assert!(n == 1 || len >= min_range, "{items} {min_range} {workers}");
                    }
                }
            }
        }
    }
}
