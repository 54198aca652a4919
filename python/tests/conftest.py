"""Fixtures: `mpm` runs a test in both precisions (the `mpm_gimp` and `mpm_gimp.f64` names)."""

import pytest

import mpm_gimp


@pytest.fixture(params=["f32", "f64"])
def mpm(request):
    return mpm_gimp if request.param == "f32" else mpm_gimp.f64


def block_world(mpm, **fields):
    """A 2D world of 40 x 40 cells of 2.5 cm with a neo-Hookean block; (world, its ids)."""
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025, particle_capacity=4096, **fields)
    d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
    w = mpm.World(d)
    ids = w.fill_box((0.3, 0.4), (0.7, 0.7), w.add_material(mpm.MaterialDef()))
    return w, ids
