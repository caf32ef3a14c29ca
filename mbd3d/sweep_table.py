"""The table a sweep returns (:class:`SweepTable`): one row per run, with its parameters,
metrics, status and wall time; as a terminal table, CSV, pandas, and each run's full results.
"""

from __future__ import annotations

import csv
import json
import os
from typing import Any, Mapping

import numpy as np

from mbd3d.errors import MBDError
from mbd3d.io.files import atomic_write
from mbd3d.io.exports import format_table, import_pandas

__all__ = ["SweepTable"]


class SweepTable:
    """The outcome of a sweep: one row per run (``dict`` with ``key``, the parameters, the
    metrics, ``status`` ("ok" or "failed"), ``error`` and ``wall_time`` [s]).

    Attributes
    ----------
    rows : list of dict
        In the order of the points given.
    parameters, metrics : list of str
        Column names.
    folder : str
        Where the runs are stored.
    summary : dict
        ``runs``, ``ok``, ``failed``, ``skipped`` (done before, resumed), ``wall_time`` [s]
        of this session, ``run_time`` [s] (sum over the runs of this session), ``speedup``
        (their ratio), ``workers``, ``interrupted``.
    """

    def __init__(self, rows: list[dict], parameters: list[str], metrics: list[str], folder: str,
                 summary: dict):
        self.rows, self.parameters, self.metrics = rows, parameters, metrics
        self.folder, self.summary = folder, summary

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def column(self, name: str) -> np.ndarray:
        """One parameter or metric over the rows; NaN where a run failed (numbers), or an
        object array (text).

        Parameters
        ----------
        name : str
            One of :attr:`columns`.
        """
        if name not in self.columns:
            raise MBDError(f"sweep table has no column '{name}'; columns: "
                           f"{', '.join(self.columns)}")
        values = [row.get(name) for row in self.rows]
        try:
            return np.array([np.nan if v is None else v for v in values], dtype=float)
        except (TypeError, ValueError):
            return np.array(values, dtype=object)

    @property
    def columns(self) -> list[str]:
        """The table's columns, in order: the run's key, the parameters, the metrics, and its
        status, error and wall time [s]."""
        return ["key", *self.parameters, *self.metrics, "status", "error", "wall_time"]

    @property
    def failed(self) -> list[dict]:
        """The rows whose run failed, with their parameters and error messages."""
        return [row for row in self.rows if row["status"] != "ok"]

    def results(self, row: Mapping[str, Any]) -> dict[str, np.ndarray]:
        """The full results of a run swept with ``keep_results=True``: the arrays of
        :meth:`mbd3d.Results.to_npz` (``t``, ``q``, ``qd``, ``qdd``, ``lam``, labels).

        Parameters
        ----------
        row : mapping
            One of the table's rows.
        """
        path = os.path.join(self.folder, "runs", f"{row['key']}.npz")
        if row["status"] != "ok":
            raise MBDError(f"run {row['key']} ({_describe(row, self)}) failed, so it has no "
                           f"results: {row['error']}")
        if not os.path.exists(path):
            raise MBDError(f"no full results for run {row['key']} ({_describe(row, self)}): "
                           "sweep with keep_results=True to keep them")
        with np.load(path) as data:
            return {name: data[name] for name in data.files}

    def to_pandas(self):
        """The table as a ``pandas.DataFrame``, one row per run, columns as :attr:`columns`
        (metric names carry the units their authors gave them). Needs pandas
        (``pip install "mbd3d[pandas]"``)."""
        pd = import_pandas()
        return pd.DataFrame([{c: row.get(c) for c in self.columns} for row in self.rows],
                            columns=self.columns)

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write the table (one row per run) to a CSV file, atomically.

        Parameters
        ----------
        path : str or path-like
            The CSV file.
        """
        def write(f):
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(self.columns)
            for row in self.rows:
                writer.writerow(["" if row.get(c) is None else _cell(row.get(c))
                                 for c in self.columns])
        atomic_write(path, write, text=True)

    def __repr__(self) -> str:
        shown = [c for c in self.columns if c not in ("key", "error")]
        table = format_table({c: [_text(row.get(c)) for row in self.rows] for c in shown},
                             rows=20)
        return f"SweepTable({len(self)} runs, {len(self.failed)} failed)\n{table}"


def _cell(value: Any) -> Any:
    # str() of a float is already its shortest round-tripping form
    return json.dumps(value) if isinstance(value, (list, dict)) else value


def _text(value: Any) -> Any:
    if value is None:
        return "-"
    return value if isinstance(value, (int, float)) and not isinstance(value, bool) else str(value)


def _describe(row: Mapping[str, Any], table: SweepTable) -> str:
    return ", ".join(f"{name}={row.get(name)!r}" for name in table.parameters)
