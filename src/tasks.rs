//! The host's task system: how a step runs on several cores without owning a thread
//! (Box2D v3's model). The host hands [`crate::World::step_with_tasks`] a [`TaskSystem`] (and
//! sizes [`crate::WorldDef::workers`] for it); the step cuts each pass into items (ranges of
//! particle chunks, slabs of grid lines) whose results never depend on how the items are
//! spread over workers: every floating-point sum is added in the order a single worker adds
//! it (ARCHITECTURE.md, "Threads"). So the state after a step is bit-identical for any number
//! of workers, and to [`Serial`]'s. Rust hosts with rayon have the `mpm-gimp-rayon` crate; C
//! hosts pass their callbacks to `mpm_world_step_tasks`.
//!
//! The unsafe of the parallel step is here, in one primitive: a region of memory that the
//! items of a pass carve disjoint windows of (`Shared`).

use core::marker::PhantomData;
use core::ops::Range;

/// A task over the items `start..end`, run by worker `worker` (`< worker_count`).
pub type Task<'t> = dyn Fn(usize, usize, usize) + Sync + 't;

/// The most items of one loop the step hands a task system ([`TaskSystem::parallel_for`]'s
/// `items`): four per worker of [`crate::MAX_WORKERS`]. A system that checks its ranges can
/// keep a bit per item in this many bits, on its stack (the C interface's adapter does).
pub const MAX_ITEMS: usize = 1024;

/// A host's task system (Box2D v3's enqueue and finish, as one call).
///
/// # Safety
/// The step's memory safety rests on this contract (each item's view of the world is its
/// own): [`TaskSystem::parallel_for`] calls `task(start, end, worker)` on ranges that together
/// cover `0..items`, each item exactly once, each range at least `min_range` items long
/// except possibly the last; at most [`TaskSystem::worker_count`] ranges run at once, no two
/// of them with the same `worker`; it returns once every range has returned. A system may run
/// everything on the calling thread. The step's results do not depend on how the ranges are
/// cut nor on which worker runs which. The step's loops have at most [`MAX_ITEMS`] items.
pub unsafe trait TaskSystem: Sync {
    /// The workers the system runs tasks on, at least 1.
    fn worker_count(&self) -> usize;

    /// Runs `task` over `0..items` as the trait's contract says, returning when it is done.
    fn parallel_for(&self, items: usize, min_range: usize, task: &Task<'_>);
}

/// The task system of a host without one: everything on the calling thread, one worker.
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

// SAFETY: one range, `0..items`, on the calling thread, returning when it has run.
unsafe impl TaskSystem for Serial {
    fn worker_count(&self) -> usize {
        1
    }

    fn parallel_for(&self, items: usize, _min_range: usize, task: &Task<'_>) {
        if items > 0 {
            task(0, items, 0);
        }
    }
}

/// Runs `item(i)` for every `i` in `0..items` (at most [`MAX_ITEMS`]) on `tasks`, one item
/// per range at least.
pub(crate) fn for_each(tasks: &dyn TaskSystem, items: usize, item: &(dyn Fn(usize) + Sync)) {
    debug_assert!(items <= MAX_ITEMS, "a loop of {items} items");
    tasks.parallel_for(items, 1, &|start, end, _worker| {
        for i in start..end {
            item(i);
        }
    });
}

/// The most ranges a reduction ([`reduce`]) cuts its values into.
pub(crate) const MAX_PARTS: usize = 64;

/// `item` of `0..n` cut into at most `parts` ranges of whole `unit`s (at most [`MAX_PARTS`]),
/// the results folded in range order with `fold` from `init`: one worker's fold for an
/// associative `fold`, whatever runs where.
pub(crate) fn reduce<T: Copy + Send>(
    tasks: &dyn TaskSystem,
    (n, parts, unit): (usize, usize, usize),
    init: T,
    item: &(dyn Fn(Range<usize>) -> T + Sync),
    fold: impl Fn(T, T) -> T,
) -> T {
    let parts = parts.min(MAX_PARTS).min(n.div_ceil(unit.max(1)));
    if parts < 2 {
        return fold(init, item(0..n));
    }
    let mut results = [init; MAX_PARTS];
    let slots = Shared::new(&mut results[..parts]);
    for_each(tasks, parts, &|i| {
        // SAFETY: item i alone writes slot i.
        if let Some(slot) = unsafe { slots.window(i..i + 1) }.first_mut() {
            *slot = item(part(n, parts, unit, i));
        }
    });
    results[..parts].iter().fold(init, |acc, &r| fold(acc, r))
}

/// `0..n` cut into `parts` consecutive ranges whose boundaries are multiples of `unit`
/// (the last ends at `n`), as even as that allows; part `i`.
pub(crate) fn part(n: usize, parts: usize, unit: usize, i: usize) -> Range<usize> {
    let units = n.div_ceil(unit);
    let at = |k: usize| (units * k / parts * unit).min(n);
    at(i)..at(i + 1)
}

/// A region of memory (`len` values of `T` from `ptr`) that concurrent items carve disjoint
/// windows of ([`Shared::window`]), as `split_at_mut` would if the items ran one after another.
pub(crate) struct Shared<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a mut [T]>,
}

impl<T> Clone for Shared<'_, T> {
    fn clone(&self) -> Self {
        Shared { ..*self }
    }
}

// SAFETY: a `Shared` is a `&mut [T]` handed to items that each take a disjoint part of it
// (the contract of `window`); sending those parts to other threads needs `T: Send`.
unsafe impl<T: Send> Sync for Shared<'_, T> {}
// SAFETY: as for Sync.
unsafe impl<T: Send> Send for Shared<'_, T> {}

impl<'a, T> Shared<'a, T> {
    /// Shares `region` for the lifetime of the borrow.
    pub fn new(region: &'a mut [T]) -> Self {
        Shared {
            ptr: region.as_mut_ptr(),
            len: region.len(),
            _borrow: PhantomData,
        }
    }

    /// The values `r` of the region (clipped to its end).
    ///
    /// # Safety
    /// No other window that overlaps `r` is alive at the same time (the items of one
    /// parallel pass take disjoint ranges).
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn window(&self, r: Range<usize>) -> &'a mut [T] {
        let end = r.end.min(self.len);
        let start = r.start.min(end);
        // SAFETY: start <= end <= len keeps the window inside the region, which the borrow
        // `'a` keeps alive and unaliased outside these windows; the caller keeps windows
        // disjoint.
        unsafe { core::slice::from_raw_parts_mut(self.ptr.add(start), end - start) }
    }

    /// The values `r` of the region (clipped to its end), to read.
    ///
    /// # Safety
    /// No window ([`Shared::window`]) that overlaps `r` is alive at the same time: items may
    /// read the same values at once, but none may change them meanwhile.
    pub unsafe fn read(&self, r: Range<usize>) -> &'a [T] {
        let end = r.end.min(self.len);
        let start = r.start.min(end);
        // SAFETY: as for `window`, inside the region; the caller keeps every writer away.
        unsafe { core::slice::from_raw_parts(self.ptr.add(start), end - start) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_cover_the_range_in_units() {
        for n in [0, 1, 31, 32, 33, 1000, 4097] {
            for parts in 1..=9 {
                let mut next = 0;
                for i in 0..parts {
                    let r = part(n, parts, 32, i);
                    assert_eq!(r.start, next, "n {n} parts {parts}");
                    assert!(r.start.is_multiple_of(32) && r.end >= r.start && r.end <= n);
                    assert!(r.end == n || r.end.is_multiple_of(32));
                    next = r.end;
                }
                assert_eq!(next, n, "n {n} parts {parts}");
            }
        }
    }
}
