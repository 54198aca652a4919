//! The native library of the `mpm_gimp` Python package: the C interface of `mpm-gimp-ffi`
//! (every `mpm_*` entry point, exported from this cdylib unchanged) and a worker pool the
//! package owns, as three more C functions:
//!
//! - `mpm_py_pool_new(threads)`: a rayon pool of `threads` threads, or NULL;
//! - `mpm_py_pool_free(pool)`: ends its threads;
//! - `mpm_py_world_step_pool(world, dt, pool, report_out)`: `mpm_world_step_tasks` on the
//!   pool, through the header's `MpmTaskSystem` contract.
//!
//! The pool runs each of the step's loops to its end inside `enqueue_task` (which the contract
//! allows: it then returns NULL and `finish_task` is not called), cutting the items with
//! `rayon::join` and passing each range the index of the pool thread that runs it, below the
//! pool's thread count. The library checks every range it is handed, so no cut can corrupt a
//! world; the results are bit-identical to `mpm_world_step`'s for any thread count.
#![deny(missing_docs)]

use core::ffi::c_void;
use ffi::{mpm_real, MpmStatus, MpmStepReport, MpmTaskCallback, MpmTaskSystem, MpmWorld};
use rayon::{ThreadPool, ThreadPoolBuilder};

/// Ranges a loop is cut into per worker (at least `min_range` items each): a few, so that a
/// thread that finishes early takes a range of a slower one (as `mpm-gimp-rayon` cuts them).
const RANGES_PER_WORKER: u32 = 4;

/// A worker pool of the package: `mpm_py_pool_new` makes one.
pub struct MpmPyPool {
    pool: ThreadPool,
}

/// A pool of `threads` threads (1..=256), or NULL when `threads` is out of range or the system
/// refuses a thread. Free it with `mpm_py_pool_free`.
#[no_mangle]
pub extern "C" fn mpm_py_pool_new(threads: u32) -> *mut MpmPyPool {
    if !(1..=256).contains(&threads) {
        return core::ptr::null_mut();
    }
    let built = std::panic::catch_unwind(|| {
        ThreadPoolBuilder::new()
            .num_threads(threads as usize)
            .thread_name(|i| format!("mpm-gimp-{i}"))
            .build()
    });
    match built {
        Ok(Ok(pool)) => Box::into_raw(Box::new(MpmPyPool { pool })),
        _ => core::ptr::null_mut(),
    }
}

/// Ends the pool's threads. NULL is accepted and does nothing.
///
/// # Safety
/// `pool` is NULL or from `mpm_py_pool_new`, not freed before, and no step runs on it.
#[no_mangle]
pub unsafe extern "C" fn mpm_py_pool_free(pool: *mut MpmPyPool) {
    if !pool.is_null() {
        // SAFETY: the caller promises a pool from `mpm_py_pool_new`, freed once.
        drop(unsafe { Box::from_raw(pool) });
    }
}

/// One loop of the step, as `enqueue_task` receives it.
#[derive(Clone, Copy)]
struct Loop {
    task: unsafe extern "C" fn(u32, u32, u32, *mut c_void),
    context: *mut c_void,
    chunk: u32,
}

// SAFETY: the context is the library's task, which the contract lets any thread call with
// its own ranges while the loop runs.
unsafe impl Send for Loop {}
// SAFETY: as Send; the loop is only read.
unsafe impl Sync for Loop {}

/// Runs `start .. end` on the current pool thread or splits it in two with `rayon::join`.
fn run(l: Loop, start: u32, end: u32) {
    if end - start <= l.chunk {
        let worker = rayon::current_thread_index().unwrap_or(0) as u32;
        // SAFETY: a range of the loop's items on the thread's own worker index, while
        // `enqueue` has not returned (the contract of `MpmTaskCallback`).
        unsafe { (l.task)(start, end, worker, l.context) };
    } else {
        let mid = start + (end - start) / 2;
        rayon::join(|| run(l, start, mid), || run(l, mid, end));
    }
}

/// `MpmEnqueueTaskCallback`: runs the whole loop on the pool and returns NULL.
unsafe extern "C" fn enqueue(
    task: MpmTaskCallback,
    item_count: u32,
    min_range: u32,
    task_context: *mut c_void,
    user_context: *mut c_void,
) -> *mut c_void {
    let Some(task) = task else {
        return core::ptr::null_mut();
    };
    // SAFETY: `user_context` is the pool `mpm_py_world_step_pool` put there.
    let pool = unsafe { &*(user_context as *const MpmPyPool) };
    let workers = pool.pool.current_num_threads() as u32;
    let chunk = item_count
        .div_ceil(workers * RANGES_PER_WORKER)
        .max(min_range)
        .max(1);
    let l = Loop {
        task,
        context: task_context,
        chunk,
    };
    pool.pool.install(|| run(l, 0, item_count));
    core::ptr::null_mut()
}

/// `MpmFinishTaskCallback`: never called, since `enqueue` returns NULL.
unsafe extern "C" fn finish(_user_task: *mut c_void, _user_context: *mut c_void) {}

/// `mpm_world_step_tasks` on `pool`: its thread count is the task system's `worker_count`
/// (at most the definition's `workers`, else `MPM_STATUS_INVALID_LIMIT`). NULL `pool` is
/// `MPM_STATUS_NULL_POINTER`; every other check is `mpm_world_step_tasks`'s.
///
/// # Safety
/// `world` is NULL or a world; `pool` is NULL or a live pool from `mpm_py_pool_new`;
/// `report_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_py_world_step_pool(
    world: *mut MpmWorld,
    dt: mpm_real,
    pool: *const MpmPyPool,
    report_out: *mut MpmStepReport,
) -> MpmStatus {
    if pool.is_null() {
        return MpmStatus::NullPointer;
    }
    // SAFETY: the caller promises a live pool.
    let workers = unsafe { &*pool }.pool.current_num_threads() as u32;
    let tasks = MpmTaskSystem {
        enqueue_task: Some(enqueue),
        finish_task: Some(finish),
        user_context: pool as *mut c_void,
        worker_count: workers,
    };
    // SAFETY: the caller's promises for `world` and `report_out`; `tasks` lives through the
    // call and its callbacks keep the contract.
    unsafe { ffi::mpm_world_step_tasks(world, dt, &tasks, report_out) }
}
