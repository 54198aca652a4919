"""A convergence study from Python: the fixed-free elastic bar in its first mode (the Rust
tests' bar, tests/kernel/verification.rs) at several resolutions, against the exact solution

    u(x0, t) = (v0 / omega) sin(pi (x0 - wall) / 2L) sin(omega t),  omega = pi c / 2L,

printing the RMS displacement error (sampled 16 times a period, worst sample, over the
amplitude) and the order it converges at. uGIMP converges at first order in h here.

    python python/examples/convergence.py                  # 8 to 64 cells per length, f64
    python python/examples/convergence.py --cells 8 16 --precision f32
"""

import argparse
import math

import numpy as np

import mpm_gimp


def bar_error(mpm, cells_per_l, periods, v0=0.05):
    length, young, density = 1.0, 1.0e6, 1000.0
    h = length / cells_per_l
    margin = 1  # uGIMP's, in cells
    d = mpm.WorldDef(cells=(cells_per_l + 2 * margin + cells_per_l // 2, 4 + 2 * margin, 1))
    d.cell_size, d.gravity, d.flip_beta = h, (0, 0, 0), 1.0
    d.particle_capacity = 4 * cells_per_l * 4
    d.faces[mpm.Face.X_MIN] = mpm.Boundary.STICK
    d.faces[mpm.Face.X_MAX] = mpm.Boundary.OPEN
    w = mpm.World(d)
    elastic = mpm.MaterialDef(
        model=mpm.MaterialModel.LINEAR_ELASTIC,
        youngs_modulus=young,
        poisson_ratio=0.0,  # no lateral coupling: c = sqrt(E / rho)
        density=density,
    )
    material = w.add_material(elastic)
    wall, s = margin * h, h / 2  # 2 x 2 particles per cell
    i, j = np.meshgrid(np.arange(round(length / s)), np.arange(8))
    x0 = wall + (i.ravel() + 0.5) * s
    y0 = wall + (j.ravel() + 0.5) * s
    c = math.sqrt(young / density)
    omega = math.pi * c / (2 * length)
    shape = np.sin(math.pi * (x0 - wall) / (2 * length))
    n = x0.size
    w.add_particles(
        position=np.stack([x0, y0]).astype(mpm.dtype),
        velocity=np.stack([v0 * shape, np.zeros(n)]).astype(mpm.dtype),
        mass=np.full(n, density * s * s, mpm.dtype),
        volume=np.full(n, s * s, mpm.dtype),
        material=material,
    )
    x_start = np.array(w.particles().position[0], dtype=np.float64)
    samples = 16 * periods
    dt_sample = periods * 4 * length / c / samples
    steps = math.ceil(dt_sample / w.stable_dt())
    p = w.particles()
    worst = 0.0
    for _ in range(samples):
        for _ in range(steps):
            w.step(dt_sample / steps)
        t = w.diagnostics().time
        exact = v0 / omega * shape * math.sin(omega * t)
        worst = max(worst, float(np.sqrt(np.mean((p.position[0] - x_start - exact) ** 2))))
    return worst / (v0 / omega)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[8, 16, 32, 64])
    parser.add_argument("--periods", type=int, default=1)
    parser.add_argument("--precision", choices=["f32", "f64"], default="f64")
    args = parser.parse_args()
    mpm = mpm_gimp if args.precision == "f32" else mpm_gimp.f64
    print(f"{'cells per L':>12} {'RMS error / amplitude':>22} {'order':>6}")
    previous = None
    for cells in args.cells:
        error = bar_error(mpm, cells, args.periods)
        order = (
            "" if previous is None else f"{math.log(previous[1] / error, cells / previous[0]):6.2f}"
        )
        print(f"{cells:12d} {error:22.3e} {order:>6}")
        previous = (cells, error)


if __name__ == "__main__":
    main()
