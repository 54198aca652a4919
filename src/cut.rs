//! The parallel cut: how a step's work is divided among workers, bit-identical to one
//! worker's ([`crate::world`]'s `parallel` runs the passes on these pieces).
//!
//! - [`Tile`]: the nodes a grid view holds, the whole grid or a slab of lines along the
//!   slowest axis; [`Tiles`]: the scatter's slabs, their colours and where they are cut.
//! - [`Chunks`]: the chunks of particles a view's scatter takes, past the groups of
//!   [`REACH_GROUP`] particles whose reach (the lines their stencils may touch, a table the
//!   node box fills) misses its slab.
//! - [`Partial`]: what one item of a parallel pass leaves for the step's report, and its one
//!   merge ([`Partial::absorb`]); [`SLOTS_PER_WORKER`] of them per worker in the world's
//!   scratch.

use crate::shape::ROW;
use crate::tasks;
use bytemuck::{Pod, Zeroable};
use core::ops::Range;

/// Particles per entry of the reach table (`Layout::reach_groups`): a multiple of every
/// chunk width. Particles in fill order (bins along x) span one line of cells per 256 in the
/// default scenes, so a tile takes few chunks it does not need; per 16 the table took 5 % of
/// the 2D step to fill (benches/PERFORMANCE.md, "Decisions").
///
/// Public for hosts that step part of a scene (mpm-gimp-mpi): the step walks chunks from
/// particle 0, so a world whose particles are whole groups of a larger world's, in its order,
/// has that world's chunks and blocks, and a node all of whose particles it holds gets that
/// world's sums, bit for bit.
pub const REACH_GROUP: usize = 256;

/// The parallel step's items per worker ([`crate::layout::Layout::scratch_slots`]): the particle passes cut
/// their chunks into this many ranges per worker (so that a slow range does not hold the
/// others up), the scatter its grid into this many slabs per worker (two colours, half of
/// them at a time).
pub(crate) const SLOTS_PER_WORKER: usize = 4;

/// What one item of a parallel pass leaves for the step to merge, in item order: its part of
/// the [`crate::StepReport`] (the frozen ids local to the item's first particle). Plain data
/// in the world's buffer ([`crate::layout::Layout::scratch_slots`] of them).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
pub(crate) struct Partial {
    pub stopped: u32,
    pub escaped: u32,
    pub frozen: u32,
    pub runaway: u32,
    /// How many of `first_frozen` hold ids.
    pub first_count: u32,
    pub first_frozen: [u32; 8],
    pub _pad: [u32; 3],
}

// SAFETY: repr(C), u32 fields only (no padding: 16 of them), any bit pattern valid.
unsafe impl Zeroable for Partial {}
// SAFETY: as above; Partial is Copy and 'static.
unsafe impl Pod for Partial {}

impl Partial {
    /// Adds `part`, whose particle 0 is particle `first`, in any order: the counts add and
    /// the frozen ids keep the least 8 in order, so the parts of a pass absorbed in any order
    /// give the part one worker gives (which [`crate::StepReport`]'s `merge` adds). Each part's
    /// ids are its least, in order (an item updates its particles in order).
    pub(crate) fn absorb(&mut self, part: &Partial, first: u32) {
        self.stopped += part.stopped;
        self.escaped += part.escaped;
        self.frozen += part.frozen;
        self.runaway += part.runaway;
        let cap = self.first_frozen.len();
        let n = (part.first_count as usize).min(part.first_frozen.len());
        for &id in &part.first_frozen[..n] {
            let id = first + id;
            let len = (self.first_count as usize).min(cap);
            let at = self.first_frozen[..len].partition_point(|&k| k < id);
            if at == cap {
                break; // The rest of the part's ids are larger still.
            }
            self.first_frozen.copy_within(at..cap - 1, at + 1);
            self.first_frozen[at] = id;
            self.first_count = (len + 1).min(cap) as u32;
        }
    }
}

/// The nodes a view of the node columns holds ([`crate::grid::GridCols::tile`]): entry 0 of each column is
/// node `first`, and the stencil rows that start at nodes `first..first + rows` are the view's
/// to add to ([`Tile::ALL`]: the whole grid). A tile of the parallel scatter is a slab of whole
/// grid lines (rows run along x, so a row never straddles two), its columns `rows + ROW - 1`
/// long: a row of the slab's last line may reach the first entries of the next line (zeros;
/// `world::parallel` then never runs neighbouring tiles at once), unless no row reaches past
/// its line's end ([`Tile::within_lines`]: the columns are the slab's alone).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Tile {
    pub first: usize,
    pub rows: usize,
    /// The nodes of the tile's slab, whose sums it completes (`first..first + nodes`).
    pub nodes: usize,
}

impl Tile {
    /// The whole grid: every row whose stencil fits ([`crate::grid::rows_fit`]).
    pub const ALL: Tile = Tile {
        first: 0,
        rows: usize::MAX,
        nodes: usize::MAX,
    };

    /// The tile of the grid lines `lines` along the slowest axis, whose stride is `stride`
    /// (nodes per line in 2D, per plane in 3D).
    pub fn of_lines(lines: Range<usize>, stride: usize) -> Tile {
        Tile {
            first: lines.start * stride,
            rows: lines.len() * stride,
            nodes: lines.len() * stride,
        }
    }

    /// [`Tile::of_lines`] for rows that never reach past their line's end: the rows that
    /// start in the slab's last `ROW - 1` nodes are left out (none start there), so that the
    /// columns (`rows + ROW - 1` entries) are the slab's alone and neighbouring tiles can
    /// run at once.
    pub fn within_lines(lines: Range<usize>, stride: usize) -> Tile {
        let t = Tile::of_lines(lines, stride);
        Tile {
            rows: t.rows.saturating_sub(ROW - 1),
            ..t
        }
    }

    /// The last entry past the tile's columns: rows added from its last row start reach
    /// `ROW - 1` entries past it.
    pub fn end(&self) -> usize {
        self.first.saturating_add(self.rows).saturating_add(ROW - 1)
    }

    /// Where the stencil row that starts at node `row` starts in the tile's columns, if it is
    /// the tile's to add to: every row for the whole grid, the rows of its slab for a tile of
    /// the parallel scatter, which adds each row in the order the whole grid's scatter does. A
    /// row added at the place returned fits: for the whole grid, the caller checked the
    /// stencil's rows ([`crate::grid::rows_fit`]); a tile's columns hold `rows + ROW - 1` entries
    /// ([`crate::grid::GridCols::lengths_consistent`]).
    #[inline(always)]
    pub fn own(&self, row: usize) -> Option<usize> {
        let at = row.wrapping_sub(self.first);
        (at < self.rows).then_some(at)
    }

    /// The lines along the slowest axis this tile holds (stride as in [`Tile::of_lines`]);
    /// `None` for the whole grid.
    pub fn slab(&self, stride: usize) -> Option<Range<usize>> {
        (*self != Tile::ALL && stride > 0)
            .then(|| self.first / stride..(self.first + self.nodes) / stride)
    }
}

/// The first particles of the chunks a view's scatter takes ([`crate::grid::GridCols::chunks`]).
pub(crate) struct Chunks<'a> {
    next: usize,
    count: usize,
    w: usize,
    reach: &'a [[u32; 2]],
    /// A tile's lines; `None` for the whole grid.
    slab: Option<Range<usize>>,
}

impl<'a> Chunks<'a> {
    /// The chunks of `w` particles of `0..count`, past the groups whose `reach` misses the
    /// lines `slab` (`None`: the whole grid's, every chunk).
    pub fn new(count: usize, w: usize, reach: &'a [[u32; 2]], slab: Option<Range<usize>>) -> Self {
        Chunks {
            next: 0,
            count,
            w,
            reach,
            slab,
        }
    }
}

impl Iterator for Chunks<'_> {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        while self.next < self.count {
            let start = self.next;
            if let Some(slab) = &self.slab {
                // A group whose particles reach no line of the slab: past all its chunks (a
                // chunk across two groups, which no chunk width makes, is taken).
                let group = start / REACH_GROUP;
                if let Some(&[lo, hi]) = self.reach.get(group) {
                    let in_group = (start + self.w - 1) / REACH_GROUP == group;
                    if in_group && ((lo as usize) >= slab.end || (hi as usize) < slab.start) {
                        self.next = (group + 1) * REACH_GROUP;
                        continue;
                    }
                }
            }
            self.next = start + self.w;
            return Some(start);
        }
        None
    }
}

/// The most tiles a scatter is cut into: two per worker up to 64 workers.
pub(crate) const MAX_TILES: usize = 128;

// Every loop of the parallel step has at most `tasks::MAX_ITEMS` items (a task system may keep
// a bit per item): tiles, the particle passes' and the grid's ranges, reductions' parts.
const _: () = assert!(
    MAX_TILES <= tasks::MAX_ITEMS
        && crate::cut::SLOTS_PER_WORKER * crate::def::MAX_WORKERS as usize <= tasks::MAX_ITEMS
        && tasks::MAX_PARTS <= tasks::MAX_ITEMS
);

/// The tiles of the parallel scatter: `n` slabs of whole lines along the slowest axis, the
/// first from line 0 and the last to the grid's end (no stencil reaches past the node box).
/// Where no row reaches past its line's end, every tile's columns are its slab's alone
/// ([`Tile::within_lines`]) and they all run at once (`apart`). Else a tile's rows may add
/// zeros to the next tile's first entries: tiles `0, 2, 4, ..` are the first colour, `1, 3,
/// ..` the second, and tiles of one colour, a tile between them, run at once.
#[derive(Clone, Copy)]
pub(crate) struct Tiles {
    pub n: usize,
    pub apart: bool,
    /// Nodes per line.
    pub stride: usize,
    /// The first line of each tile, then the grid's lines.
    bounds: [u32; MAX_TILES + 1],
}

impl Tiles {
    /// `n` tiles (at least 2, at most [`MAX_TILES`]; `apart` or in two colours) of the node
    /// box's lines `box_lines`, cut
    /// where about as many groups of particles reach each (`reach`, [`crate::grid::GridCols::reach`]; the
    /// lines evenly without one): the lines at the box's ends, which the stencils' edges
    /// reach, carry less work than the others. The results do not depend on the cut.
    pub fn balanced(
        n: usize,
        apart: bool,
        box_lines: Range<usize>,
        lines: usize,
        stride: usize,
        reach: &[[u32; 2]],
    ) -> Tiles {
        const BINS: usize = 256;
        let (lo, span) = (box_lines.start, box_lines.len());
        // Bins of `per` lines of the box, each with the groups that reach it.
        let per = span.div_ceil(BINS).max(1);
        let mut weight = [0u32; BINS];
        for &[a, b] in reach {
            let (a, b) = (a as usize, b as usize);
            if a > b || b < lo || a >= lo + span {
                continue;
            }
            let (a, b) = (a.max(lo) - lo, b.min(lo + span - 1) - lo);
            for w in &mut weight[a / per..=b / per] {
                *w += 1;
            }
        }
        let total: u64 = weight.iter().map(|&w| w as u64).sum();
        let mut bounds = [lines as u32; MAX_TILES + 1];
        bounds[0] = 0;
        let (mut bin, mut sum) = (0, 0u64);
        for t in 1..n {
            let cut = if total == 0 {
                lo + tasks::part(span, n, 1, t).start
            } else {
                // After the bin where the groups reached so far pass t / n of all.
                while bin < BINS && sum * (n as u64) < total * t as u64 {
                    sum += weight[bin] as u64;
                    bin += 1;
                }
                lo + bin * per
            };
            // At least one line per tile, and room for the rest.
            let least = if t == 1 {
                lo + 1
            } else {
                bounds[t - 1] as usize + 1
            };
            bounds[t] = cut.max(least).min(lo + span - (n - t)) as u32;
        }
        Tiles {
            n,
            apart,
            stride,
            bounds,
        }
    }

    /// The first line of tile `t` (the grid's lines for `t == n`).
    pub fn bound(&self, t: usize) -> usize {
        self.bounds[t.min(self.n)] as usize
    }

    pub fn tile(&self, t: usize) -> Tile {
        let lines = self.bound(t)..self.bound(t + 1);
        if self.apart {
            Tile::within_lines(lines, self.stride)
        } else {
            Tile::of_lines(lines, self.stride)
        }
    }

    /// The colours the tiles run in, one after the other: 1 where they are apart, else 2.
    pub fn colours(&self) -> usize {
        if self.apart {
            1
        } else {
            2
        }
    }

    /// Tile `i` of colour `c`.
    pub fn nth(&self, c: usize, i: usize) -> usize {
        if self.apart {
            i
        } else {
            2 * i + c
        }
    }

    /// The tile that holds line `line` (the last for a line past the grid).
    pub fn of_line(&self, line: usize) -> usize {
        self.bounds[1..self.n].partition_point(|&b| b as usize <= line)
    }

    /// How many tiles colour `c` has.
    pub fn of_colour(&self, c: usize) -> usize {
        if self.apart {
            self.n
        } else {
            (self.n - c).div_ceil(2)
        }
    }
}

/// The runs of consecutive indices of `range` that `class` puts in one class, in order, each
/// with its class.
pub(crate) fn runs<T: PartialEq + Copy>(
    range: Range<usize>,
    class: impl Fn(usize) -> T,
) -> impl Iterator<Item = (T, Range<usize>)> {
    let mut next = range.start;
    core::iter::from_fn(move || {
        let start = next;
        (start < range.end).then(|| {
            let c = class(start);
            next = (start + 1..range.end)
                .find(|&k| class(k) != c)
                .unwrap_or(range.end);
            (c, start..next)
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::vec::Vec;

    /// Balanced tiles cover the grid's lines in order, one line each at least, and cut where
    /// the groups' reach is even: a box of 40 lines whose first 10 lines are reached by nine
    /// times as many groups as the rest gives its first tiles a few lines each.
    #[test]
    fn balanced_tiles_cover_the_lines_and_even_out_the_groups() {
        let mut reach = Vec::new();
        for line in 10..50u32 {
            let groups = if line < 20 { 9 } else { 1 };
            reach.extend((0..groups).map(|_| [line, line + 2]));
        }
        reach.push([u32::MAX, 0]); // A group without an active particle.
        for n in 2..=12 {
            let t = Tiles::balanced(n, false, 10..52, 60, 7, &reach);
            assert_eq!((t.bound(0), t.bound(n)), (0, 60), "{n}");
            for k in 0..n {
                assert!(t.bound(k) < t.bound(k + 1), "{n}: tile {k} empty");
                for line in t.bound(k)..t.bound(k + 1) {
                    assert_eq!(t.of_line(line), k, "{n}: line {line}");
                }
            }
            // Each tile's share of the reached lines is within one line's worth of 1 / n.
            let total: usize = reach.iter().filter(|r| r[0] <= r[1]).map(|_| 3).sum();
            for k in 0..n {
                let lines = t.bound(k)..t.bound(k + 1);
                let work: usize = reach
                    .iter()
                    .filter(|r| r[0] <= r[1])
                    .map(|r| {
                        (r[0]..=r[1])
                            .filter(|l| lines.contains(&(*l as usize)))
                            .count()
                    })
                    .sum();
                assert!(
                    work <= total / n + 3 * 9 * 3,
                    "{n}: tile {k} takes {work} of {total}"
                );
            }
        }
        // Without a reached group: the box's lines evenly.
        let t = Tiles::balanced(4, false, 10..50, 60, 7, &[]);
        assert_eq!((1..4).map(|k| t.bound(k)).collect::<Vec<_>>(), [20, 30, 40]);
    }

    /// The runs of a class cover the range in order, each of one class and longest.
    #[test]
    fn runs_are_the_longest_of_one_class() {
        let class = |k: usize| (k / 3).is_multiple_of(2) || k == 10;
        let got: Vec<_> = runs(1..12, class).collect();
        assert_eq!(
            got,
            [
                (true, 1..3),
                (false, 3..6),
                (true, 6..9),
                (false, 9..10),
                (true, 10..11),
                (false, 11..12)
            ]
        );
        assert_eq!(runs(5..5, class).count(), 0);
    }
}
