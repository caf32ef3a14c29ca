"""Parameters by name: every number a model was built with, named by the path of its field in
the model's file (:mod:`mbd3d.io.model_file`): ``bodies.crank.mass``,
``joints.A.point_i[0]``, ``forces.spring.stiffness``, ``joints.motor.motion.rate``,
``gravity[1]``. A model built in Python has the same names as one read from a file, since
the file is the list of constructor calls that built the model
(:func:`mbd3d.io.model_writer.model_data`); the names are those ``mbd3d run --set`` and
:func:`mbd3d.io.model_file.read`'s ``changes`` take, and :class:`ModelVariants` makes a
sweep's factory of them.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import weakref
from typing import Any, Mapping, Sequence

import numpy as np

from mbd3d.errors import ModelError, did_you_mean
from mbd3d.io.model_file import ModelFileError, _Reader
from mbd3d.io.model_writer import model_data
from mbd3d.model.tangents import OFFSETS, ModelTangent

__all__ = ["parameters", "with_parameters", "ModelVariants", "parameter_value",
           "parameter_variants", "parameter_tangent"]

#: the parts of a model's data that hold its parameters (not its format, name or analyses)
_SECTIONS = ("gravity", "bodies", "joints", "forces")


def parameters(model) -> dict[str, float]:
    """Every number ``model`` was built with, by name (see the module doc), in the order of
    the model's file: bodies, then joints and drivers, then force elements.

    Parameters
    ----------
    model : Model

    Examples
    --------
    >>> import mbd3d as mb
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    >>> bob = b.add_body("bob", mass=2.0, inertia=0.01, position=(1.0, 0.0))
    >>> mb.parameters(b.build())["bodies.bob.mass"]
    2.0
    """
    return {name: float(container[key])
            for name, (container, key) in _fields(_data(model)).items()}


def with_parameters(model, values: Mapping[str, float]):
    """A new model, ``model`` built again with the parameters ``values`` (by name, see
    :func:`parameters`) changed; ``model`` itself is left as it is.

    Parameters
    ----------
    model : Model
    values : mapping of str to float
        Parameter name -> its new value.

    Raises
    ------
    ModelError
        A name that is not a parameter of the model (with the nearest ones), a value that is
        not a finite number (or not a whole one where the field is), or a model that the
        changed value makes invalid (named as a model file's field would be).
    """
    return _changed(_data(model), values)


class ModelVariants:
    """A parameter sweep's factory (:func:`mbd3d.sweeps.sweep`): ``ModelVariants(model)(**values)``
    is ``with_parameters(model, values)``, the points' keys being parameter names (e.g.
    ``mb.grid(**{"forces.spring.stiffness": [10.0, 20.0]})``). It holds the model as its
    file's plain data, which Dask ships to its workers, and names itself to the sweep's store
    by a digest of that data, so that a changed model is a new sweep.

    Parameters
    ----------
    model : Model
        The model whose variants the sweep builds.

    Examples
    --------
    >>> import mbd3d as mb
    >>> b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81))
    >>> bob = b.add_body("bob", mass=2.0, inertia=0.01, position=(1.0, 0.0))
    >>> heavier = mb.ModelVariants(b.build())(**{"bodies.bob.mass": 3.0})
    >>> mb.parameters(heavier)["bodies.bob.mass"]
    3.0
    """

    def __init__(self, model):
        self.data = _data(model)
        text = json.dumps(self.data, default=_mesh_digest, separators=(",", ":"))
        self.digest = hashlib.sha1(text.encode()).hexdigest()

    def sweep_identity(self) -> str:
        """What a sweep's stored results were computed from (the model file's name and
        digest): a sweep resumed with another model computes them again."""
        return f"model {self.data.get('name')!r} {self.digest}"

    def __call__(self, **values: float):
        return _changed(copy.deepcopy(self.data), values)


def _mesh_digest(value: Any) -> str:
    """A body's shape given as a mesh object, as text that is the same in every session."""
    digest = hashlib.sha1()
    for part in (getattr(value, "vertices", None), getattr(value, "faces", None)):
        if part is None:
            raise ModelError(f"a model's shape must be a mesh, a path or a primitive, got a "
                             f"{type(value).__name__}")
        digest.update(np.ascontiguousarray(part).tobytes())
    return digest.hexdigest()


def _changed(data: dict, values: Mapping[str, float], whole: bool = True):
    """The model of ``data`` (a model's file as plain data, changed in place) with the
    parameters ``values`` set, checked (``whole``: a field written as a whole number takes
    only whole numbers)."""
    fields = _fields(data)
    name = data.get("name")
    for key, value in values.items():
        if key not in fields:
            raise ModelError(f"model '{name}': no parameter '{key}'"
                             f"{did_you_mean(key, fields)}; mb.parameters(model) lists them")
        container, field = fields[key]
        old = container[field] if whole else float(container[field])
        container[field] = _number(value, old, f"parameter '{key}'")
    return _Reader(f"<model '{name}'>", {}).build(data).model


def _changed_at(data: dict, path: tuple, name: str, value: float):
    """The model of ``data`` with the number at ``path`` (parameter ``name``) set to
    ``value``: ``data`` is left as it is, and only the containers along the path are copied
    (a build reads its data and never changes it; a 100-link chain's whole copy took a
    third as long as its build)."""
    root = node = dict(data)
    for key in path[:-1]:
        node[key] = node = (dict if isinstance(node[key], dict) else list)(node[key])
    node[path[-1]] = _number(value, float(node[path[-1]]), f"parameter '{name}'")
    return _Reader(f"<model '{data.get('name')}'>", {}).build(root).model


def parameter_variants(model, name: str, offsets: Sequence[float], refine: int = 0
                       ) -> tuple[list, float]:
    """The model built again with parameter ``name`` moved by each of ``offsets`` steps, and
    the step: the power of two nearest a thousandth of the parameter's size (of its vector's
    length where it is a component, or of the model's length scale where both are zero),
    divided by ``2**refine``. A field written as a whole number (a point drawn at ``(0,
    0)``) takes the fractions; one that counts refuses them, naming the parameter.

    Raises
    ------
    ModelError
        A name that is not a parameter of the model (with the nearest ones), or a model the
        changed value makes invalid (a universal joint's axes no longer perpendicular).
    """
    data = _data(model)
    value, size = _value_in(data, name)
    # a power of two: the changed values are then exact, and so are the data that are
    # linear in them (a joint's point is the parameter itself)
    step = 2.0 ** (round(math.log2(1e-3 * (max(abs(value), size) or model.length_scale)))
                   - refine)
    path = _fields(data, paths=True)[name]
    variants = []
    for o in offsets:
        try:
            variants.append(_changed_at(data, path, name, value + o * step))
        except ModelError as exc:
            raise ModelError(f"parameter '{name}' changed by {o * step:.3g} alone makes the "
                             f"model invalid ({exc}): it has no derivative of its own; change "
                             "it together with the numbers it must agree with") from None
    return variants, step


def parameter_tangent(model, name: str, what: str) -> ModelTangent:
    """The :class:`~mbd3d.model.tangents.ModelTangent` of ``model`` along parameter ``name``
    (its variants, and at shorter steps when asked), messages naming ``what``."""
    return ModelTangent(model, *parameter_variants(model, name, OFFSETS),
                        f"{what} to parameter '{name}'",
                        finer=lambda k: parameter_variants(model, name, OFFSETS, refine=k))


#: each model's file as plain data, written once per model (a built model does not change;
#: writing a 100-link chain's takes 13 ms, as long as building a variant from it), kept while
#: the model lives
_FILE_DATA: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _data(model) -> dict:
    """The model's file as plain data (its dicts and lists the caller's own to change), or why
    a file cannot hold it (a Python function)."""
    data = _FILE_DATA.get(model)
    if data is None:
        try:
            data = model_data(model)
        except ModelFileError as exc:
            raise ModelError(f"model '{model.name}': parameters are named by the fields of "
                             f"the model's file, which cannot hold it: {exc}") from None
        _FILE_DATA[model] = data
    return _plain_copy(data)


def _plain_copy(data: Any) -> Any:
    """A copy of a model's file as plain data: its dicts and lists copied, what they hold
    (numbers, strings, a mesh) shared, as a build reads but never changes it."""
    if isinstance(data, dict):
        return {key: _plain_copy(value) for key, value in data.items()}
    if isinstance(data, list):
        return [_plain_copy(value) for value in data]
    return data


def _fields(data: dict, paths: bool = False) -> dict[str, tuple]:
    """The numeric leaves of a model's data: name -> (the list or mapping holding it, its
    index or key), or with ``paths`` the keys and indices that lead to it from ``data``."""
    found: dict[str, tuple] = {}
    for section in _SECTIONS:
        if section in data:
            _collect(data, section, section, found, (section,) if paths else None)
    return found


def _collect(container: Any, key: Any, name: str, found: dict, path: tuple | None) -> None:
    value = container[key]
    if isinstance(value, bool) or value is None:
        return
    if isinstance(value, (int, float)):
        found[name] = (container, key) if path is None else path
    elif isinstance(value, dict):
        for field in value:
            if field not in ("name", "type"):
                _collect(value, field, f"{name}.{field}", found,
                         None if path is None else path + (field,))
    elif isinstance(value, list):
        # a list of named entries (bodies, joints) by name, any other by index
        named = bool(value) and all(isinstance(v, dict) and "name" in v for v in value)
        for index, item in enumerate(value):
            _collect(value, index, f"{name}.{item['name']}" if named else f"{name}[{index}]",
                     found, None if path is None else path + (index,))


def parameter_value(model, name: str) -> tuple[float, float]:
    """The value of parameter ``name`` (see :func:`parameters`) and the length of the vector
    it is a component of (zero for a lone number).

    Raises
    ------
    ModelError
        A name that is not a parameter of the model, with the nearest ones.
    """
    return _value_in(_data(model), name)


def _value_in(data: dict, name: str) -> tuple[float, float]:
    """:func:`parameter_value` read from the model's file as plain data."""
    fields = _fields(data)
    if name not in fields:
        raise ModelError(f"model '{data.get('name')}': no parameter '{name}'"
                         f"{did_you_mean(name, fields)}; mb.parameters(model) lists them")
    container, key = fields[name]
    size = 0.0
    if isinstance(container, list) and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in container):
        size = float(np.linalg.norm(np.asarray(container, dtype=float)))
    return float(container[key]), size


def _number(value: Any, old: Any, what: str) -> float | int:
    """``value`` as the field's kind of number: a finite real, whole where ``old`` is."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(
            value):
        raise ModelError(f"{what}: give a finite number, got {value!r}")
    if isinstance(old, int):
        if value != int(value):
            raise ModelError(f"{what}: give a whole number (the field counts), got {value!r}")
        return int(value)
    return float(value)
