"""Model files: a mechanism written down as YAML, checked, analysed and versioned without code.

Why YAML: nested lists of bodies and joints read naturally in it, it takes comments, and its
parser reports the line of every value, so that a mistake is reported where it is. It is read
with PyYAML's safe loader (plain data only: nothing in a file is ever executed) and written
with its safe dumper, floats in their shortest exact form (a model saved and loaded is the same
model to the last bit).

The format, version 1 (every field in SI units)::

    mbd3d: 1                       # the format version
    name: slider-crank             # optional
    dim: 2                         # 2 (planar) or 3 (spatial)
    gravity: [0.0, -9.81]          # optional, [m/s^2]
    urdf: {file: arm.urdf}         # optional, dim 3: a robot to start from (see mbd3d.io.urdf;
                                   # also fixed_base, joint_positions, drive)
    mjcf: {file: arm.xml}          # optional, dim 3: a MuJoCo model to start from (see
                                   # mbd3d.io.mjcf; also joint_positions, drive, keyframe)
    bodies:                        # the arguments of ModelBuilder.add_body, by name
      - {name: crank, mass: 1.0, inertia: 0.01, position: [0.05, 0.0], angle: 0.0}
      - {name: arm, shape: arm.stl, density: 7850.0, position: [0, 0, 0]}   # a mesh file
      - {name: hub, shape: {cylinder: [0.05, 0.02]}, density: 2700.0, position: [0, 0, 0]}
    joints:                        # joints and drivers, in order: a type and its arguments
      - {type: Revolute, name: O, body_i: ground, body_j: crank, at: [0.0, 0.0]}
      - type: RotationDriver
        name: motor
        joint: O                   # bodies and joints are named
        motion: {type: Ramp, initial: 0.0, rate: 6.283185307179586}
    forces:                        # force elements: a type and its arguments
      - {type: Torque, name: load, body: crank, torque: 2.0}
    analyses:                      # optional: what `mbd3d run` does, and where it writes
      - {kind: forward, t: {start: 0.0, stop: 2.0, step: 0.01}, method: DOP853, rtol: 1e-10,
         rrd: run.rrd, csv: results}
    optimize:                      # optional: what `mbd3d optimize` varies and minimises
      vary: {bodies.crank.mass: [0.5, 2.0]}           # (mbd3d.io.optimization_spec)
      minimize: peak:crank.omega

Types are the classes of :mod:`mbd3d.joints` and the force elements of :mod:`mbd3d`
(``PointForce``, ``Torque``, ``SpringDamper``, ``RotationalSpringDamper``, ``JointFriction``
and ``JointLimit``, whose ``joint`` names a joint, ``Contact``, ``ContactGroup``); their fields
are their constructors' keyword arguments, as documented there. A contact's shapes (a group's:
a list of them) and law are
``{type: Sphere | Plane | Capsule | Box | Hole | Cam, body: ...}`` and ``{type: LinearContact |
HertzContact | HuntCrossley | ImpactFunction | RigidImpact, ...}``. A motion is a number (constant)
or ``{type: Constant | Ramp | Harmonic | Polynomial | SmoothStep, ...}`` with that class's
arguments, or ``{type: Sum, terms: [...]}``; Python functions cannot be written to a file. A
cam's profile is ``{type: CamProfile, angles: [...], radii: [...]}``.
Analyses have a ``kind`` (``kinematic``, ``inverse``, ``forward``, ``equilibrium``,
``modes``: the vibration modes about the equilibrium at each time with the drivers held, and
``linearize``: the linear state-space model at one time, about the drawing or the
equilibrium, see :func:`mbd3d.analyses.linearization.linearize_at`), times
``t`` (a list, or ``{start, stop, step}`` or ``{start, stop, points}``), the keyword
arguments of that analysis function, and optionally where ``mbd3d run`` writes the recording
(``rrd``) and the CSV (``csv``, a folder). Paths are relative to the file. A body's shape is a
mesh file or a primitive (``{box: [x, y, z]}``, ``{cylinder: [radius, height]}``,
``{sphere: radius}``).

The file is read as YAML 1.2 (:mod:`mbd3d.io.yaml12`): ``1e-10`` is a number, ``010`` is ten,
``no`` and ``1:30`` are strings; a key given twice, anchors and aliases, and tags other than
YAML's own are refused. A mistake is reported with the file, the line and the field:
``model.yaml:14: joints[3].axis: ...``.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import os
import pathlib
import re
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from mbd3d.errors import ModelError, did_you_mean
from mbd3d.io.optimization_spec import read_optimization
from mbd3d.io.yaml12 import YamlError, load_yaml

__all__ = ["AnalysisSpec", "ModelFile", "load", "read", "FORMAT_VERSION"]

FORMAT_VERSION = 1
#: the largest model file read [bytes]: reading takes about 2 s per MB (libyaml's tree and the
#: YAML 1.2 reading of it), so a hostile file cannot hold a run for more than a few minutes
MAX_FILE_BYTES = 64_000_000
_TOP_LEVEL = ("mbd3d", "name", "dim", "gravity", "urdf", "mjcf", "bodies", "joints", "forces",
              "analyses", "optimize")
_URDF_FIELDS = ("file", "fixed_base", "joint_positions", "drive")
_MJCF_FIELDS = ("file", "joint_positions", "drive", "keyframe")
_BODY_FIELDS = ("name", "mass", "inertia", "position", "angle", "orientation", "velocity",
                "angular_velocity", "shape", "density")
#: constructor arguments that name a body or a joint
_REFERENCES = ("body_i", "body_j", "body", "joint")
#: analysis kind -> the function that runs it, ``f(model, t, **options)``: filled by
#: :mod:`mbd3d.analyses` when it is imported (the analyses live above this package, which
#: reads their options and hands the runs back to them)
ANALYSES: dict[str, Callable] = {}


class ModelFileError(ModelError):
    """A model file that cannot be read or written (names the file, line and field)."""


@dataclass(frozen=True)
class AnalysisSpec:
    """An analysis a model file asks for: ``kind`` (kinematic, inverse, forward,
    equilibrium, modes, linearize), output times ``t`` [s] and keyword arguments of the
    analysis function."""

    kind: str
    t: np.ndarray
    options: dict[str, Any] = field(default_factory=dict)
    #: where ``mbd3d run`` writes the results: ``rrd`` (a recording) and ``csv`` (a folder),
    #: absolute paths (a file gives them relative to itself)
    outputs: dict[str, str] = field(default_factory=dict)

    def run(self, model, **overrides: Any):
        """Run it on ``model`` (``overrides`` replace options, e.g. ``observers``)."""
        return ANALYSES[self.kind](model, self.t, **{**self.options, **overrides})


@dataclass(frozen=True)
class ModelFile:
    """A model file read: the model built, the analyses it asks for, and the plain data."""

    model: Any
    analyses: list[AnalysisSpec]
    data: dict
    path: str
    #: every other file the model was built from (a URDF and its meshes, mesh files of
    #: bodies), absolute paths: what a result made from the file also depends on
    sources: tuple[str, ...] = ()
    #: its ``optimize:`` section (:mod:`mbd3d.io.optimization_spec`), or None
    optimization: Any = None


# -- reading ----------------------------------------------------------------------------------
def load(path: str | os.PathLike):
    """Build the model a model file describes (see the module doc for the format).

    Parameters
    ----------
    path : str or path-like
        The model file (YAML).

    Raises
    ------
    ModelFileError
        With the file, the line and the field path of the mistake.
    """
    return read(path).model


def read(path: str | os.PathLike, changes: dict[str, Any] | None = None) -> ModelFile:
    """Read a model file: its model, its analyses and its data.

    ``changes`` sets values by field path before the model is built, e.g.
    ``{"bodies.crank.mass": 2.0, "joints.motor.motion.rate": 10.0}`` (bodies and elements
    by name, list entries by index), as a parameter sweep does.
    """
    path = str(path)
    try:
        size = pathlib.Path(path).stat().st_size
        if size > MAX_FILE_BYTES:
            raise ModelFileError(f"{path}: {size / 1e6:.0f} MB is not a model file (at most "
                                 f"{MAX_FILE_BYTES / 1e6:.0f} MB are read: a model file "
                                 "describes a mechanism; its reading time grows with its size)")
        text = pathlib.Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelFileError(f"model file '{path}' cannot be read: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        line = pathlib.Path(path).read_bytes()[:exc.start].count(b"\n") + 1
        raise ModelFileError(f"{path}:{line}: not UTF-8 text (byte {exc.object[exc.start]:#x}); "
                             "a model file is YAML in UTF-8: save it so, or check that "
                             "this is the model file") from None
    try:
        data, lines = load_yaml(text)
    except YamlError as exc:
        where = path if exc.line is None else f"{path}:{exc.line}"
        raise ModelFileError(f"{where}: {exc}") from None
    reader = _Reader(path, lines)
    if not isinstance(data, dict):
        raise reader.error((), "a model file is a mapping with bodies:, joints:, ...")
    for key, value in (changes or {}).items():
        _apply_change(reader, data, key, value)
    return reader.build(data)


def _apply_change(reader, data: dict, key: str, value: Any) -> None:
    """Set the value at a dotted field path; names pick list entries by their ``name``, and
    ``[k]`` an entry of a list value (``joints.A.point_i[0]``, as
    :func:`mbd3d.io.parameters.parameters` names it)."""
    parts = []
    for part in key.split("."):
        field, *indices = part.split("[")
        if not field or not all(i[-1:] == "]" and i[:-1].isdigit() for i in indices):
            raise reader.error((), f"change '{key}': '{part}' is not a field name or a "
                                   "field with [index]")
        parts += [field] + [int(i[:-1]) for i in indices]
    target: Any = data
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(part, int):
            if not isinstance(target, list) or part >= len(target):
                raise reader.error((), f"change '{key}': no entry [{part}] in a value of "
                                       f"{len(target) if isinstance(target, list) else 1}")
            if last:
                target[part] = value
            target = target[part]
            continue
        if isinstance(target, list):
            chosen = next((item for item in target if isinstance(item, dict)
                           and item.get("name") == part), None)
            if chosen is None and part.isdigit() and int(part) < len(target):
                chosen = target[int(part)]
            if chosen is None:
                names = [item.get("name") for item in target if isinstance(item, dict)]
                raise reader.error((), f"change '{key}': no entry '{part}' (entries: "
                                       f"{', '.join(map(str, names))})")
            if last:
                raise reader.error((), f"change '{key}': name a field of '{part}'")
            target = chosen
        elif isinstance(target, dict):
            if last:
                target[part] = value
            elif part not in target:
                raise reader.error((), f"change '{key}': no field '{part}'"
                                       f"{did_you_mean(part, target)}")
            else:
                target = target[part]
        else:
            raise reader.error((), f"change '{key}': '{part}' is inside a value, not a field")


def _types() -> tuple[dict[str, type], dict[str, type], dict[str, type]]:
    """Joint, force and motion classes by name."""
    import mbd3d.joints as joints  # noqa: PLC0415
    from mbd3d.model import (contact_laws, contacts, forces, friction, motion,  # noqa: PLC0415
                             springs)
    from mbd3d.model.element import ConstraintElement  # noqa: PLC0415

    joint_types = {name: getattr(joints, name) for name in joints.__all__
                   if isinstance(getattr(joints, name), type)
                   and issubclass(getattr(joints, name), ConstraintElement)}
    force_types = {cls.__name__: cls for cls in (forces.PointForce, forces.Torque,
                                                  springs.SpringDamper,
                                                  springs.RotationalSpringDamper,
                                                  friction.JointFriction, contacts.Contact,
                                                  contacts.ContactGroup, contacts.JointLimit)}
    motion_types = {cls.__name__: cls for cls in (motion.Constant, motion.Ramp,
                                                   motion.Harmonic, motion.Polynomial,
                                                   motion.SmoothStep, joints.CamProfile,
                                                   contacts.Sphere, contacts.Plane,
                                                   contacts.Capsule, contacts.Box,
                                                   contacts.Hole, contacts.Cam,
                                                   contact_laws.LinearContact,
                                                   contact_laws.HertzContact,
                                                   contact_laws.HuntCrossley,
                                                   contact_laws.ImpactFunction,
                                                   contact_laws.RigidImpact)}
    return joint_types, force_types, motion_types


def _field_named(message: str, where: tuple, entry: dict) -> tuple:
    """``where``, or ``where`` and the field of ``entry`` the message is about (named as
    ``field must``, ``field [`` or ``field:``)."""
    for key in entry:
        if re.search(rf"(^|[\s:(]){re.escape(str(key))}\b( must| \[|:)", message):
            return where + (key,)
    return where



@functools.lru_cache(maxsize=None)
def _arguments_of(function: Callable) -> tuple[list, list]:
    """The keyword arguments ``function`` (a class or a function) takes, and those it needs:
    read once per function, since every element of a file (and every variant a sensitivity
    builds) is checked against its class's."""
    parameters = inspect.signature(function).parameters
    accepted = [name for name, p in parameters.items()
                if name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    return accepted, [name for name in accepted
                      if parameters[name].default is inspect.Parameter.empty]

class _Reader:
    """Builds a model from plain data, naming the file, line and field of each mistake."""

    def __init__(self, path: str, lines: dict[tuple, int]):
        self.path, self.lines = path, lines
        self.folder = pathlib.Path(path).resolve().parent

    def error(self, where: tuple, message: str) -> ModelFileError:
        line = None
        for depth in range(len(where), -1, -1):
            line = self.lines.get(where[:depth])
            if line is not None:
                break
        field_path = "".join(f"[{p}]" if isinstance(p, int) else (f".{p}" if i else p)
                             for i, p in enumerate(where))
        place = f"{self.path}:{line}" if line is not None else self.path
        return ModelFileError(f"{place}: {field_path + ': ' if field_path else ''}{message}")

    def build(self, data: dict) -> ModelFile:
        from mbd3d.model.builder import ModelBuilder  # noqa: PLC0415

        for key in data:
            if key not in _TOP_LEVEL:
                raise self.error((key,), f"unknown field{did_you_mean(key, _TOP_LEVEL)} (fields: "
                                         f"{', '.join(_TOP_LEVEL)})")
        version = data.get("mbd3d", FORMAT_VERSION)
        if version != FORMAT_VERSION:
            raise self.error(("mbd3d",), f"format version {version!r}; this mbd3d reads "
                                         f"version {FORMAT_VERSION}")
        dim = data.get("dim", 2)
        if type(dim) is not int or dim not in (2, 3):  # not 2.0 or True
            raise self.error(("dim",), f"must be 2 (planar) or 3 (spatial), got {dim!r}")
        try:
            builder = ModelBuilder(dim=dim, gravity=data.get("gravity"),
                                   name=str(data.get("name", pathlib.Path(self.path).stem)))
        except ModelError as exc:
            raise self.error(("gravity",), str(exc)) from None
        named: dict[str, Any] = {"ground": builder.ground}
        self.sources: list[str] = []
        self.places: dict[str, tuple[tuple, dict]] = {}  # name -> (field path, entry)
        for robot in ("urdf", "mjcf"):
            if robot in data:
                self._robot(robot, data[robot], builder, named)
        for index, entry in enumerate(self._list(data, "bodies")):
            where = ("bodies", index)
            entry = self._mapping(entry, where)
            if "name" not in entry:
                raise self.error(where, "a body needs a name")
            for key in entry:
                if key not in _BODY_FIELDS:
                    raise self.error(where + (key,), f"unknown body field"
                                                     f"{did_you_mean(key, _BODY_FIELDS)} (fields: "
                                                     f"{', '.join(_BODY_FIELDS)})")
            arguments = dict(entry)
            name = str(arguments.pop("name"))
            if isinstance(arguments.get("shape"), str):
                arguments["shape"] = str(self.folder / arguments["shape"])
                self.sources.append(str(pathlib.Path(arguments["shape"]).resolve()))
            with self._at(where, entry):
                named[name] = builder.add_body(name, **arguments)
            self.places[name] = (where, entry)
        joint_types, force_types, motion_types = _types()
        for section, types in (("joints", joint_types), ("forces", force_types)):
            for index, entry in enumerate(self._list(data, section)):
                where = (section, index)
                element = self._element(self._mapping(entry, where), where, types, named,
                                        motion_types)
                with self._at(where):
                    named[element.name] = builder.add(element)
                self.places[element.name] = (where, entry)
        try:
            model = builder.build()
        except ModelFileError:
            raise
        except ModelError as exc:
            raise self.error(self._blamed(str(exc)), str(exc)) from None
        analyses = [self._analysis(self._mapping(entry, ("analyses", index)),
                                   ("analyses", index))
                    for index, entry in enumerate(self._list(data, "analyses"))]
        optimization = (read_optimization(self, data["optimize"]) if "optimize" in data
                        else None)
        return ModelFile(model, analyses, data, self.path, tuple(dict.fromkeys(self.sources)),
                         optimization)

    def _robot(self, kind: str, entry, builder, named: dict) -> None:
        """The robot of a URDF or MJCF file (``kind``), the start of the model (bodies and
        joints by name)."""
        from mbd3d.io.mjcf import mjcf_builder  # noqa: PLC0415
        from mbd3d.io.urdf import urdf_builder  # noqa: PLC0415

        where = (kind,)
        fields = _URDF_FIELDS if kind == "urdf" else _MJCF_FIELDS
        entry = self._mapping(entry, where)
        for key in entry:
            if key not in fields:
                raise self.error(where + (key,), f"unknown {kind} field"
                                                 f"{did_you_mean(key, fields)} (fields: "
                                                 f"{', '.join(fields)})")
        if "file" not in entry:
            raise self.error(where, f"{kind} needs its file (relative to this file)")
        if builder.dim != 3:
            raise self.error(("dim",), f"a {kind.upper()} robot is spatial: dim: 3")
        _, _, motion_types = _types()
        drive = {joint: (self._motion(value, where + ("drive", joint), motion_types)
                         if isinstance(value, dict) else value)
                 for joint, value in (entry.get("drive") or {}).items()}
        options = ({"fixed_base": entry.get("fixed_base", True)} if kind == "urdf"
                   else {"keyframe": entry.get("keyframe")})
        with self._at(where):
            (urdf_builder if kind == "urdf" else mjcf_builder)(
                self.folder / str(entry["file"]), joint_positions=entry.get("joint_positions"),
                drive=drive, builder=builder, files_read=self.sources, **options)
        named.update({body.name: body for body in builder._bodies})
        named.update({element.name: element for element in builder._elements})

    def _blamed(self, message: str) -> tuple:
        """Where in the file an error of the built model points: the first body or element
        the message names in quotes, and the field it names, if any."""
        for name in re.findall(r"'([^']+)'", message):
            if name in self.places:
                return _field_named(message, *self.places[name])
        return ()

    def _list(self, data: dict, key: str) -> list:
        value = data.get(key) or []
        if not isinstance(value, list):
            raise self.error((key,), f"must be a list (entries starting with '- '), got "
                                     f"{type(value).__name__}")
        return value

    def _mapping(self, entry, where) -> dict:
        if not isinstance(entry, dict):
            raise self.error(where, f"must be a mapping of fields, got {entry!r}")
        return entry

    @contextlib.contextmanager
    def _at(self, where: tuple, entry: dict | None = None):
        """A context in which a ModelError is reported at ``where``, or at the field of
        ``entry`` its message names (``position must ...``)."""
        try:
            yield
        except ModelFileError:
            raise
        except ModelError as exc:
            raise self.error(_field_named(str(exc), where, entry or {}), str(exc)) from None

    def _element(self, entry: dict, where: tuple, types: dict, named: dict, motion_types):
        kind = entry.get("type")
        if kind not in types:
            what = "joint or driver" if where[0] == "joints" else "force element"
            raise self.error(where + ("type",), f"unknown {what} type {kind!r}"
                                                f"{did_you_mean(kind, types)} (types: "
                                                f"{', '.join(sorted(types))})")
        cls = types[kind]
        arguments = {key: value for key, value in entry.items() if key != "type"}
        self._check_arguments(cls, arguments, where, kind)
        for key, value in arguments.items():
            if key in _REFERENCES and isinstance(value, str):
                if value not in named:
                    raise self.error(where + (key,), f"no body or joint '{value}' (so far: "
                                                     f"{', '.join(named)})"
                                                     f"{did_you_mean(value, named)}")
                arguments[key] = named[value]
            elif isinstance(value, dict) and "type" in value:
                arguments[key] = self._motion(value, where + (key,), motion_types, named)
            elif isinstance(value, list) and any(isinstance(v, dict) for v in value):
                arguments[key] = [self._motion(v, where + (key, k), motion_types, named)
                                  if isinstance(v, dict) else v for k, v in enumerate(value)]
        with self._at(where, entry):
            return cls(**arguments)

    def _check_arguments(self, function: Callable, arguments: dict, where: tuple,
                         kind: str) -> None:
        accepted, required = _arguments_of(function)
        for key in arguments:
            if key not in accepted:
                raise self.error(where + (key,), f"{kind} takes no '{key}'"
                                                 f"{did_you_mean(key, accepted)} (it takes: "
                                                 f"{', '.join(accepted)})")
        for name in required:
            if name not in arguments:
                raise self.error(where, f"{kind} needs '{name}'")

    def _motion(self, value: dict, where: tuple, motion_types: dict, named: dict | None = None):
        """A value given as ``{type: ...}``: a motion, a cam profile, a contact's shape (whose
        ``body`` names a body of ``named``) or law."""
        kind = value.get("type")
        if kind == "Sum":
            terms = value.get("terms")
            if not isinstance(terms, list) or not terms:
                raise self.error(where + ("terms",), "a Sum needs a list of terms")
            total = None
            for index, term in enumerate(terms):
                part = (self._motion(term, where + ("terms", index), motion_types)
                        if isinstance(term, dict) else term)
                total = part if total is None else total + part
            return total
        if kind not in motion_types:
            raise self.error(where + ("type",), f"unknown motion type {kind!r}"
                                                f"{did_you_mean(kind, motion_types)} (types: "
                                                f"{', '.join(motion_types)}, Sum)")
        arguments = {key: v for key, v in value.items() if key != "type"}
        self._check_arguments(motion_types[kind], arguments, where, kind)
        if named is not None and isinstance(arguments.get("body"), str):
            if arguments["body"] not in named:
                raise self.error(where + ("body",), f"no body '{arguments['body']}' (so far: "
                                                    f"{', '.join(named)})"
                                                    f"{did_you_mean(arguments['body'], named)}")
            arguments["body"] = named[arguments["body"]]
        for key, part in arguments.items():  # a cam's profile
            if isinstance(part, dict) and "type" in part:
                arguments[key] = self._motion(part, where + (key,), motion_types, named)
        with self._at(where, value):
            return motion_types[kind](**arguments)

    def _analysis(self, entry: dict, where: tuple) -> AnalysisSpec:
        kind = entry.get("kind")
        if kind not in ANALYSES:
            raise self.error(where + ("kind",), f"unknown analysis {kind!r}"
                                                f"{did_you_mean(kind, ANALYSES)} (kinds: "
                                                f"{', '.join(ANALYSES)})")
        if "t" not in entry:
            raise self.error(where, "an analysis needs its times t: a list, or {start, stop, "
                                    "step} or {start, stop, points}")
        t = self._times(entry["t"], where + ("t",))
        outputs = {}
        for key in ("rrd", "csv"):
            if key in entry:
                outputs[key] = self._output(entry[key], where + (key,))
        options = {key: value for key, value in entry.items()
                   if key not in ("kind", "t", "rrd", "csv")}
        function = ANALYSES[kind]
        parameters = inspect.signature(function).parameters
        allowed = [name for name in list(parameters)[2:]
                   if name not in ("observers", "progress")]
        for key in options:
            if key not in allowed:
                raise self.error(where + (key,), f"{function.__name__} takes no '{key}'"
                                                 f"{did_you_mean(key, allowed)} (it takes: "
                                                 f"{', '.join(allowed)})")
        return AnalysisSpec(kind, t, options, outputs)

    def _output(self, value, where: tuple) -> str:
        """An output path of the file: relative to its folder and inside it, so that a model
        file (perhaps someone else's) cannot make ``mbd3d run`` write anywhere else."""
        if not isinstance(value, str) or not value.strip():
            raise self.error(where, "a path (relative to this file)")
        relative = pathlib.PurePath(value)
        if relative.is_absolute() or ".." in relative.parts:
            raise self.error(where, f"{value!r} leaves the model file's folder; outputs stay "
                                    "inside it (give a path relative to it, without '..'), or "
                                    "choose another place with mbd3d run --rrd/--csv")
        target = (self.folder / relative).resolve()
        if not target.is_relative_to(self.folder.resolve()):  # through a link out of it
            raise self.error(where, f"{value!r} leads out of the model file's folder (a link); "
                                    "outputs stay inside it")
        return str(self.folder / relative)

    def _times(self, value, where: tuple) -> np.ndarray:
        if isinstance(value, dict):
            unknown = set(value) - {"start", "stop", "step", "points"}
            if unknown or "stop" not in value or ("step" in value) == ("points" in value):
                raise self.error(where, "times are {start, stop, step} or {start, stop, "
                                        f"points}}, got {value!r}")
            try:
                start, stop = float(value.get("start", 0.0)), float(value["stop"])
                step = float(value["step"]) if "step" in value else None
            except (TypeError, ValueError):
                raise self.error(where, f"start, stop and step are numbers [s], got {value!r}"
                                 ) from None
            if "points" in value:
                points = value["points"]
                if type(points) is not int or points < 2:
                    raise self.error(where + ("points",), f"a whole number of output times, 2 "
                                                          f"or more, got {points!r}")
                if not (np.isfinite(start) and np.isfinite(stop) and stop > start):
                    raise self.error(where, f"times from {start} to {stop}: need finite "
                                            "start < stop")
                _check_count(points, self.error, where)
                return np.linspace(start, stop, points)
            return times_from_step(start, stop, step, self.error, where)
        try:
            t = np.asarray(value, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            t = np.zeros(0) * np.nan
        if t.size == 0 or not np.all(np.isfinite(t)):
            raise self.error(where, f"times must be finite numbers, got {value!r}")
        return t


#: the most output times an analysis is given from a start, stop and step or points: ten
#: million rows of a slider-crank's results take about 2 GB
MAX_POINTS = 10_000_000


def _check_count(count: float, error=None, where=()) -> None:
    if count > MAX_POINTS:
        message = (f"that makes {count:.3g} output times, more than {MAX_POINTS:.0e}: give a "
                   "larger step or fewer points (the results of each are kept in memory)")
        raise error(where, message) if error else ModelError(message)


def times_from_step(start: float, stop: float, step: float, error=None, where=()) -> np.ndarray:
    """``start, start + step, ..., stop`` (the last point is ``stop``)."""
    if not (np.isfinite(start) and np.isfinite(stop) and np.isfinite(step) and step > 0
            and stop > start):
        message = (f"times from {start} to {stop} by {step}: need finite numbers with "
                   "stop > start and step > 0")
        raise error(where, message) if error else ModelError(message)
    _check_count((stop - start) / step + 1, error, where)
    count = int(round((stop - start) / step))
    if not np.isclose(start + count * step, stop, rtol=1e-9, atol=0.0):
        count = int(np.floor((stop - start) / step))
        return np.append(start + step * np.arange(count + 1), stop)
    return np.linspace(start, stop, count + 1)
