//! Seeding: the fill helpers (box, disk, sphere) and the lattice of sites they walk in
//! stencil-bin order.

use super::{GeomAny, World};
use crate::def::Dimension;
use crate::math::ceil;
use crate::{Error, Real, Vec3};
use core::ops::Range;

impl<'a> World<'a> {
    /// Fills the axis-aligned box `[min, max]` with particles of `material` on the lattice of
    /// `particles_per_cell` sites per cell per axis (sites at the centres of the sub-cells), each
    /// with the volume of its sub-cell and the mass of that volume at the material's density
    /// (axisymmetric: per radian, the sub-cell's area times the site's radius).
    /// All or nothing; the box must lie inside the admissible region.
    ///
    /// The particles are written in stencil-bin order, not x fastest: the sites whose stencils
    /// start at the same node come together (one run per node), which lets the step's scatter
    /// sum a run in registers before it touches the grid and its gathers read a stencil row
    /// once for four particles; the runs of a multiple of 4 particles come first, those at the
    /// box's edges last. Find a face's particles by position.
    pub fn fill_box(
        &mut self,
        min: Vec3,
        max: Vec3,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.fill(
            min,
            max,
            material,
            velocity,
            |_| true,
            |_, _| Some([min.x, max.x]),
        )
    }

    /// Fills the disk (2D) of `center` and `radius` like [`World::fill_box`]. In 3D the disk is
    /// not defined: use [`World::fill_sphere`].
    pub fn fill_disk(
        &mut self,
        center: Vec3,
        radius: Real,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.fill_ball(2, center, radius, material, velocity)
    }

    /// Fills the sphere (3D) of `center` and `radius` like [`World::fill_box`].
    pub fn fill_sphere(
        &mut self,
        center: Vec3,
        radius: Real,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        self.fill_ball(3, center, radius, material, velocity)
    }

    /// A disk (`axes` = 2) or sphere (`axes` = 3); a world of the other dimension rejects it.
    fn fill_ball(
        &mut self,
        axes: usize,
        center: Vec3,
        radius: Real,
        material: u32,
        velocity: Vec3,
    ) -> Result<Range<u32>, Error> {
        if self.def().axes() != axes {
            return Err(Error::InvalidRegion);
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::InvalidRegion);
        }
        let r = Vec3::splat(radius);
        let d = self.def().axes();
        let inside = |x: [Real; 3]| {
            let mut q = 0.0;
            for a in 0..d {
                q += (x[a] - center[a]) * (x[a] - center[a]);
            }
            q <= radius * radius
        };
        // The ball's chord along x through the sites of `y` and `z` (ranges of coordinates;
        // z is [0, 0] in 2D): `c_x -+ sqrt(r^2 - dy^2 - dz^2)`, with dy, dz the distances
        // from the centre to those ranges; none where the ball does not reach them.
        let chord = |y: [Real; 2], z: [Real; 2]| {
            let gap = |c: Real, [lo, hi]: [Real; 2]| (lo - c).max(c - hi).max(0.0);
            let (dy, dz) = (
                gap(center.y, y),
                if d == 3 { gap(center.z, z) } else { 0.0 },
            );
            let q = radius * radius - dy * dy - dz * dz;
            (q >= 0.0).then(|| {
                let half = crate::math::sqrt(q);
                [center.x - half, center.x + half]
            })
        };
        self.fill(center - r, center + r, material, velocity, inside, chord)
    }

    /// Lattice sites of the bounding box `[min, max]` for which `inside` holds. `chord(y, z)`
    /// bounds the region's x extent over the sites whose y and z coordinates lie in the
    /// ranges `y` and `z` (`None`: the region misses them), so that the sites visited are
    /// those of the region's rows, not of its whole bounding box: a call costs in proportion
    /// to the particles it seeds, plus one test per row of bins of the bounding box within
    /// the grid.
    fn fill(
        &mut self,
        min: Vec3,
        max: Vec3,
        material: u32,
        velocity: Vec3,
        inside: impl Fn([Real; 3]) -> bool,
        chord: impl Fn([Real; 2], [Real; 2]) -> Option<[Real; 2]>,
    ) -> Result<Range<u32>, Error> {
        let def = self.def();
        let d = def.axes();
        // The axes the dimension uses (z is ignored in 2D, as `add_particles` ignores it).
        let finite =
            (0..d).all(|a| min[a].is_finite() && max[a].is_finite() && velocity[a].is_finite());
        if !finite || (0..d).any(|a| min[a] > max[a]) {
            return Err(if finite {
                Error::InvalidRegion
            } else {
                Error::NonFiniteInput
            });
        }
        let rec = self.material(material).ok_or(Error::UnknownMaterial)?;
        if !super::add::speed_resolvable(&def, [velocity.x, velocity.y, velocity.z]) {
            return Err(Error::StableStepTooShort);
        }
        let geom = GeomAny::new(&def);
        let spacing = def.cell_size / def.particles_per_cell as Real;
        let mut volume = 1.0;
        for _ in 0..d {
            volume *= spacing;
        }
        // Axisymmetric: the volume per radian of a site's sub-cell, its area times its radius.
        let axisymmetric = def.dimension == Dimension::Axisymmetric2D;
        let per_site = move |x: [Real; 3]| {
            let v = if axisymmetric { volume * x[0] } else { volume };
            (v * rec.density, v)
        };
        // Lattice index range per axis: sites at origin + (k + 1/2) spacing inside [lo, hi],
        // clipped to the admissible region widened by one site, so that a huge region costs
        // no more than the grid while a region reaching out of the grid still meets a site
        // outside it (and is rejected). The sites, not the region's corners, are checked.
        let margin = def.shape.margin_cells() as Real * def.particles_per_cell as Real;
        let sites_in = |a: usize, lo: Real, hi: Real| -> [i64; 2] {
            let sites_per_axis = (def.cells[a] * def.particles_per_cell) as Real;
            let (adm_lo, adm_hi) = (margin - 1.5, sites_per_axis - margin + 0.5);
            let lattice = |x: Real| ((x - def.origin[a]) / spacing - 0.5).clamp(adm_lo, adm_hi);
            [ceil(lattice(lo)) as i64, libm_floor(lattice(hi)) as i64]
        };
        let mut k_lo = [0i64; 3];
        let mut k_hi = [0i64; 3];
        for a in 0..d {
            [k_lo[a], k_hi[a]] = sites_in(a, min[a], max[a]);
        }
        let coordinate = |a: usize, k: i64| def.origin[a] + (k as Real + 0.5) * spacing;
        let site = |k: [i64; 3]| -> [Real; 3] {
            core::array::from_fn(|a| if a < d { coordinate(a, k[a]) } else { 0.0 })
        };
        let bins = Bins {
            n: def.particles_per_cell as i64,
            shift_halves: def.shape.first_node_shift_halves(),
        };
        // The x sites of the region's chord through the sites `y`, `z` (inclusive index
        // ranges), widened by a site on each side against the chord's round-off (the sites
        // themselves are tested with `inside`).
        let row = |y: [i64; 2], z: [i64; 2]| -> [i64; 2] {
            let at = |a: usize, k: [i64; 2]| {
                if a < d {
                    [coordinate(a, k[0]), coordinate(a, k[1])]
                } else {
                    [0.0; 2]
                }
            };
            match chord(at(1, y), at(2, z)) {
                Some([lo, hi]) => {
                    let [l, h] = sites_in(0, lo, hi);
                    [l - 1, h + 1]
                }
                None => [1, 0],
            }
        };
        let sites = || {
            BinnedSites::new(k_lo, k_hi, bins, &row)
                .map(site)
                .filter(|x| inside(*x))
        };
        // Pass 1: count and validate as `add_particles` does (nothing is written on failure).
        // Stops at the first problem, so a region far larger than the capacity costs no more
        // than the capacity.
        let room = def.particle_capacity as usize - self.particle_count();
        let mut n = 0usize;
        for x in sites() {
            // The position first: a site's mass follows from it (axisymmetric: its radius).
            if !geom.admits(x) {
                return Err(Error::PositionOutsideDomain);
            }
            let (mass, volume) = per_site(x);
            if !(mass.is_finite() && volume.is_finite()) {
                return Err(Error::NonFiniteInput);
            }
            if !(mass > 0.0 && volume > 0.0) {
                return Err(Error::NonPositiveMassOrVolume);
            }
            n += 1;
            if n > room {
                return Err(Error::ParticleCapacityExceeded);
            }
        }
        // Pass 2: write the same sites in the same order.
        let v3 = core::array::from_fn(|a| if a < d { velocity[a] } else { 0.0 });
        Ok(self.append(
            &def,
            sites().map(|x| {
                let (mass, volume) = per_site(x);
                (x, v3, mass, volume, material)
            }),
        ))
    }
}

fn libm_floor(x: Real) -> Real {
    -ceil(-x)
}

/// Lattice indices in `[lo, hi]` (inclusive per axis, x fastest).
struct Sites {
    lo: [i64; 3],
    hi: [i64; 3],
    next: Option<[i64; 3]>,
}

impl Sites {
    fn new(lo: [i64; 3], hi: [i64; 3]) -> Self {
        let empty = (0..3).any(|a| lo[a] > hi[a]);
        Sites {
            lo,
            hi,
            next: if empty { None } else { Some(lo) },
        }
    }
}

impl Iterator for Sites {
    type Item = [i64; 3];
    fn next(&mut self) -> Option<[i64; 3]> {
        let cur = self.next?;
        let mut k = cur;
        let mut a = 0;
        self.next = loop {
            if a == 3 {
                break None;
            }
            if k[a] < self.hi[a] {
                k[a] += 1;
                break Some(k);
            }
            k[a] = self.lo[a];
            a += 1;
        };
        Some(cur)
    }
}

/// How lattice sites fall into stencil bins along an axis: site `k` sits at `s = (k + 1/2) / n`
/// cells from the grid origin, and its stencil's first node is `floor(s + shift) - lead`, so
/// the sites of bin `b = floor((2k + 1 + 2 n shift) / 2n)` share their first node.
#[derive(Clone, Copy)]
struct Bins {
    /// Sites per cell per axis.
    n: i64,
    /// `2 shift` ([`crate::ShapeFunction::first_node_shift_halves`]).
    shift_halves: i64,
}

impl Bins {
    /// The bin of site `k`.
    fn of(self, k: i64) -> i64 {
        (2 * k + 1 + self.shift_halves * self.n).div_euclid(2 * self.n)
    }

    /// The first site of bin `b` (the least `k` whose bin is at least `b`).
    fn first(self, b: i64) -> i64 {
        -((1 + self.shift_halves * self.n - 2 * self.n * b).div_euclid(2))
    }
}

/// The x sites of a row of a region: given the row's y and z site ranges (inclusive), the
/// inclusive x range that holds every site of the region in those rows (empty if lo > hi).
type RowSpan<'r> = &'r dyn Fn([i64; 2], [i64; 2]) -> [i64; 2];

/// Lattice indices in `[lo, hi]` (inclusive per axis) in stencil-bin order: the bins x
/// fastest, and within a bin its sites x fastest. The sites of a bin share their stencil's
/// first node, so they come one after another and the scatter sums them before it adds to the
/// grid ([`crate::phases::p2g`]'s runs): one load and store per node row for the bin rather
/// than one per particle. In each row of bins (y and z fixed) only the bins that meet the
/// region's x span for that row ([`RowSpan`]) are visited.
///
/// The bins whose number of sites is a multiple of 4 come first, the others (the partial bins
/// at the box's edges) after them: a run of the first kind then starts where a 4-lane block
/// of the passes' chunks starts (when the fill itself starts there), so that the gathers read
/// one stencil row for the block's four particles ([`crate::simd::rows::blocks_share`]).
/// At 2 sites per cell per axis that is every bin inside the box (4 sites in 2D, 8 in 3D) and,
/// in 3D, those on its faces (4).
struct BinnedSites<'r> {
    lo: [i64; 3],
    hi: [i64; 3],
    bins: Bins,
    span: RowSpan<'r>,
    /// The rows of bins (x index 0; y and z the row's).
    rows: Sites,
    /// The bins of the current row still to visit.
    row: Sites,
    inner: Sites,
    /// Visiting the bins whose site count is a multiple of 4 (else the others).
    whole: bool,
}

impl<'r> BinnedSites<'r> {
    fn new(lo: [i64; 3], hi: [i64; 3], bins: Bins, span: RowSpan<'r>) -> Self {
        BinnedSites {
            lo,
            hi,
            bins,
            span,
            rows: Self::rows(lo, hi, bins),
            row: Sites::new([0; 3], [-1; 3]),
            inner: Sites::new([0; 3], [-1; 3]),
            whole: true,
        }
    }

    /// The rows of the bins the sites `[lo, hi]` fall into.
    fn rows(lo: [i64; 3], hi: [i64; 3], bins: Bins) -> Sites {
        Sites::new(
            [0, bins.of(lo[1]), bins.of(lo[2])],
            [0, bins.of(hi[1]), bins.of(hi[2])],
        )
    }

    /// The sites of bin `b` inside `[lo, hi]` (inclusive; empty on an axis where lo > hi).
    fn sites_of(&self, b: [i64; 3]) -> ([i64; 3], [i64; 3]) {
        let bins = self.bins;
        let from = core::array::from_fn(|a| self.lo[a].max(bins.first(b[a])));
        let to = core::array::from_fn(|a| self.hi[a].min(bins.first(b[a] + 1) - 1));
        (from, to)
    }
}

impl Iterator for BinnedSites<'_> {
    type Item = [i64; 3];
    fn next(&mut self) -> Option<[i64; 3]> {
        loop {
            if let Some(k) = self.inner.next() {
                return Some(k);
            }
            if let Some(b) = self.row.next() {
                let (from, to) = self.sites_of(b);
                let count: i64 = (0..3).map(|a| (to[a] - from[a] + 1).max(0)).product();
                if (count % 4 == 0) == self.whole {
                    self.inner = Sites::new(from, to);
                }
                continue;
            }
            let Some(r) = self.rows.next() else {
                if !self.whole {
                    return None;
                }
                // Then the bins of the other kind.
                self.whole = false;
                self.rows = Self::rows(self.lo, self.hi, self.bins);
                continue;
            };
            // The row's sites in y and z, and the region's x span over them, in bins.
            let (from, to) = self.sites_of(r);
            let [x0, x1] = (self.span)([from[1], to[1]], [from[2], to[2]]);
            let (x0, x1) = (x0.max(self.lo[0]), x1.min(self.hi[0]));
            self.row = if x0 > x1 {
                Sites::new([0; 3], [-1; 3])
            } else {
                Sites::new(
                    [self.bins.of(x0), r[1], r[2]],
                    [self.bins.of(x1), r[1], r[2]],
                )
            };
        }
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::shape::{first_node, CpGimp, CubicBspline, Gimp, Linear, QuadraticBspline, Shape1D};
    use crate::{HeapBuffer, MaterialDef, ShapeFunction, WorldDef};
    use std::vec::Vec;

    /// A small deterministic generator in `[0, 1)`.
    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The bin order visits exactly the sites of the plain lattice order, each once, for boxes
    /// anywhere (negative indices included), every bin width and shift.
    #[test]
    fn binned_sites_are_a_permutation_of_the_lattice() {
        let mut state = 7;
        for n in 1..=4 {
            for shift_halves in [0, 1] {
                let bins = Bins { n, shift_halves };
                for _ in 0..200 {
                    let mut lo = [0i64; 3];
                    let mut hi = [0i64; 3];
                    for a in 0..3 {
                        lo[a] = (lcg(&mut state) * 30.0) as i64 - 15;
                        hi[a] = lo[a] + (lcg(&mut state) * 9.0) as i64 - 1;
                    }
                    let mut plain: Vec<[i64; 3]> = Sites::new(lo, hi).collect();
                    let mut binned: Vec<[i64; 3]> =
                        BinnedSites::new(lo, hi, bins, &|_, _| [i64::MIN, i64::MAX]).collect();
                    plain.sort_unstable();
                    binned.sort_unstable();
                    assert_eq!(plain, binned, "n {n}, shift {shift_halves}, {lo:?}..{hi:?}");
                }
            }
        }
    }

    /// The particles a fill seeds come in runs that share their stencil's first node, one run
    /// per first node (what the scatter's run sums rely on), the runs of a multiple of 4
    /// first and each on a 4-lane block (what the gathers' shared row reads rely on), for
    /// every shape, 2D and 3D, 1 to 4 particles per cell per axis and boxes at random places.
    /// The first node is the one the step computes ([`first_node`] with the shape's own shift
    /// and lead).
    #[test]
    fn filled_particles_come_in_one_run_per_first_node() {
        fn check<const K: usize, S: Shape1D<K>>(shape: ShapeFunction) {
            let mut state = 11;
            for dim in [Dimension::Plane2D, Dimension::ThreeD] {
                for ppc in 1..=4u32 {
                    let cells = 12u32;
                    let def = WorldDef {
                        dimension: dim,
                        cells: if dim == Dimension::ThreeD {
                            [cells; 3]
                        } else {
                            [cells, cells, 1]
                        },
                        cell_size: 0.5,
                        origin: Vec3::new(-1.25, 0.75, -2.0),
                        shape,
                        particles_per_cell: ppc,
                        particle_capacity: 20_000,
                        ..WorldDef::DEFAULT
                    };
                    let d = def.axes();
                    let h = def.cell_size;
                    let mut buf = HeapBuffer::new(crate::memory_requirements(&def).unwrap().bytes);
                    for _ in 0..6 {
                        let mut world = World::init(&def, buf.as_mut_bytes()).unwrap();
                        let mat = world.add_material(&MaterialDef::DEFAULT).unwrap();
                        // A box within the cells 2..10 of each axis (inside every margin).
                        let corner = |t: f64| 2.0 + 8.0 * t;
                        let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
                        for a in 0..3 {
                            let (p, q) = (corner(lcg(&mut state)), corner(lcg(&mut state)));
                            lo[a] = def.origin[a] + h * p.min(q) as Real;
                            hi[a] = def.origin[a] + h * p.max(q) as Real;
                        }
                        let filled = world
                            .fill_box(Vec3::from(lo), Vec3::from(hi), mat, Vec3::ZERO)
                            .unwrap();
                        let v = world.particles();
                        let key = |i: usize| -> [i32; 3] {
                            core::array::from_fn(|a| {
                                if a < d {
                                    let s = (v.position[a][i] - def.origin[a]) / h;
                                    first_node::<K, S>(s, cells as usize + 1)
                                } else {
                                    0
                                }
                            })
                        };
                        let keys: Vec<[i32; 3]> = (filled.start as usize..filled.end as usize)
                            .map(key)
                            .collect();
                        let runs = 1 + keys.windows(2).filter(|w| w[0] != w[1]).count();
                        let mut distinct = keys.clone();
                        distinct.sort_unstable();
                        distinct.dedup();
                        if !keys.is_empty() {
                            assert_eq!(
                                runs,
                                distinct.len(),
                                "{shape:?} {dim:?} ppc {ppc}: a first node in two runs"
                            );
                        }
                        // The runs of a multiple of 4 particles come first, each starting a
                        // multiple of 4 particles after the fill's first.
                        let mut start = 0;
                        let mut others = false;
                        for (i, w) in keys.iter().enumerate() {
                            if i + 1 == keys.len() || keys[i + 1] != *w {
                                let len = i + 1 - start;
                                if len % 4 == 0 {
                                    assert!(
                                        !others && start % 4 == 0,
                                        "{shape:?} {dim:?} ppc {ppc}: a run of {len} at {start}"
                                    );
                                } else {
                                    others = true;
                                }
                                start = i + 1;
                            }
                        }
                    }
                }
            }
        }
        check::<2, Linear>(ShapeFunction::Linear);
        check::<3, Gimp>(ShapeFunction::Gimp);
        check::<3, QuadraticBspline>(ShapeFunction::QuadraticBspline);
        check::<4, CubicBspline>(ShapeFunction::CubicBspline);
        check::<3, CpGimp>(ShapeFunction::CpGimp);
    }
}
