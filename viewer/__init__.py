"""Rerun as the GUI of mbd3d: live viewing and ``.rrd`` recordings of analyses.

Usage::

    from mbd3d.viewer import Recorder, record, show
    res = mb.forward_dynamics(model, t, observers=[Recorder("run.rrd")])   # live, to a file
    record(res, "again.rrd")                                               # finished results
    show("run.rrd")                                    # opens the viewer (needs a display)
    record_modes(mb.vibration_modes_along(model, t), "modes.rrd")       # frequencies along it

Open a recording with ``rerun run.rrd``: the mechanism moves on the left (bodies, joints,
reaction and effort arrows, point trails); the plots of the kinematic and force analyses, the
energies and the constraint residuals are on the right. A script that records its results
takes ``--rrd FILE`` and ``--show`` through :func:`run_script`, and checks where its
recording goes before computing with :func:`check_recording_first`, as the examples do.

What belongs here: everything that talks to Rerun (recording, viewing, reading recordings
back); nothing in the analyses depends on it, and it only reads :class:`mbd3d.Results` and
the model.
"""

from mbd3d.viewer.modes import record_modes
from mbd3d.viewer.readback import entity_paths, read_component
from mbd3d.viewer.recorder import (VIEWER_BIND, VIEWER_PORT, Recorder, RecordingError,
                                   check_destination, record,
                                   require_display, rerun_executable, show, spawn_viewer)
from mbd3d.viewer.timeline import SIM_TIME, STEP
from mbd3d.viewer.script import check_recording_first, run_script

__all__ = ["Recorder", "RecordingError", "record", "record_modes", "show", "rerun_executable", "entity_paths",
           "read_component", "SIM_TIME", "STEP", "check_destination", "require_display",
           "spawn_viewer", "VIEWER_PORT", "VIEWER_BIND", "run_script",
           "check_recording_first"]
