"""The sensitivities of an analysis' results to the model's parameters, read like
:class:`mbd3d.Results`: by coordinate and parameter name, over time, as arrays or in pandas."""

from __future__ import annotations

import os
from typing import Any, Callable, Sequence

import numpy as np

from mbd3d.errors import ModelError, did_you_mean
from mbd3d.io.exports import write_columns
from mbd3d.io.results import Results
from mbd3d.model.tangents import reach, state_scale

__all__ = ["Sensitivities", "ModeSensitivities"]


#: the derivatives of the coordinates a sensitivity may be asked of, and their column suffix
_OF = {"q": "", "qd": "_dot", "qdd": "_ddot"}


class Sensitivities:
    """Derivatives of an analysis' results with respect to parameters (made by
    :func:`mbd3d.sensitivities`).

    Attributes
    ----------
    results : Results
        The results differentiated.
    model : Model
    analysis : str
        Their analysis (e.g. "kinematic analysis").
    t : ndarray (k,)
        Times [s].
    parameters : tuple of str
        The parameters' names (:func:`mbd3d.parameters`), in the order of the last axis.
    dq, dqd, dqdd : ndarray (k, n, p)
        ``dq/dp``, ``dqd/dp`` and ``dqdd/dp`` at each time: coordinate units (m, rad; per s,
        per s^2) per unit of each parameter. A spatial body's orientation coordinates are its
        Rodrigues parameters relative to the chart of the results at that time
        (``Results.charts``); its centre's are global.
    dlam : ndarray (k, m, p) or None
        ``dlam/dp`` of the multipliers (inverse dynamics, static equilibrium).
    tangents : tuple of ModelTangent
        Each parameter's :class:`mbd3d.model.tangents.ModelTangent` (its model variants).
    integrals : dict
        Forward dynamics' integrals (:func:`mbd3d.forward_sensitivities`), by name:
        ``(G (k,), dG/dp (k, p))``; read them with :meth:`integral`.
    """

    def __init__(self, results, parameters: Sequence[str], tangents: Sequence,
                 dq: np.ndarray, dqd: np.ndarray, dqdd: np.ndarray,
                 dlam: np.ndarray | None = None,
                 integrals: dict[str, tuple[np.ndarray, np.ndarray]] | None = None) -> None:
        self.results, self.model, self.analysis = results, results.model, results.analysis
        self.t = results.t
        self.parameters = tuple(parameters)
        self.tangents = tuple(tangents)
        self.dq, self.dqd, self.dqdd = dq, dqd, dqdd
        self.dlam = dlam
        self.integrals = dict(integrals or {})

    def __repr__(self) -> str:
        return (f"<Sensitivities of the {self.analysis} of '{self.model.name}': "
                f"{len(self.t)} times, {len(self.parameters)} parameters>")

    def sensitivity(self, coordinate: str, parameter: str, of: str = "q") -> np.ndarray:
        """``d(coordinate)/d(parameter)`` over time (k,), e.g.
        ``sens.sensitivity("slider.x", "joints.B.point_i[0]")`` [m per unit of the
        parameter]; ``of="qd"`` or ``"qdd"`` for the coordinate's rate or acceleration.

        Parameters
        ----------
        coordinate : str
            ``"body.coordinate"``, e.g. ``"slider.x"``.
        parameter : str
            One of the parameters asked for.
        of : {"q", "qd", "qdd"}
            The coordinate, its rate or its acceleration.
        """
        if of not in _OF:
            raise ModelError(f"sensitivity(of={of!r}): give 'q', 'qd' or 'qdd'")
        array = {"q": self.dq, "qd": self.dqd, "qdd": self.dqdd}[of]
        return array[:, self._coordinate(coordinate), self._parameter(parameter)]

    def integral(self, name: str, parameter: str | None = None) -> np.ndarray:
        """An integral's value ``G(t) = int_{t0}^{t} g dt`` over time (k,), or its derivative
        with respect to ``parameter`` (forward sensitivities' ``integrals``).

        Parameters
        ----------
        name : str
            One of the integrals given to :func:`mbd3d.forward_sensitivities`.
        parameter : str, optional
            One of the parameters asked for (None: the integral itself).
        """
        if name not in self.integrals:
            raise ModelError(f"sensitivities of '{self.model.name}': no integral '{name}'"
                             f"{did_you_mean(name, list(self.integrals))}; the integrals are "
                             f"{list(self.integrals)} (given to mb.forward_sensitivities)")
        G, dG = self.integrals[name]
        return G if parameter is None else dG[:, self._parameter(parameter)]

    def effort(self, driver: str, parameter: str) -> np.ndarray:
        """``d(effort)/d(parameter)`` of a driver over time (k,) [N m or N per unit of the
        parameter] (inverse dynamics).

        Parameters
        ----------
        driver : str
            A driver of the model.
        parameter : str
            One of the parameters asked for.
        """
        if self.dlam is None:
            raise ModelError(f"sensitivities of the {self.analysis} of '{self.model.name}': "
                             "efforts have sensitivities after inverse dynamics or a "
                             "static equilibrium")
        drivers = [e.name for e in self.model.joints if e.is_driver]
        if driver not in drivers:
            raise ModelError(f"no driver '{driver}' in '{self.model.name}'"
                             f"{did_you_mean(driver, drivers)}; its drivers are {drivers}")
        rows = self.model.rows_of(driver)
        return -self.dlam[:, rows[0], self._parameter(parameter)]

    def derivative(self, quantity: Callable[[Any], Any], parameter: str | None = None
                   ) -> np.ndarray:
        """The derivative of ``quantity(results)`` (an array read from results of this
        model, e.g. ``lambda r: r.joint("O").reaction(on="crank").force``) with respect to
        ``parameter``, or to each parameter along a last axis: a fourth-order central
        difference along the parameter, the results' state moving by its sensitivities and
        the model through its variants (1e-11 relative or better for smooth quantities).

        Parameters
        ----------
        quantity : callable
            ``quantity(results) -> array``.
        parameter : str, optional
            One of the parameters asked for (None: each of them, along a last axis).
        """
        columns = [j for j, name in enumerate(self.parameters)
                   if parameter is None or name == parameter]
        if parameter is not None and not columns:
            self._parameter(parameter)
        out = [self.tangents[j].along(lambda variant, h: np.asarray(
            quantity(self._moved(variant, j, h)), dtype=float), self._reach(j))
            for j in columns]
        return out[0] if parameter is not None else np.stack(out, axis=-1)

    def _reach(self, j: int) -> float:
        """How far the results' state moves per unit of parameter ``j``, relative to its
        scale, at the time it moves furthest (:func:`mbd3d.model.tangents.reach`)."""
        res = self.results
        return max((reach(state_scale(self.model, res.qd[k], res.qdd[k]), self.dq[k, :, j],
                          self.dqd[k, :, j], self.dqdd[k, :, j]) for k in range(len(self.t))),
                   default=0.0)

    def _moved(self, variant, j: int, h: float):
        """The results with their state moved by ``h`` times parameter ``j``'s
        sensitivities, read through ``variant``."""
        res = self.results
        lam = None if res.lam is None else res.lam + h * self.dlam[:, :, j]
        return Results(variant, res.analysis, res.t, res.q + h * self.dq[:, :, j],
                       res.qd + h * self.dqd[:, :, j], res.qdd + h * self.dqdd[:, :, j], lam,
                       charts=res.charts, model_t=res.model_t)

    def _coordinate(self, name: str) -> int:
        labels = self.model.coordinate_labels
        if name not in labels:
            raise ModelError(f"sensitivities of '{self.model.name}': no coordinate '{name}'"
                             f"{did_you_mean(name, labels)}; the coordinates are "
                             "'body.c' (e.g. 'crank.theta')")
        return labels.index(name)

    def _parameter(self, name: str) -> int:
        if name not in self.parameters:
            raise ModelError(f"sensitivities of '{self.model.name}': no parameter '{name}' "
                             f"among those asked for{did_you_mean(name, self.parameters)}")
        return self.parameters.index(name)

    def columns(self) -> dict[str, np.ndarray]:
        """The sensitivities as named columns over time: ``t [s]``, then per parameter
        ``d(coordinate)/d(parameter)``, ``d(coordinate_dot)/d(parameter)`` and
        ``d(coordinate_ddot)/d(parameter)`` for every coordinate (after inverse dynamics or
        an equilibrium also ``d(driver.effort)/d(parameter)`` for every driver; forward
        dynamics' integrals ``d(name)/d(parameter)`` and their values ``name``)."""
        columns = {"t [s]": self.t}
        drivers = [e.name for e in self.model.joints if e.is_driver]
        for j, p in enumerate(self.parameters):
            for of, suffix in _OF.items():
                array = {"q": self.dq, "qd": self.dqd, "qdd": self.dqdd}[of]
                for i, c in enumerate(self.model.coordinate_labels):
                    columns[f"d({c}{suffix})/d({p})"] = array[:, i, j]
            if self.dlam is not None:
                for driver in drivers:
                    columns[f"d({driver}.effort)/d({p})"] = self.effort(driver, p)
            for name in self.integrals:
                columns[f"d({name})/d({p})"] = self.integral(name, p)
        for name in self.integrals:
            columns[name] = self.integral(name)
        return columns

    def to_csv(self, path: str | os.PathLike, overwrite: bool = True) -> str:
        """Write :meth:`columns` to a CSV file (atomically; an existing file is replaced only
        with ``overwrite``); returns its path.

        Parameters
        ----------
        path : str or path-like
            The CSV file.
        overwrite : bool
            Replace ``path`` where it exists.
        """
        return write_columns(self.columns(), path, overwrite)

    def to_pandas(self):
        """:meth:`columns` as a DataFrame indexed by time."""
        import pandas as pd  # noqa: PLC0415

        columns = self.columns()
        t = columns.pop("t [s]")
        return pd.DataFrame(columns, index=pd.Index(t, name="t"))


class ModeSensitivities:
    """Derivatives of vibration modes' frequencies and damping ratios with respect to
    parameters (made by :func:`mbd3d.sensitivities` of :class:`mbd3d.Modes` or
    :class:`mbd3d.ModesAlong`).

    Attributes
    ----------
    parameters : tuple of str
        The parameters' names, in the order of the last axis.
    frequencies, damping_ratios : ndarray (r, p), or (k, r, p) along a motion
        ``df/dp`` [Hz per unit of the parameter] and ``dzeta/dp`` of each mode, in the order
        of the modes' own (lowest frequency first; NaN where a position has fewer modes).
        Where two frequencies cross, the order switches and the derivatives there are not
        those of either mode.
    equilibrium : Sensitivities
        Those of the equilibrium the modes are about.
    """

    def __init__(self, parameters: Sequence[str], frequencies: np.ndarray,
                 damping_ratios: np.ndarray, equilibrium: Sensitivities) -> None:
        self.parameters = tuple(parameters)
        self.frequencies, self.damping_ratios = frequencies, damping_ratios
        self.equilibrium = equilibrium

    def __repr__(self) -> str:
        return (f"<ModeSensitivities of {self.frequencies.shape[-2]} modes, "
                f"{len(self.parameters)} parameters>")

    def frequency(self, mode: int, parameter: str) -> np.ndarray:
        """``d(frequency of mode)/d(parameter)`` [Hz per unit of the parameter]: a number
        about one equilibrium, an array (k,) along a motion.

        Parameters
        ----------
        mode : int
            The mode's index, lowest frequency first.
        parameter : str
            One of the parameters asked for.
        """
        return self.frequencies[..., mode, self.equilibrium._parameter(parameter)]
