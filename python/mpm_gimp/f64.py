"""mpm_gimp in double precision: the same names as `mpm_gimp`, whose arrays are float64 (the
kernel's f64 build, a library of its own)."""

from . import _api
from ._api import ERRORS, MpmError, Particles, Status
from ._native import ENUMS

__all__ = ["MpmError", "Particles", "Status"]

for _enum in ENUMS.values():
    globals()[_enum.__name__] = _enum
    __all__.append(_enum.__name__)
for _error in ERRORS.values():
    globals()[_error.__name__] = _error
    __all__.append(_error.__name__)
for _name, _value in _api.namespace("f64").items():
    globals()[_name] = _value
    if not _name.startswith("_"):
        __all__.append(_name)

del _enum, _error, _name, _value
