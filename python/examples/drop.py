"""The README's drop scene from Python: a rubber block dropped on a sticky floor.

python python/examples/drop.py                 # prints the block's fall and bounce
python python/examples/drop.py --gif drop.gif  # and animates it (needs matplotlib)
"""

import argparse

import numpy as np

import mpm_gimp as mpm


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--gif", help="write an animation (matplotlib and Pillow)")
    args = parser.parse_args()

    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
    d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
    w = mpm.World(d)
    rubber = w.add_material(mpm.MaterialDef())  # neo-Hookean, E = 1 MPa, nu = 0.3
    w.fill_box((0.3, 0.4), (0.7, 0.7), rubber)
    p = w.particles()  # views: each frame's step shows through them

    frames = []
    for frame in range(args.frames):
        report = w.step(1 / 60)
        frames.append(np.array(p.position))  # a copy of this frame's positions
        if frame % 15 == 0:
            print(
                f"t = {w.diagnostics().time:5.3f} s  lowest y = {p.position[1].min():.4f} m  "
                f"substeps {report.substeps}  frozen {report.frozen}"
            )

    if args.gif:
        import matplotlib.pyplot as plt
        from matplotlib.animation import FuncAnimation, PillowWriter

        fig, ax = plt.subplots(figsize=(4, 4))
        ax.set(xlim=(0, 1), ylim=(0, 1), aspect="equal")
        dots = ax.scatter(*frames[0], s=2)
        animation = FuncAnimation(fig, lambda i: dots.set_offsets(frames[i].T), len(frames))
        animation.save(args.gif, writer=PillowWriter(fps=30))
        print(f"wrote {args.gif}")


if __name__ == "__main__":
    main()
