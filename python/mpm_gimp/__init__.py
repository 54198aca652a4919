"""mpm_gimp: the GIMP kernel (Generalized Interpolation Material Point method) for Python.

Single precision here, double precision in `mpm_gimp.f64` (the same names):

    import mpm_gimp as mpm
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
    d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
    w = mpm.World(d)
    rubber = w.add_material(mpm.MaterialDef())
    w.fill_box((0.3, 0.4), (0.7, 0.7), rubber)
    report = w.step(1 / 60)
    y = w.particles().position[1]   # a read-only numpy view, no copy

Definitions (`WorldDef`, `MaterialDef`, `ColliderDef`) start from the C library's defaults;
`help(mpm_gimp.WorldDef)` lists every field with its unit, range and default. Errors are
`MpmError` subclasses named after the kernel's status (`InvalidCflError`, ...).
"""

from . import _api

# The f32 names: World, WorldDef, MaterialDef, ColliderDef, Vec3, Schedule, StepReport, the
# enums (`Dimension`, `Shape`, `Face`, ...) and one exception class per status.
__all__ = _api.export(globals(), "f32") + ["f64"]

from . import f64  # noqa: E402  (after the f32 names: it re-exports the shared ones)
