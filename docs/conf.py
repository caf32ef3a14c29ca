"""Sphinx configuration of mbd3d's documentation site.

Build: ``python -m sphinx -W --keep-going -n -b html docs docs/_build/html`` from the
repository root (``pip install -e ".[docs]"`` first). ``-W`` makes every warning an error,
``-n`` every reference to a name that is not documented: the API pages are generated from
the public modules' ``__all__``, so a public name without a docstring, a parameter its
docstring does not give, or a link to one that does not exist, fails the build.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import inspect
import os
import pathlib
import sys

from sphinx.util import logging
from sphinx.util.nodes import make_refnode

#: the repository: the site documents the tree it is built from, and its examples and
#: notebooks, run in processes of their own, import that tree too
ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ["PYTHONPATH"] = os.pathsep.join(
    part for part in (str(ROOT), os.environ.get("PYTHONPATH")) if part)


project = "mbd3d"
author = "The mbd3d developers"
copyright = "2026, the mbd3d developers"
release = version = importlib.metadata.version("mbd3d")

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_nb",  # Markdown pages, and the tutorials: notebooks executed as the site is built
]

templates_path = ["_templates"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb"}
exclude_patterns = ["_build", "api/generated/*.md"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
# every notebook runs at every build, in a folder of its own (what it writes stays there), and
# an error in any cell fails the build
nb_execution_mode = "force"
nb_execution_in_temp = True
nb_execution_raise_on_error = True
nb_execution_timeout = 600
nb_merge_streams = True

html_theme = "pydata_sphinx_theme"
html_static_path = ["_static"]
html_title = "mbd3d"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}

# the API reference: one page per public name, from the docstrings (NumPy style)
autosummary_imported_members = True
autodoc_typehints = "none"  # the docstrings' Parameters sections give types with units
autodoc_default_options = {"members": True, "inherited-members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

logger = logging.getLogger(__name__)
#: see _public_names; filled as the build starts
_PUBLIC_NAMES: dict[str, str] = {}

#: the public modules whose ``__all__`` the reference documents, with a line on each
PUBLIC = {
    "mbd3d": "models, analyses and results: everything ``import mbd3d as mb`` gives",
    "mbd3d.joints": "joints, drivers and higher pairs",
    "mbd3d.planar": "planar bodies",
    "mbd3d.viewer": "recordings for the Rerun viewer",
    "mbd3d.mechanisms": "ready-made models",
    "mbd3d.sweeps": "parameter sweeps and Monte Carlo on Dask",
    "mbd3d.optimization": "optimisation and identification from several starts",
}

# the pages _api_pages writes, named here: autosummary reads them before the build finds them
autosummary_generate = [f"api/{name}.rst" for name in PUBLIC]

# names the reference does not link into: other projects' types in signatures and docstrings
nitpick_ignore_regex = [
    ("py:.*", r"(numpy|np|scipy|pandas|pd|rerun|rr|trimesh|dask|distributed|numba)(\..*)?"),
    ("py:.*", r"(abc|argparse|warnings|typing|collections|pathlib|enum)\..*"),
    # private base classes, as show-inheritance names them
    ("py:class", r".*\._[A-Za-z]\w*"),
    ("py:.*", r"(ndarray|array_like|callable|optional|sequence|mapping|iterable|path-like)"),
]


def _api_pages(app) -> None:
    """Write ``api/<module>.rst``: an autosummary table of the module's ``__all__``, so that
    every public name has a page and none can be forgotten."""
    folder = pathlib.Path(app.srcdir) / "api"
    folder.mkdir(exist_ok=True)
    index = ["API reference", "=============", "",
             "Every public name of mbd3d, from its docstring.", "", ".. toctree::",
             "   :maxdepth: 1", ""]
    for name, what in PUBLIC.items():
        module = importlib.import_module(name)
        index.append(f"   {name}")
        # the module itself is declared where the internals document it
        lines = [name, "=" * len(name), "", f".. automodule:: {name}", "   :no-members:",
                 "   :no-index:", "",
                 what[0].upper() + what[1:] + ".", "", f".. currentmodule:: {name}", "",
                 ".. autosummary::", "   :toctree: generated", ""]
        for attribute in module.__all__:
            obj = getattr(module, attribute)
            if inspect.ismodule(obj):
                continue
            lines.append(f"   {attribute}")
            for missing in _undocumented(f"{name}.{attribute}", obj):
                logger.warning(f"{missing} is public but has no docstring: write one")
            for gap in _parameter_gaps(f"{name}.{attribute}", obj):
                logger.warning(gap)
        _write(folder / f"{name}.rst", "\n".join(lines) + "\n")
    _write(folder / "index.rst", "\n".join(index) + "\n")


def _internals_pages(app) -> None:
    """Write ``internals/index.rst``: every module of the package documented as it is, for
    developers (and so that the docstrings' links into the implementation resolve)."""
    modules = sorted(_module_names())
    folder = pathlib.Path(app.srcdir) / "internals"
    folder.mkdir(exist_ok=True)
    lines = ["Internals", "=========", "",
             "Every module of mbd3d as it is built: the model, the analyses, the numerics and",
             "their compiled core, input and output. The :doc:`API reference <../api/index>`",
             "is what a user needs; this is how it works.", ""]
    public = _public_objects()
    for name in modules:
        module = importlib.import_module(name)
        # what the API reference documents already (under its public name) is left out
        shown = sorted(attribute for attribute, obj in vars(module).items()
                       if id(obj) in public and getattr(obj, "__module__", None) == name)
        lines += [name, "-" * len(name), "", f".. automodule:: {name}", "   :members:",
                  "   :private-members:", "   :ignore-module-all:"]
        if shown:
            lines.append(f"   :exclude-members: {', '.join(shown)}")
        lines.append("")
    _write(folder / "index.rst", "\n".join(lines) + "\n")


def _public_objects() -> set[int]:
    """The ids of the objects the API reference documents."""
    return {id(getattr(importlib.import_module(name), attribute))
            for name in PUBLIC for attribute in importlib.import_module(name).__all__}


def _module_names():
    """The modules of the package (the folders beside ``mbd3d/`` in the repository are
    installed inside it), private ones left out."""
    for package in ("mbd3d", "mbd3d.joints", "mbd3d.planar", "mbd3d.viewer"):
        folder = pathlib.Path(importlib.import_module(package).__file__).parent
        for path in sorted(folder.rglob("*.py")):
            parts = path.relative_to(folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            if any(p.startswith("_") for p in parts):
                continue
            if package == "mbd3d" and parts and parts[0] in ("joints", "planar", "viewer"):
                continue
            yield ".".join((package,) + parts)


def _undocumented(name: str, obj) -> list[str]:
    """``name`` and the names of its public methods and properties that have no docstring
    (``inspect.getdoc``: a method overriding a documented one inherits its text)."""
    if isinstance(obj, (int, float, str, tuple, dict, frozenset)):  # constants: see the module
        return []
    missing = [] if inspect.getdoc(obj) else [name]
    if inspect.isclass(obj) and not issubclass(obj, BaseException):
        for attribute, member in vars(obj).items():
            if attribute.startswith("_"):
                continue
            if isinstance(member, (staticmethod, classmethod)):
                member = member.__func__
            if (inspect.isfunction(member) or isinstance(member, property)) \
                    and not inspect.getdoc(getattr(obj, attribute)):
                missing.append(f"{name}.{attribute}")
    return missing


def _parameter_gaps(name: str, obj) -> list[str]:
    """What ``name`` and its public methods' docstrings leave out of their signatures, or
    give that they do not have (numpydoc's PR01 and PR02); exceptions, which mbd3d raises
    and users do not build, and constants are not checked."""
    from numpydoc.validate import validate  # noqa: PLC0415

    if not callable(obj) or (inspect.isclass(obj) and issubclass(obj, BaseException)):
        return []
    names = [name]
    if inspect.isclass(obj):
        names += [f"{name}.{attribute}" for attribute, member in vars(obj).items()
                  if not attribute.startswith("_") and (
                      inspect.isfunction(member) or isinstance(member, (staticmethod,
                                                                        classmethod)))]
    gaps = []
    for full in names:
        found = validate(full)["errors"]
        errors = [text for code, text in found if code == "PR02"]
        if any(code == "PR01" for code, _ in found):
            errors += (_not_attributes(obj) if full == name and inspect.isclass(obj)
                       else [text for code, text in found if code == "PR01"])
        if errors:
            gaps.append(f"{full}: {'; '.join(errors)}: give each in its docstring")
    return gaps


def _not_attributes(cls) -> list[str]:
    """A class the analyses make (results, reports) documents its constructor's arguments
    as its attributes: those in neither section of its docstring."""
    from numpydoc.docscrape import ClassDoc  # noqa: PLC0415

    doc = ClassDoc(cls, config={"show_class_members": False})
    documented = {part.strip().lstrip("*") for section in ("Parameters", "Attributes")
                  for entry in doc[section] for part in entry.name.split(",")}
    missing = [name for name in inspect.signature(cls).parameters if name not in documented]
    return [f"Parameters {set(missing)} neither in its Parameters nor in its Attributes"] \
        if missing else []


def _write(path: pathlib.Path, text: str) -> None:
    """Write ``text`` unless the file holds it already (an unchanged page is not rebuilt)."""
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def _public_names() -> dict[str, str]:
    """Where each public object is defined, ``module.qualname``, to the name the API
    reference documents it under."""
    names = {}
    for module_name in PUBLIC:
        module = importlib.import_module(module_name)
        for attribute in module.__all__:
            obj = getattr(module, attribute)
            if hasattr(obj, "__qualname__") and hasattr(obj, "__module__"):
                names[f"{obj.__module__}.{obj.__qualname__}"] = f"{module_name}.{attribute}"
    return names


def _inherited(module: str, cls: str | None, target: str) -> list[str]:
    """``target`` as a member of the class ``cls`` of ``module`` finds it: in the class and
    its bases, in Python's order."""
    if not cls:
        return []
    try:
        owner = importlib.import_module(module)
        for part in cls.split("."):
            owner = getattr(owner, part)
    except (ImportError, AttributeError):
        return []
    return [f"{base.__module__}.{base.__qualname__}.{target}"
            for base in getattr(owner, "__mro__", ())]


def _resolve(app, env, node, contnode):
    """Links the docstrings write as the code names things: ``Results`` or
    ``mbd3d.io.results.Results.to_csv`` where the reference documents ``mbd3d.Results``, and
    names beside the current module in its package. Whatever this does not find stays a
    broken link, which fails the build."""
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    objects = env.get_domain("py").objects
    candidates = [f"{name}.{target}" for name in PUBLIC]
    module = node.get("py:module") or ""
    if module:
        candidates.append(f"{module.rpartition('.')[0]}.{target}")
        candidates += _inherited(module, node.get("py:class"), target)
    for defined, public in _PUBLIC_NAMES.items():
        if target == defined or target.startswith(defined + "."):
            candidates.append(public + target[len(defined):])
    found = [name for name in candidates if name in objects]
    if not found:  # a name imported into the module that refers to it, defined elsewhere:
        # the documented one ending so that shares the most of the current module's path;
        # two as near are ambiguous, and stay a broken link
        ending = "." + target
        found = sorted((name for name in objects if name.endswith(ending)),
                       key=lambda name: -len(os.path.commonprefix([name, module])))
        if len(found) > 1 and (len(os.path.commonprefix([found[0], module]))
                               == len(os.path.commonprefix([found[1], module]))):
            return None
    if not found:
        return None
    entry = objects[found[0]]
    return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id, contnode,
                        found[0])


def _gallery(app) -> None:
    """Run the examples and write the gallery's pages (:mod:`gallery`, beside this file)."""
    sys.path.insert(0, str(app.srcdir))
    import gallery

    gallery.build(ROOT, pathlib.Path(app.srcdir) / "gallery",
                  pathlib.Path(app.doctreedir) / "gallery", logger.warning)


def setup(app) -> None:
    _PUBLIC_NAMES.update(_public_names())
    app.connect("missing-reference", _resolve)
    app.connect("builder-inited", _api_pages, priority=100)
    app.connect("builder-inited", _internals_pages, priority=100)  # before autosummary
    app.connect("builder-inited", _gallery)
