"""Two results against exact solutions, through the package, in both precisions."""

import math

import numpy as np


def test_free_fall_is_exact_to_round_off(mpm):
    """A stress-free block thrown upward in a large empty grid: FLIP moves each particle by
    the grid's velocity and acceleration (E26 of docs/equations.md, exact for a constant
    acceleration), and a uniform velocity field has no gradient, so every particle follows
    x = x0 + v0 t, y = y0 + v0 t - g t^2 / 2 to round-off (positions summed with their low
    parts, and g as the kernel holds it). Tolerance: 32 eps of the precision, of the largest
    coordinate (2 m), after 30 steps (measured 0.35 eps in f32, 2.3 eps in f64); no stress
    beyond 1e-6 of E / rho0."""
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.05)
    w = mpm.World(d)
    v0 = (0.5, 2.0)
    ids = w.fill_box((0.8, 0.6), (1.2, 0.9), w.add_material(mpm.MaterialDef()), v0)
    p = w.particles()
    x0 = p.position.astype(np.float64) + p.position_low
    steps, dt = 30, 1 / 60
    for _ in range(steps):
        w.step(dt)
    t = w.diagnostics().time
    assert math.isclose(t, steps * dt, rel_tol=1e-6)
    g = -d.gravity.y
    x = p.position.astype(np.float64) + p.position_low
    exact_x = x0[0] + v0[0] * t
    exact_y = x0[1] + v0[1] * t - g * t * t / 2
    tol = 32 * np.finfo(mpm.dtype).eps * 2.0
    assert len(ids) > 100
    assert np.abs(x[0] - exact_x).max() < tol
    assert np.abs(x[1] - exact_y).max() < tol
    assert np.abs(p.velocity[1] - (v0[1] - g * t)).max() < tol * 10
    assert np.abs(p.stress).max() < 1e-6 * 1e6 / 1000  # no stress: 1e-6 of E / rho0


def test_a_prestretched_bar_released_gains_the_exact_momentum(mpm):
    """tests/kernel/initial_state.rs's bar, through Python: a neo-Hookean bar pre-stretched
    along x (F = diag(1 + e0, 1), e0 = 1e-3) at rest between slip walls, free at both ends, is
    released. Until the release waves meet at the middle (t < L / 2c) the stress across the
    middle stays the initial sigma_xx, so the right half's momentum is exactly -sigma_xx A t
    and the left half's +sigma_xx A t (A the height, per unit thickness); checked at t = L/4c.
    The method keeps it exactly (uniform stress: the nodes' internal forces cancel), so the
    tolerance is round-off: 1e-4 relative (as the Rust test), total momentum 0 to 1e-4."""
    young, nu, rho, e0 = 1.0e6, 0.3, 1000.0, 1.0e-3
    h, cells, margin = 0.02, 80, 1  # uGIMP's margin: 1 cell
    d = mpm.WorldDef(cells=(cells + 2 * margin + 10, 4 + 2 * margin, 1), cell_size=h)
    d.gravity = (0, 0, 0)
    d.particle_capacity = 4 * cells * 4
    d.faces[mpm.Face.X_MIN] = mpm.Boundary.OPEN
    d.faces[mpm.Face.X_MAX] = mpm.Boundary.OPEN
    w = mpm.World(d)
    mat = w.add_material(mpm.MaterialDef(youngs_modulus=young, poisson_ratio=nu, density=rho))
    s = h / 2  # 2 x 2 particles per reference cell, placed in the stretched configuration
    wall = margin * h
    i, j = np.meshgrid(np.arange(2 * cells), np.arange(8))
    x = (wall + 5 * h) + (i.ravel() + 0.5) * s * (1 + e0)
    y = wall + (j.ravel() + 0.5) * s
    n = x.size
    right = i.ravel() >= cells
    w.add_particles(
        position=np.stack([x, y]).astype(mpm.dtype),
        mass=np.full(n, rho * s * s, mpm.dtype),
        volume=np.full(n, s * s, mpm.dtype),
        material=mat,
    )
    stretch = np.zeros((2, 2, n), mpm.dtype)
    stretch[0, 0] = e0
    w.set_displacement_gradient(0, stretch)
    mu = young / (2 * (1 + nu))
    lam = young * nu / ((1 + nu) * (1 - 2 * nu))
    c = math.sqrt((lam + 2 * mu) / rho)
    sigma_xx = (mu * ((1 + e0) ** 2 - 1) + lam * math.log(1 + e0)) / (1 + e0)
    length, height = 2 * cells * s * (1 + e0), 8 * s
    dt = w.stable_dt()
    steps = round(length / (4 * c) / dt)
    for _ in range(steps):
        w.step(dt)
    t = steps * float(dt)
    p = w.particles()
    momentum = p.mass.astype(np.float64) * p.velocity[0]
    want = sigma_xx * height * t
    p_right, p_left = momentum[right].sum(), momentum[~right].sum()
    assert abs(p_right + want) < 1e-4 * want and abs(p_left - want) < 1e-4 * want
    assert abs(p_right + p_left) < 1e-4 * want
