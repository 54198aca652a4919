"""A rigid body Python integrates itself, floating on water through the impulse the world
reports: a wooden box (0.2 x 0.1 m, 500 kg/m^3) in a 2D tank of water, 60 Hz frames.

    python python/examples/float.py                # 20 s: depth over Archimedes' in time
    python python/examples/float.py --seconds 5 --density 800 --every 0.1

The box is a kinematic collider (mass 0), so the host owns its pose and velocity and the step
moves it at the velocity last set. After each step the host reads the impulse the water put
on it over that step (`World.collider(id).impulse`, N s, refreshed by every step; in 2D per
metre of thickness, as the box's mass), integrates the body over the frame (semi-implicit
Euler: the pose moved with the velocity the step held, then the velocity changes by the
impulse and gravity) and sets the new pose and velocity (`set_collider`) for the next step.
The box is held level (a host would integrate the torque alike).

An impulse applied once a frame is stable only for a body heavier than the water its contact
carries in a frame (README, "Colliders and rigid bodies"): about rho width c frame = 32 kg/m
here (c = 9.5 m/s), and the box weighs 10 kg/m, so that with its mass alone (`--added-mass
0`) it rings from frame to frame and floats 20 % high. The host therefore integrates with
that water's mass added to the box's (`--added-mass`, kg/m): the weight and the impulse are
the same, so the box floats where it would, and comes to rest. Measured (f32): its depth 2.5 %
short of Archimedes' at 5 s, creeping down to 1.7 % short at 30 s. A world that moves the box itself
(a `mass` > 0, coupled every substep: examples/float.rs, the Rust twin) floats within 0.8 %.
"""

import argparse

import numpy as np

import mpm_gimp as mpm


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--density", type=float, default=500.0, help="the box's, kg/m^3")
    parser.add_argument("--width", type=float, default=0.2)
    parser.add_argument("--height", type=float, default=0.1)
    parser.add_argument("--every", type=float, default=0.5, help="print every this many s")
    parser.add_argument("--added-mass", type=float, help="kg/m (default: a frame's water)")
    args = parser.parse_args()

    # The tank: 1 m square, 50 cells a metre, slip walls; water 0.35 m deep, weakly
    # compressible (K = 90 kPa: a sound speed of 9.5 m/s), with the grid damping a game
    # declares for water.
    n, frame = 50, 1 / 60
    h = 1 / n
    d = mpm.WorldDef(cells=(n, n, 1), cell_size=h, particle_capacity=20_000)
    for face in mpm.Face:
        d.faces[face] = mpm.Boundary.SLIP
    d.effects.collider_capacity = 1
    d.effects.damping.declared = 1
    d.effects.damping.grid = mpm.Schedule.from_points([(0.0, 20.0)])
    w = mpm.World(d)
    water = mpm.MaterialDef(model=mpm.MaterialModel.FLUID, bulk_modulus=90e3, viscosity=1.0)
    floor, surface = h, h + 0.35  # uGIMP's walls lie a cell inside the grid
    w.fill_box((h, floor), (1 - h, surface), w.add_material(water))

    # The box, per metre of thickness: placed at Archimedes' depth, the water it displaces
    # removed (every particle whose domain, a square of half-width h / 4, reaches it).
    half = np.array([args.width / 2, args.height / 2])
    mass = args.density * args.width * args.height  # kg per metre
    archimedes = args.density / water.density * args.height
    x = np.array([0.5, surface - archimedes + half[1]])
    v = np.zeros(2)
    body = mpm.ColliderDef(shape=mpm.ColliderShape.BOX, half_extents=(*half, 0.5))
    body.position = (*x, 0)
    box = w.add_collider(body)
    w.remove_particles_in_collider(box)

    g = np.array([d.gravity.x, d.gravity.y])
    sound = (water.bulk_modulus / water.density) ** 0.5
    added = args.added_mass
    if added is None:  # the water a frame's contact carries: rho width c frame
        added = water.density * args.width * sound * frame
    print(
        f"box {args.width} x {args.height} m, {mass:.1f} kg/m (integrated with {added:.1f} "
        f"kg/m of water added); Archimedes' depth {archimedes:.4f} m"
    )
    next_print, worst = 0.0, 0.0
    while w.diagnostics().time < args.seconds - frame / 2:
        w.step(frame)
        state = w.collider(box)
        dt = state.duration
        x += v * dt  # where the step moved the box (at the velocity it held)
        v += (np.array([state.impulse.x, state.impulse.y]) + mass * g * dt) / (mass + added)
        body.position, body.velocity = (*x, 0), (*v, 0)
        w.set_collider(box, body)

        # Depth below the surface 15 cm past the box's edges: the median of the tops of its
        # columns of particles (h / 2 wide), not the highest particle, which the walls lift.
        p = w.particles()
        far = np.abs(p.position[0] - x[0]) > half[0] + 0.15
        columns = np.floor(p.position[0][far] / (h / 2)).astype(int)
        tops = np.full(columns.max() + 1, -np.inf)
        np.maximum.at(tops, columns, p.position[1][far])
        top = np.median(tops[np.isfinite(tops)]) + h / 4
        del p  # no view alive: the step releases the interpreter lock
        depth = top - (x[1] - half[1])
        t = w.diagnostics().time
        if t > 2:
            worst = max(worst, abs(depth / archimedes - 1))
        if t >= next_print - frame / 2:
            print(f"t {t:6.2f} s  depth/Archimedes {depth / archimedes:.4f}  v_y {v[1]:+.4f} m/s")
            next_print += args.every
    print(f"largest |depth/Archimedes - 1| after 2 s: {worst:.4f}")


if __name__ == "__main__":
    main()
