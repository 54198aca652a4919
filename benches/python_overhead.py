#!/usr/bin/env python3
"""What `World.step` adds to the C call it makes: `mpm_world_step` called straight through
ctypes (the binding `World.step` uses, its argument types set, one report for every call)
against `World.step` on the same world, in turn, so that the load of a shared machine falls
on both alike.

    python benches/python_overhead.py                   # 10,000 and 100,000 particles
    python benches/python_overhead.py --particles 1000 --seconds 2

The scene: a 2D neo-Hookean block (the default material, E = 1 MPa) resting on a sticky floor
under gravity, 2 x 2 particles a cell, one worker, f32; `dt` is 3.5 of the world's stable
substeps, so that each call runs 4 (the script checks that every call ran as many). Calls
are timed alone, in CPU time of the calling thread (the machine's other work then counts
less), in triples: the C call, World.step, the C call again, the order rotating. Columns,
medians over the triples:

- C call: `mpm_world_step` through ctypes (the interpreter lock released, as `World.step`
  releases it while no view is alive);
- World.step adds: World.step less the C call of its triple, over the C call;
- control: the second C call less the first, over the C call: what the method reads where
  there is nothing to find (its noise);
- fixed cost: what World.step adds on a world without particles, whose C call returns at
  once (the wrapper's own work, the same at any size), over the C call.

The package must be installed (`pip install ./python`).
"""

import argparse
import ctypes
import statistics
import time

import mpm_gimp as mpm


def block_world(particles):
    """A world with a block of `particles` (a multiple of 4) resting on its floor."""
    cells = particles // 4
    bx = max(1, int(round(cells**0.5)))
    while cells % bx:
        bx -= 1
    by = cells // bx
    h = 0.01
    d = mpm.WorldDef(cells=(bx + 8, by + 8, 1), cell_size=h, particle_capacity=max(particles, 1))
    d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
    w = mpm.World(d)
    if particles:
        rubber = w.add_material(mpm.MaterialDef())
        ids = w.fill_box((4 * h, h), ((4 + bx) * h, (1 + by) * h), rubber)
        assert len(ids) == particles, (len(ids), particles)
    return w


def measure(w, dt, triples):
    """Times `triples` triples of calls on `w`: the C call, World.step and the C call again,
    each call timed alone, the order rotating from triple to triple. Returns the median C
    call (ns), the medians within a triple of World.step less the C call (the overhead) and
    of the second C call less the first (the control: what the method reads where there is
    nothing to find), and the substeps each call ran."""
    lib = mpm._precision.lib  # the library and binding World.step calls
    step_c = lib.mpm_world_step
    world = w._world
    report = mpm.StepReport()
    ref = ctypes.byref(report)
    clock = time.thread_time_ns
    substeps = set()

    def bare():
        start = clock()
        status = step_c(world, dt, ref)
        took = clock() - start
        if status != 0:
            raise RuntimeError(f"mpm_world_step: {lib.mpm_status_string(status).decode()}")
        substeps.add(report.substeps)
        return took

    def wrapped():
        start = clock()
        r = w.step(dt)
        took = clock() - start
        substeps.add(r.substeps)
        return took

    kinds = [bare, wrapped, bare]
    for _ in range(max(1, triples // 10)):  # warm-up
        for kind in kinds:
            kind()
    c_ns, overhead, control = [], [], []
    for i in range(triples):
        order = [(k + i) % 3 for k in range(3)]
        took = [0, 0, 0]
        for k in order:
            took[k] = kinds[k]()
        c_ns.append(took[0])
        overhead.append(took[1] - took[0])
        control.append(took[2] - took[0])
    # Every call ran as many substeps, or the kinds would not time the same work.
    if len(substeps) != 1:
        raise RuntimeError(f"the calls ran different numbers of substeps: {sorted(substeps)}")
    med = statistics.median
    return med(c_ns), med(overhead), med(control), substeps.pop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, nargs="+", default=[10_000, 100_000])
    parser.add_argument("--seconds", type=float, default=15, help="of calls per world size")
    parser.add_argument("--substeps", type=int, default=4, help="substeps a call (dt)")
    args = parser.parse_args()
    if any(n <= 0 or n % 4 for n in args.particles):
        parser.error("--particles: positive multiples of 4 (2 x 2 particles a cell)")

    # The wrapper's own cost: a world without particles, whose step returns at once.
    c0, fixed, control0, _ = measure(block_world(0), 1 / 60, 20_000)
    print(f"mpm_gimp {mpm.precision}, one worker, CPU time of the calling thread, medians")
    print(
        f"no particles: C call {c0 / 1e3:.2f} us, World.step adds {fixed / 1e3:.2f} us "
        f"(control {control0 / 1e3:+.2f} us)"
    )
    print()
    print(
        "| particles | substeps a call | triples | C call | World.step adds | control "
        "| fixed cost |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for n in args.particles:
        w = block_world(n)
        # `dt` half a substep short of `--substeps` stable ones: the block's speed may change
        # the stable step a little without changing the substeps a call runs.
        dt = (args.substeps - 0.5) * w.stable_dt()
        for _ in range(20):  # settle the block on the floor
            w.step(dt)
        dt = (args.substeps - 0.5) * w.stable_dt()
        start = time.perf_counter_ns()
        w.step(dt)
        triples = max(3, int(args.seconds * 1e9 / 3 / (time.perf_counter_ns() - start)))
        c_ns, over, control, substeps = measure(w, dt, triples)
        pct = lambda x: f"{100 * x / c_ns:+.3f} %"  # noqa: E731
        print(
            f"| {n:,} | {substeps} | {triples:,} | {c_ns / 1e6:.3f} ms | {pct(over)} | "
            f"{pct(control)} | {pct(fixed)} |"
        )


if __name__ == "__main__":
    main()
