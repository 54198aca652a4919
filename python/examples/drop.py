"""The README's drop scene: a rubber block dropped on a sticky floor, animated.

python python/examples/drop.py [--frames 90] [--gif drop.gif]   # the animation: matplotlib
"""

import argparse

import numpy as np

import mpm_gimp as mpm

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--frames", type=int, default=90)
parser.add_argument("--gif", help="write the animation to this file (matplotlib, Pillow)")
args = parser.parse_args()

d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
w = mpm.World(d)
w.fill_box((0.3, 0.4), (0.7, 0.7), w.add_material(mpm.MaterialDef()))  # E = 1 MPa
p = w.particles()  # read-only views: each step shows through them
frames = []
for i in range(args.frames):
    report = w.step(1 / 60)
    frames.append(np.array(p.position))  # this frame's positions, copied
    if i % 15 == 0:
        t, low = w.diagnostics().time, p.position[1].min()
        print(f"t {t:.3f} s  lowest y {low:.4f} m  frozen {report.frozen}")

if args.gif:
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation

    fig, ax = plt.subplots(figsize=(4, 4))
    ax.set(xlim=(0, 1), ylim=(0, 1), aspect="equal")
    dots = ax.scatter(*frames[0], s=2)
    FuncAnimation(fig, lambda i: dots.set_offsets(frames[i].T), len(frames)).save(
        args.gif, writer="pillow", fps=30
    )
    print(f"wrote {args.gif}")
