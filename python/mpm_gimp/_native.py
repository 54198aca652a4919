"""The native libraries and their ctypes declarations, built from the header's data
(_header.py, generated from ffi/include/mpm_gimp.h).

Each precision has its own library (_native_f32.so, _native_f64.so: the crate python/ built
twice) and so its own struct classes, whose `mpm_real` fields are float or double. Every
function is bound twice: through `ctypes.CDLL`, which releases the interpreter lock during the
call, and `ctypes.PyDLL`, which holds it (World.step uses the latter while views are alive).
"""

import ctypes
import enum
import keyword
import os
import textwrap

from . import _header

_SCALARS = {
    "uint32_t": ctypes.c_uint32,
    "uint64_t": ctypes.c_uint64,
    "size_t": ctypes.c_size_t,
    "double": ctypes.c_double,
    "void": None,
}


def _make_enums():
    enums = {}
    for name, doc, values in _header.ENUMS:
        cls = enum.IntEnum(name[3:], {v: n for v, n, _ in values})
        cls.__doc__ = doc + "\n\n" + "\n".join(f"{v} = {n}: {d}" for v, n, d in values)
        cls.__module__ = "mpm_gimp"
        enums[name] = cls
    return enums


#: The header's enums as IntEnum classes, by C name (`MpmDimension` -> `Dimension`).
ENUMS = _make_enums()


class Struct(ctypes.Structure):
    """A C struct of the header: assigning a name it lacks is an error, not a new attribute."""

    def __setattr__(self, name, value):
        if name not in self._names:
            raise AttributeError(f"{type(self).__name__} has no field {name!r}")
        super().__setattr__(name, value)

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(f'{n}={_plain(getattr(self, n))!r}' for n in self._names)})"


def _plain(value):
    if isinstance(value, ctypes.Array):
        return [_plain(v) for v in value]
    return value


def _wrap(text, indent=""):
    return textwrap.fill(text, 92, subsequent_indent=indent)


def _name(field):
    return field + "_" if keyword.iskeyword(field) else field


def _field_doc(field, ctype, size, doc):
    kind = ctype.replace("mpm_real", "real").replace("Mpm", "")
    if size is not None:
        kind += f"[{size}]"
    return f"{_name(field)} ({kind}): {doc}"


class Precision:
    """One precision's library, struct classes and functions."""

    def __init__(self, name):
        self.name = name
        self.real = ctypes.c_float if name == "f32" else ctypes.c_double
        path = os.path.join(os.path.dirname(__file__), f"_native_{name}.so")
        # RTLD_LOCAL (ctypes' default): the two libraries export the same names, and each
        # must resolve its own.
        self.lib = ctypes.CDLL(path)
        self.pylib = ctypes.PyDLL(path)
        self.structs = {}
        for sname, doc, fields in _header.STRUCTS:
            # A field named as a Python keyword (`def`) takes a trailing underscore.
            cfields = [(_name(f), self._ctype(t, n)) for f, t, n, _ in fields]
            body = {"_fields_": cfields, "__module__": "mpm_gimp"}
            body["_names"] = frozenset(f for f, _ in cfields)
            body["__doc__"] = "\n\n".join(
                [_wrap(doc), "Fields:"]
                + ["\n".join(_wrap("- " + _field_doc(*f), "  ") for f in fields)]
            )
            self.structs[sname] = type(sname[3:], (Struct,), body)
        for fname, ret, args, doc in _header.FUNCTIONS:
            for lib in (self.lib, self.pylib):
                try:
                    fn = getattr(lib, fname)
                except AttributeError:
                    continue  # the other precision's default functions
                fn.restype = self._ctype(ret, None)
                fn.argtypes = [self._ctype(t, None) for _, t in args]
                fn.__doc__ = doc
        self.lib.mpm_status_string.restype = ctypes.c_char_p
        for lib in (self.lib, self.pylib):
            lib.mpm_py_pool_new.restype = ctypes.c_void_p
            lib.mpm_py_pool_new.argtypes = [ctypes.c_uint32]
            lib.mpm_py_world_step_pool.restype = ctypes.c_uint32
            lib.mpm_py_world_step_pool.argtypes = [
                ctypes.c_void_p,
                self.real,
                ctypes.c_void_p,
                ctypes.c_void_p,
            ]

    def _ctype(self, t, size):
        if t.endswith("*"):
            base = ctypes.c_void_p  # every pointer is passed as an address
        elif t == "mpm_real":
            base = self.real
        elif t in _SCALARS:
            base = _SCALARS[t]
        elif t in ENUMS:
            base = ctypes.c_uint32
        else:
            base = self.structs[t]
        return base if size is None else base * size

    def default(self, what):
        """The defaults with the cookie: `what` is 'world', 'material' or 'collider'."""
        return getattr(self.lib, f"mpm_{what}_def_default_{self.name}")()
