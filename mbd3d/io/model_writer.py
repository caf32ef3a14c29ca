"""Writing a model file: :func:`save`, the inverse of :func:`mbd3d.io.model_file.read` for
models built in Python (the format is described there). Meshes go beside the file under
sanitised names, and nothing existing is replaced unless asked.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import pathlib
from typing import Any, Callable, Sequence

import numpy as np

from mbd3d.io import files
from mbd3d.io.model_file import FORMAT_VERSION, AnalysisSpec, ModelFileError

__all__ = ["save", "model_data"]


def save(model, path: str | os.PathLike, *, analyses: Sequence[AnalysisSpec | dict] = (),
         overwrite: bool = False, optimization: Any = None) -> str:
    """Write ``model`` as a model file that rebuilds it (see the module doc).

    Each body is written with the arguments of ``add_body`` that made it, each joint, driver
    and force element with those of its constructor. A mesh given as a file is referenced
    (relative to the model file); one given as a trimesh object is written beside the file as
    ``<stem>.<body>.obj``, the body's name made a file name (characters other than letters,
    digits, ``.``, ``_`` and ``-`` replaced, and a digest of the name added when any was),
    so that no name can put a file elsewhere. Every file is checked before any is written,
    and none that exists is replaced unless ``overwrite``. ``optimization`` (a file's
    :class:`~mbd3d.io.optimization_spec.OptimizationSpec`) is written as its ``optimize:``
    section, its measurements' file named relative to the new file.

    Parameters
    ----------
    model : Model
    path : str or path-like
        The model file to write (YAML).
    analyses : sequence of AnalysisSpec or dict
        Analyses the file lists for ``mbd3d run`` (its ``analyses:`` section).
    overwrite : bool
        Replace ``path`` and the meshes beside it where they exist.
    optimization : OptimizationSpec, optional
        A file's ``optimize:`` section to write (see above).

    Raises
    ------
    ModelFileError
        An element made with a Python function (a ``Function`` motion, a force given as a
        callable), which a file cannot hold; or a path that cannot be written (or exists,
        without ``overwrite``).
    """
    import yaml  # noqa: PLC0415

    try:
        target = pathlib.Path(files.check_output_path(path, overwrite, "the model file"))
        folder = target.parent
        meshes = {body.name: folder / f"{target.stem}.{_file_name(body.name)}.obj"
                  for body in model.bodies if _is_mesh(body.arguments.get("shape"))}
        for mesh_path in meshes.values():
            files.check_output_path(mesh_path, overwrite, "the mesh file")
    except files.OutputError as exc:
        raise ModelFileError(str(exc)) from None
    data = model_data(model, lambda body, shape: _shape_file(
        shape, body.name, meshes.get(body.name), folder, overwrite))
    if analyses:
        data["analyses"] = [_analysis_entry(a) for a in analyses]
    if optimization is not None:
        data["optimize"] = optimization.entry(folder)
    text = yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)
    return files.atomic_write(target, lambda f: f.write(text), text=True, overwrite=overwrite,
                              what="the model file")


def model_data(model, shape: Callable[[Any, Any], Any] | None = None) -> dict[str, Any]:
    """The plain data of ``model``'s file (see :mod:`mbd3d.io.model_file`): each body with the
    arguments of ``add_body`` that made it, each joint, driver and force element with those
    of its constructor; a body's shape as ``shape(body, value)`` gives it (default: as given,
    a path or a mesh object).

    Raises
    ------
    ModelFileError
        An element made with a Python function, which plain data cannot hold.
    """
    data: dict[str, Any] = {"mbd3d": FORMAT_VERSION, "name": model.name, "dim": model.dim,
                            "gravity": _plain(model.gravity, "gravity")}
    bodies = []
    for body in model.bodies:
        entry: dict[str, Any] = {"name": body.name}
        for key, value in body.arguments.items():
            if key == "shape":
                entry[key] = value if shape is None else shape(body, value)
            else:
                entry[key] = _plain(value, f"body '{body.name}': {key}")
        bodies.append(entry)
    data["bodies"] = bodies
    data["joints"] = [_element_entry(e) for e in model.joints]
    data["forces"] = [_element_entry(f) for f in model.forces]
    if not data["forces"]:
        del data["forces"]
    return data


def _element_entry(element) -> dict:
    where = f"{type(element).__name__} '{element.name}'"
    entry = {"type": type(element).__name__}
    for key, value in element.arguments.items():
        entry[key] = _plain(value, f"{where}: {key}")
    return entry


def _analysis_entry(spec: AnalysisSpec | dict) -> dict:
    if isinstance(spec, dict):
        return {key: _plain(value, f"analysis {key}") for key, value in spec.items()}
    entry = {"kind": spec.kind, "t": _plain(spec.t, "analysis t")}
    entry.update({key: _plain(value, f"analysis {key}") for key, value in spec.options.items()})
    return entry


def _plain(value: Any, where: str) -> Any:
    """``value`` as YAML's plain data: bodies and joints by name, motions as mappings."""
    from mbd3d.model.body import Body  # noqa: PLC0415
    from mbd3d.model.element import ConstraintElement  # noqa: PLC0415
    from mbd3d.model.motion import Motion, _Sum  # noqa: PLC0415

    if isinstance(value, (Body, ConstraintElement)):
        return value.name
    if isinstance(value, _Sum):
        terms = []
        for part in value.parts:
            plain = _plain(part, where)
            terms += plain["terms"] if plain.get("type") == "Sum" else [plain]
        return {"type": "Sum", "terms": terms}
    from mbd3d.joints.cams import CamProfile  # noqa: PLC0415

    if isinstance(value, CamProfile):
        return {"type": "CamProfile", **{k: _plain(v, where) for k, v in value.arguments.items()}}
    if _is_contact_part(value):
        return {"type": type(value).__name__,
                **{f.name: _plain(getattr(value, f.name), where)
                   for f in dataclasses.fields(value)
                   if not _is_default(getattr(value, f.name), f.default)}}
    if isinstance(value, Motion):
        if value.terms() is None:
            raise ModelFileError(f"{where}: a motion given by Python functions cannot be "
                                 "written to a model file; use Constant, Ramp, Harmonic, "
                                 "Polynomial, SmoothStep or their sum")
        return {"type": type(value).__name__,
                **{k: _plain(v, where) for k, v in value.arguments.items()}}
    if isinstance(value, np.ndarray):
        return _plain(value.tolist(), where)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v, where) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v, where) for k, v in value.items()}
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if callable(value):
        raise ModelFileError(f"{where}: a Python function cannot be written to a model file; "
                             "give a number or a motion (Constant, Ramp, Harmonic, Polynomial, "
                             "SmoothStep)")
    raise ModelFileError(f"{where}: {type(value).__name__} values cannot be written to a model "
                         "file")


def _is_default(value: Any, default: Any) -> bool:
    """Whether a field holds its default (a shape's point may be an array: compared whole)."""
    if default is None or value is None:
        return value is default
    return bool(np.array_equal(np.asarray(value, dtype=object), np.asarray(default, dtype=object)))


def _is_contact_part(value: Any) -> bool:
    """A contact's shape or law (frozen dataclasses, written field by field)."""
    from mbd3d.model.contact_laws import ContactLaw  # noqa: PLC0415
    from mbd3d.model.shapes import Box, Cam, Capsule, Hole, Plane, Sphere  # noqa: PLC0415

    return (isinstance(value, (Sphere, Plane, Capsule, Box, Hole, Cam, ContactLaw))
            and dataclasses.is_dataclass(value))


def _is_mesh(shape: Any) -> bool:
    """Whether a body's shape is a mesh object, which is saved as a file of its own."""
    return shape is not None and not isinstance(shape, (dict, str, os.PathLike))


def _file_name(name: str) -> str:
    """``name`` as part of a file name: only letters, digits, ``.``, ``_`` and ``-`` (so no
    folder separator or drive), with a digest of the name when anything was replaced, so
    that two names never share a file."""
    safe = "".join(c if c.isascii() and (c.isalnum() or c in "._-") else "_" for c in name)
    if safe == name and safe.strip("."):
        return name
    return f"{safe.strip('.') or 'body'}-{hashlib.sha1(name.encode()).hexdigest()[:8]}"


def _shape_file(shape: Any, body: str, mesh_path: pathlib.Path | None, folder: pathlib.Path,
                overwrite: bool) -> Any:
    if isinstance(shape, dict):  # a primitive: its sizes
        return _plain(shape, f"body '{body}': shape")
    if isinstance(shape, (str, os.PathLike)):
        source = pathlib.Path(shape).resolve()
        try:
            return os.path.relpath(source, folder)
        except ValueError:  # another drive
            return str(source)
    from trimesh.exchange.obj import export_obj  # noqa: PLC0415

    # OBJ with 20 decimals: the vertices read back as written (STL and PLY hold float32)
    text = export_obj(shape, digits=20, include_normals=False, include_texture=False,
                      include_color=False)
    try:
        files.atomic_write(mesh_path, lambda f: f.write(text), text=True, overwrite=overwrite,
                           what="the mesh file")
    except files.OutputError as exc:
        raise ModelFileError(str(exc)) from None
    return mesh_path.name
