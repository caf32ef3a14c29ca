"""Writing result files: checks made before any computing, and writes that never leave half a file.

Every file mbd3d writes (CSV, NPZ, Rerun recordings, sweep tables) goes through
:func:`check_output_path` first, so that a path that cannot be written is reported before an
analysis spends minutes on results it could not save, and through :func:`atomic_write`, so
that an interrupted write leaves the previous file or none, never a truncated one.
"""

from __future__ import annotations

import os
import stat
import tempfile
from typing import Callable

from mbd3d.errors import MBDError

__all__ = ["OutputError", "check_output_path", "check_output_folder", "atomic_write"]


class OutputError(MBDError, OSError):
    """A result file cannot be written where it was asked for (the message says why and what
    to do)."""


def check_output_folder(folder: str | os.PathLike, what: str = "results") -> str:
    """The absolute path of an existing folder this process can write files into.

    Raises
    ------
    OutputError
        Naming the folder and what is wrong with it (missing, a file, not writable).
    """
    folder = os.path.abspath(os.fspath(folder))
    if not os.path.exists(folder):
        raise OutputError(f"cannot write {what} to '{folder}': the folder does not exist; "
                          "create it first (mkdir)")
    if not os.path.isdir(folder):
        raise OutputError(f"cannot write {what} to '{folder}': it is a file, not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write {what} to '{folder}': no permission to write in this "
                          "folder; choose one you can write to")
    return folder


def check_output_path(path: str | os.PathLike, overwrite: bool = True,
                      what: str = "results") -> str:
    """The absolute path of a file that can be written, checked before anything is computed.

    Parameters
    ----------
    path : str or path
        The file to write.
    overwrite : bool
        Whether an existing file may be replaced.
    what : str
        What is being written, for the messages ("the CSV file", "the recording").

    Raises
    ------
    OutputError
        If ``path`` is a folder, its folder is missing or not writable, the file exists and
        ``overwrite`` is false, or the file is write-protected (never replaced silently).
    """
    path = os.path.abspath(os.fspath(path))
    if os.path.isdir(path):
        raise OutputError(f"cannot write {what} to '{path}': it is a folder; give a file name")
    check_output_folder(os.path.dirname(path), what)
    if os.path.exists(path):
        if not overwrite:
            raise OutputError(f"'{path}' already exists; allow replacing it (overwrite=True "
                              "in Python, --overwrite on the command line) or choose another "
                              "file name")
        # the mode bits too: root may write anywhere, but a file without write bits was
        # protected on purpose
        if not os.access(path, os.W_OK) or not os.stat(path).st_mode & 0o222:
            raise OutputError(f"cannot write {what} to '{path}': the file is write-protected; "
                              "make it writable or choose another file name")
    return path


def _mode_for(path: str) -> int:
    """Permission bits for a file written at ``path``: those of the file it replaces, else what
    the process's umask gives a new file (mkstemp's temporary file is private, 0600)."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def atomic_write(path: str | os.PathLike, write: Callable, text: bool, overwrite: bool = True,
                 what: str = "results") -> str:
    """Write a file through a temporary file in the same folder, then rename it into place.

    ``write(f)`` writes to the open temporary file. The target is checked first
    (:func:`check_output_path`); an existing file keeps its permission bits, a new one gets
    the umask's. Returns the absolute path written.
    """
    path = check_output_path(path, overwrite, what)
    mode = _mode_for(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".mbd3d-", suffix=".tmp")
    except OSError as exc:
        raise OutputError(f"cannot write {what} to '{path}': {exc.strerror}") from exc
    try:
        with os.fdopen(fd, "w", newline="") if text else os.fdopen(fd, "wb") as f:
            write(f)
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path
