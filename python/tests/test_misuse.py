"""Property tests (hypothesis): whatever a caller passes, a call either works or raises
MpmError, TypeError or ValueError, and the interpreter never crashes; a refused call leaves
the world's bytes as they were."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import mpm_gimp

ERRORS = (mpm_gimp.MpmError, TypeError, ValueError)
floats = st.floats(allow_nan=True, allow_infinity=True, width=32)
ints = st.integers(min_value=-(2**33), max_value=2**33)
precisions = st.sampled_from([mpm_gimp, mpm_gimp.f64])


def world(mpm):
    d = mpm.WorldDef(cells=(12, 12, 1), cell_size=0.1, particle_capacity=256, max_substeps=50)
    d.effects.collider_capacity = 2
    d.effects.traction_capacity = 8
    w = mpm.World(d)
    w.fill_box((0.3, 0.3), (0.6, 0.6), w.add_material(mpm.MaterialDef()))
    return w


@settings(max_examples=60, deadline=None)
@given(
    mpm=precisions,
    cells=st.tuples(ints, ints, ints),
    cell_size=floats,
    capacity=st.integers(min_value=-5, max_value=5000),
    dimension=ints,
    shape=ints,
    cfl=floats,
    ppc=ints,
)
def test_any_definition_makes_a_world_or_an_error(
    mpm, cells, cell_size, capacity, dimension, shape, cfl, ppc
):
    d = mpm.WorldDef()
    try:
        d.cells = tuple(max(0, min(c, 64)) for c in cells)
        d.cell_size, d.particle_capacity, d.cfl = cell_size, capacity, cfl
        d.dimension, d.shape, d.particles_per_cell = dimension, shape, ppc
        mpm.World(d)
    except ERRORS:
        pass


@settings(max_examples=80, deadline=None)
@given(
    mpm=precisions,
    call=st.sampled_from(
        ["fill_box", "step", "remove", "material", "tractions", "collider", "set", "add"]
    ),
    a=floats,
    b=floats,
    i=ints,
    j=ints,
)
def test_any_call_works_or_raises_and_a_refusal_changes_nothing(mpm, call, a, b, i, j):
    w = world(mpm)
    before = w.snapshot()
    try:
        if call == "fill_box":
            w.fill_box((a, b), (b, a), i)
        elif call == "step":
            w.step(a)
        elif call == "remove":
            w.remove_particles(i, j)
        elif call == "material":
            w.add_material(mpm.MaterialDef(youngs_modulus=a, poisson_ratio=b, model=i))
        elif call == "tractions":
            w.add_tractions(i, j, 1, (a, b))
        elif call == "collider":
            w.add_collider(mpm.ColliderDef(shape=i, radius=a, friction=b))
        elif call == "set":
            n = max(0, min(j, 300))
            w.set_particle_positions(i, np.full((2, n), a, mpm.dtype))
        elif call == "add":
            n = max(0, min(j, 300))
            w.add_particles(
                position=np.full((2, n), a, mpm.dtype),
                mass=np.full(n, b, mpm.dtype),
                volume=np.full(n, b, mpm.dtype),
                material=np.full(n, i % 4, np.uint32),
            )
    except ERRORS as e:
        if isinstance(e, mpm_gimp.MpmError):
            assert np.array_equal(w.snapshot(), before), e
    float(w.particles().position.sum())  # the views still read
