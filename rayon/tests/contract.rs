//! `RayonTasks` keeps the `TaskSystem` contract (mpm_gimp::tasks) for many item counts, range
//! lengths and pool sizes, called from outside the pool, from inside it and from another pool:
//! the ranges cover `0..items`, each item once, each at least `min_range` long but the last;
//! the worker is below `worker_count` and no two ranges run at once on the same worker.

use mpm_gimp::TaskSystem;
use mpm_gimp_rayon::RayonTasks;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::Mutex;

/// Runs one `parallel_for` on `tasks` and checks every clause of the contract.
fn check(tasks: &RayonTasks, items: usize, min_range: usize) {
    let workers = tasks.worker_count();
    assert!(workers >= 1);
    let visits: Vec<AtomicU32> = (0..items).map(|_| AtomicU32::new(0)).collect();
    let busy: Vec<AtomicBool> = (0..workers).map(|_| AtomicBool::new(false)).collect();
    let running = AtomicUsize::new(0);
    let ranges = Mutex::new(Vec::new());
    tasks.parallel_for(items, min_range, &|start, end, worker| {
        let case = format!("items {items} min_range {min_range} workers {workers}");
        assert!(worker < workers, "worker {worker}: {case}");
        assert!(
            !busy[worker].swap(true, Ordering::SeqCst),
            "worker {worker} ran two ranges at once: {case}"
        );
        let now = running.fetch_add(1, Ordering::SeqCst) + 1;
        assert!(now <= workers, "{now} ranges at once: {case}");
        assert!(start < end && end <= items, "range {start}..{end}: {case}");
        for v in &visits[start..end] {
            v.fetch_add(1, Ordering::Relaxed);
        }
        // A little work, so that the ranges overlap in time.
        let mut x = start as u64;
        for _ in 0..(end - start) * 64 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        ranges.lock().unwrap().push((start, end));
        running.fetch_sub(1, Ordering::SeqCst);
        busy[worker].store(false, Ordering::SeqCst);
    });
    let case = format!("items {items} min_range {min_range} workers {workers}");
    assert!(
        visits.iter().all(|v| v.load(Ordering::Relaxed) == 1),
        "an item not visited exactly once: {case}"
    );
    let mut ranges = ranges.into_inner().unwrap();
    ranges.sort_unstable();
    let mut next = 0;
    for (k, &(start, end)) in ranges.iter().enumerate() {
        assert_eq!(start, next, "{case}");
        assert!(
            k + 1 == ranges.len() || end - start >= min_range,
            "range {start}..{end} shorter than {min_range} and not the last: {case}"
        );
        next = end;
    }
    assert_eq!(next, items, "{case}");
}

/// A fixed 64-bit LCG: the same cases every run.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n) as usize
    }

    /// An item count or range length: small, near powers of two, or anywhere up to `max`.
    fn size(&mut self, max: u64) -> usize {
        match self.below(3) {
            0 => self.below(9),
            1 => {
                let p = 1usize << self.below(12);
                (p + self.below(3)).saturating_sub(1)
            }
            _ => self.below(max),
        }
    }
}

#[test]
fn every_item_once_on_a_worker_below_the_count() {
    let mut rng = Lcg(0x2545_f491_4f6c_dd1d);
    for threads in 1..=8 {
        let tasks = RayonTasks::new(threads).expect("a pool");
        assert_eq!(tasks.worker_count(), threads);
        for _ in 0..150 {
            let items = rng.size(20_000);
            let min_range = rng.size(600);
            check(&tasks, items, min_range);
        }
    }
}

#[test]
fn called_from_inside_the_pool_and_from_another_pool() {
    let mut rng = Lcg(7);
    let tasks = RayonTasks::new(3).expect("a pool");
    let other = RayonTasks::new(5).expect("another pool");
    for _ in 0..40 {
        let (items, min_range) = (rng.size(5000), rng.size(200));
        // From its own threads (two ranges of an outer call, each on a pool thread): those
        // threads take part in the inner call under their own indices.
        tasks.parallel_for(2, 1, &|_, _, _| check(&tasks, items, min_range));
        // From threads of another pool (with more threads than this one): still this pool's
        // threads and indices.
        other.parallel_for(2, 1, &|_, _, _| check(&tasks, items, min_range));
    }
}

#[test]
fn the_global_pool() {
    let tasks = RayonTasks::global();
    assert_eq!(tasks.worker_count(), rayon::current_num_threads());
    let mut rng = Lcg(11);
    for _ in 0..100 {
        check(&tasks, rng.size(20_000), rng.size(600));
    }
    // From a thread of another pool, the global system runs on that pool, and counts its
    // threads.
    let pool = RayonTasks::new(3).expect("a pool");
    pool.parallel_for(2, 1, &|_, _, _| {
        assert_eq!(tasks.worker_count(), 3);
        check(&tasks, 5000, 10);
    });
}

#[test]
fn no_items_no_call() {
    let tasks = RayonTasks::new(2).expect("a pool");
    tasks.parallel_for(0, 1, &|_, _, _| panic!("called on no items"));
    tasks.parallel_for(0, 0, &|_, _, _| panic!("called on no items"));
}

#[test]
fn a_panic_reaches_the_caller() {
    let tasks = RayonTasks::new(2).expect("a pool");
    let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tasks.parallel_for(1000, 1, &|start, _, _| {
            if start == 0 {
                panic!("range 0");
            }
        })
    }));
    assert!(caught.is_err());
    // The pool still works.
    check(&tasks, 1000, 1);
}

/// `install` returns its closure's value, carries its panic to the caller (the pool's other
/// threads, spinning meanwhile, are released), and runs rayon work handed to the pool inside
/// it; the pool works after either.
#[test]
fn install_returns_unwinds_and_runs_rayon_work() {
    let tasks = RayonTasks::new(3).expect("a pool");
    assert_eq!(tasks.install(|| 7), 7);
    let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tasks.install(|| -> u32 { panic!("inside install") })
    }));
    assert!(caught.is_err());
    let (a, b) = tasks.install(|| rayon::join(|| 1 + 1, rayon::current_thread_index));
    assert_eq!(a, 2);
    assert!(b.is_some_and(|i| i < 3));
    tasks.install(|| check(&tasks, 1000, 1));
    check(&tasks, 1000, 7);
}
