"""Recording analyses for the Rerun viewer: live while they run, or from finished results.

A :class:`Recorder` is an observer of an analysis (``observers=[Recorder(...)]``): it streams
the time points to a viewer and/or an ``.rrd`` file as the solver produces them, and closes the
file however the analysis ends, so a failing or interrupted run leaves a valid recording of
everything computed. :func:`record` writes finished results the same way.

What is recorded (entity paths):

- ``world/bodies/<body>``: the pose (translation, quaternion) on the timelines ``sim_time``
  (simulated time) and ``step`` (output time point); ``.../shape`` the body's mesh and
  ``.../joints`` its joint points, both fixed in the body frame;
- ``world/ground``: the ground's joint points and sliding rails;
- ``world/reactions/<joint>``, ``world/efforts/<driver>``: arrows of the reaction forces on the
  joints' moving bodies and of the driver efforts (torques along their axis, right-hand rule);
- ``world/springs/<spring>``: spring-dampers as lines; ``world/trails/<point>``: paths of
  requested body points;
- ``plots/...``: time series of positions, angles, velocities, accelerations, driver efforts,
  joint reactions, energies and constraint residuals;
- ``info``: the model, the analysis, its status and the arrow scales;
- ``world/impacts`` and ``impacts``: where and when rigid contacts struck, with the impulse
  and the energy lost (text), and ``impacts/rests`` when they came to rest and let go, on
  ``sim_time``.
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import uuid
from typing import Any, Mapping, Sequence

import numpy as np

from mbd3d.io import files
from mbd3d.errors import ModelError
from mbd3d.io.observers import Observer
from mbd3d.io.results import Results
from mbd3d.viewer.scene import Scene
from mbd3d.viewer.timeline import _rerun

__all__ = ["Recorder", "RecordingError", "record", "show", "rerun_executable",
           "check_destination", "require_display", "spawn_viewer", "VIEWER_PORT",
           "VIEWER_BIND"]

#: the gRPC port a Rerun viewer listens on by default
VIEWER_PORT = 9876
#: the address the viewers mbd3d starts listen on: this machine only (Rerun's own default,
#: 0.0.0.0, would let any machine on the network read and send recordings)
VIEWER_BIND = "127.0.0.1"
#: how long a spawned viewer may take to start listening [s]
_VIEWER_START_TIMEOUT = 30.0


class RecordingError(files.OutputError):
    """A recording cannot be written or sent (path, viewer address)."""


def _application_id(model_name: str) -> str:
    # blueprints apply per application id: one per model, so that a layout made for one
    # mechanism is not applied to another
    return "mbd3d " + (re.sub(r"[^A-Za-z0-9_\- ]", "_", model_name)[:160] or "model")


def check_output_path(path: str | os.PathLike, overwrite: bool) -> str:
    """The absolute path of a new ``.rrd`` file, or a :class:`RecordingError` saying why it
    cannot be written there (see :func:`mbd3d.io.files.check_output_path`)."""
    try:
        return files.check_output_path(path, overwrite, "the recording")
    except files.OutputError as exc:
        raise RecordingError(str(exc)) from None


class Recorder(Observer):
    """Records an analysis for the Rerun viewer, live as it runs.

    Pass it to an analysis, ``mb.forward_dynamics(model, t, observers=[Recorder("run.rrd")])``,
    or record finished results with :func:`record`. One recorder records one analysis.

    Parameters
    ----------
    save : str or path, optional
        Write an ``.rrd`` file there (open it with ``rerun FILE``).
    spawn : bool
        Stream to a Rerun viewer on this machine: the one already listening on
        ``viewer_port``, or a new viewer window started for this recording (needs a display;
        without one the Recorder refuses at once and says how to view a file instead).
    viewer_port : int
        The gRPC port of the spawned viewer (default 9876, Rerun's own).
    viewer_bind : str
        The address the spawned viewer listens on: ``"127.0.0.1"`` (this machine only) unless
        another is given, e.g. ``"0.0.0.0"`` to accept recordings from the network.
    connect : str, optional
        Stream to a running viewer or server at this gRPC address, e.g.
        ``"rerun+http://127.0.0.1:9876/proxy"`` (what ``rerun`` listens on by default).
    overwrite : bool
        Replace an existing ``save`` file (refused by default).
    plots : sequence of str, optional
        Bodies whose position, angle (planar) or angular velocity (spatial), velocity and
        acceleration are plotted; default all bodies up to 12, none above.
    points : mapping, optional
        Body points to plot and trace: ``{label: (body, point)}``, the point [m] in the body
        frame; each gets plots and a trail of its path in the 3D view.
    reactions : sequence of str, optional
        Joints whose reactions are plotted and drawn as arrows (dynamics); default all joints
        up to 24, none above.
    shapes : mapping, optional
        ``{body: mesh}`` to draw bodies with a trimesh mesh or mesh file (body frame [m])
        instead of their default shape.
    interval : float
        Smallest wall time [s] between two live updates.
    announce : bool
        Print where the file went and how to open it when the recording is closed.

    Raises
    ------
    RecordingError
        No destination; ``save`` in a missing or read-only folder, or an existing file without
        ``overwrite=True``.
    """

    def __init__(self, save: str | os.PathLike | None = None, *, spawn: bool = False,
                 viewer_port: int = VIEWER_PORT, viewer_bind: str = VIEWER_BIND,
                 connect: str | None = None, overwrite: bool = False,
                 plots: Sequence[str] | None = None,
                 points: Mapping[str, tuple[str, Sequence[float]]] | None = None,
                 reactions: Sequence[str] | None = None,
                 shapes: Mapping[str, Any] | None = None, interval: float = 0.5,
                 announce: bool = True):
        if save is None and not spawn and connect is None:
            raise RecordingError("a Recorder needs somewhere to send the recording: save= "
                                 "(an .rrd file), spawn=True (a viewer) or connect= (an address)")
        self.path = None if save is None else check_output_path(save, overwrite)
        if spawn and not _listening(viewer_port):
            require_display(self.path)  # now, not after the analysis has run
        self.spawn, self.connect, self.overwrite = bool(spawn), connect, overwrite
        self.viewer_port, self.viewer_bind = int(viewer_port), str(viewer_bind)
        #: the viewer process this Recorder started (None when it used a running one)
        self.viewer_process: subprocess.Popen | None = None
        self.plots = None if plots is None else list(plots)
        self.points = dict(points or {})
        self.reactions = None if reactions is None else list(reactions)
        self.shapes = dict(shapes or {})
        self.interval = float(interval)
        self.announce = announce
        self.stream = None
        self._scene = None
        self._sent = 0
        self._used = False

    # -- the Observer interface ------------------------------------------------------------------
    def start(self, model, times: np.ndarray, analysis: str) -> None:
        """Open the recording and log what does not change: shapes, joints, layout.

        Parameters
        ----------
        model : Model
        times : (k,) ndarray
        analysis : str
            See :meth:`mbd3d.Observer.start`.
        """
        if self._used:
            raise RecordingError("this Recorder has already recorded an analysis; make a new "
                                 "Recorder (and file) for each analysis")
        self._used = True
        scene = Scene(model, analysis, plots=self.plots, points=self.points,
                      reactions=self.reactions, shapes=self.shapes)
        self._open(model, scene)
        self._scene = scene
        scene.log_static(self.stream, times)
        self._sent = 0

    def update(self, results: Results, time: float, steps: int) -> None:
        """Send the time points computed since the last update.

        Parameters
        ----------
        results : Results
        time : float
        steps : int
            See :meth:`mbd3d.Observer.update`.
        """
        self._send(results)

    def finish(self, results: Results) -> None:
        """Send the rest, record how the analysis ended and close the file.

        Parameters
        ----------
        results : Results
            All of the run's results.
        """
        if self.stream is None:
            return
        try:
            self._send(results)
            self._scene.log_info(self.stream, results)
            self._scene.log_impacts(self.stream, results)
        finally:
            self.close()
        if self.announce and self.path is not None:
            print(f"recording of {len(results)} time points written to {self.path}\n"
                  f"  open it with: rerun {_quote(self.path)}")

    # -- plumbing --------------------------------------------------------------------------------
    def _open(self, model, scene) -> None:
        rr = _rerun()
        stream = rr.RecordingStream(_application_id(model.name), recording_id=uuid.uuid4())
        sinks = []
        if self.path is not None:
            # checked again now: the file may have appeared since the Recorder was made
            check_output_path(self.path, self.overwrite)
            sinks.append(rr.FileSink(self.path))
        if self.spawn:
            url, self.viewer_process = spawn_viewer(self.viewer_port, self.path,
                                                    self.viewer_bind)
            sinks.append(rr.GrpcSink(url))
        if self.connect is not None:
            sinks.append(rr.GrpcSink(self.connect))
        try:
            stream.set_sinks(*sinks, default_blueprint=scene.blueprint())
        except Exception as exc:
            raise RecordingError(f"cannot open the recording ({self._where()}): {exc}") from exc
        self.stream = stream

    def _where(self) -> str:
        places = [] if self.path is None else [f"file '{self.path}'"]
        if self.spawn:
            places.append(f"the viewer on port {self.viewer_port}")
        if self.connect is not None:
            places.append(f"viewer at {self.connect}")
        return ", ".join(places)

    def _send(self, results: Results) -> None:
        if self.stream is None or len(results) <= self._sent:
            return
        start = self._sent
        self._scene.log_block(self.stream, results.subset(start), start)
        self._sent = len(results)

    def close(self) -> None:
        """Flush and close the recording (the file gets its footer). Safe to call twice."""
        stream, self.stream = self.stream, None
        if stream is None:
            return
        try:
            stream.flush(timeout_sec=30.0)
        except Exception as exc:
            raise RecordingError(f"could not deliver the recording to {self._where()}: {exc}"
                                 ) from exc
        finally:
            stream.disconnect()

    def __enter__(self) -> "Recorder":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Recorder({self._where()})"


def record(results: Results, save: str | os.PathLike | None = None, *, show: bool = False,
           **options: Any) -> Recorder:
    """Record finished ``results`` (any analysis) to an ``.rrd`` file and/or a viewer.

    Parameters
    ----------
    results : Results
    save : str or path, optional
        The ``.rrd`` file to write.
    show : bool
        Then open the file in the Rerun viewer (see :func:`show`).
    **options
        ``spawn``, ``connect``, ``overwrite``, ``plots``, ``points``, ``reactions``, ``shapes``,
        ``announce``: see :class:`Recorder`.

    Returns
    -------
    Recorder
        Closed; ``.path`` is the file written.
    """
    if not isinstance(results, Results):
        raise ModelError(f"record() takes the Results of an analysis, got {type(results).__name__}")
    return write_recording(results, save, show=show, **options)


def write_recording(results: Results, save: str | os.PathLike | None, *, show: bool = False,
                    analysis: str | None = None, extra: Any = None, **options: Any) -> Recorder:
    """:func:`record` with the analysis whose layout the recording takes (default the
    results') and ``extra(stream)``, called to log more entities before the file closes."""
    recorder = Recorder(save, **options)
    recorder.start(results.model, results.t, analysis or results.analysis)
    if extra is not None:
        try:
            recorder.update(results, float(results.t[-1]), len(results))
            extra(recorder.stream)
        except BaseException:
            recorder.close()
            raise
    recorder.finish(results)
    if show:
        if recorder.path is None:
            raise RecordingError("show=True needs save= (the file to open)")
        _open_viewer(recorder.path)
    return recorder


def rerun_executable() -> str:
    """The path of the ``rerun`` viewer that comes with the installed rerun-sdk."""
    try:
        import rerun_cli  # noqa: PLC0415

        candidate = os.path.join(os.path.dirname(rerun_cli.__file__), "rerun")
        if os.path.isfile(candidate):
            return candidate
    except ImportError:
        pass
    found = shutil.which("rerun")
    if found is None:
        raise RecordingError("the rerun viewer is not installed; pip install rerun-sdk==0.41.0")
    return found


def require_display(path: str | None = None) -> None:
    """Raise a :class:`RecordingError` that says how to view a recording when this machine
    has no display to open a viewer window on (Linux without X11 or Wayland).

    Parameters
    ----------
    path : str, optional
        The recording, to name in the message.
    """
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        where = f"'{path}'" if path else "the recording (save it to a file with save=...)"
        raise RecordingError(f"no display to open a viewer on; copy {where} to a machine "
                             "with one and run: rerun FILE there")


def check_destination(path: str | os.PathLike, overwrite: bool = True, show: bool = False
                      ) -> str:
    """Check before an analysis runs that its recording can be written to ``path`` and, with
    ``show``, opened in a viewer here; returns the absolute path. Examples call this first so
    that a wrong path fails at once instead of after the computing.

    Parameters
    ----------
    path : str or path-like
        Where the ``.rrd`` file will be written.
    overwrite : bool
        Whether an existing file may be replaced.
    show : bool
        Whether the recording will also be opened in a viewer here.
    """
    path = check_output_path(path, overwrite)
    if show:
        require_display(path)
    return path


def _listening(port: int) -> bool:
    """Whether something accepts connections on ``port`` of this machine."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.settimeout(0.2)
        return sock.connect_ex(("127.0.0.1", port)) == 0


def _viewer_command(port: int, bind: str = VIEWER_BIND) -> list[str]:
    """The command line of a Rerun viewer window listening on ``port`` of ``bind``."""
    return [rerun_executable(), "--bind", bind, "--port", str(port)]


def spawn_viewer(port: int = VIEWER_PORT, path: str | None = None, bind: str = VIEWER_BIND
                 ) -> tuple[str, subprocess.Popen | None]:
    """The gRPC address of a Rerun viewer on ``port``: the one already listening there, or a
    new viewer window started now (its own process, which stays open after Python ends),
    listening on ``bind`` (this machine only, unless another address is given; Rerun's own
    default would be every interface).

    Returns ``(url, process)``, ``process`` None when a running viewer was used.

    Parameters
    ----------
    port : int
        The viewer's gRPC port on this machine.
    path : str, optional
        A recording it opens, and names in messages.
    bind : str
        The address its server listens on.

    Raises
    ------
    RecordingError
        Without a display, or when the viewer exits or does not listen within 30 s.
    """
    url = f"rerun+http://127.0.0.1:{port}/proxy"
    if _listening(port):
        return url, None
    require_display(path)
    # the viewer's messages go to a file, read only if it fails to start: a pipe nobody
    # reads would block a viewer that keeps printing
    log = tempfile.TemporaryFile()
    try:
        process = subprocess.Popen(_viewer_command(port, bind), stdin=subprocess.DEVNULL,
                                   stdout=log, stderr=log, start_new_session=True)
    except OSError as exc:
        raise RecordingError(f"could not start the Rerun viewer: {exc}") from exc
    deadline = time.monotonic() + _VIEWER_START_TIMEOUT
    while not _listening(port):
        if process.poll() is not None:
            log.seek(0)
            detail = log.read().decode(errors="replace").strip()[-400:]
            raise RecordingError(f"the Rerun viewer exited at once (exit status "
                                 f"{process.returncode}): {detail or 'no message'}")
        if time.monotonic() > deadline:
            process.terminate()
            raise RecordingError(f"the Rerun viewer did not listen on port {port} within "
                                 f"{_VIEWER_START_TIMEOUT:.0f} s")
        time.sleep(0.05)
    log.close()  # the viewer keeps its own handle
    return url, process


def show(path: str | os.PathLike, bind: str = VIEWER_BIND) -> subprocess.Popen:
    """Open an ``.rrd`` recording in the Rerun viewer (a separate process; needs a display),
    whose server listens on ``bind`` (this machine only, unless another address is given).

    Parameters
    ----------
    path : str or path-like
        The ``.rrd`` file.
    bind : str
        The address the viewer's server listens on.
    """
    path = os.path.abspath(os.fspath(path))
    if not os.path.isfile(path):
        raise RecordingError(f"no recording at '{path}'")
    require_display(path)
    return subprocess.Popen([rerun_executable(), "--bind", bind, path])


_open_viewer = show  # record() has a parameter called show


def _quote(path: str) -> str:
    return f'"{path}"' if " " in path else path
