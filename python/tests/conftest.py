"""Fixtures: `mpm` runs a test in both precisions (the `mpm_gimp` and `mpm_gimp.f64` names)."""

import atexit
import os
import shutil
import tempfile

import pytest

# Hypothesis keeps its files out of the source tree (before it is imported).
if "HYPOTHESIS_STORAGE_DIRECTORY" not in os.environ:
    os.environ["HYPOTHESIS_STORAGE_DIRECTORY"] = tempfile.mkdtemp(prefix="hypothesis-")
    atexit.register(shutil.rmtree, os.environ["HYPOTHESIS_STORAGE_DIRECTORY"], True)
from hypothesis import settings  # noqa: E402

import mpm_gimp

# No example database: each run draws afresh.
settings.register_profile("mpm", database=None)
settings.load_profile("mpm")


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
