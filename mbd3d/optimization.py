"""Design optimisation and identification on exact gradients, from several starts at once.

``optimize(model, analysis, bounds, objective, starts=8)`` moves the parameters named in
``bounds`` (as :func:`mbd3d.parameters` names them) within their bounds to minimise
``objective``:

- :class:`Objective`: a statistic of one column of the results (``"rms"``, ``"peak"`` (the
  largest magnitude), ``"mean"``, ``"final"``), e.g. the motor's peak torque, by SciPy's
  L-BFGS-B;
- :class:`Fit`: columns of the results against measured values at the measurement's times,
  least squares, by SciPy's ``least_squares`` (trust-region reflective, within the bounds).

Every gradient is exact, from the analysis' own sensitivities (:func:`mbd3d.sensitivities`, or
:func:`mbd3d.forward_sensitivities` for forward dynamics): one analysis and its sensitivities
per iteration, whatever the number of parameters' differences would cost. Each start is one
run of a sweep (:func:`mbd3d.sweeps.sweep`): on Dask when it is installed, kept in ``folder`` as it
finishes, resumed when run again. The first start is the model's own values (clipped into the
bounds), the others are spread over the bounds by a seeded Latin hypercube.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.optimize

from mbd3d.errors import MBDError, ModelError, did_you_mean
from mbd3d.io.optimization_spec import OptimizationSpec
from mbd3d.io.parameters import ModelVariants, parameter_value, with_parameters
from mbd3d.io.results import Results
from mbd3d.sweep_table import SweepTable
from mbd3d.sweeps import Analysis, sweep

__all__ = ["Objective", "Fit", "LocalOptimization", "optimize", "best", "column",
           "starting_points", "check_forward_options"]

_STATISTICS = ("rms", "peak", "mean", "final")


def column(res: Results, name: str) -> np.ndarray:
    """The results' column ``name`` over time, named as ``res.columns()`` names it, with or
    without its unit (``"motor.effort"`` or ``"motor.effort [N m]"``).

    Parameters
    ----------
    res : Results
    name : str
        A column's name, with or without its unit.
    """
    columns = res.columns()
    if name in columns:
        return np.asarray(columns[name], dtype=float)
    for key, values in columns.items():
        if key.split(" [")[0] == name:
            return np.asarray(values, dtype=float)
    plain = [key.split(" [")[0] for key in columns if key != "t [s]"]
    raise ModelError(f"the results of '{res.model.name}' have no column '{name}'"
                     f"{did_you_mean(name, plain)}; e.g. {', '.join(plain[:4])}")


@dataclass(frozen=True)
class Objective:
    """Minimise ``statistic`` of the results' column ``name`` (see :func:`column`): "rms"
    (root mean square over the output times), "peak" (largest magnitude: not smooth where
    two times share it, so the optimiser may stop short there), "mean" or "final".

    Parameters
    ----------
    name : str
        A column of the results (see :func:`column`).
    statistic : {"rms", "peak", "mean", "final"}
    """

    name: str
    statistic: str = "rms"

    def __post_init__(self):
        if self.statistic not in _STATISTICS:
            raise ModelError(f"objective: statistic must be one of {', '.join(_STATISTICS)}, "
                             f"got {self.statistic!r}")

    def __str__(self) -> str:
        return f"{self.statistic} of {self.name}"

    def value(self, res: Results, sens) -> tuple[float, np.ndarray]:
        """The objective and its gradient (p,) from the results and their sensitivities.

        Parameters
        ----------
        res : Results
            Of the analysis.
        sens : Sensitivities
            Of those results, in the parameters being optimised.
        """
        c = column(res, self.name)
        dc = sens.derivative(lambda r: column(r, self.name))  # (k, p)
        if self.statistic == "rms":
            J = math.sqrt(float(np.mean(c * c)))
            return J, (c @ dc) / (len(c) * J) if J > 0 else np.zeros(dc.shape[1])
        if self.statistic == "peak":
            k = int(np.argmax(np.abs(c)))
            return abs(float(c[k])), np.sign(c[k]) * dc[k]
        if self.statistic == "mean":
            return float(np.mean(c)), np.mean(dc, axis=0)
        return float(c[-1]), dc[-1]


@dataclass(frozen=True)
class Fit:
    """Least squares of results' columns against measurements: ``t`` (k,) [s] the times
    measured (the analysis runs at them) and ``values`` the measured columns by name (see
    :func:`column`), each (k,), in the columns' units.

    Parameters
    ----------
    t : sequence of float
        The times measured [s].
    values : mapping of str to sequence of float
        Column name -> the measured values, each as long as ``t``.
    """

    t: tuple
    values: Mapping[str, tuple]

    def __post_init__(self):
        t = tuple(float(x) for x in self.t)
        values = {name: tuple(float(x) for x in v) for name, v in dict(self.values).items()}
        if not values:
            raise ModelError("fit: give at least one measured column")
        for name, v in values.items():
            if len(v) != len(t) or not all(map(math.isfinite, v)):
                raise ModelError(f"fit: column '{name}' must have {len(t)} finite values (one "
                                 f"per time), got {len(v)}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "values", values)

    def __str__(self) -> str:
        return f"fit of {', '.join(self.values)} at {len(self.t)} times"

    def residuals(self, res: Results, sens) -> tuple[np.ndarray, np.ndarray]:
        """The residuals (computed minus measured) and their Jacobian (rows, p).

        Parameters
        ----------
        res : Results
            Of the analysis.
        sens : Sensitivities
            Of those results, in the parameters being optimised.
        """
        r = np.concatenate([column(res, name) - np.asarray(v) for name, v in
                            self.values.items()])
        J = np.concatenate([sens.derivative(lambda x, n=name: column(x, n))
                            for name in self.values])
        return r, J


class LocalOptimization:
    """One start of :func:`optimize`, as a sweep runs it: ``self(model) -> Results`` (those of
    the optimised model, with ``stats["optimization"]``), from the model's own values.

    Parameters
    ----------
    analysis : Analysis
        What each evaluation runs.
    bounds : mapping of str to (float, float)
        Parameter name -> its lower and upper bound.
    objective : Objective or Fit
    """

    def __init__(self, analysis: Analysis, bounds: Mapping[str, tuple[float, float]],
                 objective: Objective | Fit):
        self.analysis, self.objective = analysis, objective
        self.names = list(bounds)
        self.bounds = np.array([bounds[name] for name in self.names], dtype=float)

    def sweep_identity(self) -> str:
        """What a stored start's outcome was computed from (the analysis, the parameters,
        their bounds and the objective): an optimisation resumed with any of them changed
        computes it again."""
        described = [self.analysis.kind, list(self.analysis.t), repr(sorted(
            self.analysis.options.items())), self.names, self.bounds.tolist(),
            repr(self.objective)]
        return "optimization " + hashlib.sha1(json.dumps(described).encode()).hexdigest()

    def evaluate(self, model, x: np.ndarray) -> tuple[Results, Any]:
        """The analysis of ``model`` with the parameters at ``x``, and its sensitivities.

        Parameters
        ----------
        model : Model
        x : (p,) ndarray
            The parameters' values, in the order of ``bounds``.
        """
        import mbd3d as mb  # noqa: PLC0415  (the analyses are above this module's users)

        moved = with_parameters(model, dict(zip(self.names, map(float, x))))
        if self.analysis.kind == "forward dynamics":
            sens = mb.forward_sensitivities(moved, self.analysis.t, self.names,
                                            **self.analysis.options)
            return sens.results, sens
        res = self.analysis(moved)
        return res, mb.sensitivities(res, self.names)

    def __call__(self, model) -> Results:
        x0 = np.array([parameter_value(model, name)[0] for name in self.names])
        cache: dict = {}

        def at(x: np.ndarray):
            key = tuple(np.asarray(x, dtype=float))
            if key not in cache:
                cache.clear()  # only the last point is asked for twice
                res, sens = self.evaluate(model, x)
                if res.status != "complete":
                    raise MBDError(f"the analysis at {dict(zip(self.names, key))} is "
                                   f"{res.status}: {res.message}")
                cache[key] = (res, sens, self.objective_at(res, sens))
            return cache[key]
        start = at(x0)[2][0]
        lower, upper = self.bounds.T
        if isinstance(self.objective, Fit):
            fit = scipy.optimize.least_squares(lambda x: at(x)[2][0], x0,
                                               jac=lambda x: at(x)[2][1], bounds=(lower, upper),
                                               x_scale="jac")
            x, value, evaluations = fit.x, 2 * fit.cost, fit.nfev
        else:
            fit = scipy.optimize.minimize(lambda x: at(x)[2], x0, jac=True, method="L-BFGS-B",
                                          bounds=self.bounds)
            x, value, evaluations = fit.x, float(fit.fun), fit.nfev
        res = at(x)[0]
        res.stats["optimization"] = {
            "values": dict(zip(self.names, map(float, x))), "objective": float(value),
            "start": float(start if not isinstance(self.objective, Fit) else start @ start),
            "evaluations": int(evaluations), "success": bool(fit.success),
            "message": str(fit.message)}
        return res

    def objective_at(self, res: Results, sens) -> tuple:
        """``(residuals, Jacobian)`` of a fit, ``(value, gradient)`` of an objective.

        Parameters
        ----------
        res : Results
            Of the analysis.
        sens : Sensitivities
            Of those results, in the parameters being optimised.
        """
        if isinstance(self.objective, Fit):
            return self.objective.residuals(res, sens)
        return self.objective.value(res, sens)


def starting_points(model, bounds: Mapping[str, tuple[float, float]], count: int, seed: int
                    ) -> list[dict]:
    """``count`` starting points: the model's own values clipped into the bounds, then a
    seeded Latin hypercube over them (each parameter's range cut into ``count - 1`` strata,
    one point in each, the strata paired at random).

    Parameters
    ----------
    model : Model
    bounds : mapping of str to (float, float)
        Parameter name -> its lower and upper bound.
    count : int
        How many points, the model's own included.
    seed : int
        Of the Latin hypercube.
    """
    names = list(bounds)
    own = {name: float(np.clip(parameter_value(model, name)[0], *bounds[name]))
           for name in names}
    rng = np.random.default_rng(seed)
    n = count - 1
    points = [own]
    if n:
        cube = (np.array([rng.permutation(n) for _ in names]).T + rng.random((n, len(names)))
                ) / n
        for row in cube:
            points.append({name: float(lo + u * (hi - lo)) for name, u, (lo, hi) in zip(
                names, row, (bounds[name] for name in names))})
    return points


def optimize(model, analysis: Analysis, bounds: Mapping[str, tuple[float, float]],
             objective: Objective | Fit, *, starts: int = 1, seed: int = 0,
             folder: str | os.PathLike, client: Any = None,
             backend: str = "auto", factory=None, progress: bool = True) -> SweepTable:
    """Minimise ``objective`` over the parameters in ``bounds`` from ``starts`` starts.

    Parameters
    ----------
    model : Model
    analysis : Analysis
        The analysis whose results the objective reads (``mbd3d.sweeps.Analysis("inverse dynamics",
        t)``; for a :class:`Fit` its times must be the measurement's).
    bounds : dict
        Parameter name -> ``(lower, upper)`` [its unit], lower < upper.
    objective : Objective or Fit
    starts, seed : int
        How many starts (the model's own values first) and the seed of the others.
    folder, client, backend, progress
        As :func:`mbd3d.sweeps.sweep` takes them: where each start's outcome is kept, the Dask
        cluster, "auto", "dask" or "serial".
    factory : callable, optional
        ``factory(**values) -> Model`` with the starts' values as keywords (default:
        :class:`mbd3d.ModelVariants` of ``model``).

    Returns
    -------
    SweepTable
        One row per start: the start's values (its parameters) and the metrics ``objective``
        (the least found; of a fit, the sum of the squared residuals), ``start objective``,
        ``evaluations``, ``success`` and each parameter's optimised value (``"<name>
        optimised"``); :func:`best` picks the best.
    """
    bounds = _checked_bounds(model, bounds)
    if not isinstance(objective, (Objective, Fit)):
        raise ModelError(f"optimize: objective must be an mb.Objective or mb.Fit, got "
                         f"{objective!r}")
    if isinstance(objective, Fit) and not np.array_equal(np.asarray(objective.t),
                                                          analysis.t):
        raise ModelError("optimize: a fit's analysis must run at the measured times")
    if not (isinstance(starts, int) and starts >= 1):
        raise ModelError(f"optimize: starts must be a whole number >= 1, got {starts!r}")
    if analysis.kind == "forward dynamics":
        check_forward_options(analysis.options, "optimize")
    _check_columns(model, analysis, objective)
    local = LocalOptimization(analysis, bounds, objective)
    metrics = {"objective": _stat("objective"), "start objective": _stat("start"),
               "evaluations": _stat("evaluations"), "success": _stat("success")}
    metrics.update({f"{name} optimised": _Value(name) for name in bounds})
    factory = factory or ModelVariants(model)
    return sweep(factory, starting_points(model, bounds, starts, seed), local, metrics, folder,
                 client=client, backend=backend, progress=progress)


def best(table: SweepTable) -> dict | None:
    """The row of an :func:`optimize` table with the least objective among the starts that
    succeeded (None if none did).

    Parameters
    ----------
    table : SweepTable
        Of :func:`optimize`.
    """
    rows = [row for row in table.rows if row.get("status") == "ok" and row.get("success")]
    return min(rows, key=lambda row: row["objective"], default=None)


def check_forward_options(options: Mapping[str, Any], what: str) -> None:
    """Forward dynamics' ``options`` are those its sensitivities take (an explicit method);
    messages start with ``what``.

    Parameters
    ----------
    options : mapping
        Keyword arguments for forward dynamics.
    what : str
        What the messages start with.
    """
    import inspect  # noqa: PLC0415
    import mbd3d as mb  # noqa: PLC0415

    accepted = inspect.signature(mb.forward_sensitivities).parameters
    refused = [f"option {name}" for name in options if name not in accepted]
    if options.get("method") == "generalized-alpha":
        refused.insert(0, "method 'generalized-alpha'")
    if refused:
        raise ModelError(f"{what}: forward dynamics' gradients come from "
                         f"mb.forward_sensitivities, which takes the explicit methods and "
                         f"not {', '.join(refused)}: give method='DOP853' (or RK45, RK23) "
                         "and its options")


def _check_columns(model, analysis: Analysis, objective: Objective | Fit) -> None:
    """The objective's columns are the results', checked on the analysis' first two times
    before any start runs (where a misspelt name would fail every start)."""
    res = Analysis(analysis.kind, analysis.t[:2], analysis.options)(model)
    for name in ([objective.name] if isinstance(objective, Objective) else objective.values):
        column(res, name)


def _checked_bounds(model, bounds) -> dict:
    checked = {}
    for name, pair in dict(bounds).items():
        parameter_value(model, name)  # a parameter, or "did you mean"
        try:
            lower, upper = (float(v) for v in pair)
        except (TypeError, ValueError):
            lower = upper = math.nan
        if not (math.isfinite(lower) and math.isfinite(upper) and lower < upper):
            raise ModelError(f"optimize: the bounds of '{name}' must be two finite numbers, "
                             f"lower < upper, got {pair!r}")
        checked[name] = (lower, upper)
    if not checked:
        raise ModelError("optimize: give at least one parameter to vary, with its bounds")
    return checked


class _stat:
    """A sweep metric: one entry of the optimised results' ``stats["optimization"]``."""

    def __init__(self, key: str):
        self.key = key

    def sweep_identity(self) -> str:
        return f"optimization stat {self.key}"

    def __call__(self, res: Results):
        return res.stats["optimization"][self.key]


class _Value(_stat):
    """A sweep metric: a parameter's optimised value."""

    def sweep_identity(self) -> str:
        return f"optimized value {self.key}"

    def __call__(self, res: Results) -> float:
        return res.stats["optimization"]["values"][self.key]


# -- the command line's terms (mbd3d optimize) ---------------------------------------------------
#: the largest measurement file read (a fit's data), and its most rows
MAX_DATA_BYTES, MAX_DATA_ROWS = 50_000_000, 1_000_000


def command_terms(args: Any, loaded: Any) -> tuple[dict, Objective | Fit, int, int]:
    """``(bounds, objective, starts, seed)`` of ``mbd3d optimize``: the command line's
    (``args.vary``, ``fit``, ``minimize``, ``starts``, ``seed``) over those of the model
    file ``loaded`` (its ``optimize:`` section, :mod:`mbd3d.io.optimization_spec`)."""
    section = loaded.optimization or OptimizationSpec({})
    bounds = parse_bounds(args.vary) if args.vary else section.vary
    fit = args.fit if args.fit or args.minimize else section.fit
    if not bounds or not (fit or args.minimize or section.minimize):
        raise ModelError(f"{loaded.path}: give the parameters to vary (--vary) and what to "
                         "minimise (--minimize or --fit), or an optimize: section")
    objective = (read_measurements(fit) if fit is not None
                 else parse_objective(args.minimize or section.minimize))
    return (bounds, objective, section.starts if args.starts is None else args.starts,
            section.seed if args.seed is None else args.seed)


def parse_bounds(items: Sequence[str]) -> dict:
    """``{"FIELD": (low, high)}`` from ``FIELD=LOW:HIGH`` texts (``--vary``)."""
    bounds = {}
    for item in items:
        name, sep, text = item.partition("=")
        low, colon, high = text.partition(":")
        try:
            bounds[name] = (float(low), float(high))
        except ValueError:
            sep = ""
        if not (sep and colon and name):
            raise ModelError(f"--vary {item!r}: give FIELD=LOW:HIGH, e.g. "
                             "bodies.rod.mass=0.5:5")
    return bounds


def parse_objective(text: str) -> Objective:
    """An :class:`Objective` from ``STATISTIC:COLUMN`` (``--minimize peak:motor.effort``)."""
    statistic, sep, name = text.partition(":")
    if not (sep and name):
        raise ModelError(f"--minimize {text!r}: give STATISTIC:COLUMN, e.g. "
                         f"peak:motor.effort (statistics: {', '.join(_STATISTICS)})")
    return Objective(name, statistic)


def read_measurements(path: str | os.PathLike) -> Fit:
    """A :class:`Fit` from a CSV file: a header of column names, the first ``t [s]`` (or
    ``t``), the others named as the results' columns; one row per measured time."""
    import csv  # noqa: PLC0415

    path = os.fspath(path)
    try:
        size = os.path.getsize(path)
        if size > MAX_DATA_BYTES:
            raise ModelError(f"{path}: {size / 1e6:.0f} MB; measurements are read up to "
                             f"{MAX_DATA_BYTES / 1e6:.0f} MB")
        with open(path, newline="", encoding="utf-8") as file:
            rows = list(_bounded(csv.reader(file), path))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ModelError(f"{path}: cannot be read as CSV measurements: {exc}") from None
    if len(rows) < 3 or rows[0][0].strip() not in ("t [s]", "t") or len(rows[0]) < 2:
        raise ModelError(f"{path}: give a header 't [s]', then the measured columns, and at "
                         "least two rows of numbers")
    values = np.full((len(rows) - 1, len(rows[0])), np.nan)
    for line, row in enumerate(rows[1:], start=2):
        try:
            values[line - 2] = [float(x) for x in row]
        except ValueError:
            raise ModelError(f"{path}, line {line}: {len(rows[0])} numbers expected, got "
                             f"{row!r}") from None
    if not np.all(np.isfinite(values)) or np.any(np.diff(values[:, 0]) <= 0):
        raise ModelError(f"{path}: the values must be finite and the times increasing")
    return Fit(tuple(values[:, 0]), {name.strip(): tuple(values[:, k + 1])
                                     for k, name in enumerate(rows[0][1:])})


def _bounded(reader, path: str):
    for count, row in enumerate(reader):
        if count > MAX_DATA_ROWS:
            raise ModelError(f"{path}: more than {MAX_DATA_ROWS} rows of measurements")
        yield row
