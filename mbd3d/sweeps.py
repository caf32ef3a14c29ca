"""Parameter sweeps and Monte Carlo studies, on a Dask cluster or on this machine.

A sweep runs one analysis on many variants of a model: ``factory(**params)`` builds each
variant, an :class:`Analysis` runs on it, and ``metrics`` (name -> function of the
:class:`~mbd3d.Results`) reduce each run to the numbers kept. :func:`sweep` returns a
:class:`SweepTable`, one row per run: parameters, metrics, status, error message, wall time.

Where it runs: on a Dask cluster given as a ``distributed.Client`` or a scheduler address,
otherwise on a ``LocalCluster`` of worker processes on the loopback interface
(``pip install "mbd3d[distributed]"``); without Dask, serially in this process.

Nothing is lost: each run's outcome is written to ``folder/runs/<key>.json`` (and its full
results to ``<key>.npz`` with ``keep_results``) as soon as it finishes, and
``folder/table.csv`` is rewritten atomically as the sweep goes. Run the same sweep again on the
same folder and it skips the points already done: an interrupted sweep resumes where it
stopped. A run that fails (a model that does not assemble, a singular position) is recorded
with its error and does not stop the others; a worker process that dies is replaced by Dask and
its run done again.
"""

from __future__ import annotations

import hashlib
import inspect
import io
import json
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from mbd3d.errors import MBDError
from mbd3d.io.files import atomic_write
from mbd3d.io.results import Results
from mbd3d.sampling import _plain, grid, monte_carlo
from mbd3d.sweep_table import SweepTable

__all__ = ["Analysis", "grid", "monte_carlo", "sweep", "SweepTable", "default_metrics"]

_ANALYSES = ("kinematic", "inverse dynamics", "forward dynamics")
#: seconds between rewrites of table.csv while a sweep runs (each run's own file is immediate)
TABLE_INTERVAL = 1.0
_DASK_HINT = ('to run sweeps in parallel processes or on a cluster, install Dask: '
              'pip install "mbd3d[distributed]"')


@dataclass(frozen=True)
class Analysis:
    """The analysis a sweep runs on every model: one of ``"kinematic"``, ``"inverse
    dynamics"``, ``"forward dynamics"``, over the times ``t`` [s], with the keyword ``options``
    of :func:`mbd3d.kinematic_analysis`, :func:`mbd3d.inverse_dynamics` or
    :func:`mbd3d.forward_dynamics` (e.g. ``method="DOP853", rtol=1e-9``).

    Parameters
    ----------
    kind : {"kinematic", "inverse dynamics", "forward dynamics"}
    t : sequence of float
        The output times [s].
    options : mapping, optional
        Keyword arguments of the analysis.
    """

    kind: str
    t: Sequence[float]
    options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        if self.kind not in _ANALYSES:
            raise MBDError(f"Analysis: unknown kind {self.kind!r}; use one of "
                           f"{', '.join(repr(k) for k in _ANALYSES)}")
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or len(t) < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise MBDError("Analysis: t must be at least two finite, increasing times [s], got "
                           f"{self.t!r}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "options", dict(self.options))
        # checked here, once, rather than failing every run of a sweep the same way
        accepted = inspect.signature(self._function()).parameters
        for name in self.options:
            if name in ("progress", "observers") or name not in accepted or name in (
                    "model", "times"):
                raise MBDError(f"Analysis: {self.kind} takes no option {name!r}; its options "
                               f"are {', '.join(n for n in accepted if n not in ('model', 'times', 'progress', 'observers'))}")
        method = self.options.get("method")
        if self.kind == "forward dynamics" and method is not None:
            from mbd3d.analyses.dynamics import GENERALIZED_ALPHA, METHODS  # noqa: PLC0415
            if method not in METHODS and method != GENERALIZED_ALPHA:
                raise MBDError(f"Analysis: method must be one of {', '.join(METHODS)}, "
                               f"{GENERALIZED_ALPHA}; got {method!r}")

    def _function(self) -> Callable:
        import mbd3d as mb  # noqa: PLC0415  (the analyses import this module's users)
        return {"kinematic": mb.kinematic_analysis, "inverse dynamics": mb.inverse_dynamics,
                "forward dynamics": mb.forward_dynamics}[self.kind]

    def __call__(self, model) -> Results:
        return self._function()(model, self.t, **{**self.options, "progress": False})


def _key(params: Mapping[str, Any], signature: str = "") -> str:
    """A name for a run, the same for the same parameters and the same sweep (analysis,
    factory: :func:`_signature`) in any session. Numbers are compared by value: ``1`` and
    ``1.0`` are one point."""
    plain = {name: (float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v)
             for name, v in params.items()}
    text = json.dumps([plain, signature], sort_keys=True, separators=(",", ":"))
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def _code_digest(code, into) -> None:
    """Feed a code object to a hash: its bytecode, names and constants, nested code objects
    (comprehensions, inner functions) by their own contents, never by their repr (which
    holds a memory address that changes from session to session)."""
    into.update(code.co_code)
    into.update(repr(code.co_names).encode())
    for const in code.co_consts:
        if hasattr(const, "co_code"):
            _code_digest(const, into)
        else:
            into.update(repr(const).encode())


def _plain_value(value: Any) -> str:
    """A value captured by a function, as text that is the same in every session."""
    if isinstance(value, (int, float, str, bool, type(None), tuple)):
        return repr(value)
    if isinstance(value, np.ndarray):
        return hashlib.sha1(np.ascontiguousarray(value).tobytes()).hexdigest()
    if callable(value):
        return _identity(value)
    return type(value).__qualname__


def _identity(function: Callable) -> str:
    """What makes a function the same function across sessions: where it is defined, its
    compiled code and the values it captures (so an edited factory or metric counts as a
    new one); a callable object's own ``sweep_identity()`` where it has one."""
    if hasattr(function, "sweep_identity"):  # a callable object that says what it is
        return str(function.sweep_identity())
    digest = hashlib.sha1()
    code = getattr(function, "__code__", None)
    if code is not None:
        _code_digest(code, digest)
    for value in (getattr(function, "__defaults__", None) or ()):
        digest.update(_plain_value(value).encode())
    for cell in (getattr(function, "__closure__", None) or ()):
        try:
            digest.update(_plain_value(cell.cell_contents).encode())
        except ValueError:  # an empty cell
            pass
    name = getattr(function, "__qualname__", type(function).__qualname__)
    return f"{getattr(function, '__module__', '')}.{name}:{digest.hexdigest()[:12]}"


def _signature(factory: Callable, analysis: Callable, metrics: Mapping[str, Callable]) -> str:
    """Everything besides the parameters that determines a run's results: the analysis (kind,
    every time, options), the factory and the metrics (an added or edited metric runs the
    points again, so that no row shows a metric it was not computed with)."""
    if isinstance(analysis, Analysis):
        described = [analysis.kind, hashlib.sha1(np.ascontiguousarray(analysis.t).tobytes())
                     .hexdigest(), repr(sorted((k, repr(v)) for k, v in analysis.options.items()))]
    else:
        described = [_identity(analysis)]
    return json.dumps([described, _identity(factory),
                       {name: _identity(metric) for name, metric in sorted(metrics.items())}])


def _run_one(factory: Callable[..., Any], analysis: Callable[[Any], Results],
             metrics: Mapping[str, Callable[[Results], Any]], params: dict, keep: bool) -> dict:
    """Build, analyse and measure one point (runs on a worker). Never raises: an error is
    returned in the record with the stage it happened in."""
    start = time.perf_counter()
    record = {"params": params, "metrics": {}, "status": "ok", "error": "", "npz": None}
    stage = "building the model"
    try:
        model = factory(**params)
        stage = "the analysis"
        results = analysis(model)
        if results.status == "interrupted":
            raise KeyboardInterrupt  # Ctrl-C during a serial sweep: stop, do not record
        if results.status != "complete":
            raise MBDError(f"analysis {results.status}: {results.message}")
        for name, metric in metrics.items():
            stage = f"metric '{name}'"
            value = _plain(metric(results))
            if isinstance(value, (float, int)) and not isinstance(value, bool):
                value = float(value)
            json.dumps(value)  # a metric must be a number, a string or a list of them
            record["metrics"][name] = value
        if keep:
            buffer = io.BytesIO()
            results.to_npz(buffer)
            record["npz"] = buffer.getvalue()
    except Exception as exc:  # recorded, never stops the sweep
        record["status"] = "failed"
        record["error"] = f"{stage}: {type(exc).__name__}: {exc}"
        record["metrics"] = {}
    record["wall_time"] = time.perf_counter() - start
    return record


def sweep(factory: Callable[..., Any], points: Sequence[Mapping[str, Any]],
          analysis: Callable[[Any], Results], metrics: Mapping[str, Callable[[Results], Any]],
          folder: str | os.PathLike, *, keep_results: bool = False, client: Any = None,
          workers: int | None = None, backend: str = "auto", retry_failed: bool = False,
          progress: bool = True) -> SweepTable:
    """Run ``analysis`` on ``factory(**point)`` for every point and keep ``metrics``.

    Parameters
    ----------
    factory : callable
        ``factory(**params) -> Model``. It runs on the workers: define it at module level (a
        script's own functions are shipped by Dask).
    points : sequence of dict
        Parameter values per run (:func:`grid`, :func:`monte_carlo`, or your own list);
        numbers, strings or booleans, so that each run can be named and stored.
    analysis : Analysis or callable
        ``analysis(model) -> Results``, e.g. ``Analysis("forward dynamics", t, method="DOP853")``.
    metrics : dict
        Name -> ``function(results)`` returning a number (or a string, or a list).
    folder : path
        Where each run's outcome and the table are written; created if missing. Points found
        there from an earlier sweep are not run again (their stored rows are returned).
    keep_results : bool
        Also store each run's full results (``runs/<key>.npz``, see :meth:`SweepTable.results`).
    client : distributed.Client or str, optional
        A Dask client, or a scheduler address ("tcp://host:8786"), to run on that cluster.
    workers : int, optional
        Worker processes of the local cluster (default: the machine's cores, at most the
        number of runs).
    backend : {"auto", "dask", "serial"}
        "auto": Dask if installed (the given client, else a local cluster), serial otherwise;
        "serial": in this process, one run after the other (debugging, small sweeps).
    retry_failed : bool
        Run again the points recorded as failed in ``folder``.
    progress : bool
        Show the progress in the terminal (stderr) and print a summary at the end.

    Returns
    -------
    SweepTable
        One row per point. If the sweep is interrupted (Ctrl-C), the rows done so far, with
        ``summary["interrupted"]`` set; run it again to finish.
    """
    if backend not in ("auto", "dask", "serial"):
        raise MBDError(f"sweep: backend must be 'auto', 'dask' or 'serial', got {backend!r}")
    if not callable(factory):
        raise MBDError(f"sweep: factory must be a function params -> model, got {factory!r}")
    if not callable(analysis):
        raise MBDError(f"sweep: analysis must be an Analysis or a function model -> Results, "
                       f"got {analysis!r}")
    for name, metric in metrics.items():
        if not callable(metric):
            raise MBDError(f"sweep: metric '{name}' must be a function of the results, got "
                           f"{metric!r}")
    points = [{name: _plain(v) for name, v in dict(p).items()} for p in points]
    if not points:
        raise MBDError("sweep: no points to run (give a grid or a list of parameter dicts)")
    parameters = list(dict.fromkeys(name for p in points for name in p))
    for index, point in enumerate(points):
        for name, value in point.items():
            if not isinstance(value, (int, float, str, bool)) or (
                    isinstance(value, float) and not math.isfinite(value)):
                raise MBDError(f"sweep: point {index}, parameter '{name}' = {value!r}: "
                               "parameters must be finite numbers, strings or booleans")
    # a run is named by its parameters and by everything else that determines its results
    # (the analysis with its times and options, the factory, the metrics): a change runs again
    keys = [_key(p, _signature(factory, analysis, metrics)) for p in points]
    if len(set(keys)) != len(keys):
        raise MBDError("sweep: the same parameters appear more than once among the points "
                       "(1 and 1.0 are the same value)")

    folder = os.fspath(folder)
    runs_folder = os.path.join(folder, "runs")
    os.makedirs(runs_folder, exist_ok=True)
    with _FolderLock(folder):
        return _sweep_locked(factory, analysis, metrics, points, parameters, keys, folder,
                             runs_folder, keep_results, client, workers, backend, retry_failed,
                             progress)


class _FolderLock:
    """An exclusive lock on a sweep's folder for the time of the sweep (``folder/.lock``, an
    OS lock that dies with its process), so that two sweeps never write one folder at once."""

    def __init__(self, folder: str):
        self.path = os.path.join(folder, ".lock")
        self.file = None

    def __enter__(self) -> "_FolderLock":
        self.file = open(self.path, "a+")
        try:
            import fcntl  # noqa: PLC0415  (POSIX)
            fcntl.flock(self.file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except ImportError:  # no advisory locks here: the folder is not protected
            pass
        except OSError:
            self.file.seek(0)
            holder = self.file.read().strip() or "another process"
            self.file.close()
            raise MBDError(f"sweep: the folder '{os.path.dirname(self.path)}' is in use by "
                           f"another sweep ({holder}); wait for it to finish, or give this "
                           "sweep another folder") from None
        self.file.seek(0)
        self.file.truncate()
        self.file.write(f"process {os.getpid()} since {time.strftime('%Y-%m-%d %H:%M:%S')}")
        self.file.flush()
        return self

    def __exit__(self, *exc_info) -> None:
        self.file.close()  # releases the lock


def _sweep_locked(factory, analysis, metrics, points, parameters, keys, folder, runs_folder,
                  keep_results, client, workers, backend, retry_failed, progress) -> "SweepTable":
    """The body of :func:`sweep`, with the folder locked."""
    metric_names = list(metrics)
    records = _load_records(runs_folder, set(keys))
    if retry_failed:
        records = {k: r for k, r in records.items() if r["status"] == "ok"}
    todo = [(k, p) for k, p in zip(keys, points) if k not in records]
    skipped = len(points) - len(todo)

    summary = {"runs": len(points), "ok": 0, "failed": 0, "skipped": skipped,
               "wall_time": 0.0, "run_time": 0.0, "speedup": float("nan"), "workers": 1,
               "interrupted": False}

    def table() -> SweepTable:
        rows = []
        for key, point in zip(keys, points):
            record = records.get(key)
            if record is not None:
                rows.append({"key": key, **point, **record["metrics"], "status": record["status"],
                             "error": record["error"], "wall_time": record["wall_time"]})
        return SweepTable(rows, parameters, metric_names, folder, summary)

    start = time.perf_counter()
    display = _Progress(len(todo), skipped, progress)
    last_table = [0.0]

    def finished(key: str, record: dict) -> None:
        npz = record.pop("npz", None)
        if npz is not None:
            atomic_write(os.path.join(runs_folder, f"{key}.npz"), lambda f: f.write(npz),
                          text=False)
        record["key"] = key
        atomic_write(os.path.join(runs_folder, f"{key}.json"),
                      lambda f: json.dump(record, f, indent=1), text=True)
        records[key] = record
        summary["ok" if record["status"] == "ok" else "failed"] += 1
        summary["run_time"] += record["wall_time"]
        display.update(record)
        now = time.perf_counter()
        if now - last_table[0] >= TABLE_INTERVAL:
            table().to_csv(os.path.join(folder, "table.csv"))
            last_table[0] = now

    use_dask = backend == "dask" or (backend == "auto" and (client is not None
                                                            or _dask_available()))
    if backend == "dask" and not _dask_available():
        raise MBDError(f"sweep: backend 'dask' asked for, but Dask is not installed; {_DASK_HINT}")
    try:
        if todo and use_dask:
            _run_on_dask(todo, factory, analysis, metrics, keep_results, client, workers,
                         finished, summary)
        elif todo:
            if backend == "auto" and progress:
                print(f"sweep: running serially in this process; {_DASK_HINT}", file=sys.stderr)
            for key, point in todo:
                finished(key, _run_one(factory, analysis, metrics, point, keep_results))
    except KeyboardInterrupt:
        summary["interrupted"] = True
    finally:
        summary["wall_time"] = time.perf_counter() - start
        if summary["wall_time"] > 0 and summary["run_time"] > 0:
            summary["speedup"] = summary["run_time"] / summary["wall_time"]
        result = table()
        result.to_csv(os.path.join(folder, "table.csv"))
        display.close(summary)
    return result


def _dask_available() -> bool:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def _run_on_dask(todo, factory, analysis, metrics, keep, client, workers, finished,
                 summary: dict) -> None:
    """Submit every point, hand each record to ``finished`` as it arrives; the number of
    workers goes into ``summary`` as soon as it is known (an interrupted sweep reports it
    too). A local cluster (loopback, one thread per worker process) is started when no
    client is given and closed at the end."""
    from distributed import Client, LocalCluster, as_completed

    own = []
    try:
        if client is None:
            n = workers or os.cpu_count() or 1
            cluster = LocalCluster(n_workers=max(1, min(n, len(todo))), threads_per_worker=1,
                                   processes=True, host="127.0.0.1", dashboard_address=None)
            own.append(cluster)
            client = Client(cluster)
            own.append(client)
        elif isinstance(client, str):
            client = Client(client)
            own.append(client)
        futures = {}
        for key, point in todo:
            # pure=False: the same point is computed again when asked again (after a failure)
            future = client.submit(_run_one, factory, analysis, metrics, point, keep,
                                   pure=False)
            futures[future] = (key, point)
        summary["workers"] = len(client.scheduler_info().get("workers", {})) or 1
        try:
            for future in as_completed(futures):
                key, point = futures[future]
                try:
                    record = future.result()
                except Exception as exc:  # the task could not run (e.g. its worker kept dying)
                    record = {"params": point, "metrics": {}, "status": "failed",
                              "error": f"could not be run on the cluster: "
                                       f"{type(exc).__name__}: {exc}", "wall_time": 0.0}
                finished(key, record)
        except KeyboardInterrupt:
            client.cancel(list(futures))
            raise
    finally:
        for resource in reversed(own):
            resource.close()


def _load_records(runs_folder: str, wanted: set) -> dict:
    """The stored outcomes of earlier runs of the points ``wanted`` (by key). A run file that
    cannot be read, or does not hold a run, is reported by name and its point runs again."""
    records = {}
    for name in os.listdir(runs_folder):
        key, ext = os.path.splitext(name)
        if ext != ".json" or key not in wanted:
            continue
        path = os.path.join(runs_folder, name)
        try:
            with open(path) as f:
                record = json.load(f)
        except (OSError, ValueError) as exc:
            warnings.warn(f"sweep: run file '{path}' cannot be read ({exc}); its point runs "
                          "again", stacklevel=4)
            continue
        if not (isinstance(record, dict)
                and {"status", "metrics", "error", "wall_time"} <= set(record)
                and isinstance(record["metrics"], dict) and record["status"] in ("ok", "failed")
                and isinstance(record["wall_time"], (int, float))):
            warnings.warn(f"sweep: run file '{path}' does not hold a run's outcome; its point "
                          "runs again", stacklevel=4)
            continue
        records[key] = record
    return records


class _Progress:
    """One line in the terminal: runs done, failed, elapsed and remaining time."""

    def __init__(self, total: int, skipped: int, enabled: bool):
        self.total, self.skipped, self.enabled = total, skipped, enabled
        self.done = self.failed = 0
        self.start = time.perf_counter()
        self.tty = enabled and sys.stderr.isatty()
        self.last_line = 0.0
        if enabled and skipped:
            print(f"sweep: {skipped} points done earlier (skipped), {total} to run",
                  file=sys.stderr)

    def update(self, record: dict) -> None:
        self.done += 1
        self.failed += record["status"] != "ok"
        if not self.enabled:
            return
        elapsed = time.perf_counter() - self.start
        remaining = elapsed / self.done * (self.total - self.done)
        line = (f"sweep: {self.done}/{self.total} runs, {self.failed} failed, "
                f"{elapsed:.1f} s elapsed, about {remaining:.0f} s to go")
        if self.tty:
            print("\r" + line, end="", file=sys.stderr, flush=True)
        elif elapsed - self.last_line >= 10.0 or self.done == self.total:
            print(line, file=sys.stderr)
            self.last_line = elapsed

    def close(self, summary: dict) -> None:
        if not self.enabled:
            return
        if self.tty and self.done:
            print(file=sys.stderr)
        state = "interrupted: run it again to finish; " if summary["interrupted"] else ""
        timing = ""
        if summary["run_time"] > 0:
            timing = (f"; {summary['wall_time']:.1f} s on {summary['workers']} worker(s), runs "
                      f"{summary['run_time']:.1f} s in total (speed-up "
                      f"{summary['speedup']:.2f})")
        print(f"sweep: {state}{summary['ok']} ok, {summary['failed']} failed, "
              f"{summary['skipped']} done earlier, of {summary['runs']} points{timing}",
              file=sys.stderr)


def default_metrics(model) -> dict:
    """A file's sweep's metrics (``mbd3d sweep``): the peak ``|effort|`` of every driver and the
    final position of every body (up to 12).

    Parameters
    ----------
    model : Model
    """
    metrics = {}
    for element in model.joints:
        if element.is_driver:
            metrics[f"peak |{element.name} effort|"] = _PeakEffort(element.name)
    for body in model.bodies[:12]:
        for axis, label in enumerate("xyz"[:model.dim]):
            metrics[f"final {body.name}.{label}"] = _FinalPosition(body.name, axis)
    return metrics


class _PeakEffort:
    def __init__(self, driver: str):
        self.driver = driver

    def sweep_identity(self) -> str:
        return f"peak effort of {self.driver}"

    def __call__(self, results) -> float:
        return float(np.max(np.abs(results.driver(self.driver).effort)))


class _FinalPosition:
    def __init__(self, body: str, axis: int):
        self.body, self.axis = body, axis

    def sweep_identity(self) -> str:
        return f"final position of {self.body} along {self.axis}"

    def __call__(self, results) -> float:
        return float(results.body(self.body).position[-1, self.axis])
