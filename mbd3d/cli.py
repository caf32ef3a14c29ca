"""The ``mbd3d`` command: check, run, view, sweep and optimize model files.

::

    mbd3d check MODEL.yaml                     # mobility, assembly, the analyses it asks for
    mbd3d run MODEL.yaml [--analysis forward] [--t 0:2:0.01] [--method DOP853]
                         [--rrd out.rrd] [--csv FOLDER] [--show] [--set bodies.crank.mass=2]
    mbd3d view FILE.rrd                        # the Rerun viewer of the right version
    mbd3d sweep MODEL.yaml --grid joints.motor.motion.rate=5,10,20 [--folder sweep]
                           [--scheduler tcp://host:8786]
    mbd3d optimize MODEL.yaml --vary bodies.rod.mass=0.5:5 (--minimize peak:motor.effort |
                   --fit DATA.csv) [--starts 4] [--out BEST.yaml] [--scheduler ...]

Exit status: 0 done, 1 the analysis failed or the model has a problem, 2 a bad command line or
model file, 130 interrupted (Ctrl-C; a sweep keeps the runs done). Messages go to stderr;
results and reports to stdout.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import pathlib
import sys
from typing import Sequence

import numpy as np

__all__ = ["main"]

_KINDS = ("kinematic", "inverse", "forward", "equilibrium", "modes", "linearize")
#: what --help says of the exit status (the module doc says the same)
EXIT_STATUS = ("exit status: 0 done, 1 the analysis failed or the model has a problem, 2 a bad "
               "command line or model file, 130 interrupted (a sweep keeps the runs done: run "
               "it again to finish)")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    from mbd3d.errors import MBDError  # noqa: PLC0415

    try:
        return args.command(args)
    except MBDError as exc:
        print(f"mbd3d {args.name}: error: {exc}", file=sys.stderr)
        return 2 if _is_input_error(exc) else 1
    except KeyboardInterrupt:
        print(f"mbd3d {args.name}: interrupted", file=sys.stderr)
        return 130


def _is_input_error(exc) -> bool:
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io.files import OutputError  # noqa: PLC0415
    return isinstance(exc, (ModelError, OutputError))


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mbd3d", description="Kinematic and dynamic analysis of mechanisms described in "
                                  "model files (YAML; see mbd3d.io.model_file).",
        epilog=EXIT_STATUS)
    commands = parser.add_subparsers(required=True, metavar="COMMAND")

    check = commands.add_parser("check", help="report the model's mobility and problems "
                                              "without analysing it")
    check.add_argument("model", help="the model file (.yaml)")
    check.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                       help="change a value first, e.g. bodies.crank.mass=2 (repeatable)")
    check.set_defaults(command=_check, name="check")

    run = commands.add_parser("run", help="run an analysis and write its results")
    run.add_argument("model", help="the model file (.yaml)")
    run.add_argument("--analysis", choices=_KINDS,
                     help="default: the file's first analysis, else inverse for a fully "
                          "driven mechanism and forward otherwise")
    run.add_argument("--t", metavar="START:STOP:STEP",
                     help="output times [s] (default: the file's analysis)")
    run.add_argument("--method", help="forward dynamics: RK45, DOP853, RK23 or "
                                      "generalized-alpha")
    run.add_argument("--step", type=float, help="generalized-alpha's step [s]")
    run.add_argument("--rtol", type=float, help="relative tolerance of RK45, DOP853, RK23")
    run.add_argument("--rrd", metavar="FILE", help="write the Rerun recording there")
    run.add_argument("--csv", metavar="FOLDER", help="write the results as CSV there")
    run.add_argument("--show", action="store_true", help="open the recording in the viewer")
    run.add_argument("--overwrite", action="store_true",
                     help="replace existing output files (refused by default)")
    run.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                     help="change a value first, e.g. bodies.crank.mass=2 (repeatable)")
    run.add_argument("--rows", type=int, default=11, help="rows of the summary table")
    run.add_argument("--sensitivity", action="append", default=[], metavar="PARAMETER",
                     help="also the results' derivatives with respect to a parameter, e.g. "
                          "bodies.rod.mass (repeatable; kinematic, inverse, equilibrium and "
                          "forward with an explicit method)")
    run.set_defaults(command=_run, name="run")

    view = commands.add_parser("view", help="open a recording in the Rerun viewer")
    view.add_argument("recording", help="the .rrd file")
    view.add_argument("--bind", default="127.0.0.1", metavar="ADDRESS",
                      help="the address the viewer listens on (default 127.0.0.1: this "
                           "machine only)")
    view.set_defaults(command=_view, name="view")

    sweep = commands.add_parser("sweep", help="run the model's analysis over a grid of "
                                              "values of its fields, on Dask")
    sweep.add_argument("model", help="the model file (.yaml)")
    sweep.add_argument("--grid", action="append", required=True, metavar="FIELD=V1,V2,...",
                       help="a field and its values, e.g. joints.motor.motion.rate=5,10,20 "
                            "(repeatable: the grid of all combinations)")
    sweep.add_argument("--analysis", choices=_KINDS[:3], help="default: as for run")
    sweep.add_argument("--t", metavar="START:STOP:STEP", help="output times [s]")
    sweep.add_argument("--folder", default=None,
                       help="where runs and table.csv are kept (default: MODEL_sweep in "
                            "the working directory); "
                            "a sweep run again there resumes")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="a Dask scheduler, e.g. tcp://host:8786 (default: worker "
                            "processes on this machine)")
    sweep.add_argument("--serial", action="store_true", help="run in this process")
    sweep.set_defaults(command=_sweep, name="sweep")

    _optimize_parser(commands)
    return parser


def _optimize_parser(commands) -> None:
    """``mbd3d optimize``'s arguments."""
    optimize = commands.add_parser("optimize", help="move parameters within bounds to "
                                   "minimise an objective, from several starts, on Dask")
    optimize.add_argument("model", help="the model file (.yaml)")
    optimize.add_argument("--vary", action="append", metavar="FIELD=LOW:HIGH",
                          help="a parameter and its bounds, e.g. bodies.rod.mass=0.5:5 "
                               "(repeatable; these, or the file's optimize: section)")
    goal = optimize.add_mutually_exclusive_group()
    goal.add_argument("--minimize", metavar="STATISTIC:COLUMN",
                      help="rms, peak, mean or final of a results column, e.g. "
                           "peak:motor.effort")
    goal.add_argument("--fit", metavar="DATA.csv",
                      help="least squares against measured columns: a header 't [s]' and "
                           "results' column names, a row per time (the analysis' times)")
    optimize.add_argument("--analysis", choices=_KINDS[:3], help="default: as for run")
    optimize.add_argument("--t", metavar="START:STOP:STEP", help="output times [s]")
    optimize.add_argument("--starts", type=int,
                          help="starts: the file's values, then spread over the bounds "
                               "(default 4)")
    optimize.add_argument("--seed", type=int, help="of the spread starts (default 0)")
    optimize.add_argument("--out", metavar="FILE.yaml", help="write the best model there")
    optimize.add_argument("--overwrite", action="store_true", help="replace --out")
    optimize.add_argument("--folder", help="where the starts are kept (default: "
                                           "MODEL_optimize); run again there, it resumes")
    optimize.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler, as for "
                                                                 "sweep")
    optimize.add_argument("--serial", action="store_true", help="run in this process")
    optimize.set_defaults(command=_optimize, name="optimize")


# -- helpers -----------------------------------------------------------------------------------
def _changes(settings: Sequence[str]) -> dict:
    from mbd3d.io.yaml12 import load_value  # noqa: PLC0415

    from mbd3d.errors import ModelError  # noqa: PLC0415
    changes = {}
    for setting in settings:
        key, sep, text = setting.partition("=")
        if not sep or not key:
            raise ModelError(f"--set {setting!r}: give FIELD=VALUE, e.g. bodies.crank.mass=2")
        changes[key] = load_value(text)  # a number, a list [1, 2], a word
    return changes


def _times(text: str):
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io.model_file import times_from_step  # noqa: PLC0415
    try:
        start, stop, step = (float(part) for part in text.split(":"))
    except ValueError:
        raise ModelError(f"--t {text!r}: give START:STOP:STEP in seconds, e.g. 0:2:0.01"
                         ) from None
    return times_from_step(start, stop, step)


def _chosen_analysis(args, loaded, t=None):
    """The analysis to run: the command line's choices over the file's (``t``: its times,
    given)."""
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io.model_file import AnalysisSpec  # noqa: PLC0415
    import mbd3d as mb  # noqa: PLC0415

    spec = loaded.analyses[0] if loaded.analyses else None
    kind = args.analysis or (spec.kind if spec else None)
    if kind is None:
        kind = "inverse" if mb.mobility(loaded.model).dof == 0 else "forward"
    options = dict(spec.options) if spec is not None and spec.kind == kind else {}
    if t is not None:
        pass
    elif args.t is not None:
        t = _times(args.t)
    elif spec is not None:
        t = spec.t
    else:
        raise ModelError(f"{loaded.path} asks for no analysis: give the times with --t "
                         "START:STOP:STEP")
    for option in ("method", "step", "rtol"):
        value = getattr(args, option, None)
        if value is not None:
            if kind != "forward":
                raise ModelError(f"--{option} is for forward dynamics, not {kind}")
            options[option] = value
    outputs = dict(spec.outputs) if spec is not None else {}
    return AnalysisSpec(kind, t, options, outputs)


def _destinations(args, loaded, spec) -> tuple[str | None, str | None]:
    """``(recording, CSV file)`` of a run: the command line's, else the file's analysis's
    (kept inside the model file's folder when it is read), None where nothing is written."""
    rrd = getattr(args, "rrd", None) or spec.outputs.get("rrd")
    folder = getattr(args, "csv", None) or spec.outputs.get("csv")
    csv_path = None
    if folder is not None:
        csv_path = os.path.join(folder, f"{pathlib.Path(loaded.path).stem}_{spec.kind}.csv")
    return rrd, csv_path


# -- the commands ------------------------------------------------------------------------------
def _check(args) -> int:
    from mbd3d.io.model_file import read  # noqa: PLC0415
    import mbd3d as mb  # noqa: PLC0415

    loaded = read(args.model, _changes(args.set))
    model = loaded.model
    report = mb.mobility(model)
    print(f"{args.model}: {model!r}\n")
    print(report)
    problems = 0
    try:
        mb.solve_position(model, model.q0, 0.0)
        print("\nassembles at t = 0 from the drawing")
    except mb.MBDError as exc:
        problems += 1
        print(f"\nproblem: does not assemble at t = 0: {exc}")
    for spec in loaded.analyses:
        span = f"{spec.t[0]:g} to {spec.t[-1]:g} s, {len(spec.t)} points"
        needs_drivers = spec.kind in ("kinematic", "inverse") and report.dof > 0
        note = (f"  problem: needs {report.dof} more driver(s)" if needs_drivers else "")
        problems += needs_drivers
        options = ", ".join(f"{k}={v}" for k, v in spec.options.items())
        print(f"analysis: {spec.kind} over {span}{'; ' + options if options else ''}{note}")
        for what, path in zip(("recording", "CSV"), _destinations(args, loaded, spec)):
            if path is not None:
                exists = " (exists: mbd3d run replaces it only with --overwrite)"
                print(f"  writes the {what} to {os.path.abspath(path)}"
                      f"{exists if os.path.exists(path) else ''}")
    return 1 if problems else 0


def _run(args) -> int:
    from mbd3d.io.model_file import read  # noqa: PLC0415
    from mbd3d.io.results import format_table  # noqa: PLC0415
    import mbd3d as mb  # noqa: PLC0415

    loaded = read(args.model, _changes(args.set))
    spec = _chosen_analysis(args, loaded)
    # the command line's destinations over the file's, checked before the computing; an
    # existing file is replaced only with --overwrite; both are written as the time points
    # are computed, so that a run stopped by any means (even killed) leaves what it did
    rrd, csv_path = _destinations(args, loaded, spec)
    model = loaded.model
    sensitivity_csv = _check_sensitivities(args, model, spec, csv_path)
    if spec.kind == "modes":
        return _run_modes(args, model, spec, rrd, csv_path)
    if spec.kind == "linearize":
        return _run_linearize(args, model, spec, rrd, csv_path)
    observers = []
    if rrd is not None:
        from mbd3d.viewer import Recorder, check_destination  # noqa: PLC0415
        check_destination(rrd, overwrite=args.overwrite, show=args.show)
        observers.append(Recorder(rrd, overwrite=args.overwrite))
    if csv_path is not None:
        from mbd3d.io.exports import CsvWriter  # noqa: PLC0415
        observers.append(CsvWriter(csv_path, overwrite=args.overwrite))
    failure = forward = None
    try:
        if args.sensitivity and spec.kind == "forward":  # integrated with the motion
            forward = mb.forward_sensitivities(model, spec.t, args.sensitivity,
                                               observers=observers, **spec.options)
            res = forward.results
        else:
            res = spec.run(model, observers=observers)
    except mb.MBDError as exc:  # what was computed before the failure is still written
        if getattr(exc, "results", None) is None:
            raise
        res, failure = exc.results, exc
    stats = ", ".join(f"{key} {value:.3g}" if isinstance(value, float) else f"{key} {value}"
                      for key, value in res.stats.items()
                      if isinstance(value, (int, float)) and not isinstance(value, bool))
    print(f"{model.name}: {res.analysis}, {len(res)} time points, {res.status}"
          f"{' (' + res.message + ')' if res.message else ''}\n{stats}\n")
    if len(res):
        for title, columns in _tables(res):
            print(f"{title}:\n{format_table(columns, rows=args.rows)}\n")
    if csv_path is not None:
        print(f"\nCSV written to {os.path.abspath(csv_path)}")
    if args.sensitivity and failure is None and res.status == "complete":
        _run_sensitivities(args, forward or mb.sensitivities(res, args.sensitivity),
                           sensitivity_csv)
    if rrd is not None and args.show and failure is None:
        from mbd3d.viewer import show  # noqa: PLC0415
        show(rrd)
    if failure is not None:
        print(f"mbd3d run: error: {failure}", file=sys.stderr)
    return 0 if res.status == "complete" else 1


def _check_sensitivities(args, model, spec, csv_path) -> str | None:
    """Before computing: the ``--sensitivity`` names are parameters and the analysis has
    sensitivities; the CSV file they go to (beside the results'), checked."""
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io.files import check_output_path  # noqa: PLC0415
    from mbd3d.io.parameters import parameter_value  # noqa: PLC0415

    if not args.sensitivity:
        return None
    if spec.kind not in ("kinematic", "inverse", "equilibrium", "forward"):
        raise ModelError(f"--sensitivity is for kinematic, inverse, equilibrium and forward "
                         f"analyses, not {spec.kind}")
    if spec.kind == "forward":
        from mbd3d.optimization import check_forward_options  # noqa: PLC0415
        check_forward_options(spec.options, "--sensitivity")
    for name in args.sensitivity:
        parameter_value(model, name)
    if csv_path is None:
        return None
    return check_output_path(csv_path[:-len(".csv")] + "_sensitivities.csv", args.overwrite,
                             "the sensitivities' CSV file")


def _run_sensitivities(args, sens, csv_path: str | None) -> None:
    """Print the results' sensitivities ``sens`` to each ``--sensitivity`` parameter, a
    table per parameter (the first coordinates, and the drivers' efforts), and write them."""
    from mbd3d.io.results import format_table  # noqa: PLC0415

    res = sens.results
    columns = sens.columns()
    for name in args.sensitivity:
        shown = {"t [s]": columns["t [s]"]}
        for label in res.model.coordinate_labels[:2 * _SHOWN]:
            shown[f"d({label})"] = columns[f"d({label})/d({name})"]
        for key in columns:
            if key.endswith(f".effort)/d({name})"):
                shown[key.split("/")[0]] = columns[key]
        print(f"sensitivities to {name}:\n{format_table(shown, rows=args.rows)}\n")
    if csv_path is not None:
        sens.to_csv(csv_path, overwrite=args.overwrite)
        print(f"sensitivities written to {os.path.abspath(csv_path)}")


#: most bodies and joints the summary tables of mbd3d run show (the CSV has them all)
_SHOWN = 4


def _tables(res) -> list[tuple[str, dict]]:
    """The summary tables of a run: the first bodies' centres of mass; the first joints'
    coordinates and the drivers' efforts (where the analysis has multipliers)."""
    from mbd3d.errors import ModelError  # noqa: PLC0415

    model = res.model
    bodies = {"t [s]": res.t}
    for body in model.bodies[:_SHOWN]:
        history = res.body(body.name)
        for axis, label in enumerate("xyz"[:model.dim]):
            bodies[f"{body.name}.{label} [m]"] = history.position[:, axis]
    joints = {"t [s]": res.t}
    for element in [e for e in model.joints if not e.is_driver]:
        if len(joints) > _SHOWN:
            break
        for quantity, unit in (("angle", "rad"), ("displacement", "m")):
            try:
                joints[f"{element.name}.{quantity} [{unit}]"] = getattr(
                    res.joint(element.name), quantity)
            except ModelError:  # a joint without this coordinate
                pass
    if res.lam is not None:
        for element in [e for e in model.joints if e.is_driver][:_SHOWN]:
            joints[f"{element.name}.effort [{element.effort_unit}]"] = res.driver(
                element.name).effort
    tables = [(f"centres of mass{_more(len(model.bodies))}", bodies)]
    if len(joints) > 1:
        tables.append(("joint coordinates" + (" and driver efforts" if res.lam is not None
                                              else ""), joints))
    return tables


def _more(count: int) -> str:
    return f" (the first {_SHOWN} of {count}; the CSV has all)" if count > _SHOWN else ""


def _run_modes(args, model, spec, rrd: str | None, csv_path: str | None) -> int:
    """``mbd3d run`` of a ``modes`` analysis: the frequencies and damping ratios at each
    time's equilibrium, as a table, a CSV and a recording (written when all are computed)."""
    from mbd3d.io.files import check_output_path  # noqa: PLC0415
    from mbd3d.io.results import format_table  # noqa: PLC0415
    import mbd3d as mb  # noqa: PLC0415

    # the destinations checked before the computing, as for the other analyses
    if rrd is not None:
        from mbd3d.viewer import check_destination  # noqa: PLC0415
        check_destination(rrd, overwrite=args.overwrite, show=args.show)
    if csv_path is not None:
        check_output_path(csv_path, overwrite=args.overwrite)
    modes = mb.vibration_modes_along(model, spec.t, **spec.options)
    print(f"{model.name}: vibration modes at {len(modes.t)} positions, complete\n")
    print(format_table(modes.columns(), rows=args.rows))
    if csv_path is not None:
        modes.to_csv(csv_path, overwrite=args.overwrite)
        print(f"\nCSV written to {os.path.abspath(csv_path)}")
    if rrd is not None:
        from mbd3d.viewer import record_modes  # noqa: PLC0415
        record_modes(modes, rrd, overwrite=args.overwrite, show=args.show)
    return 0


def _run_linearize(args, model, spec, rrd: str | None, csv_path: str | None) -> int:
    """``mbd3d run`` of a ``linearize`` analysis: the eigenvalues printed, the matrices A, B,
    C, D as a CSV in long form (matrix, row, column, value; rows and columns named)."""
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io import files  # noqa: PLC0415
    from mbd3d.io.results import format_table  # noqa: PLC0415

    if rrd is not None:
        raise ModelError("a linearisation has no motion to record; leave out the recording "
                         "(rrd)")
    if csv_path is not None:
        files.check_output_path(csv_path, overwrite=args.overwrite)
    lin = spec.run(model)
    values = lin.eigenvalues
    size = np.abs(values)
    print(f"{model.name}: linearisation at t = {lin.t:g} s, {len(lin.states)} states: "
          f"{', '.join(lin.states)}\n")
    print(format_table({"Re s [1/s]": values.real, "Im s [1/s]": values.imag,
                        "f [Hz]": size / (2 * np.pi),
                        "zeta [-]": np.where(size > 0, -values.real / np.where(
                            size > 0, size, 1.0), 0.0)}))
    if csv_path is not None:
        rows = []
        for matrix, names_r, names_c in (("A", lin.states, lin.states),
                                         ("B", lin.states, lin.inputs),
                                         ("C", lin.outputs, lin.states),
                                         ("D", lin.outputs, lin.inputs)):
            values_m = getattr(lin, matrix)
            rows += [(matrix, r, c, repr(float(values_m[i, j])))
                     for i, r in enumerate(names_r) for j, c in enumerate(names_c)]

        def write(f):
            import csv  # noqa: PLC0415
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(("matrix", "row", "column", "value"))
            writer.writerows(rows)
        files.atomic_write(csv_path, write, text=True, overwrite=args.overwrite,
                           what="the CSV file")
        print(f"\nCSV written to {os.path.abspath(csv_path)}")
    return 0


def _view(args) -> int:
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.viewer import show  # noqa: PLC0415

    if not os.path.isfile(args.recording):
        raise ModelError(f"no recording '{args.recording}'")
    with open(args.recording, "rb") as f:
        if f.read(4) != b"RRF2":  # every .rrd begins so (Rerun's file header)
            raise ModelError(f"'{args.recording}' is not a Rerun recording (.rrd); mbd3d run "
                             "--rrd FILE writes one")
    show(args.recording, bind=args.bind)
    return 0


def _sweep(args) -> int:
    from mbd3d.io.yaml12 import load_value  # noqa: PLC0415

    from mbd3d import sweeps  # noqa: PLC0415
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io.model_file import read  # noqa: PLC0415

    path = str(pathlib.Path(args.model).resolve())
    axes = {}
    for item in args.grid:
        key, sep, text = item.partition("=")
        values = load_value(f"[{text}]") if sep else None
        if not key or not values:
            raise ModelError(f"--grid {item!r}: give FIELD=V1,V2,..., e.g. "
                             "joints.motor.motion.rate=5,10,20")
        axes[key] = values
    points = sweeps.grid(**{_parameter(k): v for k, v in axes.items()})
    loaded = read(path)  # checks the file, and each field of the grid, before any run
    for key, values in axes.items():
        read(path, {key: values[0]})
    analysis = _study_analysis(args, loaded)
    metrics = sweeps.default_metrics(loaded.model)
    # by default in the working directory, not beside the model file (which may be in a
    # repository, or someone else's folder)
    folder = args.folder or pathlib.Path(args.model).stem + "_sweep"
    table = sweeps.sweep(_FileFactory(path, dict(zip(map(_parameter, axes), axes))), points,
                         analysis, metrics, folder, client=args.scheduler,
                         backend="serial" if args.serial else "auto")
    print(table)
    if table.summary.get("interrupted"):
        print("mbd3d sweep: interrupted; the runs done are kept in the folder: run the same "
              "sweep again to finish", file=sys.stderr)
        return 130
    return 1 if table.failed else 0


def _study_analysis(args, loaded, t=None):
    """The :class:`mbd3d.sweeps.Analysis` a sweep or an optimization runs (kinematic,
    inverse or forward; ``t``: its times, given)."""
    from mbd3d import sweeps  # noqa: PLC0415
    from mbd3d.errors import ModelError  # noqa: PLC0415

    spec = _chosen_analysis(args, loaded, t)
    kind = {"kinematic": "kinematic", "inverse": "inverse dynamics",
            "forward": "forward dynamics"}.get(spec.kind)
    if kind is None:
        raise ModelError(f"{args.name} runs kinematic, inverse or forward analyses")
    return sweeps.Analysis(kind, spec.t if t is None else t, spec.options)


def _optimize(args) -> int:
    from mbd3d import optimization  # noqa: PLC0415
    from mbd3d.errors import ModelError  # noqa: PLC0415
    from mbd3d.io.files import check_output_path  # noqa: PLC0415
    from mbd3d.io.model_file import read  # noqa: PLC0415
    import mbd3d as mb  # noqa: PLC0415

    path = str(pathlib.Path(args.model).resolve())
    loaded = read(path)
    bounds, objective, starts, seed = optimization.command_terms(args, loaded)
    if isinstance(objective, optimization.Fit) and args.t is not None:
        raise ModelError("--t: a fit runs at its measurements' times")
    analysis = _study_analysis(args, loaded, getattr(objective, "t", None))
    out = args.out and check_output_path(args.out, args.overwrite, "the optimised model file")
    table = optimization.optimize(
        loaded.model, analysis, bounds, objective,
        starts=starts, seed=seed,
        folder=args.folder or pathlib.Path(args.model).stem + "_optimize",
        client=args.scheduler, backend="serial" if args.serial else "auto",
        factory=_FileFactory(path, {name: name for name in bounds}))
    print(table)
    if table.summary.get("interrupted"):
        print("mbd3d optimize: interrupted; the starts done are kept in the folder",
              file=sys.stderr)
        return 130
    row = optimization.best(table)
    if row is None:
        print("mbd3d optimize: no start converged", file=sys.stderr)
        return 1
    values = {name: row[f"{name} optimised"] for name in bounds}
    print(f"\nbest: {objective} = {row['objective']:.6g} (from {row['start objective']:.6g})"
          + "".join(f"\n  {name} = {value:.9g}" for name, value in values.items()))
    if out:
        mb.save(mb.with_parameters(loaded.model, values), out, analyses=loaded.analyses,
                overwrite=args.overwrite, optimization=loaded.optimization)
        print(f"optimised model written to {os.path.abspath(out)}")
    return 0


def _parameter(field: str) -> str:
    """A sweep parameter's name for a field path (an identifier, as factories take)."""
    return "p_" + "".join(c if c.isalnum() else "_" for c in field)


class _FileFactory:
    """Builds the model file's model with sweep parameters set (pickled to Dask workers); the
    digest of the file and of the files it reads makes an edit of any of them a new sweep."""

    def __init__(self, path: str, fields: dict[str, str]):
        from mbd3d.io.model_file import read  # noqa: PLC0415
        self.path, self.fields = path, fields
        # the file and every file it builds from (a URDF, meshes): an edit of any of them
        # makes a new sweep, whose rows are computed again
        digest = hashlib.sha1(pathlib.Path(path).read_bytes())
        for source in sorted(read(path).sources):
            digest.update(source.encode() + b"\0" + pathlib.Path(source).read_bytes())
        self.digest = digest.hexdigest()

    def sweep_identity(self) -> str:
        return f"model file {self.path} {self.digest} {sorted(self.fields.items())}"

    def __call__(self, **params):
        from mbd3d.io.model_file import read  # noqa: PLC0415
        return read(self.path, {self.fields[k]: v for k, v in params.items()}).model


if __name__ == "__main__":
    sys.exit(main())
