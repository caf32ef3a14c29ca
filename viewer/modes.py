"""Recording vibration modes along a motion: the mechanism through its positions, the natural
frequencies as time series, and the frequencies drawn against a position coordinate.

Entities, beside those of every recording (:mod:`mbd3d.viewer.recorder`):

- ``plots/modes/frequency``: one series per mode [Hz], on the ``sim_time`` timeline of the
  positions (the drivers' time);
- ``modes/curves``, ``modes/axes``: the frequency-against-position plot, in the
  "Frequencies against position" view (a 2D view, its axes scaled to a square, with labelled
  ticks in the units of the position and Hz).

Each mode's shape is animated by recording :meth:`mbd3d.Modes.animation` with
:func:`mbd3d.viewer.record`.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from mbd3d.analyses.modes import ModesAlong
from mbd3d.errors import ModelError
from mbd3d.viewer.recorder import Recorder, write_recording
from mbd3d.viewer.timeline import _rerun, sim_time_column

__all__ = ["record_modes"]

#: width and height of the frequency plot in the 2D view's units
_PLOT_SIZE = 100.0
_MODE_COLORS = np.array([[31, 119, 180], [214, 39, 40], [44, 160, 44], [148, 103, 189],
                         [255, 127, 14], [23, 190, 207]], dtype=np.uint8)


def record_modes(modes: ModesAlong, save: str | os.PathLike | None = None, *,
                 against: str | None = None, show: bool = False, **options: Any) -> Recorder:
    """Record the modes along a motion (from :func:`mbd3d.vibration_modes_along`).

    Parameters
    ----------
    modes : ModesAlong
    save : str or path, optional
        The ``.rrd`` file to write.
    against : str, optional
        The coordinate on the frequency plot's horizontal axis, ``"body.coordinate"`` (an
        angle in degrees, a length in metres); default the time [s].
    show : bool
        Then open the file in the Rerun viewer.
    **options
        As for :class:`mbd3d.viewer.Recorder` (``overwrite``, ``spawn``, ``plots``, ...).

    Returns
    -------
    Recorder
        Closed; ``.path`` is the file written.
    """
    if not isinstance(modes, ModesAlong):
        raise ModelError("record_modes() takes the result of mb.vibration_modes_along; to "
                         "animate one mode, record(modes.animation(k), ...)")
    results = modes.equilibrium
    model = results.model
    if against is None:
        x, x_label = modes.t, "t [s]"
    else:
        index = model.coordinate_index(against)
        angle = not model.position_coordinates[index]
        x = np.degrees(results.q[:, index]) if angle else results.q[:, index]
        x_label = f"{against} [{'deg' if angle else 'm'}]"
    return write_recording(results, save, show=show, analysis="vibration modes",
                           extra=lambda stream: _log_frequencies(stream, modes, x, x_label),
                           **options)


def _log_frequencies(stream, modes: ModesAlong, x: np.ndarray, x_label: str) -> None:
    rr = _rerun()
    frequencies = modes.frequencies
    count = frequencies.shape[1]
    names = [f"mode {j + 1}" for j in range(count)]
    colors = _MODE_COLORS[np.arange(count) % len(_MODE_COLORS)]
    stream.log("plots/modes/frequency", rr.SeriesLines(colors=colors, names=names, widths=2.0),
               static=True)
    stream.send_columns("plots/modes/frequency", indexes=[sim_time_column(modes.t)],
                        columns=rr.Scalars.columns(scalars=frequencies))

    # the plot against position: both axes scaled to a square, y up
    top = float(np.nanmax(frequencies)) if np.any(np.isfinite(frequencies)) else 1.0
    top = top if top > 0 else 1.0
    left, right = float(np.min(x)), float(np.max(x))
    span = right - left if right > left else 1.0

    def point(u, f):
        return np.column_stack([(np.asarray(u) - left) / span * _PLOT_SIZE,
                                -np.asarray(f) / top * _PLOT_SIZE])

    curves = [point(x, frequencies[:, j]) for j in range(count)]
    curves = [c[np.all(np.isfinite(c), axis=1)] for c in curves]
    stream.log("modes/curves", rr.LineStrips2D(curves, colors=colors, labels=names), static=True)
    ticks_x = np.linspace(left, right, 5)
    ticks_f = np.linspace(0.0, top, 5)
    tick_points = np.vstack([point(ticks_x, np.zeros(5)), point(np.full(5, left), ticks_f)])
    tick_labels = ([f"{u:.4g}" for u in ticks_x] + [f"{f:.4g} Hz" for f in ticks_f])
    stream.log("modes/axes", rr.LineStrips2D(
        [point([left, right], [0.0, 0.0]), point([left, left], [0.0, top])],
        colors=[128, 128, 128], labels=[x_label, "frequency [Hz]"]), static=True)
    stream.log("modes/axes/ticks", rr.Points2D(tick_points, labels=tick_labels,
                                               colors=[128, 128, 128], radii=0.6),
               static=True)
