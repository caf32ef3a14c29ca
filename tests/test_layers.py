"""The package's layers point one way, and its imports make no circle.

From the bottom: ``mbd3d.errors``; ``mbd3d.numerics`` (linear algebra, rotations, the compiled
core); ``mbd3d.model`` and ``mbd3d.planar`` (bodies, primitives, forces, the built model);
``mbd3d.joints``; ``mbd3d.io`` (results, files, URDF); ``mbd3d.analyses``; ``mbd3d.viewer``;
and the top (``mbd3d`` itself, the command line, sweeps, the example mechanisms). A module
imports only from its own layer or below, wherever the import stands (in a function too);
imports for type annotations only (``if TYPE_CHECKING:``) are not imports at run time. The
analyses a model file asks for are handed down to :mod:`mbd3d.io.model_file` by
:mod:`mbd3d.analyses` (a table it fills), not imported from above.
"""

from __future__ import annotations

import ast
import pathlib

REPO = pathlib.Path(__file__).resolve().parent.parent
#: the repository's folders and the names they are installed under
FOLDERS = {"mbd3d": "mbd3d", "joints": "mbd3d.joints", "planar": "mbd3d.planar",
           "viewer": "mbd3d.viewer"}
LAYERS = ["mbd3d.errors", "mbd3d.numerics", "mbd3d.model mbd3d.planar", "mbd3d.joints",
          "mbd3d.io", "mbd3d.analyses", "mbd3d.viewer"]


def modules() -> dict[str, pathlib.Path]:
    found = {}
    for folder, package in FOLDERS.items():
        for path in (REPO / folder).rglob("*.py"):
            parts = [p for p in path.relative_to(REPO / folder).with_suffix("").parts
                     if p != "__init__"]
            found[".".join([package, *parts])] = path
    return found


def _type_checking_only(node: ast.AST, parents: dict) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            return True
    return False


def imports() -> dict[str, set[str]]:
    """Module -> the package modules it imports at run time."""
    names = modules()
    graph = {}
    for name, path in names.items():
        tree = ast.parse(path.read_text())
        parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
        targets = set()
        for node in ast.walk(tree):
            if (not isinstance(node, (ast.Import, ast.ImportFrom))
                    or _type_checking_only(node, parents)):
                continue
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                for alias in node.names:  # a submodule, or a name of the module
                    sub = f"{node.module}.{alias.name}"
                    targets.add(sub if sub in names else node.module)
        graph[name] = {t for t in targets if t in names and t != name}
    return graph


def layer(module: str) -> int:
    for rank, members in enumerate(LAYERS):
        if any(module == m or module.startswith(m + ".") for m in members.split()):
            return rank
    if module == "mbd3d._checkout":
        return 0
    return len(LAYERS)  # the top


def test_no_module_imports_from_a_layer_above_its_own():
    upward = sorted((a, b) for a, targets in imports().items() for b in targets
                    if layer(b) > layer(a))
    assert not upward, upward


def test_the_imports_make_no_circle():
    graph = imports()
    state: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        for target in sorted(graph[module]):
            if state.get(target) == 1:
                circle = path[path.index(target):] + [target]
                raise AssertionError("import circle: " + " -> ".join(circle))
            if target not in state:
                visit(target, path + [target])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])


#: a module holds one concern: above this many lines it holds several (the compiled kernels,
#: loops over instances written out once, are measured apart)
LONGEST_MODULE = 600
#: a function that does one thing fits on a screen: code lines, its docstring left out
LONGEST_FUNCTION = 85


def test_modules_and_functions_stay_of_one_concern():
    too_long = []
    for name, path in modules().items():
        if ".numerics.compiled" in name:
            continue
        text = path.read_text()
        if len(text.splitlines()) > LONGEST_MODULE:
            too_long.append(f"module {name}: {len(text.splitlines())} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                first = node.body[0]
                documented = (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
                              and isinstance(first.value.value, str))
                start = first.end_lineno + 1 if documented else node.lineno
                if node.end_lineno - start + 1 > LONGEST_FUNCTION:
                    too_long.append(f"{name}.{node.name}: {node.end_lineno - start + 1} lines")
    assert not too_long, too_long
