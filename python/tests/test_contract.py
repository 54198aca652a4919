"""The API contract: defaults, errors, input checks, views, snapshots, memory, workers."""

import ctypes
import gc
import pydoc
import threading

import numpy as np
import pytest
from conftest import block_world

import mpm_gimp

# -- definitions and their documentation ---------------------------------------------------


def test_definitions_start_from_the_c_defaults(mpm):
    d = mpm.WorldDef()
    assert d.dimension == mpm.Dimension.PLANE2D
    assert list(d.cells) == [100, 100, 1]
    assert d.cell_size == pytest.approx(0.01, rel=1e-7)
    assert d.gravity.y == pytest.approx(-9.81, rel=1e-7)
    assert list(d.faces) == [mpm.Boundary.SLIP] * 6
    assert d.particle_capacity == 65536 and d.workers == 1
    assert d.internal_cookie != 0
    m = mpm.MaterialDef()
    assert m.model == mpm.MaterialModel.NEO_HOOKEAN
    assert (m.youngs_modulus, m.density) == (1e6, 1000)
    c = mpm.ColliderDef()
    assert c.shape == mpm.ColliderShape.HALF_SPACE and list(c.rotation) == [0, 0, 0, 1]


def test_fields_are_set_by_name_and_unknown_names_are_refused(mpm):
    d = mpm.WorldDef(cell_size=0.5, cells=(8, 9, 1), gravity=(0, -1, 0))
    assert (d.cell_size, list(d.cells), d.gravity.y) == (0.5, [8, 9, 1], -1)
    d.effects.damping.grid = mpm.Schedule.from_points([(0.0, 20.0), (0.5, 0.0)])
    assert d.effects.damping.grid.points == 2
    with pytest.raises(AttributeError, match="celss"):
        mpm.WorldDef(celss=3)
    with pytest.raises(AttributeError):
        d.effects.plastcity = 1
    with pytest.raises(TypeError):
        d.cell_size = "big"


def test_help_gives_units_ranges_and_defaults(mpm):
    text = pydoc.render_doc(mpm.WorldDef)
    assert "cell_size (real): Cell edge length h, m, > 0. Default 0.01." in text
    assert "Default `MPM_SHAPE_GIMP`" in text
    assert "Young's modulus E, Pa, > 0. Default 1e6." in mpm.MaterialDef.__doc__
    assert "STICK = 0" in mpm.Boundary.__doc__
    assert "Advances the world by `dt` seconds" in mpm.World.step.__doc__


def test_the_definition_reads_back_byte_for_byte(mpm):
    d = mpm.WorldDef(cells=(20, 30, 1), cell_size=0.05, flip_beta=0.5, workers=2)
    d.effects.collider_capacity = 3
    d.wall_friction[2] = 0.25
    back = mpm.World(d).definition()
    assert repr(back) == repr(d)  # every field (the bytes differ in padding)


# -- errors ----------------------------------------------------------------------------------


def test_a_refused_call_raises_the_status_as_an_exception(mpm):
    with pytest.raises(mpm_gimp.InvalidCflError) as e:
        mpm.World(mpm.WorldDef(cfl=2.0))
    assert isinstance(e.value, mpm_gimp.MpmError)
    assert e.value.status == mpm_gimp.Status.INVALID_CFL and e.value.name == "INVALID_CFL"
    assert "MPM_STATUS_INVALID_CFL" in str(e.value) and "Courant" in str(e.value)
    w, ids = block_world(mpm)
    with pytest.raises(mpm_gimp.InvalidTimeStepError):
        w.step(-1.0)
    with pytest.raises(mpm_gimp.InvalidMaterialError):
        w.add_material(mpm.MaterialDef(poisson_ratio=0.7))
    with pytest.raises(mpm_gimp.UnknownMaterialError):
        w.fill_box((0.1, 0.1), (0.2, 0.2), 7)
    with pytest.raises(mpm_gimp.PositionOutsideDomainError):
        w.fill_box((-1, 0.1), (0.2, 0.2), 0)
    with pytest.raises(mpm_gimp.UnknownParticleError):
        w.remove_particles(len(ids), 1)
    with pytest.raises(mpm_gimp.EffectNotDeclaredError):
        w.add_collider(mpm.ColliderDef())
    # Nothing changed.
    assert w.diagnostics().particle_count == len(ids)


def test_arguments_of_the_wrong_kind_raise_type_and_value_errors(mpm):
    w, ids = block_world(mpm)
    with pytest.raises(TypeError):
        w.step("soon")
    with pytest.raises(TypeError):
        w.fill_box((0.1, 0.1), (0.2, 0.2), 0.5)
    with pytest.raises(ValueError):
        w.fill_box((0.1,), (0.2, 0.2), 0)
    with pytest.raises(ValueError):
        w.remove_particles(-1, 1)
    with pytest.raises(ValueError):
        w.collider(2**32)
    with pytest.raises(TypeError):
        mpm.World(mpm.MaterialDef())
    other = mpm_gimp.f64 if mpm is mpm_gimp else mpm_gimp
    with pytest.raises(TypeError):
        mpm.World(other.WorldDef())


# -- input arrays ----------------------------------------------------------------------------


def particle_arrays(mpm, n=4):
    x = np.stack([np.linspace(0.3, 0.4, n), np.full(n, 0.5)]).astype(mpm.dtype)
    return dict(
        position=x,
        mass=np.full(n, 0.1, mpm.dtype),
        volume=np.full(n, 1e-4, mpm.dtype),
        material=np.zeros(n, np.uint32),
    )


def test_particles_are_added_from_arrays(mpm):
    w, ids = block_world(mpm)
    a = particle_arrays(mpm)
    v = np.ones((2, 4), mpm.dtype)
    added = w.add_particles(velocity=v, **a)
    assert added == range(len(ids), len(ids) + 4)
    p = w.particles()
    assert np.array_equal(p.position[:, added.start :], a["position"])
    assert np.array_equal(p.velocity[:, added.start :], v)
    assert w.add_particles(**dict(a, material=0)) == range(added.stop, added.stop + 4)


def test_input_arrays_are_checked(mpm):
    w, _ = block_world(mpm)
    a = particle_arrays(mpm)
    wrong = np.float64 if mpm.dtype == np.float32 else np.float32
    with pytest.raises(TypeError, match="dtype"):
        w.add_particles(**dict(a, mass=a["mass"].astype(wrong)))
    with pytest.raises(TypeError, match="numpy.ndarray"):
        w.add_particles(**dict(a, mass=[0.1] * 4))
    with pytest.raises(ValueError, match="shape"):
        w.add_particles(**dict(a, volume=a["volume"][:3]))
    with pytest.raises(ValueError, match="shape"):
        w.add_particles(**dict(a, position=np.zeros((3, 4), mpm.dtype)))
    with pytest.raises(ValueError, match="contiguous"):
        w.add_particles(**dict(a, mass=np.full(8, 0.1, mpm.dtype)[::2]))
    with pytest.raises(TypeError, match="uint32"):
        w.add_particles(**dict(a, material=np.zeros(4, np.int64)))
    with pytest.raises(mpm_gimp.NonFiniteInputError):
        w.add_particles(**dict(a, mass=np.full(4, np.nan, mpm.dtype)))
    # A view of the world's own memory as input is refused by the kernel.
    with pytest.raises(mpm_gimp.OverlappingMemoryError):
        w.add_particles(**dict(a, mass=w.particles().mass[:4]))


# -- views -----------------------------------------------------------------------------------


def c_view(mpm, w):
    view = mpm.ParticlesView()
    assert mpm._precision.lib.mpm_world_particles(w._world, ctypes.byref(view)) == 0
    return view


def test_views_are_read_only_and_stay_so(mpm):
    w, _ = block_world(mpm)
    p = w.particles()
    for column in (p.position, p.velocity, p.mass, p.stress, p.status, p.displacement_gradient):
        assert not column.flags.writeable
        with pytest.raises(ValueError):
            column.flags.writeable = True
        with pytest.raises(ValueError):
            column[..., 0] = 1
    assert p.force is None and p.temperature is None and p.plastic is None


def test_views_are_the_worlds_memory_without_copies(mpm):
    w, ids = block_world(mpm)
    p = w.particles()
    view = c_view(mpm, w)
    assert p.count == view.count == len(ids)
    assert p.position.shape == (2, len(ids)) and p.displacement_gradient.shape == (2, 2, len(ids))
    assert p.position[0].ctypes.data == view.position[0]
    assert p.position[1].ctypes.data == view.position[1]
    assert p.mass.ctypes.data == view.mass
    assert p.displacement_gradient[1, 0].ctypes.data == view.displacement_gradient[3]
    assert p.stress[3].ctypes.data == view.stress[3]
    assert np.shares_memory(p.velocity, w.memory)
    before = p.position[1].copy()
    w.step(1 / 120)
    assert not np.array_equal(p.position[1], before)  # the step shows through
    assert np.array_equal(p.position, w.particles().position)


def test_views_survive_removal_and_the_world(mpm):
    w, ids = block_world(mpm)
    p = w.particles()
    y = p.position[1][10:20]
    assert w.remove_particles(0, len(ids)) == len(ids)
    assert w.particles().count == 0
    assert np.isfinite(p.position.sum())  # memory that is still there
    del w
    gc.collect()
    assert np.isfinite(float(y.sum())) and np.isfinite(float(p.mass.sum()))


def test_the_step_holds_the_interpreter_lock_only_while_views_are_alive(mpm):
    w, _ = block_world(mpm)
    assert not w.views_alive()
    p = w.particles()
    column = p.position[0][5:]
    del p
    gc.collect()
    assert w.views_alive()
    del column
    gc.collect()
    assert not w.views_alive()


def test_threads_may_share_a_world(mpm):
    w, _ = block_world(mpm)
    errors = []

    def work():
        try:
            for _ in range(5):
                w.step(1 / 600)
                float(w.particles().position.sum())
        except Exception as e:  # noqa: BLE001 (reported below)
            errors.append(e)

    threads = [threading.Thread(target=work) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and w.diagnostics().step_count == 15


# -- memory and snapshots ----------------------------------------------------------------------


def test_a_snapshot_reopens_bit_for_bit(mpm, tmp_path):
    w, _ = block_world(mpm)
    w.step(1 / 60)
    np.save(tmp_path / "world.npy", w.snapshot())
    again = mpm.World.open(np.load(tmp_path / "world.npy"))
    assert np.array_equal(again.snapshot(), w.snapshot())
    w.step(1 / 60)
    again.step(1 / 60)
    assert np.array_equal(again.snapshot(), w.snapshot())
    assert np.array_equal(again.particles().position, w.particles().position)


def test_a_damaged_snapshot_is_refused(mpm):
    w, _ = block_world(mpm)
    snap = w.snapshot()
    snap[:8] = 0
    with pytest.raises(mpm_gimp.NotAWorldError):
        mpm.World.open(snap)
    with pytest.raises(TypeError):
        mpm.World.open(b"not an array")


def test_the_world_lives_in_memory_the_caller_passes(mpm, tmp_path):
    d = mpm.WorldDef(cells=(16, 16, 1), cell_size=0.05, particle_capacity=1024)
    size = mpm.World(d).bytes()
    mapped = np.memmap(tmp_path / "world.bin", dtype=np.uint8, mode="w+", shape=(size,))
    w = mpm.World(d, memory=mapped)
    w.fill_box((0.2, 0.2), (0.5, 0.5), w.add_material(mpm.MaterialDef()))
    w.step(1 / 60)
    assert w.memory.ctypes.data == mapped.ctypes.data
    mapped.flush()
    reopened = mpm.World.open(np.fromfile(tmp_path / "world.bin", dtype=np.uint8))
    assert np.array_equal(reopened.particles().position, w.particles().position)
    with pytest.raises(mpm_gimp.BufferTooSmallError):
        mpm.World(d, memory=np.zeros(64, np.uint8))
    with pytest.raises(mpm_gimp.BufferMisalignedError):
        mpm.World(d, memory=np.zeros(size + 64, np.uint8)[1 : size + 1])
    with pytest.raises(ValueError, match="read-only"):
        mpm.World(d, memory=np.frombuffer(bytes(size), np.uint8))


# -- workers ---------------------------------------------------------------------------------


def test_a_step_on_the_packages_threads_equals_one_on_one(mpm):
    one, _ = block_world(mpm, workers=3)
    many, _ = block_world(mpm, workers=3)
    for _ in range(3):
        one.step(1 / 60)
        many.step(1 / 60, workers=3)
    a, b = one.particles(), many.particles()
    for column in ("position", "position_low", "velocity", "displacement_gradient", "stress"):
        assert np.array_equal(getattr(a, column), getattr(b, column))
    with pytest.raises(mpm_gimp.InvalidLimitError):
        one.step(1 / 60, workers=4)
    with pytest.raises(ValueError):
        one.step(1 / 60, workers=0)


# -- colliders and effects -------------------------------------------------------------------


def test_colliders_are_added_set_and_read_back(mpm):
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
    d.effects.collider_capacity = 2
    w = mpm.World(d)
    w.fill_box((0.3, 0.3), (0.7, 0.5), w.add_material(mpm.MaterialDef()))
    floor = w.add_collider(mpm.ColliderDef(position=(0.5, 0.28, 0), contact=mpm.Contact.STICK))
    ball = mpm.ColliderDef(shape=mpm.ColliderShape.SPHERE, radius=0.05, position=(0.2, 0.8, 0))
    assert w.add_collider(ball) == 1
    ball.position = (0.25, 0.8, 0)
    w.set_collider(1, ball)
    assert w.collider(1).def_.position.x == pytest.approx(0.25, rel=1e-6)  # `def`, a keyword
    for _ in range(10):
        w.step(1 / 60)
    f = w.collider(floor).force
    # The block presses on the floor with about its weight m g (it still rings).
    weight = w.diagnostics().mass * 9.81
    assert -1.5 * weight < f.y < -0.5 * weight  # downward on the floor
    with pytest.raises(mpm_gimp.UnknownColliderError):
        w.collider(5)
    with pytest.raises(mpm_gimp.ColliderCapacityExceededError):
        w.add_collider(ball)
    # A box pressed into the block takes the particles whose domains it reaches, once.
    box = mpm.ColliderDef(
        shape=mpm.ColliderShape.BOX, half_extents=(0.05, 0.05, 0.05), position=(0.5, 0.5, 0)
    )
    w.set_collider(1, box)
    n = w.diagnostics().particle_count
    assert w.remove_particles_in_collider(1) > 0
    assert w.diagnostics().particle_count < n and w.remove_particles_in_collider(1) == 0
    with pytest.raises(mpm_gimp.UnknownColliderError):
        w.remove_particles_in_collider(2)


def test_effects_setters_and_removal(mpm):
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
    d.effects.particle_forces = 1
    d.effects.traction_capacity = 100
    d.effects.body_force_gradient[0].x = -0.5  # a field that changes along x
    d.effects.body_force_scale = mpm.Schedule.from_points([(0, 1)])
    d.effects.heat.declared = 1
    d.effects.plasticity = 1
    w = mpm.World(d)
    metal = w.add_material(mpm.MaterialDef(model=mpm.MaterialModel.VON_MISES, conductivity=10))
    ids = w.fill_box((0.3, 0.3), (0.5, 0.5), metal)
    n = len(ids)
    w.set_particle_forces(0, np.ones((2, n), mpm.dtype))
    w.set_particle_scalar(mpm.ScalarField.TEMPERATURE, 0, np.full(n, 300, mpm.dtype))
    tr = w.add_tractions(0, 4, mpm.Face.X_MAX, (1e3, 0))
    assert tr == range(0, 4) and w.traction_count() == 4
    assert w.add_follower_tractions(4, 2, (0, 1), 0.01, (-1e3, 0)) == range(4, 6)
    with pytest.raises(mpm.InvalidEffectError):
        w.add_follower_tractions(4, 1, (0, 0), 0.01, (-1e3, 0))
    p = w.particles()
    assert np.all(p.force == 1) and np.all(p.temperature == 300) and p.plastic.shape == (n,)
    w.step(1 / 120)
    w.set_particle_velocities(0, np.zeros((2, n), mpm.dtype))
    assert np.all(w.particles().velocity == 0)
    w.remove_tractions(0, 2)
    assert w.traction_count() == 4
    w.set_traction_schedule(4, 2, 1)  # the other ids stay
    with pytest.raises(mpm.UnknownTractionError):
        w.remove_tractions(0, 1)
    assert w.remove_particles_in_box((0.3, 0.3), (0.4, 0.5)) > 0
    assert w.remove_particle_list(np.array([0, 1, 1], np.uint32)) == 2
    assert w.remove_inactive_particles() == 0
    h = np.zeros((2, 2, 3), mpm.dtype)
    h[0, 0] = 0.01
    w.set_displacement_gradient(0, h)
    assert np.allclose(w.jacobians()[:3], 1.01)


def test_a_particles_state_goes_back_bit_for_bit(mpm):
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025, transfer=mpm.Transfer.APIC)
    d.effects.heat.declared = 1
    d.effects.plasticity = 1
    a, b = mpm.World(d), mpm.World(d)
    for w in (a, b):
        w.add_material(mpm.MaterialDef(model=mpm.MaterialModel.VON_MISES, conductivity=1))
    a.fill_box((0.3, 0.4), (0.7, 0.7), 0, (0.5, -1))
    for _ in range(3):
        a.step(1 / 60)
    state = a.particles().copy()
    assert set(state) >= {"affine", "temperature", "plastic", "position_low"}
    assert b.add_particles_with_state(state) == range(0, a.particles().count)
    a.step(1 / 60)
    b.step(1 / 60)
    pa, pb = a.particles(), b.particles()
    for column in state:
        assert np.array_equal(getattr(pa, column), getattr(pb, column)), column
    b.set_particle_state(0, {"velocity": np.zeros((2, 4), mpm.dtype)}, 4)
    assert np.all(pb.velocity[:, :4] == 0) and np.array_equal(pb.position, pa.position)
    b.set_particle_affine(0, np.zeros((2, 2, 4), mpm.dtype))
    assert np.all(pb.affine[..., :4] == 0)
    with pytest.raises(ValueError, match="shape"):
        b.set_particle_state(0, {"velocity": np.zeros((2, 4), mpm.dtype)}, 5)


def test_a_forked_child_steps_on_threads_of_its_own(mpm):
    """multiprocessing's fork copies no thread: a child makes its own pool (one taken over from
    the parent would wait for threads that do not exist)."""
    import multiprocessing

    w, _ = block_world(mpm, workers=2)
    w.step(1 / 60, workers=2)  # the parent's pool exists
    context = multiprocessing.get_context("fork")
    with context.Pool(1) as pool:
        assert pool.apply_async(_child_steps, (mpm.precision,)).get(timeout=60) > 0


def _child_steps(precision):
    mpm = mpm_gimp if precision == "f32" else mpm_gimp.f64
    w, _ = block_world(mpm, workers=2)
    return w.step(1 / 60, workers=2).substeps


@pytest.mark.parametrize("model", list(mpm_gimp.MaterialModel))
def test_every_material_model_steps(mpm, model):
    d = mpm.WorldDef(cells=(24, 24, 1), cell_size=0.05, shape=mpm.Shape.QUADRATIC_BSPLINE)
    d.transfer = mpm.Transfer.MLS
    d.effects.plasticity = 1
    d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
    w = mpm.World(d)
    m = w.add_material(mpm.MaterialDef(model=model, youngs_modulus=1e5))
    w.fill_box((0.3, 0.1), (0.6, 0.5), m)
    for _ in range(5):
        assert w.step(1 / 60).frozen == 0
    assert np.isfinite(w.particles().stress).all()


def test_a_3d_world_has_three_axes_and_six_stresses(mpm):
    d = mpm.WorldDef(dimension=mpm.Dimension.SPACE3D, cells=(12, 12, 12), cell_size=0.1)
    w = mpm.World(d)
    ids = w.fill_sphere((0.6, 0.6, 0.6), 0.25, w.add_material(mpm.MaterialDef()))
    w.step(1 / 60)
    p = w.particles()
    n = len(ids)
    assert p.position.shape == (3, n) and p.velocity.shape == (3, n)
    assert p.displacement_gradient.shape == (3, 3, n) and p.stress.shape == (6, n)
    assert p.position[2].ctypes.data == c_view(mpm, w).position[2]
    with pytest.raises(mpm_gimp.InvalidRegionError):
        w.fill_disk((0.6, 0.6, 0.6), 0.2, 0)


def test_sort_particles_returns_the_permutation_and_keeps_each_particle(mpm):
    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
    w = mpm.World(d)
    m = w.add_material(mpm.MaterialDef())
    # Two boxes side by side, the right one added first: out of cell order.
    w.fill_box((0.5, 0.3), (0.6, 0.5), m)
    w.fill_box((0.3, 0.3), (0.45, 0.5), m)
    w.step(1 / 240)
    before = {k: np.array(getattr(w.particles(), k)) for k in ("position", "velocity", "mass")}
    order = w.sort_particles()
    n = w.diagnostics().particle_count
    assert order.dtype == np.uint32 and order.shape == (n,)
    assert np.array_equal(np.sort(order), np.arange(n))
    assert not np.array_equal(order, np.arange(n))
    after = w.particles()
    for k, v in before.items():
        assert np.array_equal(getattr(after, k), v[..., order]), k
    # Sorted already: the identity.
    assert np.array_equal(w.sort_particles(), np.arange(n))
