"""mpm_gimp in double precision: the same names as `mpm_gimp`, whose arrays are float64 (the
kernel's f64 build, a library of its own)."""

from . import _api

__all__ = _api.export(globals(), "f64")
