//! The host's task system from C, in the manner of Box2D v3 (`b2TaskCallback`,
//! `b2EnqueueTaskCallback`, `b2FinishTaskCallback`): `MpmTaskSystem` and
//! `mpm_world_step_tasks`, and the adapter that makes an `MpmTaskSystem` the kernel's
//! [`TaskSystem`].
//!
//! The host is not trusted with the kernel's memory: the task it is handed checks every range
//! it is called with (inside `0..item_count`, a worker index below `worker_count`, no two
//! ranges at once on one worker, no item that another range of the task took before) and runs
//! only those that pass, so that whatever the host does with its ranges each of the kernel's
//! items runs at most once. Each loop keeps one bit per item (`Loop::taken`): a range sets its
//! items' bits before it runs and is refused if one was set already, and the loop is complete
//! when every bit is set. So an item run twice or never is caught whatever the counts of the
//! ranges add up to. A range that fails a check, an item left out, a finish that returns while
//! a range still runs, and a panic inside a task make the step answer an error
//! (`MPM_STATUS_TASK_CONTRACT`, `MPM_STATUS_INTERNAL`) once the task is finished.

use crate::status::MpmStatus;
use crate::world::{put, step_report, world_at, MpmStepReport, MpmWorld};
use crate::{apart, guard, mpm_real, non_null};
use core::ffi::c_void;
use core::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use kernel::tasks::{Task, MAX_ITEMS};
use kernel::{TaskSystem, MAX_WORKERS};

/// The fewest particles at which two workers step a world faster than one (measured; the
/// kernel's `PARALLEL_FROM`): below it `mpm_world_step` is the faster call.
pub const MPM_PARALLEL_FROM: usize = 4096;

const _: () = assert!(MPM_PARALLEL_FROM == kernel::PARALLEL_FROM);

/// Words of a loop's item bits ([`Loop::taken`]): one bit for each of the most items a loop of
/// the kernel has ([`MAX_ITEMS`]).
const TAKEN_WORDS: usize = MAX_ITEMS.div_ceil(64);

/// A task the library hands the host: runs the items `start .. end` (`start < end <=
/// item_count`) on worker `worker` (`< worker_count`) and returns when they are done.
/// `task_context` is the value `MpmEnqueueTaskCallback` received with the task, passed back
/// unchanged. The host may call it from any thread, with its ranges in any order, only between
/// the call of `enqueue_task` that received it and the return of the matching `finish_task` (or
/// of `enqueue_task`, when that returned NULL).
pub type MpmTaskCallback =
    Option<unsafe extern "C" fn(start: u32, end: u32, worker: u32, task_context: *mut c_void)>;

/// The host's side of one parallel loop: run `task` over the items `0 .. item_count`
/// (`item_count >= 1`), with `task_context`, in ranges on its workers, and return a handle
/// that `MpmFinishTaskCallback` takes, or NULL after running the whole loop itself before
/// returning (a host may run everything serially on the calling thread: `task(0, item_count,
/// 0, task_context)`). `user_context` is `MpmTaskSystem::user_context`.
///
/// Contract: the ranges together cover every item exactly once; each is at least `min_range`
/// items long, except possibly the last (items are cheap below that; the library does not
/// check it); at most `worker_count` ranges run at once, each with its own worker index below
/// `worker_count` (ranges that run one after another may share one). How the items are cut and
/// spread does not change the results. The library refuses to run a range outside the items,
/// with a worker index out of range or in use, or with an item that a range of the task ran
/// or runs already, and checks when the task is finished that every item ran: each item of
/// the kernel runs at most once, and a broken contract (items run twice or left out, whatever
/// the ranges' lengths add up to) makes the step answer `MPM_STATUS_TASK_CONTRACT`. The
/// callbacks must return normally (no `longjmp`, no C++ exception).
pub type MpmEnqueueTaskCallback = Option<
    unsafe extern "C" fn(
        task: MpmTaskCallback,
        item_count: u32,
        min_range: u32,
        task_context: *mut c_void,
        user_context: *mut c_void,
    ) -> *mut c_void,
>;

/// Waits until every range of the task whose handle `enqueue_task` returned (`user_task`, never
/// NULL) has returned, and makes what the ranges wrote visible to the calling thread (a mutex
/// or a condition variable does). Called once per non-NULL handle, on the thread that enqueued
/// the task.
pub type MpmFinishTaskCallback =
    Option<unsafe extern "C" fn(user_task: *mut c_void, user_context: *mut c_void)>;

/// A host's task system: `mpm_world_step_tasks` runs the parallel parts of a step on it. The
/// library calls `enqueue_task` and `finish_task` only from the thread that called
/// `mpm_world_step_tasks`, finishing each task before it enqueues the next, and never keeps
/// the struct or its pointers past the call. A host without threads of its own steps with
/// `mpm_world_step`.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmTaskSystem {
    /// Starts a task on the workers (not NULL).
    pub enqueue_task: MpmEnqueueTaskCallback,
    /// Waits for a task that `enqueue_task` returned a handle of (not NULL).
    pub finish_task: MpmFinishTaskCallback,
    /// Passed to both callbacks unchanged; the library never reads it.
    pub user_context: *mut c_void,
    /// The workers the system runs ranges on: 1 to the world definition's `workers`.
    pub worker_count: u32,
}

/// [`MpmTaskSystem`] as the kernel's [`TaskSystem`]: each `parallel_for` enqueues, then
/// finishes what the host did not run inside enqueue.
struct HostTasks {
    enqueue:
        unsafe extern "C" fn(MpmTaskCallback, u32, u32, *mut c_void, *mut c_void) -> *mut c_void,
    finish: unsafe extern "C" fn(*mut c_void, *mut c_void),
    user_context: *mut c_void,
    workers: usize,
    /// A task panicked (a bug of the library: `MPM_STATUS_INTERNAL`).
    panicked: AtomicBool,
    /// The host broke the contract of `MpmEnqueueTaskCallback` (`MPM_STATUS_TASK_CONTRACT`);
    /// later loops run on the calling thread, without the host.
    broken: AtomicBool,
    /// A loop is in the host's hands: the kernel calls `parallel_for` from the stepping thread
    /// alone, one loop at a time (never from a task), which `MpmTaskSystem` promises the host.
    in_loop: AtomicBool,
}

// SAFETY: the adapter's fields are read-only after it is made, but for the atomics; its raw
// pointer `user_context` is never dereferenced, only handed to the host's callbacks, which it
// calls one loop at a time (`in_loop`), from the stepping thread.
unsafe impl Sync for HostTasks {}

/// One `parallel_for` as the trampoline sees it: what `task_context` points to.
struct Loop<'a, 't> {
    task: &'a Task<'t>,
    items: usize,
    workers: usize,
    /// The range each worker runs now, packed as `start << 32 | end` (0: none; a range that
    /// runs is never empty, so its end is at least 1).
    running: [AtomicU64; MAX_WORKERS as usize],
    /// One bit per item (item `i`: bit `i % 64` of word `i / 64`), set by the range that takes
    /// it, before the range runs: the items run or running. A range that finds one of its
    /// bits set is refused (the bits it set before it found it stay set, and the loop is
    /// broken anyway).
    taken: [AtomicU64; TAKEN_WORDS],
    panicked: &'a AtomicBool,
    broken: &'a AtomicBool,
}

impl Loop<'_, '_> {
    /// Whether any worker's range still runs.
    fn any_running(&self) -> bool {
        self.running[..self.workers]
            .iter()
            .any(|r| r.load(Ordering::SeqCst) != 0)
    }

    /// Takes the items `start..end` (`start < end <= items`): sets their bits, and answers
    /// whether none was set before. Two ranges that share an item both set its bit, one after
    /// the other (one atomic word), so the later one sees it, whether the two run at once or
    /// one after the other.
    fn take(&self, start: usize, end: usize) -> bool {
        let mut fresh = true;
        for w in start / 64..end.div_ceil(64) {
            let lo = start.max(64 * w) - 64 * w;
            let hi = end.min(64 * w + 64) - 64 * w;
            // Bits lo..hi of the word (hi > lo, hi <= 64).
            let mask = (u64::MAX >> (64 - (hi - lo))) << lo;
            fresh &= self.taken[w].fetch_or(mask, Ordering::Relaxed) & mask == 0;
        }
        fresh
    }

    /// Whether every item of the loop was taken.
    fn all_taken(&self) -> bool {
        self.taken.iter().enumerate().all(|(w, bits)| {
            // The bits of items 64 w .. 64 w + 64 that the loop has.
            let have = self.items.saturating_sub(64 * w).min(64);
            let want = if have == 64 {
                u64::MAX
            } else {
                (1 << have) - 1
            };
            bits.load(Ordering::Relaxed) == want
        })
    }
}

/// The `MpmTaskCallback` the library hands the host: checks the range, then runs it.
///
/// # Safety
/// `task_context` is the `task_context` of a call of `enqueue_task` whose task is not finished
/// yet (the contract of `MpmTaskCallback`).
unsafe extern "C" fn run_range(start: u32, end: u32, worker: u32, task_context: *mut c_void) {
    if task_context.is_null() {
        return;
    }
    // SAFETY: the caller promises the context of a task not yet finished: `parallel_for`
    // keeps its `Loop` alive until the host's finish (or enqueue) has returned and no range
    // runs any more.
    let lp = unsafe { &*(task_context as *const Loop<'_, '_>) };
    let (s, e, w) = (start as usize, end as usize, worker as usize);
    if s == e && e <= lp.items && w < lp.workers {
        return;
    }
    if !(s < e && e <= lp.items && w < lp.workers) {
        lp.broken.store(true, Ordering::Relaxed);
        return;
    }
    let packed = (start as u64) << 32 | end as u64;
    // Claim the worker, then the items: a range that shares an item with one that ran or
    // runs (on any worker) finds its bit set and does not run.
    if lp.running[w]
        .compare_exchange(0, packed, Ordering::SeqCst, Ordering::SeqCst)
        .is_err()
    {
        lp.broken.store(true, Ordering::Relaxed);
        return;
    }
    if lp.take(s, e) {
        let ran = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (lp.task)(s, e, w)));
        if ran.is_err() {
            lp.panicked.store(true, Ordering::Relaxed);
        }
    } else {
        lp.broken.store(true, Ordering::Relaxed);
    }
    lp.running[w].store(0, Ordering::SeqCst);
}

// SAFETY: the callback runs a range only if it lies within `0..items`, its worker is below
// the count and idle, and none of its items was taken by another range of the loop before
// (`Loop::take`): each item runs at most once, so no two ranges the kernel's items see
// overlap. Items never run are found after finish (`MPM_STATUS_TASK_CONTRACT`), and
// `parallel_for` waits out a range still running before it returns.
unsafe impl TaskSystem for HostTasks {
    fn worker_count(&self) -> usize {
        self.workers
    }

    fn parallel_for(&self, items: usize, min_range: usize, task: &Task<'_>) {
        // A loop inside another (from a task, on a host's thread) would break the promise of
        // `MpmTaskSystem`: a bug of the kernel, caught as a panic (`MPM_STATUS_INTERNAL`).
        assert!(
            !self.in_loop.swap(true, Ordering::Acquire),
            "parallel_for inside parallel_for"
        );
        self.run_loop(items, min_range, task);
        self.in_loop.store(false, Ordering::Release);
    }
}

impl HostTasks {
    /// [`TaskSystem::parallel_for`], one loop at a time.
    fn run_loop(&self, items: usize, min_range: usize, task: &Task<'_>) {
        if items == 0 {
            return;
        }
        let count = match u32::try_from(items) {
            Ok(count) if items <= MAX_ITEMS => count,
            // More items than a loop's bits hold (no loop of the kernel's has that many) or the
            // C interface counts: on the calling thread, which no range occupies now.
            _ => return task(0, items, 0),
        };
        if self.broken.load(Ordering::Relaxed) {
            return task(0, items, 0);
        }
        let lp = Loop {
            task,
            items,
            workers: self.workers.min(MAX_WORKERS as usize),
            running: [const { AtomicU64::new(0) }; MAX_WORKERS as usize],
            taken: [const { AtomicU64::new(0) }; TAKEN_WORDS],
            panicked: &self.panicked,
            broken: &self.broken,
        };
        let context = &lp as *const Loop<'_, '_> as *mut c_void;
        let min = u32::try_from(min_range.max(1)).unwrap_or(u32::MAX);
        // SAFETY: the host's enqueue, with the trampoline and a context that lives until the
        // end of this function, after the host has finished the task.
        let handle =
            unsafe { (self.enqueue)(Some(run_range), count, min, context, self.user_context) };
        if !handle.is_null() {
            // SAFETY: the handle the host's enqueue returned, finished once.
            unsafe { (self.finish)(handle, self.user_context) };
        }
        // A finish that returned early: wait for the ranges that still run, whose context is
        // this frame (the host broke the contract; a range it starts after this is its bug).
        while lp.any_running() {
            lp.broken.store(true, Ordering::Relaxed);
            std::thread::yield_now();
        }
        // Items no range took (the finish made what the ranges did visible here).
        if !lp.all_taken() {
            lp.broken.store(true, Ordering::Relaxed);
        }
    }
}

/// `mpm_world_step` on the host's task system: the step's parallel parts run as tasks on
/// `tasks`, with the same results, bit for bit, for any `worker_count` and however the host
/// cuts and spreads the ranges. `tasks->worker_count` must lie in 1..=the definition's
/// `workers` (`MPM_STATUS_INVALID_LIMIT`); NULL `tasks` or a NULL callback is
/// `MPM_STATUS_NULL_POINTER`. The struct is copied when the call begins. The loops go to the
/// host at any size: below `MPM_PARALLEL_FROM` particles two workers take longer than one,
/// and `mpm_world_step` is the faster call.
///
/// A task system that breaks the contract of `MpmEnqueueTaskCallback` makes the call answer
/// `MPM_STATUS_TASK_CONTRACT` once its task is finished, without the report; the ranges that
/// broke it were not run (no item ran twice), and the world may be in an intermediate state:
/// restore a snapshot taken before the call.
///
/// # Safety
/// `world` is NULL or a world; `report_out` is NULL or valid; `tasks` is NULL or valid, and
/// its callbacks keep the contracts of `MpmEnqueueTaskCallback` and `MpmFinishTaskCallback`
/// that the library cannot check (a `task_context` passed back unchanged, no call of the task
/// after its finish returned).
#[no_mangle]
pub unsafe extern "C" fn mpm_world_step_tasks(
    world: *mut MpmWorld,
    dt: mpm_real,
    tasks: *const MpmTaskSystem,
    report_out: *mut MpmStepReport,
) -> MpmStatus {
    guard(|| {
        non_null(tasks)?;
        non_null(report_out)?;
        // SAFETY: checked non-NULL; copied before the world is opened for writing (the caller
        // may keep the struct anywhere).
        let t = unsafe { *tasks };
        let (Some(enqueue), Some(finish)) = (t.enqueue_task, t.finish_task) else {
            return Err(MpmStatus::NullPointer);
        };
        // SAFETY: the caller promises a world.
        let mut w = unsafe { world_at(world) }?;
        apart(w.as_bytes(), report_out, 1)?;
        let host = HostTasks {
            enqueue,
            finish,
            user_context: t.user_context,
            workers: t.worker_count as usize,
            panicked: AtomicBool::new(false),
            broken: AtomicBool::new(false),
            in_loop: AtomicBool::new(false),
        };
        let stepped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            // Every loop to the host at any size, so that its contract is checked each step
            // (`step_with_tasks` keeps a small world on the calling thread).
            w.step_on(dt, kernel::simd::Simd::Detect, &host)
        }));
        // First: items left out or run twice may break what the step expects of them further
        // on (a panic there is the host's doing, not the library's).
        if host.broken.load(Ordering::Relaxed) {
            return Err(MpmStatus::TaskContract);
        }
        let Ok(r) = stepped else {
            return Err(MpmStatus::Internal);
        };
        let r = r?;
        if host.panicked.load(Ordering::Relaxed) {
            return Err(MpmStatus::Internal);
        }
        // SAFETY: checked non-NULL.
        unsafe { put(report_out, step_report(&r)) };
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, AtomicUsize};
    use std::sync::Mutex;
    use std::thread::JoinHandle;

    /// Ranges a test host calls the task with: `(start, end, worker)`.
    type Ranges = &'static [(u32, u32, u32)];

    /// What a test host does with a task.
    #[derive(Clone, Copy, Debug)]
    enum Mode {
        /// Runs the whole task on the calling thread and returns NULL.
        Inline,
        /// One range of at least `min_range` items per worker, each on a thread of its own
        /// (joined before enqueue returns); returns a handle.
        Threads,
        /// Calls the task with these `(start, end, worker)`, in order, on the calling thread.
        Ranges(Ranges),
        /// Starts `(0, 10, 0)` on a thread and, while it runs, calls `(5, 15, 1)` (or
        /// `(10, 15, 0)`: another range on the busy worker) and then `(15, item_count, 1)`.
        Overlap { same_worker: bool },
        /// Starts the whole task on a thread and returns a handle at once; finish returns at
        /// once too, while the range still runs.
        EarlyFinish,
    }

    /// A host task system driven by `mode`, with what it saw.
    struct TestHost {
        mode: Mode,
        workers: u32,
        enqueued: AtomicU32,
        finished: AtomicU32,
        /// Set by the test's task when the range that starts at 0 runs.
        started: AtomicBool,
        /// Lets that range return.
        release: AtomicBool,
        thread: Mutex<Option<JoinHandle<()>>>,
    }

    impl TestHost {
        fn new(mode: Mode, workers: u32) -> TestHost {
            TestHost {
                mode,
                workers,
                enqueued: AtomicU32::new(0),
                finished: AtomicU32::new(0),
                started: AtomicBool::new(false),
                release: AtomicBool::new(true),
                thread: Mutex::new(None),
            }
        }

        fn tasks(&self) -> HostTasks {
            HostTasks {
                enqueue,
                finish,
                user_context: self as *const TestHost as *mut c_void,
                workers: self.workers as usize,
                panicked: AtomicBool::new(false),
                broken: AtomicBool::new(false),
                in_loop: AtomicBool::new(false),
            }
        }
    }

    /// Calls `task` from a test host, with the context as an address (which threads may take).
    fn call(task: MpmTaskCallback, start: u32, end: u32, worker: u32, context: usize) {
        let f = task.expect("the library hands a task");
        // SAFETY: the context the library handed the host, whose task is not finished.
        unsafe { f(start, end, worker, context as *mut c_void) }
    }

    fn wait_for(flag: &AtomicBool) {
        while !flag.load(Ordering::SeqCst) {
            std::thread::yield_now();
        }
    }

    unsafe extern "C" fn enqueue(
        task: MpmTaskCallback,
        items: u32,
        min_range: u32,
        task_context: *mut c_void,
        user_context: *mut c_void,
    ) -> *mut c_void {
        // SAFETY: `tasks()` made the user context from a `TestHost` that outlives the loop.
        let host = unsafe { &*(user_context as *const TestHost) };
        host.enqueued.fetch_add(1, Ordering::SeqCst);
        let context = task_context as usize;
        match host.mode {
            Mode::Inline => {
                call(task, 0, items, 0, context);
                core::ptr::null_mut()
            }
            Mode::Threads => {
                let ranges = (items / min_range.max(1)).clamp(1, host.workers);
                let cut = |k: u32| (u64::from(items) * u64::from(k) / u64::from(ranges)) as u32;
                std::thread::scope(|s| {
                    for i in 0..ranges {
                        s.spawn(move || call(task, cut(i), cut(i + 1), i, context));
                    }
                });
                user_context
            }
            Mode::Ranges(ranges) => {
                for &(s, e, w) in ranges {
                    call(task, s, e, w, context);
                }
                core::ptr::null_mut()
            }
            Mode::Overlap { same_worker } => {
                host.release.store(false, Ordering::SeqCst);
                std::thread::scope(|s| {
                    s.spawn(move || call(task, 0, 10, 0, context));
                    wait_for(&host.started);
                    let second = if same_worker { (10, 15, 0) } else { (5, 15, 1) };
                    call(task, second.0, second.1, second.2, context);
                    host.release.store(true, Ordering::SeqCst);
                });
                call(task, 15, items, 1, context);
                core::ptr::null_mut()
            }
            Mode::EarlyFinish => {
                host.release.store(false, Ordering::SeqCst);
                let t = std::thread::spawn(move || call(task, 0, items, 0, context));
                *host.thread.lock().expect("not poisoned") = Some(t);
                wait_for(&host.started);
                user_context
            }
        }
    }

    unsafe extern "C" fn finish(user_task: *mut c_void, user_context: *mut c_void) {
        assert_eq!(
            user_task, user_context,
            "finish gets the handle enqueue returned"
        );
        // SAFETY: as in `enqueue`.
        let host = unsafe { &*(user_context as *const TestHost) };
        host.finished.fetch_add(1, Ordering::SeqCst);
        if let Mode::EarlyFinish = host.mode {
            // The range still runs; let it end after a while, without waiting for it.
            let release = &host.release as *const AtomicBool as usize;
            std::thread::spawn(move || {
                std::thread::sleep(std::time::Duration::from_millis(50));
                // SAFETY: the host outlives the test, which joins its thread first.
                unsafe { &*(release as *const AtomicBool) }.store(true, Ordering::SeqCst);
            });
        }
    }

    /// How often each of `items` items ran and the largest worker index seen, for one loop of
    /// `parallel_for` on `host` (a fresh adapter unless `tasks` is given).
    fn run(
        host: &TestHost,
        tasks: &HostTasks,
        items: usize,
        min_range: usize,
    ) -> (Vec<u32>, usize) {
        let counts: Vec<AtomicU32> = (0..items).map(|_| AtomicU32::new(0)).collect();
        let max_worker = AtomicUsize::new(0);
        tasks.parallel_for(items, min_range, &|s, e, w| {
            max_worker.fetch_max(w, Ordering::SeqCst);
            if s == 0 {
                host.started.store(true, Ordering::SeqCst);
                wait_for(&host.release);
            }
            for c in &counts[s..e] {
                c.fetch_add(1, Ordering::SeqCst);
            }
        });
        if let Some(t) = host.thread.lock().expect("not poisoned").take() {
            t.join().expect("the host's thread");
        }
        let counts = counts.iter().map(|c| c.load(Ordering::SeqCst)).collect();
        (counts, max_worker.load(Ordering::SeqCst))
    }

    fn flags(tasks: &HostTasks) -> (bool, bool) {
        (
            tasks.panicked.load(Ordering::SeqCst),
            tasks.broken.load(Ordering::SeqCst),
        )
    }

    #[test]
    fn a_host_that_runs_inline_covers_every_item_once_without_finish() {
        let host = TestHost::new(Mode::Inline, 1);
        let tasks = host.tasks();
        let (counts, worker) = run(&host, &tasks, 37, 4);
        assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
        assert_eq!(worker, 0);
        assert_eq!(host.enqueued.load(Ordering::SeqCst), 1);
        assert_eq!(
            host.finished.load(Ordering::SeqCst),
            0,
            "no finish for NULL"
        );
        assert_eq!(flags(&tasks), (false, false));
    }

    #[test]
    fn threads_cover_every_item_once_on_their_workers() {
        for workers in [1, 2, 3, 4, 7, 8, 16] {
            for (items, min_range) in [(1, 1), (5, 1), (64, 4), (1000, 3), (33, 40)] {
                let host = TestHost::new(Mode::Threads, workers);
                let tasks = host.tasks();
                let (counts, worker) = run(&host, &tasks, items, min_range);
                assert!(
                    counts.iter().all(|&c| c == 1),
                    "{workers} {items}: {counts:?}"
                );
                assert!(worker < workers as usize);
                assert_eq!(host.finished.load(Ordering::SeqCst), 1);
                assert_eq!(flags(&tasks), (false, false), "{workers} {items}");
            }
        }
    }

    #[test]
    fn ranges_in_any_order_and_empty_ones_keep_the_contract() {
        let host = TestHost::new(
            Mode::Ranges(&[(3, 7, 0), (0, 3, 1), (9, 9, 1), (7, 10, 0)]),
            2,
        );
        let tasks = host.tasks();
        let (counts, _) = run(&host, &tasks, 10, 1);
        assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
        assert_eq!(flags(&tasks), (false, false));
    }

    /// Each case breaks the contract once: the bad range does not run, the others do, and the
    /// loop is flagged.
    #[test]
    fn ranges_out_of_bounds_are_not_run_and_flagged() {
        let cases: [(Ranges, &[u32]); 6] = [
            // Past the end.
            (&[(0, 8, 0), (8, 11, 0)], &[1, 1, 1, 1, 1, 1, 1, 1, 0, 0]),
            // Reversed.
            (&[(0, 8, 0), (10, 8, 0)], &[1, 1, 1, 1, 1, 1, 1, 1, 0, 0]),
            // Empty past the end.
            (&[(0, 10, 0), (11, 11, 0)], &[1; 10]),
            // Worker index at worker_count, and far past it.
            (&[(0, 8, 0), (8, 10, 2)], &[1, 1, 1, 1, 1, 1, 1, 1, 0, 0]),
            (
                &[(0, 8, 0), (8, 10, u32::MAX)],
                &[1, 1, 1, 1, 1, 1, 1, 1, 0, 0],
            ),
            // Items left out.
            (&[(0, 9, 0)], &[1, 1, 1, 1, 1, 1, 1, 1, 1, 0]),
        ];
        for (ranges, want) in cases {
            let host = TestHost::new(Mode::Ranges(ranges), 2);
            let tasks = host.tasks();
            let (counts, _) = run(&host, &tasks, 10, 1);
            assert_eq!(counts, want, "{ranges:?}");
            assert_eq!(flags(&tasks), (false, true), "{ranges:?}");
        }
    }

    /// A range with an item that a range of the loop ran before, on any worker, is not run
    /// and flags the loop, whatever the ranges' lengths add up to: as many items run twice as
    /// are left out (the count of items run is `items`), in one word of the item bits and
    /// across words, or more run twice than left out.
    #[test]
    fn an_item_run_twice_or_never_is_caught_whatever_the_counts() {
        let cases: [(usize, Ranges, Vec<u32>); 5] = [
            // The first item again instead of the last.
            (
                10,
                &[(0, 9, 0), (0, 1, 1)],
                [1; 9].into_iter().chain([0]).collect(),
            ),
            // A range twice, the next one left out, on one worker and on two.
            (
                10,
                &[(0, 5, 0), (0, 5, 0)],
                [1; 5].into_iter().chain([0; 5]).collect(),
            ),
            (
                10,
                &[(5, 10, 1), (5, 10, 0)],
                [0; 5].into_iter().chain([1; 5]).collect(),
            ),
            // Across words of the item bits: 0..100 twice, 100..200 left out.
            (
                200,
                &[(0, 100, 0), (0, 100, 1)],
                [1; 100].into_iter().chain([0; 100]).collect(),
            ),
            // Every item, then one again.
            (10, &[(0, 10, 0), (9, 10, 1)], vec![1; 10]),
        ];
        for (items, ranges, want) in cases {
            let host = TestHost::new(Mode::Ranges(ranges), 2);
            let tasks = host.tasks();
            let (counts, _) = run(&host, &tasks, items, 1);
            assert_eq!(counts, want, "{ranges:?}: each item runs at most once");
            assert_eq!(flags(&tasks), (false, true), "{ranges:?}");
        }
        // The counts of the first four cases add up to the items: the check is not a sum. Nor
        // does it look only at ranges that run at once.
        let host = TestHost::new(Mode::Ranges(&[(0, 128, 0), (64, 192, 1), (192, 256, 0)]), 2);
        let tasks = host.tasks();
        let (counts, _) = run(&host, &tasks, 320, 1);
        assert_eq!(&counts[64..128], &[1; 64], "the shared items run once");
        assert_eq!(flags(&tasks), (false, true));
    }

    /// Loops of every length up to the most the kernel hands out, cut in ranges that end at
    /// and across the item bits' words, keep the contract; one more item runs on the calling
    /// thread.
    #[test]
    fn loops_up_to_the_most_items_are_checked_and_longer_ones_run_inline() {
        for items in [1, 63, 64, 65, 127, 128, 129, 1000, MAX_ITEMS] {
            for min_range in [1, 7, 64] {
                let host = TestHost::new(Mode::Threads, 3);
                let tasks = host.tasks();
                let (counts, _) = run(&host, &tasks, items, min_range);
                assert!(counts.iter().all(|&c| c == 1), "{items} {min_range}");
                assert_eq!(flags(&tasks), (false, false), "{items} {min_range}");
            }
        }
        let host = TestHost::new(Mode::Threads, 3);
        let tasks = host.tasks();
        let (counts, worker) = run(&host, &tasks, MAX_ITEMS + 1, 1);
        assert!(counts.iter().all(|&c| c == 1));
        assert_eq!((worker, host.enqueued.load(Ordering::SeqCst)), (0, 0));
        assert_eq!(flags(&tasks), (false, false));
    }

    #[test]
    fn a_range_overlapping_one_that_runs_is_not_run() {
        for same_worker in [false, true] {
            let host = TestHost::new(Mode::Overlap { same_worker }, 2);
            let tasks = host.tasks();
            let (counts, _) = run(&host, &tasks, 20, 1);
            // 0..10 ran, the second range did not, 15..20 ran.
            let want: Vec<u32> = (0..20).map(|i| u32::from(!(10..15).contains(&i))).collect();
            assert_eq!(counts, want, "same worker {same_worker}");
            assert_eq!(flags(&tasks), (false, true));
        }
    }

    #[test]
    fn a_finish_that_returns_early_is_waited_out_and_flagged() {
        let host = TestHost::new(Mode::EarlyFinish, 1);
        let tasks = host.tasks();
        let (counts, _) = run(&host, &tasks, 12, 1);
        assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
        assert_eq!(host.finished.load(Ordering::SeqCst), 1);
        assert_eq!(flags(&tasks), (false, true));
    }

    #[test]
    fn after_a_broken_loop_the_next_runs_on_the_calling_thread() {
        let host = TestHost::new(Mode::Ranges(&[(0, 5, 0)]), 2);
        let tasks = host.tasks();
        run(&host, &tasks, 10, 1);
        assert_eq!(flags(&tasks), (false, true));
        let (counts, worker) = run(&host, &tasks, 10, 1);
        assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
        assert_eq!(worker, 0);
        assert_eq!(
            host.enqueued.load(Ordering::SeqCst),
            1,
            "the host is not asked again"
        );
    }

    #[test]
    fn a_panic_in_a_task_is_caught_and_flagged() {
        let host = TestHost::new(Mode::Threads, 4);
        let tasks = host.tasks();
        let ran = AtomicUsize::new(0);
        tasks.parallel_for(8, 2, &|s, e, _| {
            assert!(s != 0, "a task that panics");
            ran.fetch_add(e - s, Ordering::SeqCst);
        });
        assert_eq!(ran.load(Ordering::SeqCst), 6, "the other ranges ran");
        assert_eq!(flags(&tasks), (true, false));
    }

    #[test]
    fn no_items_enqueue_nothing_and_too_many_run_on_the_calling_thread() {
        let host = TestHost::new(Mode::Threads, 4);
        let tasks = host.tasks();
        tasks.parallel_for(0, 1, &|_, _, _| panic!("no items"));
        let seen = Mutex::new(Vec::new());
        let items = u32::MAX as usize + 1;
        tasks.parallel_for(items, 1, &|s, e, w| {
            seen.lock().expect("not poisoned").push((s, e, w))
        });
        assert_eq!(*seen.lock().expect("not poisoned"), [(0, items, 0)]);
        assert_eq!(host.enqueued.load(Ordering::SeqCst), 0);
        assert_eq!(flags(&tasks), (false, false));
    }

    #[test]
    fn a_loop_inside_a_task_is_refused() {
        let host = TestHost::new(Mode::Inline, 1);
        let tasks = host.tasks();
        tasks.parallel_for(4, 1, &|_, _, _| tasks.parallel_for(2, 1, &|_, _, _| {}));
        assert_eq!(flags(&tasks), (true, false), "the inner loop panicked");
        assert_eq!(
            host.enqueued.load(Ordering::SeqCst),
            1,
            "only the outer loop"
        );
        let (counts, _) = run(&host, &tasks, 3, 1);
        assert_eq!(counts, [1, 1, 1], "the next loop runs as usual");
    }

    #[test]
    fn a_null_context_is_ignored() {
        // SAFETY: NULL is the one context the trampoline recognises as not its own.
        unsafe { run_range(0, 1, 0, core::ptr::null_mut()) };
    }
}
