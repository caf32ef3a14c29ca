"""Results as tables and files: named columns with units, CSV, pandas and plain-text
tables for a terminal. The :class:`~mbd3d.io.results.Results` methods of the same names call
these; files are written atomically (:mod:`mbd3d.io.files`)."""

from __future__ import annotations

import csv
import os
import time as _time
from typing import TYPE_CHECKING, Sequence

import numpy as np

from mbd3d.errors import MBDError
from mbd3d.io import files
from mbd3d.io.observers import Observer

if TYPE_CHECKING:
    from mbd3d.io.results import Results

__all__ = ["columns", "export_columns", "to_csv", "write_columns", "to_pandas",
           "import_pandas", "format_table", "CsvWriter"]


def export_columns(results: Results) -> list[tuple[str, str, np.ndarray]]:
    """``(name, unit, values)`` of every exported time history (see :func:`columns`)."""
    out: list[tuple[str, str, np.ndarray]] = []
    planar = results.model.dim == 2
    axes = "xy" if planar else "xyz"
    for b in results.model.bodies:
        h = results.body(b.name)
        for label, unit, arr in (("", "m", h.position), ("v", "m/s", h.velocity),
                                 ("a", "m/s^2", h.acceleration)):
            out += [(f"{b.name}.{label}{c}", unit, arr[:, k]) for k, c in enumerate(axes)]
        if planar:
            out += [(f"{b.name}.angle", "rad", h.angle),
                    (f"{b.name}.omega", "rad/s", h.angular_velocity),
                    (f"{b.name}.alpha", "rad/s^2", h.angular_acceleration)]
        else:
            quaternion = h.quaternion  # computed per call: once
            out += [(f"{b.name}.q{c}", "-", quaternion[:, k]) for k, c in enumerate("wxyz")]
            out += [(f"{b.name}.omega_{c}", "rad/s", h.angular_velocity[:, k])
                    for k, c in enumerate(axes)]
            out += [(f"{b.name}.alpha_{c}", "rad/s^2", h.angular_acceleration[:, k])
                    for k, c in enumerate(axes)]
    out += _contact_columns(results)
    if results.lam is None:
        return out
    for element in results.model.joints:
        if element.is_driver:
            out.append((f"{element.name}.effort", element.effort_unit, results.joint(
                element.name).effort))
            continue
        on = element.body_i if element.body_j.is_ground else element.body_j
        r = results.joint(element.name).reaction(on=on)
        out += [(f"{element.name}.F{c} on {on.name}", "N", r.force[:, k])
                for k, c in enumerate(axes)]
        if planar:
            out.append((f"{element.name}.M on {on.name}", "N m", r.moment))
        else:
            out += [(f"{element.name}.M{c} on {on.name}", "N m", r.moment[:, k])
                    for k, c in enumerate(axes)]
    return out


def _contact_columns(results: Results) -> list[tuple[str, str, np.ndarray]]:
    """Each contact row's gap and normal force, a contact's friction force's size, and over a
    forward dynamics run the energy each row has dissipated."""
    from mbd3d.model.contacts import Contact, contact_group  # noqa: PLC0415

    group = contact_group(results.model, required=False)
    if group is None:
        return []
    states = results.contacts()
    out = []
    for r, (name, owner) in enumerate(zip(states.names, group.owners)):
        length, force = owner.units
        out += [(f"{name}.gap", length, states.gap[:, r]),
                (f"{name}.Fn", force, states.normal_force[:, r])]
        if isinstance(owner, Contact):
            out.append((f"{name}.Ft", "N", np.linalg.norm(states.friction_force[:, r], axis=1)))
        if states.dissipated_energy is not None:
            out.append((f"{name}.dissipated", "J", states.dissipated_energy[:, r]))
    return out


def columns(results: Results) -> dict[str, np.ndarray]:
    """:meth:`Results.columns <mbd3d.io.results.Results.columns>` of ``results``: every time
    history as a named column with its unit."""
    cols: dict[str, np.ndarray] = {"t [s]": results.t}
    for name, unit, values in export_columns(results):
        cols[f"{name} [{unit}]"] = values
    return cols


def to_csv(results: Results, path: str | os.PathLike, overwrite: bool = True) -> str:
    """Write :func:`columns` to a CSV file (see :meth:`mbd3d.io.results.Results.to_csv`)."""
    return write_columns(columns(results), path, overwrite)


def write_columns(cols: dict[str, np.ndarray], path: str | os.PathLike,
                  overwrite: bool = True) -> str:
    """Write equally long named columns to a CSV file, atomically: a header of the names,
    then one row per entry, every number as Python's shortest exact repr."""
    length = len(next(iter(cols.values())))
    data = np.column_stack(list(cols.values())) if length else np.zeros((0, len(cols)))

    def write(f):
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(cols)
        writer.writerows([repr(float(x)) for x in row] for row in data)
    return files.atomic_write(path, write, text=True, overwrite=overwrite,
                              what="the CSV file")


def to_pandas(results: Results):
    """:func:`columns` as a ``pandas.DataFrame`` (see
    :meth:`mbd3d.io.results.Results.to_pandas`)."""
    pd = import_pandas()
    cols = columns(results)
    t = cols.pop("t [s]")
    df = pd.DataFrame(cols, index=pd.Index(t, name="t [s]"))
    df.attrs["units"] = {label: label[label.rindex("[") + 1:-1] for label in df.columns}
    df.attrs["analysis"], df.attrs["model"] = results.analysis, results.model.name
    return df


class CsvWriter(Observer):
    """Write the :func:`columns` of an analysis to a CSV file as its time points are computed,
    so that a run stopped by any means (even killed) leaves every row done so far in a valid
    file. The same file :meth:`Results.to_csv <mbd3d.io.results.Results.to_csv>` writes at
    the end; the path is checked when the writer is made.

    Parameters
    ----------
    path : str or path
        The CSV file.
    overwrite : bool
        Replace an existing file (refused by default).
    interval : float
        Smallest wall-clock time [s] between two writes.
    """

    def __init__(self, path: str | os.PathLike, overwrite: bool = False, interval: float = 0.5):
        self.path = files.check_output_path(path, overwrite, "the CSV file")
        self.overwrite = overwrite
        self.interval = self._base_interval = interval
        self._file = None
        self._written = 0

    def start(self, model, times: np.ndarray, analysis: str) -> None:
        files.check_output_path(self.path, self.overwrite, "the CSV file")  # again: now
        self._file = open(self.path, "w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._file, lineterminator="\n")
        self._written = 0

    def update(self, results: Results, time: float, steps: int) -> None:
        if self._file is None or len(results) <= self._written:
            return
        # the columns of all the results so far, as to_csv takes them (a quaternion's sign
        # follows the whole motion), of which the new rows are written; their cost is kept
        # to a fifth of the run's by spacing the writes
        start = _time.perf_counter()
        cols = columns(results)
        if self._written == 0:
            self._writer.writerow(cols)
        data = np.column_stack(list(cols.values()))[self._written:]
        self._writer.writerows([repr(float(x)) for x in row] for row in data)
        self._file.flush()  # each batch on disk as it is done
        self._written = len(results)
        self.interval = max(self._base_interval, 4.0 * (_time.perf_counter() - start))

    def finish(self, results: Results) -> None:
        if self._file is None:
            return
        try:
            if self._written == 0 and len(results) == 0:
                self._writer.writerow(columns(results))
            self.update(results, 0.0, 0)
        finally:
            self._file.close()
            self._file = None


def import_pandas():
    """pandas, or an error that says how to get it (it is an optional extra)."""
    try:
        import pandas  # noqa: PLC0415  (optional)
    except ImportError:
        raise MBDError('to_pandas needs pandas: pip install "mbd3d[pandas]" (or pip install '
                       'pandas)') from None
    return pandas


def format_table(columns: dict[str, Sequence[float]], precision: int = 5,
                 rows: int | None = None) -> str:
    """A plain-text table of equally long columns (numbers or text), for printing in a terminal.

    Parameters
    ----------
    columns : dict of str to sequence
        Column name -> its values, all equally long.
    precision : int
        Significant digits of the numbers.
    rows : int, optional
        Limits a long table to that many rows, evenly spaced, first and last included.

    Examples
    --------
    >>> print(format_table({"t [s]": [0.0, 0.5], "x [m]": [1.0, -0.25]}, precision=3))
      t [s]  x [m]
          0      1
        0.5  -0.25
    >>> print(format_table({"k": range(11)}, rows=3))
       k
       0
       5
      10
    """
    names = list(columns)
    length = len(columns[names[0]]) if names else 0
    shown = range(length)
    if rows is not None and length > rows:
        shown = np.unique(np.round(np.linspace(0, length - 1, max(rows, 2))).astype(int))
    # adding 0.0 turns -0.0 into 0.0, which reads better in a table
    cells = [[v if isinstance(v, str) else f"{float(v) + 0.0:.{precision}g}"
              for v in (columns[name][k] for k in shown)] for name in names]
    widths = [max([len(name)] + [len(c) for c in col]) + 1 for name, col in zip(names, cells)]
    lines = ["".join(name.rjust(w + 1) for name, w in zip(names, widths))]
    for row in zip(*cells):
        lines.append("".join(c.rjust(w + 1) for c, w in zip(row, widths)))
    return "\n".join(line.rstrip() for line in lines)
