"""Compiled kernels never run stale: Numba's cache is keyed on the whole compiled folder.

Numba checks a cached kernel against its own file only; a kernel that calls a function of
another file keeps the old callee compiled in after that file changes. The control below shows
the trap with Numba's default keying; the same edit under :func:`key_cache_on_folder` (what
:mod:`mbd3d.numerics.compiled` uses) reaches the caller without clearing anything.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from mbd3d.numerics.compiled import DISABLED

pytestmark = pytest.mark.skipif(DISABLED, reason="no cache when Numba runs interpreted")

INIT = """
import os
import numba
from mbd3d.numerics.compiled.cache import key_cache_on_folder
if os.environ["KEYED"] == "1":
    key_cache_on_folder(os.path.dirname(__file__))
jit = numba.njit(cache=True)
"""
CALLEE = """
from {package} import jit

@jit
def scale(x):
    return {factor} * x
"""
CALLER = """
from {package} import jit
from {package}.callee import scale

@jit
def scaled_plus_one(x):
    return scale(x) + 1.0
"""


def write_package(root, package: str) -> None:
    folder = root / package
    folder.mkdir()
    (folder / "__init__.py").write_text(INIT)
    (folder / "callee.py").write_text(CALLEE.format(package=package, factor="2.0"))
    (folder / "caller.py").write_text(CALLER.format(package=package))


def run_caller(root, package: str, keyed: bool) -> tuple[float, bool]:
    """``scaled_plus_one(1.0)`` in a fresh interpreter, and whether it came from the cache."""
    script = textwrap.dedent(f"""
        from {package}.caller import scaled_plus_one
        value = scaled_plus_one(1.0)
        print(value, scaled_plus_one.stats.cache_hits.get(scaled_plus_one.signatures[0], 0))
    """)
    env = {**os.environ, "KEYED": "1" if keyed else "0", "PYTHONPATH": str(root)}
    env.pop("NUMBA_CACHE_DIR", None)  # the cache beside the files, in the temporary folder
    out = subprocess.run([sys.executable, "-c", script], cwd=root, env=env, check=True,
                         capture_output=True, text=True, timeout=120).stdout.split()
    return float(out[0]), int(out[1]) > 0


@pytest.mark.parametrize("keyed", [False, True])
def test_an_edited_callee_reaches_its_cached_caller(tmp_path, keyed):
    package = "keyed" if keyed else "unkeyed"
    write_package(tmp_path, package)
    assert run_caller(tmp_path, package, keyed) == (3.0, False)  # compiled and cached
    assert run_caller(tmp_path, package, keyed) == (3.0, True)  # served by the cache
    (tmp_path / package / "callee.py").write_text(CALLEE.format(package=package, factor="5.0"))
    if keyed:
        assert run_caller(tmp_path, package, keyed) == (6.0, False)  # recompiled once
        assert run_caller(tmp_path, package, keyed) == (6.0, True)  # and cached again
    else:
        # the trap, with Numba's default keying: the caller's file did not change, so the
        # cached caller with the old callee compiled in still answers
        assert run_caller(tmp_path, package, keyed) == (3.0, True)


def test_every_kernel_of_the_compiled_core_is_keyed_on_its_folder():
    from mbd3d.numerics import compiled
    from mbd3d.numerics.compiled import accelerations, integration, rows
    from mbd3d.numerics.compiled.cache import PackageKeyedLocator, folder_digest
    digest = folder_digest(os.path.dirname(compiled.__file__))
    for kernel in (rows.constraint_rows_into, accelerations.accelerations_into,
                   integration.advance):
        locator = kernel._cache._impl.locator
        assert isinstance(locator, PackageKeyedLocator)
        assert locator.get_source_stamp()[1] == digest


KINDS = """
import numpy as np
import mbd3d as mb
from mbd3d.joints import Revolute
from mbd3d.mechanisms import pendulum_chain, spatial_chain
from mbd3d.numerics.compiled import accelerations, alpha_loop, generalized_alpha, integration

def planar(spring, torque_function=False):
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    if spring:
        b.add(mb.SpringDamper("s", b.ground, bar, point_i=(0.0, 1.0), point_j=(0.5, 0.0),
                              stiffness=50.0, damping=0.5, free_length=1.0))
    if torque_function:
        b.add(mb.Torque("t", bar, lambda t: 0.1 * t))
    return b.build()

def ball_on_floor(dim):
    b = mb.ModelBuilder(dim=dim, gravity=(0.0,) * (dim - 1) + (-9.81,))
    ball = b.add_body("ball", mass=1.0, inertia=0.004 if dim == 2 else (0.004,) * 3,
                      position=(0.0,) * (dim - 1) + (0.2,))
    b.add(mb.Contact("floor", mb.Plane(b.ground, normal=(0.0,) * (dim - 1) + (1.0,)),
                     mb.Sphere(ball, radius=0.1),
                     law=mb.LinearContact(frequency=50.0, restitution=0.5)))
    return b.build()

def two_balls_in_a_group():
    b = mb.ModelBuilder(dim=3, gravity=(0.0, 0.0, -9.81))
    balls = [b.add_body(f"ball{k}", mass=1.0, inertia=(0.004,) * 3, position=(0.3 * k, 0, 0.2))
             for k in range(2)]
    shapes = [mb.Plane(b.ground, normal=(0, 0, 1))] + [mb.Sphere(ball, radius=0.1)
                                                        for ball in balls]
    b.add(mb.ContactGroup("pile", shapes, law=mb.LinearContact(frequency=50.0,
                                                               restitution=0.5)))
    return b.build()

models = {"planar, no forces": planar(False), "planar, a spring": planar(True),
          "planar, a torque f(t)": planar(False, True),
          "planar chain, range-space solve": pendulum_chain(40),
          "spatial chain, no forces": spatial_chain(3),
          "spatial chain, range-space solve": spatial_chain(40),
          "planar ball on a floor": ball_on_floor(2),
          "spatial ball on a floor": ball_on_floor(3),
          "spatial balls in a contact group": two_balls_in_a_group()}
for name, model in models.items():
    mb.forward_accelerations(model, 0.0, model.q0, model.qd0)
    mb.forward_dynamics(model, [0.0, 0.01], method="RK45")
    mb.forward_dynamics(model, [0.0, 0.01], method="generalized-alpha", step=1e-3)
print(sorted(models[k]._augmented_pattern.layout for k in models))
for kernel in (accelerations.accelerations_with_parts, integration.advance,
               generalized_alpha.newton_step, alpha_loop.alpha_steps):
    print(kernel.__name__, len(kernel.signatures))
print("literal_arguments", sum("Literal" in str(a)
                                for s in generalized_alpha.newton_step.signatures for a in s))
"""


def test_the_kernels_are_compiled_per_body_type_and_contacts_not_per_kind_of_model(tmp_path):
    """Models with and without force elements, with forces given as Python functions, solved
    densely or in the range space, with contacts or a contact group, planar and spatial, run
    on kernels of four types only: planar or spatial, with contacts or without (a model
    without contacts compiles none of their code). A record field that is None for some
    models made each combination a type of its own, and the whole core was compiled once per
    combination: up to 11 times over the test suite, most of its first run's ten minutes."""
    # a new process, so that only these models' kernels are loaded; it imports the mbd3d
    # under test, whatever is installed
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        filter(None, (root, os.environ.get("PYTHONPATH")))))
    run = subprocess.run([sys.executable, "-c", KINDS], capture_output=True, text=True,
                         cwd=tmp_path, env=env, check=True)
    lines = run.stdout.split("\n")
    assert lines[0] == str(sorted(["dense"] * 7 + ["range"] * 2))
    counts = dict(line.split() for line in lines[1:] if line)
    # generalized-alpha's steps: in the compiled loop for every model here but the one
    # with forces given as Python functions (its steps one by one from Python): still one
    # type per body type and contacts. newton_step's own count depends on the disk cache:
    # alpha_steps compiled here adds the types it calls it with (4), loaded from the cache
    # it adds none (1, Python's call); a flag passed as a literal would add a second type
    newton = int(counts.pop("newton_step"))
    assert counts == {"accelerations_with_parts": "4", "advance": "4", "alpha_steps": "4",
                      "literal_arguments": "0"}
    assert 1 <= newton <= 4


def test_record_constructors_take_the_fields_in_the_records_order():
    # model_arrays and force_arrays name their arguments (a star argument holding records is
    # typed in Python at every call); a field added to a record's list must be added there too
    import inspect

    from mbd3d.numerics.compiled import structures

    for build, fields in ((structures.model_arrays, structures.MODEL_FIELDS),
                          (structures.force_arrays, structures.FORCE_FIELDS)):
        function = getattr(build, "py_func", build)
        assert tuple(inspect.signature(function).parameters) == fields
