"""Running mbd3d from its repository without installing it (the test suite, a debugger).

The repository keeps ``planar/``, ``joints/`` and ``viewer/`` beside ``mbd3d/``; the wheel
installs them inside the package as ``mbd3d.planar``, ``mbd3d.joints`` and ``mbd3d.viewer``
(``package-dir`` in ``pyproject.toml``). When ``mbd3d`` is imported from the repository instead,
this finder resolves exactly those three names to the folders beside it, as the installed
layout does; nothing else of the repository becomes importable through ``mbd3d``.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import os
import sys

#: sub-packages whose folders sit beside mbd3d/ in the repository
SIBLINGS = ("planar", "joints", "viewer")


class _SiblingFinder(importlib.abc.MetaPathFinder):
    def __init__(self, root: str):
        self.root = root

    def find_spec(self, fullname, path=None, target=None):
        package, _, name = fullname.partition(".")
        if package != "mbd3d" or name not in SIBLINGS:
            return None
        folder = os.path.join(self.root, name)
        return importlib.util.spec_from_file_location(
            fullname, os.path.join(folder, "__init__.py"), submodule_search_locations=[folder])


def map_siblings(package_folder: str) -> None:
    """Install the finder when ``package_folder`` is ``mbd3d/`` of a repository checkout."""
    if all(os.path.isdir(os.path.join(package_folder, name)) for name in SIBLINGS):
        return  # installed: the sub-packages are inside
    root = os.path.dirname(os.path.abspath(package_folder))
    if not all(os.path.isfile(os.path.join(root, name, "__init__.py")) for name in SIBLINGS):
        return
    if not any(isinstance(f, _SiblingFinder) for f in sys.meta_path):
        # first: an editable install of another checkout has its own finder for these names,
        # which would pair this checkout's mbd3d with that one's joints
        sys.meta_path.insert(0, _SiblingFinder(root))
