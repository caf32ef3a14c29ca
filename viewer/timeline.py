"""The recordings' timelines, and Rerun imported on first use."""

from __future__ import annotations

import numpy as np

__all__ = ["SIM_TIME", "STEP", "sim_time_column"]

#: the timelines: simulated time (duration, ns) and the index of the output time point
SIM_TIME, STEP = "sim_time", "step"


def _rerun():
    # imported on first use: rerun takes over a second to import, and analyses without a
    # viewer should not pay for it
    import rerun as rr  # noqa: PLC0415

    return rr


def sim_time_column(t: np.ndarray):
    """The simulated times ``t`` [s] as a column of the ``sim_time`` timeline (whole
    nanoseconds)."""
    nanoseconds = np.round(np.asarray(t) * 1e9).astype(np.int64).astype("timedelta64[ns]")
    return _rerun().TimeColumn(SIM_TIME, duration=nanoseconds)
