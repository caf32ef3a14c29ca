"""Results as NumPy ``.npz`` files, written and read back: the raw arrays of a run with the
labels of the model's coordinates and constraint rows, so that a file is read back only
against a model whose coordinates and rows are the same, and its run's statistics as JSON.

Reading is bounded: no pickled objects, and no array larger than the file's own time points
make it (a hostile file's compressed member cannot expand past that)."""

from __future__ import annotations

import json
import os
import zipfile
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np

from mbd3d.errors import MBDError
from mbd3d.io import files

if TYPE_CHECKING:
    from mbd3d.io.results import Results  # written, never read here: no import circle

__all__ = ["to_npz", "read_npz"]

#: the arrays of a file, by name: the Results attribute each holds
_ARRAYS = {"t": "t", "q": "q", "qd": "qd", "qdd": "qdd", "lam": "lam", "charts": "charts",
           "chart_quaternions": "turns", "contact_forces": "contact_forces",
           "contact_dissipation": "contact_dissipation", "model_t": "model_t",
           "contact_friction": "contact_friction"}
#: the text fields of a file
_TEXTS = ("coordinate_labels", "row_labels", "analysis", "status", "message", "model", "stats")
#: the longest time series a file may hold, and the largest text [bytes]
_MAX_POINTS, _MAX_TEXT = 10 ** 8, 10 ** 8


def to_npz(results: Results, path: str | os.PathLike | BinaryIO,
           overwrite: bool = True) -> str | None:
    """Write the raw arrays to an ``.npz`` file (see :meth:`mbd3d.io.results.Results.to_npz`)."""
    arrays = dict(t=results.t, q=results.q, qd=results.qd, qdd=results.qdd,
                  coordinate_labels=np.array(results.model.coordinate_labels),
                  row_labels=np.array(results.model.row_labels),
                  analysis=np.array(results.analysis), status=np.array(results.status),
                  message=np.array(results.message), model=np.array(results.model.name),
                  stats=np.array(json.dumps(results.stats, default=_plain)))
    for name, attribute in _ARRAYS.items():
        value = getattr(results, attribute)
        if name not in arrays and value is not None and (name != "model_t"
                                                         or value is not results.t):
            arrays[name] = value

    def write(f):
        np.savez_compressed(f, **arrays)
    if hasattr(path, "write"):
        write(path)
        return None
    return files.atomic_write(path, write, text=False, overwrite=overwrite,
                              what="the NPZ file")


def _plain(value: Any) -> Any:
    """A statistic as JSON can hold it: NumPy numbers and arrays as Python's, else its text."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def read_npz(path: str | os.PathLike, model) -> dict[str, Any]:
    """The arguments of :class:`~mbd3d.Results` (but the model) that :func:`to_npz` wrote
    to ``path``, checked against ``model`` (see :func:`mbd3d.read_results`)."""
    where = f"results file '{os.fspath(path)}'"
    # the widest array per time point: charts, coordinates, rows or contact rows' friction
    width = max(9 * (model.n_bodies + 1), model.n_coordinates, len(model.row_labels),
                3 * _contact_rows(model))
    try:
        with zipfile.ZipFile(path) as archive:
            sizes = {info.filename.removesuffix(".npy"): info.file_size
                     for info in archive.infolist()}
            data = _read(archive, sizes, width, where)
    except MBDError:
        raise
    except (OSError, zipfile.BadZipFile, ValueError, KeyError) as error:
        raise MBDError(f"{where}: cannot be read as results written by Results.to_npz "
                       f"({error})") from None
    _check_labels(data, model, where)
    k, n, m = len(data["t"]), model.n_coordinates, len(model.row_labels)
    shapes = {"q": (k, n), "qd": (k, n), "qdd": (k, n), "lam": (k, m), "model_t": (k,),
              "contact_forces": (k, None), "contact_dissipation": (k, None),
              "contact_friction": (k, None, 3),
              "charts": (k, model.n_bodies + 1, 3, 3),
              "chart_quaternions": (k, model.n_bodies + 1, 4)}
    for name, shape in shapes.items():
        value = data.get(name)
        if value is not None and (value.ndim != len(shape) or any(
                s is not None and s != d for s, d in zip(shape, value.shape))):
            raise MBDError(f"{where}: '{name}' has the shape {value.shape}, where this model's "
                           f"{k} time points need {tuple(s or '*' for s in shape)}")
    try:
        stats = json.loads(str(data.get("stats", "{}")))
    except ValueError as error:
        raise MBDError(f"{where}: its statistics are not JSON ({error})") from None
    return dict(analysis=str(data["analysis"]), t=data["t"], q=data["q"], qd=data["qd"],
                qdd=data["qdd"], lam=data.get("lam"), status=str(data["status"]),
                message=str(data["message"]), stats=stats if isinstance(stats, dict) else {},
                charts=data.get("charts"), turns=data.get("chart_quaternions"),
                model_t=data.get("model_t"), contact_forces=data.get("contact_forces"),
                contact_dissipation=data.get("contact_dissipation"),
                contact_friction=data.get("contact_friction"))


def _contact_rows(model) -> int:
    from mbd3d.model.contacts import contact_group

    group = contact_group(model, required=False)
    return 0 if group is None else len(group.names)


def _read(archive: zipfile.ZipFile, sizes: dict, width: int, where: str
          ) -> dict[str, np.ndarray]:
    """The file's arrays, each refused before it is expanded where it would be larger than
    its time points allow, ``width`` numbers each (``t`` first: at most ``_MAX_POINTS``)."""
    for name in ("t", "q", "qd", "qdd", "analysis", "status", "message"):
        if name not in sizes:
            raise MBDError(f"{where}: it has no '{name}' array; is it a results file written "
                           "by Results.to_npz?")
    unknown = sorted(set(sizes) - set(_ARRAYS) - set(_TEXTS))
    if unknown:
        raise MBDError(f"{where}: unknown arrays {unknown}; is it a results file written by "
                       "Results.to_npz?")
    data = {"t": _member(archive, "t", sizes, 8 * _MAX_POINTS, where, np.float64)}
    t = data["t"]
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise MBDError(f"{where}: its times 't' are not a finite series")
    for name in sizes:
        if name in _TEXTS:
            text = _member(archive, name, sizes, _MAX_TEXT, where, np.str_)
            data[name] = text[()] if text.ndim == 0 else text
        elif name != "t":
            data[name] = _member(archive, name, sizes, 1024 + 8 * width * len(t), where,
                                 np.float64)
    return data


def _member(archive: zipfile.ZipFile, name: str, sizes: dict, limit: int, where: str,
            kind: type) -> np.ndarray:
    """Array ``name`` of the archive, refused beyond ``limit`` bytes expanded or of another
    kind than ``kind`` (no pickled objects)."""
    if sizes[name] > limit:
        raise MBDError(f"{where}: its '{name}' would expand to {sizes[name]} bytes, more than "
                       "its time points can hold")
    with archive.open(name + ".npy") as member:
        # the array's own header, checked before NumPy allocates what it declares: the
        # zip's sizes are the file's word, and a header may claim far more than they hold
        fmt = np.lib.format
        header = (fmt.read_array_header_1_0 if fmt.read_magic(member) == (1, 0)
                  else fmt.read_array_header_2_0)
        shape, _, dtype = header(member)  # a bounded header (NumPy's max_header_size)
        declared = int(np.prod(shape, dtype=object)) * dtype.itemsize
        if declared > sizes[name]:
            raise MBDError(f"{where}: its '{name}' declares {declared} bytes in {sizes[name]}")
        member.seek(0)
        value = np.lib.format.read_array(member, allow_pickle=False)
    if not np.issubdtype(value.dtype, kind) and value.size:  # an empty list: float64
        raise MBDError(f"{where}: '{name}' holds {value.dtype}, not {np.dtype(kind).name}")
    return value


def _check_labels(data: dict, model, where: str) -> None:
    """The file's coordinates and constraint rows are the model's, or the first that is not
    is named."""
    for name, labels, what in (("coordinate_labels", model.coordinate_labels, "coordinates"),
                               ("row_labels", model.row_labels, "constraint rows")):
        if name not in data:
            raise MBDError(f"{where}: it does not name its {what}")
        theirs, ours = [str(x) for x in np.atleast_1d(data[name])], list(labels)
        if theirs != ours:
            first = next((k for k, (a, b) in enumerate(zip(theirs, ours)) if a != b),
                         min(len(theirs), len(ours)))
            got = theirs[first] if first < len(theirs) else "nothing"
            want = ours[first] if first < len(ours) else "nothing"
            raise MBDError(f"{where}: its {what} are not those of model '{model.name}': "
                           f"number {first} is '{got}' in the file, '{want}' in the model "
                           f"({len(theirs)} against {len(ours)}); read it with the model "
                           f"it was written from (the file names '{data.get('model')}')")
