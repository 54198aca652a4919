#!/usr/bin/env python3
"""A model of mpm-gimp-mpi's cost past one machine, from figures measured here (the defaults,
benches/PERFORMANCE.md "Past one machine": `bash benches/mpi_cost.sh 5 8 50`) and a network's
latency and bandwidth (assumed: say which with --latency-us and --bandwidth-gbs).

    python3 benches/mpi_model.py [--particles N] [--latency-us A] [--bandwidth-gbs B]

The scene: a 3D cube of N particles, 8 a cell (2 per axis), split into slabs of cell lines
along one axis as the crate splits it today. Per substep a rank:
- steps its slab's particles and the ghosts within the halo on each side (whole lines: the
  crate holds whole 256-particle groups, so this is a lower bound), at the measured cost of
  one particle-substep on one thread;
- sends its slab's edge particles' whole state to each neighbour (halo lines x the slab's
  cross-section x particles a cell x the record's bytes) and receives as much;
- makes the exchange's collectives: 8 small ones (each log2 P latencies) and two reductions
  of one u32 per 256-particle group of the whole scene (the groups' lowest and highest lines:
  O(N) bytes on every rank, whatever P).
Strong scaling keeps N; weak scaling keeps N / P (the cube grows with P: N / 1024 particles a
rank, so that 1,024 ranks hold N). Prints seconds per substep, speed-up and efficiency, and which term
is largest. It models, it does not measure: the network figures are assumptions, the
compute figure is one machine's.
"""

import argparse
import math

# Measured (PERFORMANCE.md, "Past one machine", 3D row): 7.62 ms per substep for 73,728
# particles on one thread (median), APIC, MUSL, quadratic B-spline, sand.
NS_PER_PARTICLE = 7.62e-3 / 73_728 * 1e9
RECORD_BYTES = 156  # a ghost's whole state in that scene (3D, APIC, MUSL, plastic history)
HALO_LINES = 7  # MUSL's halo (`halo_cells`)
PER_CELL = 8
GROUP = 256
SMALL_COLLECTIVES = 8


def substep(n, ranks, latency, bandwidth):
    """Seconds per substep of a rank and its terms, or None where the slabs do not fit."""
    lines = round((n / PER_CELL) ** (1 / 3))
    if ranks > lines:
        return None
    width = lines / ranks
    section = lines * lines * PER_CELL  # particles in one cell line's cross-section
    ghosts = (min(lines, width + 2 * HALO_LINES) - width) * section if ranks > 1 else 0
    compute = (width * section + ghosts) * NS_PER_PARTICLE * 1e-9
    sides = 0 if ranks == 1 else (1 if ranks == 2 else 2)
    halo_bytes = sides * min(HALO_LINES, width) * section * RECORD_BYTES
    halo = 2 * halo_bytes / bandwidth + 2 * sides * latency
    hops = math.ceil(math.log2(ranks)) if ranks > 1 else 0
    groups_bytes = 2 * 4 * n / GROUP
    collectives = (SMALL_COLLECTIVES + 2) * hops * latency + (
        2 * groups_bytes / bandwidth if ranks > 1 else 0
    )
    terms = {"compute": compute, "halo": halo, "collectives": collectives}
    return sum(terms.values()), terms, lines, width, halo_bytes


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=float, default=1e8)
    parser.add_argument("--latency-us", type=float, default=2.0)
    parser.add_argument("--bandwidth-gbs", type=float, default=10.0)
    args = parser.parse_args()
    latency, bandwidth = args.latency_us * 1e-6, args.bandwidth_gbs * 1e9
    n = args.particles
    print(
        f"{n:.3g} particles, {NS_PER_PARTICLE:.1f} ns per particle-substep, network "
        f"{args.latency_us} us and {args.bandwidth_gbs} GB/s (assumed)"
    )
    print("| scaling | ranks | slab (lines) | s per substep | speed-up | efficiency | halo sent | largest term |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    one = substep(n, 1, latency, bandwidth)[0]
    for scaling in ("strong", "weak"):
        for ranks in (1, 2, 4, 16, 64, 256, 1024):
            size = n if scaling == "strong" else n / 1024 * ranks
            got = substep(size, ranks, latency, bandwidth)
            if got is None:
                lines = round((size / PER_CELL) ** (1 / 3))
                print(f"| {scaling} | {ranks} | - | - | - | - | - | more ranks than its {lines} lines |")
                continue
            t, terms, lines, width, halo_bytes = got
            base = one if scaling == "strong" else substep(size / ranks, 1, latency, bandwidth)[0]
            speedup = one / t if scaling == "strong" else base * ranks / t
            largest = max(terms, key=terms.get)
            print(
                f"| {scaling} | {ranks} | {width:.1f} of {lines} | {t:.3g} | {speedup:.1f} | "
                f"{speedup / ranks:.2f} | {halo_bytes / 1e6:.0f} MB | {largest} "
                f"({terms[largest] / t:.0%}) |"
            )


if __name__ == "__main__":
    main()
