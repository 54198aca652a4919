"""The Python API over the C interface: errors, definitions, World, its step and its views.

Where to look:
- errors: `MpmError` and `_check`, which turns every status but OK into an exception;
- the step: `World.step` (the interpreter lock, the package's worker pools);
- the views: `World.particles` and `_columns` (numpy arrays over the world's memory).
"""

import ctypes
import os
import textwrap
import threading
import weakref

import numpy as np

from . import _native
from ._native import ENUMS

Status = ENUMS["MpmStatus"]


class MpmError(Exception):
    """A call the kernel refused. `status` is the `Status` (the C `MpmStatus`), `name` its
    name (`"INVALID_CFL"`), `function` the C function that answered. A refused call changed
    nothing. Each status has a subclass (`InvalidCflError`, ...)."""

    def __init__(self, status, function, description):
        self.status = Status(status)
        self.name = self.status.name
        self.function = function
        super().__init__(f"{function}: {description} (MPM_STATUS_{self.name})")


def _error_class(name, doc):
    camel = "".join(part.capitalize() for part in name.split("_")) + "Error"
    return type(camel, (MpmError,), {"__doc__": doc, "__module__": "mpm_gimp"})


_STATUS_DOCS = {n: d for e in _native._header.ENUMS if e[0] == "MpmStatus" for _, n, d in e[2]}
#: The exception class of each status but OK, documented as the header documents the status.
ERRORS = {s: _error_class(s.name, _STATUS_DOCS[s]) for s in Status if s != Status.OK}


def _check(precision, function, status):
    if status != 0:
        text = precision.lib.mpm_status_string(status).decode()
        raise ERRORS.get(status, MpmError)(status, function, text)


def _u32(value, what):
    """An id, index or count: an int in 0 .. 2^32 - 1 (ctypes would wrap others silently)."""
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool):
        raise TypeError(f"{what}: expected an int, got {type(value).__name__}")
    if not 0 <= value < 2**32:
        raise ValueError(f"{what}: {value} outside 0 .. 2^32 - 1")
    return int(value)


def _vec3(value, what):
    """A point or vector of 2 or 3 numbers (z 0 when left out)."""
    try:
        items = [float(v) for v in value]
    except TypeError:
        raise TypeError(f"{what}: expected 2 or 3 numbers, got {type(value).__name__}") from None
    if len(items) not in (2, 3):
        raise ValueError(f"{what}: expected 2 or 3 numbers, got {len(items)}")
    return items + [0.0] * (3 - len(items))


def _aligned(nbytes, align):
    """Zeroed numpy memory of `nbytes` bytes starting at a multiple of `align`."""
    raw = np.zeros(nbytes + align, dtype=np.uint8)
    offset = (-raw.ctypes.data) % align
    return raw[offset : offset + nbytes]


def _memory(memory):
    """The host's memory as a flat uint8 array (a view, never a copy)."""
    if not isinstance(memory, np.ndarray):
        raise TypeError(f"memory: expected a numpy.ndarray, got {type(memory).__name__}")
    if not memory.flags.c_contiguous:
        raise ValueError("memory: not C-contiguous")
    if not memory.flags.writeable:
        raise ValueError("memory: read-only (a world writes its memory)")
    return memory.reshape(-1).view(np.uint8)


def _input(array, what, dtype, shape):
    """Checks an input array's type, dtype, shape and contiguity; returns its address."""
    if not isinstance(array, np.ndarray):
        raise TypeError(
            f"{what}: expected a numpy.ndarray of {np.dtype(dtype).name}, got {type(array).__name__}"
        )
    if array.dtype != np.dtype(dtype):
        raise TypeError(
            f"{what}: dtype {array.dtype}, expected {np.dtype(dtype).name} "
            f"(convert with .astype(np.{np.dtype(dtype).name}))"
        )
    want = tuple(a if n is None else n for a, n in zip(array.shape, shape))
    if array.shape != want or len(shape) != array.ndim:
        text = str(tuple("n" if n is None else n for n in shape)).replace("'", "")
        raise ValueError(f"{what}: shape {array.shape}, expected {text}")
    if not array.flags.c_contiguous:
        raise ValueError(f"{what}: not C-contiguous (pass np.ascontiguousarray({what}))")
    return array.ctypes.data


def _rows(array, what, dtype, rows, count):
    """The addresses of the rows of a (rows, count) input array, as the C calls take them."""
    base = _input(array, what, dtype, (rows, count))
    step = count * np.dtype(dtype).itemsize
    return [base + r * step for r in range(rows)]


class Particles:
    """Read-only numpy views of a world's particle columns, without copies.

    Each column is an array over the world's own memory: `(count,)` for a scalar column,
    `(D, count)` for a vector (D the dimension's axes), `(D, D, count)` for a matrix (entry
    `[a, b]`), `stress` `(4, count)` in 2D and `(6, count)` in 3D, `damping` `(2, count)`;
    None for a column the world does not have (an undeclared effect). The arrays are not
    writeable, and writeable cannot be turned back on; change particles with the World's
    setters. A step changes what they show (they show the world, not a copy); they keep the
    world's memory alive, so a view outlives the World object and particle removal (it then
    shows memory that no longer holds those particles, never memory that is gone). A copy
    that a step does not change: `np.array(column)`.

    Units: position m, velocity m/s, mass kg, volume0 m^3 (2D: per unit thickness; axisymmetric
    per radian), stress the Kirchhoff stress over the initial density m^2/s^2, temperature K,
    force N, damping 1/s; the C header's `MpmParticlesView` documents each column.
    """

    def __init__(self, count, dimension, columns):
        self.count = count
        self.dimension = ENUMS["MpmDimension"](dimension)
        for name, value in columns.items():
            setattr(self, name, value)

    def copy(self):
        """Every column the world has, copied (a dict of C-contiguous arrays): the state
        `World.add_particles_with_state` and `World.set_particle_state` take back, bit for
        bit."""
        out = {}
        for name in Particles.COLUMNS:
            column = getattr(self, name)
            if column is not None:
                out[name] = np.array(np.stack(column) if isinstance(column, tuple) else column)
        return out

    def __repr__(self):
        have = [n for n in Particles.COLUMNS if getattr(self, n) is not None]
        return f"Particles(count={self.count}, dimension={self.dimension.name}, columns={have})"


Particles.COLUMNS = [
    f for f, _, _, _ in next(s[2] for s in _native._header.STRUCTS if s[0] == "MpmParticlesView")
][2:]


def _strided(buffer, base, dtype, count, pointers, shape):
    """One array of shape `shape + (count,)` over the columns at `pointers` (row-major over
    `shape`), or None when they are not evenly spaced."""
    item = np.dtype(dtype).itemsize
    offsets = [p - base for p in pointers]
    strides = []
    for axis in range(len(shape)):
        inner = int(np.prod(shape[axis + 1 :]))
        strides.append(offsets[inner] - offsets[0] if shape[axis] > 1 else 0)
    index = np.indices(shape).reshape(len(shape), -1) if shape else np.zeros((0, 1), int)
    expected = [offsets[0] + int(np.dot(strides, index[:, k])) for k in range(len(offsets))]
    if expected != offsets or any(s < 0 for s in strides):
        return None
    return np.ndarray(
        tuple(shape) + (count,),
        dtype=dtype,
        buffer=buffer,
        offset=offsets[0],
        strides=tuple(strides) + (item,),
    )


def _columns(view, buffer, base, real, nbytes):
    """The columns of an `MpmParticlesView` as arrays over `buffer` (the world's memory, whose
    first byte is at address `base`)."""
    count = view.count
    out = {}
    fields = next(s[2] for s in _native._header.STRUCTS if s[0] == "MpmParticlesView")
    for name, ctype, size, _ in fields[2:]:
        dtype = np.uint32 if ctype.startswith("uint32_t") else real
        value = getattr(view, name)
        pointers = [value] if size is None else list(value)
        pointers = [p or 0 for p in pointers]
        for p in pointers:
            if p and not (base <= p and p - base + count * np.dtype(dtype).itemsize <= nbytes):
                raise MpmError(Status.INTERNAL, "mpm_world_particles", "a column outside the world")
        if size is None:
            out[name] = (
                None if not pointers[0] else _strided(buffer, base, dtype, count, pointers, [])
            )
            continue
        if size == 9:
            d = 3 if pointers[8] else 2
            if not pointers[0]:
                out[name] = None
                continue
            used = [pointers[3 * a + b] for a in range(d) for b in range(d)]
            shape = [d, d]
        else:
            used = [p for p in pointers if p]
            if not used:
                out[name] = None
                continue
            shape = [len(used)]
        array = _strided(buffer, base, dtype, count, used, shape)
        if array is None:  # not evenly spaced: a tuple of the columns
            array = tuple(_strided(buffer, base, dtype, count, [p], []) for p in used)
        out[name] = array
    return out


_NUMBERS = (int, float, np.integer, np.floating)

_PARTICLE_STATE = next(s[2] for s in _native._header.STRUCTS if s[0] == "MpmParticleState")

_POOLS = {}
_POOLS_LOCK = threading.Lock()


def _pool(precision, workers):
    """The package's pool of `workers` threads for this precision (made once per process,
    kept: a child of `fork` has none of its parent's threads, so it makes its own)."""
    if not isinstance(workers, int) or not 1 <= workers <= 256:
        raise ValueError(f"workers: expected an int in 1..=256, got {workers!r}")
    with _POOLS_LOCK:
        key = (precision.name, workers, os.getpid())
        if key not in _POOLS:
            pool = precision.lib.mpm_py_pool_new(workers)
            if not pool:
                raise OSError(f"could not start a pool of {workers} threads")
            _POOLS[key] = pool
        return _POOLS[key]


def export(scope, precision):
    """Puts the names of `precision` ('f32' or 'f64') in a module's `scope`: the enums
    (`Dimension`, `Shape`, `Face`, ...), one exception class per status, and the classes
    (`World`, `WorldDef`, `MaterialDef`, ...); returns the public ones, for `__all__`."""
    names = {"MpmError": MpmError, "Particles": Particles, "Status": Status}
    names.update((e.__name__, e) for e in ENUMS.values())
    names.update((e.__name__, e) for e in ERRORS.values())
    names.update(namespace(precision))
    scope.update(names)
    return [k for k in names if not k.startswith("_")]


def namespace(name):
    """The classes of one precision ('f32' or 'f64')."""
    P = _native.Precision(name)
    S = P.structs
    real = np.float32 if name == "f32" else np.float64
    ns = {"precision": name, "dtype": real}

    def definition(cname, what, doc):
        base = S[cname]

        def __init__(self, **fields):
            """Defaults (the C `mpm_*_def_default`, with the cookie the library checks), then
            the fields given by name."""
            default = P.default(what)
            ctypes.memmove(ctypes.addressof(self), ctypes.addressof(default), ctypes.sizeof(base))
            for field, value in fields.items():
                setattr(self, field, value)

        cls = type(base.__name__, (base,), {"__init__": __init__, "__module__": "mpm_gimp"})
        cls.__doc__ = textwrap.fill(doc, 92) + "\n\n" + base.__doc__
        return cls

    WorldDef = definition(
        "MpmWorldDef",
        "world",
        "A world's definition: `WorldDef(cell_size=0.025, cells=(40, 40, 1))`; nested fields "
        "as `d.effects.plasticity = 1`, vectors as `d.gravity = (0, -9.81, 0)`, per-face "
        "arrays as `d.faces[Face.Y_MIN] = Boundary.STICK`.",
    )
    MaterialDef = definition(
        "MpmMaterialDef",
        "material",
        "A material: `MaterialDef(model=MaterialModel.FLUID, bulk_modulus=2e5)`.",
    )
    ColliderDef = definition(
        "MpmColliderDef",
        "collider",
        "A collider: `ColliderDef(shape=ColliderShape.SPHERE, radius=0.1, position=(0.5, 0.5, 0))`.",
    )

    def schedule(points):
        """A `Schedule` through (time s, value) points, at most MPM_SCHEDULE_POINTS."""
        s = S["MpmSchedule"]()
        points = list(points)
        if len(points) > len(s.times):
            raise ValueError(f"a schedule holds at most {len(s.times)} points, got {len(points)}")
        s.points = len(points)
        for i, (t, v) in enumerate(points):
            s.times[i], s.values[i] = t, v
        return s

    S["MpmSchedule"].from_points = staticmethod(schedule)
    StepReport = S["MpmStepReport"]

    class World:
        """A world in memory this object owns, or that you pass (a numpy array, an
        `np.memmap` of a file): `World(WorldDef(...), memory=None)`.

        Every call checks its arguments and raises `MpmError` (a subclass per status) when
        the kernel refuses; a refused call changes nothing. Calls on one World are serialised
        by a lock, so several Python threads may share it. Positions and vectors are 2 or 3
        numbers (z ignored in 2D); arrays are numpy arrays of `dtype` (float32 in
        `mpm_gimp`, float64 in `mpm_gimp.f64`), with the shapes each method states.
        """

        dtype = real

        def __init__(self, definition, memory=None):
            if not isinstance(definition, S["MpmWorldDef"]):
                raise TypeError(
                    f"definition: expected a {name} WorldDef, got {type(definition).__name__}"
                )
            req = S["MpmMemoryRequirements"]()
            _check(
                P,
                "mpm_memory_requirements",
                P.lib.mpm_memory_requirements(ctypes.byref(definition), ctypes.byref(req)),
            )
            mem = _aligned(req.bytes, req.align) if memory is None else _memory(memory)
            world = ctypes.c_void_p()
            status = P.lib.mpm_world_init(
                ctypes.byref(definition), mem.ctypes.data, mem.nbytes, ctypes.byref(world)
            )
            _check(P, "mpm_world_init", status)
            self._adopt(memory if memory is not None else mem, mem, world.value)

        def _adopt(self, owner, mem, address):
            self._owner = owner  # the array the caller passed, kept alive
            self._mem = mem
            # An exported buffer pins the memory: numpy refuses to resize an array while
            # a buffer of it is held, so the world's address stays valid.
            self._pin = memoryview(mem)
            self._world = address
            self._lock = threading.Lock()
            self._anchors = []  # weak references to the views' anchors
            self._def = self.definition()

        @classmethod
        def open(cls, memory, copy=True):
            """Opens the world a snapshot (`World.snapshot`, `np.load` of a saved one) or any
            memory holds, checking every value (the C `mpm_world_open`). With `copy` (the
            default) the bytes are copied into memory of the alignment the world needs;
            `copy=False` opens the world in `memory` itself (aligned, writeable)."""
            mem = _memory(memory) if not copy else None
            if copy:
                if not isinstance(memory, np.ndarray):
                    raise TypeError(
                        f"memory: expected a numpy.ndarray, got {type(memory).__name__}"
                    )
                src = np.ascontiguousarray(memory).reshape(-1).view(np.uint8)
                mem = _aligned(src.nbytes, 4096)  # a page: more than any world asks
                mem[:] = src
            world = ctypes.c_void_p()
            _check(
                P,
                "mpm_world_open",
                P.lib.mpm_world_open(mem.ctypes.data, mem.nbytes, ctypes.byref(world)),
            )
            self = cls.__new__(cls)
            self._adopt(mem if copy else memory, mem, world.value)
            return self

        # -- calls -------------------------------------------------------------------------

        def _call(self, function, *args, lib=None):
            with self._lock:
                status = getattr(lib or P.lib, function)(self._world, *args)
            _check(P, function, status)

        def _out(self, function, ctype, *args):
            out = ctype()
            self._call(function, *args, ctypes.byref(out))
            return out

        def _dim(self):
            return 3 if self._def.dimension == ENUMS["MpmDimension"].SPACE3D else 2

        def definition(self):
            """The world's definition (`WorldDef`), which can init another world."""
            got = self._out("mpm_world_get_def", S["MpmWorldDef"])
            d = WorldDef.__new__(WorldDef)
            ctypes.memmove(ctypes.addressof(d), ctypes.addressof(got), ctypes.sizeof(d))
            return d

        @property
        def memory(self):
            """The world's memory (a uint8 array; writing into it is at your risk)."""
            return self._mem

        def bytes(self):
            """Bytes the world occupies from its start: what a snapshot copies."""
            return self._out("mpm_world_bytes", ctypes.c_size_t).value

        def snapshot(self):
            """A byte copy of the world (a uint8 array): `np.save` it, `World.open` it."""
            with self._lock:
                n = ctypes.c_size_t()
                _check(P, "mpm_world_bytes", P.lib.mpm_world_bytes(self._world, ctypes.byref(n)))
                return self._mem[: n.value].copy()

        def add_material(self, material):
            """Adds a `MaterialDef`; returns its id."""
            if not isinstance(material, S["MpmMaterialDef"]):
                raise TypeError(
                    f"material: expected a {name} MaterialDef, got {type(material).__name__}"
                )
            return self._out(
                "mpm_world_add_material", ctypes.c_uint32, ctypes.byref(material)
            ).value

        def _range(self, function, *args):
            ids = self._out(function, S["MpmIdRange"], *args)
            return range(ids.first, ids.first + ids.count)

        def fill_box(self, min, max, material, velocity=(0, 0, 0)):
            """Fills the box `[min, max]` (m) with particles of `material` moving at
            `velocity` (m/s), `particles_per_cell` per cell per axis; returns their ids (a
            range). Particles come in stencil-bin order: find a face's by position."""
            V = S["MpmVec3"]
            return self._range(
                "mpm_world_fill_box",
                V(*_vec3(min, "min")),
                V(*_vec3(max, "max")),
                _u32(material, "material"),
                V(*_vec3(velocity, "velocity")),
            )

        def fill_disk(self, center, radius, material, velocity=(0, 0, 0)):
            """Fills a disk (2D worlds) like `fill_box`; radius m."""
            V = S["MpmVec3"]
            return self._range(
                "mpm_world_fill_disk",
                V(*_vec3(center, "center")),
                float(radius),
                _u32(material, "material"),
                V(*_vec3(velocity, "velocity")),
            )

        def fill_sphere(self, center, radius, material, velocity=(0, 0, 0)):
            """Fills a sphere (3D worlds) like `fill_box`; radius m."""
            V = S["MpmVec3"]
            return self._range(
                "mpm_world_fill_sphere",
                V(*_vec3(center, "center")),
                float(radius),
                _u32(material, "material"),
                V(*_vec3(velocity, "velocity")),
            )

        def add_particles(self, position, mass, volume, material, velocity=None):
            """Adds particles from arrays: `position` (D, n) m, `velocity` (D, n) m/s (zero if
            None), `mass` (n,) kg, `volume` (n,) m^3, of `dtype`; `material` (n,) uint32 or one
            id for all. Returns their ids (a range); all or nothing."""
            d = self._dim()
            _input(position, "position", real, (d, None))
            n = position.shape[1]
            if velocity is None:
                velocity = np.zeros((d, n), dtype=real)
            if isinstance(material, (int, np.integer)):
                material = np.full(n, _u32(material, "material"), dtype=np.uint32)
            arrays = S["MpmParticleArrays"]()
            for i, p in enumerate(_rows(position, "position", real, d, n)):
                arrays.position[i] = p
            for i, p in enumerate(_rows(velocity, "velocity", real, d, n)):
                arrays.velocity[i] = p
            arrays.mass = _input(mass, "mass", real, (n,))
            arrays.volume = _input(volume, "volume", real, (n,))
            arrays.material = _input(material, "material", np.uint32, (n,))
            return self._range("mpm_world_add_particles", ctypes.byref(arrays), n)

        # -- the step ------------------------------------------------------------------

        def step(self, dt, workers=1):
            """Advances the world by `dt` seconds in stable substeps; returns the
            `StepReport` (check `frozen`). `workers` > 1 steps on a pool of that many threads
            the package owns (at most the definition's `workers`), with results
            bit-identical to one worker's.

            The interpreter lock: while no view of this world (`particles()`) is alive the
            step releases it, so other Python threads run meanwhile. While a view is alive the
            step holds it, so no Python code can read a view of a half-stepped world (numpy
            code that itself releases the lock, on another thread, still can: share a world
            between threads through the World's calls, which a lock serialises)."""
            # As little Python as can be around the C call (benches/python_overhead.py
            # measures what it adds).
            if type(dt) is not float and not isinstance(dt, _NUMBERS):
                raise TypeError(f"dt: expected a number of seconds, got {type(dt).__name__}")
            report = StepReport()
            pool = None if workers == 1 else _pool(P, workers)
            with self._lock:
                if self._anchors:  # forget the views that are gone
                    self._anchors = [r for r in self._anchors if r() is not None]
                lib = P.pylib if self._anchors else P.lib  # a view alive: hold the GIL
                if pool is None:
                    status = lib.mpm_world_step(self._world, dt, ctypes.byref(report))
                else:
                    status = lib.mpm_py_world_step_pool(self._world, dt, pool, ctypes.byref(report))
            if status:
                _check(P, "mpm_world_step" if pool is None else "mpm_py_world_step_pool", status)
            return report

        def views_alive(self):
            """Whether a view of this world (an array of `particles()`, or one derived from
            it) is alive: then `step` holds the interpreter lock."""
            return any(r() is not None for r in self._anchors)

        def stable_dt(self):
            """The largest stable time step now, s."""
            return self._out("mpm_world_stable_dt", P.real).value

        # -- reading -------------------------------------------------------------------

        def particles(self):
            """Every particle column as read-only numpy arrays over the world's memory
            (`Particles`): no copy; see `Particles` for shapes and lifetime."""
            with self._lock:
                view = S["MpmParticlesView"]()
                _check(
                    P,
                    "mpm_world_particles",
                    P.lib.mpm_world_particles(self._world, ctypes.byref(view)),
                )
                # A new object per call over the world's memory, which every column's base
                # chain ends in (a ctypes array: numpy does not collapse it, as it collapses
                # views of arrays), so that a weak reference to it says whether a view is
                # alive; read-only through `toreadonly`, which numpy does not let writeable
                # undo.
                anchor = (ctypes.c_char * self._mem.nbytes).from_buffer(self._mem)
                self._anchors = [r for r in self._anchors if r() is not None]
                self._anchors.append(weakref.ref(anchor))
                buffer = np.frombuffer(memoryview(anchor).toreadonly(), np.uint8)
                cols = _columns(view, buffer, self._mem.ctypes.data, real, self._mem.nbytes)
                return Particles(view.count, view.dimension, cols)

        def diagnostics(self):
            """Counts, time and sums over the active particles (`Diagnostics`)."""
            return self._out("mpm_world_diagnostics", S["MpmDiagnostics"])

        def jacobians(self):
            """J = det F of every particle, a new (n,) array."""
            n = self._out("mpm_world_diagnostics", S["MpmDiagnostics"]).particle_count
            out = np.empty(n, dtype=real)
            self._call(
                "mpm_world_copy_jacobians", out.ctypes.data, n, ctypes.byref(ctypes.c_size_t())
            )
            return out

        # -- edits ---------------------------------------------------------------------

        def _per_axis(self, function, first, values, what):
            d = self._dim()
            n = values.shape[-1] if isinstance(values, np.ndarray) and values.ndim == 2 else 0
            rows = _rows(values, what, real, d, n) + [None]
            self._call(
                function, _u32(first, "first"), rows[0], rows[1], rows[2] if d == 3 else None, n
            )

        def set_particle_positions(self, first, position):
            """Moves particles `first .. first + n` to `position` (D, n), m."""
            self._per_axis("mpm_world_set_particle_positions", first, position, "position")

        def set_particle_velocities(self, first, velocity):
            """Sets the velocities (D, n), m/s, of particles `first .. first + n`."""
            self._per_axis("mpm_world_set_particle_velocities", first, velocity, "velocity")

        def set_particle_forces(self, first, force):
            """Sets the external forces (D, n), N, of particles `first .. first + n`
            (`effects.particle_forces`)."""
            self._per_axis("mpm_world_set_particle_forces", first, force, "force")

        def set_particle_materials(self, first, material):
            """Gives particles `first .. first + n` the materials `material` (n,) uint32."""
            n = len(material) if isinstance(material, np.ndarray) else 0
            self._call(
                "mpm_world_set_particle_materials",
                _u32(first, "first"),
                _input(material, "material", np.uint32, (n,)),
                n,
            )

        def set_particle_damping(self, first, alpha_g, alpha_p):
            """Sets per-particle grid and particle damping (n,) each, 1/s
            (`effects.damping.per_particle`)."""
            n = len(alpha_g) if isinstance(alpha_g, np.ndarray) else 0
            self._call(
                "mpm_world_set_particle_damping",
                _u32(first, "first"),
                _input(alpha_g, "alpha_g", real, (n,)),
                _input(alpha_p, "alpha_p", real, (n,)),
                n,
            )

        def set_particle_scalar(self, field, first, values):
            """Sets the temperatures (K) or concentration potentials of particles `first ..
            first + n` (`field`: a `ScalarField`; `values` (n,))."""
            n = len(values) if isinstance(values, np.ndarray) else 0
            self._call(
                "mpm_world_set_particle_scalar",
                _u32(field, "field"),
                _u32(first, "first"),
                _input(values, "values", real, (n,)),
                n,
            )

        def set_particle_sources(self, field, first, values):
            """Sets the sources (W/m^3 for heat, 1/s for the concentration) of particles."""
            n = len(values) if isinstance(values, np.ndarray) else 0
            self._call(
                "mpm_world_set_particle_sources",
                _u32(field, "field"),
                _u32(first, "first"),
                _input(values, "values", real, (n,)),
                n,
            )

        def _matrix(self, m, what, n=None):
            """The 9 entry pointers (row-major, 3 a + b) of a (D, D, n) input array."""
            d = self._dim()
            if n is None:
                n = m.shape[-1] if isinstance(m, np.ndarray) and m.ndim == 3 else 0
            base = _input(m, what, real, (d, d, n))
            item = np.dtype(real).itemsize
            ptrs = (ctypes.c_void_p * 9)()
            for a in range(d):
                for b in range(d):
                    ptrs[3 * a + b] = base + (a * d + b) * n * item
            return ptrs, n

        def set_displacement_gradient(self, first, h):
            """Gives particles `first .. first + n` the displacement gradient `h` (D, D, n),
            H = F - I, and the stress of their material."""
            ptrs, n = self._matrix(h, "h")
            self._call(
                "mpm_world_set_displacement_gradient", _u32(first, "first"), ctypes.byref(ptrs), n
            )

        def set_particle_affine(self, first, affine):
            """Sets the affine matrix (D, D, n) of particles `first .. first + n`, as the
            view's `affine` holds it (APIC's B_p; C_p with MLS-MPM)."""
            ptrs, n = self._matrix(affine, "affine")
            self._call("mpm_world_set_particle_affine", _u32(first, "first"), ctypes.byref(ptrs), n)

        def _state(self, state, n):
            """An `MpmParticleState` over the columns of `state` (a dict, as
            `Particles.copy()` makes, or an object with those attributes); missing: NULL."""
            d = self._dim()
            rows = {3: d, 6: 6 if d == 3 else 4, 2: 2}
            get = state.get if isinstance(state, dict) else lambda k: getattr(state, k, None)
            out = S["MpmParticleState"]()
            for field, ctype, size, _ in _PARTICLE_STATE:
                value = get(field)
                if value is None:
                    continue
                dtype = np.uint32 if ctype.startswith("uint32_t") else real
                if size is None:
                    setattr(out, field, _input(value, field, dtype, (n,)))
                elif size == 9:
                    ptrs, _ = self._matrix(value, field, n)
                    getattr(out, field)[:] = list(ptrs)
                else:
                    for i, p in enumerate(_rows(value, field, dtype, rows[size], n)):
                        getattr(out, field)[i] = p
            return out

        def add_particles_with_state(self, state):
            """Adds particles with every column `state` gives (a dict of arrays shaped as the
            view's columns, as `Particles.copy()` makes; position, mass, volume0 and material
            required, others a new particle's value); returns their ids (a range). A world's
            particles so copied and added to a world of the same materials and effects are
            those particles, bit for bit."""
            position = state.get("position") if isinstance(state, dict) else state.position
            n = position.shape[-1] if isinstance(position, np.ndarray) and position.ndim == 2 else 0
            return self._range(
                "mpm_world_add_particles_with_state", ctypes.byref(self._state(state, n)), n
            )

        def set_particle_state(self, first, state, count):
            """Sets the columns `state` gives (as `add_particles_with_state` takes them) of
            particles `first .. first + count`, as given, bit for bit; the others stay."""
            self._call(
                "mpm_world_set_particle_state",
                _u32(first, "first"),
                ctypes.byref(self._state(state, _u32(count, "count"))),
                count,
            )

        def remove_particles(self, first, count):
            """Removes particles `first .. first + count`; later ones move down. Returns the
            number removed."""
            return self._out(
                "mpm_world_remove_particles",
                ctypes.c_uint32,
                _u32(first, "first"),
                _u32(count, "count"),
            ).value

        def remove_particle_list(self, ids):
            """Removes the particles of `ids` (uint32 array, any order)."""
            n = len(ids) if isinstance(ids, np.ndarray) else 0
            return self._out(
                "mpm_world_remove_particle_list",
                ctypes.c_uint32,
                _input(ids, "ids", np.uint32, (n,)),
                n,
            ).value

        def remove_particles_in_box(self, min, max):
            """Removes every particle in the box `[min, max]`, m: a sink."""
            V = S["MpmVec3"]
            return self._out(
                "mpm_world_remove_particles_in_box",
                ctypes.c_uint32,
                V(*_vec3(min, "min")),
                V(*_vec3(max, "max")),
            ).value

        def remove_particles_in_collider(self, collider):
            """Removes every particle whose domain reaches into collider `collider`'s solid:
            the material a body placed into it displaces."""
            return self._out(
                "mpm_world_remove_particles_in_collider", ctypes.c_uint32, collider
            ).value

        def remove_inactive_particles(self):
            """Removes every escaped or frozen particle."""
            return self._out("mpm_world_remove_inactive_particles", ctypes.c_uint32).value

        def sort_particles(self):
            """Reorders the particles by cell, between frames: a step of particles that lost
            their order (a stirred fluid, particles added in the host's order) costs 2 to 3.6
            times one of sorted particles. Returns the permutation, a new (n,) uint32 array:
            `order[new]` is the particle's index before the call. The state is the state
            before, permuted, to the bit; later steps agree with the unsorted world's to
            round-off."""
            n = self._out("mpm_world_diagnostics", S["MpmDiagnostics"]).particle_count
            order = np.empty(n, dtype=np.uint32)
            self._call("mpm_world_sort_particles", order.ctypes.data, n)
            return order

        # -- effects ---------------------------------------------------------------------

        def add_tractions(self, first, count, face, traction):
            """Loads `face` (a `Face`) of the domains of particles `first .. first + count`
            with `traction` (Pa, per deformed area); returns the traction ids."""
            V = S["MpmVec3"]
            return self._range(
                "mpm_world_add_tractions",
                _u32(first, "first"),
                _u32(count, "count"),
                _u32(face, "face"),
                V(*_vec3(traction, "traction")),
            )

        def add_surface_tractions(self, first, count, normal, area, traction):
            """Loads a face of outward `normal` and `area` (m^2) of each particle; returns ids."""
            return self._face_loads("surface", first, count, normal, area, traction)

        def add_follower_tractions(self, first, count, normal, area, load):
            """Loads a face of each particle, given as for `add_surface_tractions`, with a
            traction that turns with it: `load` (Pa) along the deformed face's outward normal,
            then its tangents (a pressure p is (-p, 0, 0)); returns ids."""
            return self._face_loads("follower", first, count, normal, area, load)

        def _face_loads(self, kind, first, count, normal, area, load):
            V = S["MpmVec3"]
            return self._range(
                f"mpm_world_add_{kind}_tractions",
                _u32(first, "first"),
                _u32(count, "count"),
                V(*_vec3(normal, "normal")),
                float(area),
                V(*_vec3(load, "load" if kind == "follower" else "traction")),
            )

        def set_traction_schedule(self, first, count, schedule):
            """Makes tractions `first .. first + count` follow `effects.traction_schedules[schedule]`."""
            self._call(
                "mpm_world_set_traction_schedule",
                _u32(first, "first"),
                _u32(count, "count"),
                _u32(schedule, "schedule"),
            )

        def remove_tractions(self, first, count):
            """Removes tractions `first .. first + count`; the other ids stay."""
            self._call("mpm_world_remove_tractions", _u32(first, "first"), _u32(count, "count"))

        def clear_tractions(self):
            """Removes every traction."""
            self._call("mpm_world_clear_tractions")

        def traction_count(self):
            """Number of tractions."""
            return self._out("mpm_world_traction_count", ctypes.c_size_t).value

        def feedback_alpha(self):
            """The thermostat's alpha now, 1/s."""
            return self._out("mpm_world_feedback_alpha", ctypes.c_double).value

        # -- colliders -------------------------------------------------------------------

        def add_collider(self, collider):
            """Adds a `ColliderDef` (`effects.collider_capacity`); returns its id."""
            if not isinstance(collider, S["MpmColliderDef"]):
                raise TypeError(
                    f"collider: expected a {name} ColliderDef, got {type(collider).__name__}"
                )
            return self._out(
                "mpm_world_add_collider", ctypes.c_uint32, ctypes.byref(collider)
            ).value

        def set_collider(self, id, collider):
            """Replaces collider `id`'s definition (how a host moves a kinematic collider)."""
            if not isinstance(collider, S["MpmColliderDef"]):
                raise TypeError(
                    f"collider: expected a {name} ColliderDef, got {type(collider).__name__}"
                )
            self._call("mpm_world_set_collider", _u32(id, "id"), ctypes.byref(collider))

        def collider(self, id):
            """Collider `id` now (`ColliderState`: `def`, and the last step's `impulse`,
            `force` N and `torque` N m)."""
            return self._out("mpm_world_get_collider", S["MpmColliderState"], _u32(id, "id"))

        def add_distance_field(self, samples):
            """Adds signed-distance samples (n,), m; returns the first one's index."""
            n = len(samples) if isinstance(samples, np.ndarray) else 0
            return self._out(
                "mpm_world_add_distance_field",
                ctypes.c_uint32,
                _input(samples, "samples", real, (n,)),
                n,
            ).value

    World.__module__ = "mpm_gimp"
    ns.update({cls.__name__: cls for cls in S.values()})
    ns.update(WorldDef=WorldDef, MaterialDef=MaterialDef, ColliderDef=ColliderDef, World=World)
    ns["_precision"] = P
    return ns
