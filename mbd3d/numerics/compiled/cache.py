"""Numba's on-disk cache, keyed on the content of the whole compiled package.

Numba checks a cached kernel against its own source file only. A kernel that calls a function
of another file has that function compiled into it, so after an edit of the callee the cache
keeps serving the caller built with the old code (Numba's documented limitation), and a test
run can pass on code that never ran. Here every kernel of a registered folder is stamped with
a digest of all the Python files of that folder as well: an edit anywhere in the folder
recompiles each kernel once, and an unchanged folder loads as before.

Where the cache lives is still Numba's choice (``__pycache__`` beside the files, or
``NUMBA_CACHE_DIR``); only the freshness stamp changes. Folders not registered here are
cached exactly as Numba does by default.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

from numba.core import caching

__all__ = ["PackageKeyedLocator", "key_cache_on_folder", "folder_digest"]

# Numba 0.68 made these two names public; older releases have them with a leading underscore
_Locator = getattr(caching, "CacheLocator", None) or caching._CacheLocator
_Impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl


def folder_digest(folder: str | os.PathLike) -> bytes:
    """SHA-256 of the names and contents of the ``.py`` files directly in ``folder``."""
    digest = hashlib.sha256()
    for path in sorted(Path(folder).glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.digest()


class PackageKeyedLocator(_Locator):
    """Numba's own locator for a kernel's file, with the folder's digest added to the stamp
    that decides whether a cached kernel is still fresh."""

    #: absolute folder -> digest of its sources, for the folders registered
    folders: dict[str, bytes] = {}

    def __init__(self, inner: _Locator, digest: bytes):
        self._inner = inner
        self._digest = digest

    def ensure_cache_path(self) -> None:
        self._inner.ensure_cache_path()

    def get_cache_path(self) -> str:
        return self._inner.get_cache_path()

    def get_source_stamp(self) -> Any:
        return (self._inner.get_source_stamp(), self._digest)

    def get_disambiguator(self) -> str:
        return self._inner.get_disambiguator()

    @classmethod
    def from_function(cls, py_func, py_file):
        digest = cls.folders.get(os.path.dirname(os.path.abspath(py_file)))
        if digest is None:
            return None  # not ours: the next locator class takes it, as Numba would
        for other in _Impl._locator_classes:
            if other is not cls:
                inner = other.from_function(py_func, py_file)
                if inner is not None:
                    return cls(inner, digest)
        return None


def key_cache_on_folder(folder: str | os.PathLike) -> None:
    """Stamp the cached kernels of the files in ``folder`` with the digest of all of them.

    Call it before the first kernel of the folder is decorated (Numba finds a kernel's
    locator when ``cache=True`` is applied).
    """
    PackageKeyedLocator.folders[os.path.abspath(folder)] = folder_digest(folder)
    if PackageKeyedLocator not in _Impl._locator_classes:
        _Impl._locator_classes.insert(0, PackageKeyedLocator)
