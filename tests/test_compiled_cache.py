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
