"""Mutation testing of the formula modules: change one term or operator at a time, run the
tests that cover it, report the changes no test notices (the survivors).

Run from the repository root (it works on a copy; the checkout is never written)::

    python tests/mutate.py mbd3d/numerics/compiled/rows.py --lines 398-430 \\
        --tests tests/test_primitives.py tests/test_gears.py

A mutant is one of: an additive term dropped (``a + b`` becomes ``a`` and ``b``; ``a - b``
becomes ``a`` and ``-b``), ``+``/``-`` and ``*``/``/`` swapped (``+=``/``-=`` too), a unary
minus dropped, a float factor halved. Each runs the chosen tests in a scratch copy of the
working tree, stopping at the first failure (the tests that killed the mutants just before
first, then the rest quickest first, as the unchanged code's run timed them), with the compiled
core interpreted
(``NUMBA_DISABLE_JIT=1``: a mutant of a kernel would otherwise recompile the whole core) unless
``--compiled`` is given. A survivor is either a gap in the tests or an equivalent change (one
that cannot change a result, such as a term that is zero by construction); say which where the
score is published.

Exit status: 0 when every mutant was killed, 1 when some survived, 2 on bad arguments.
"""

from __future__ import annotations

import argparse
import ast
import concurrent.futures
import contextlib
import dataclasses
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
#: what a scratch copy leaves out
IGNORED = shutil.ignore_patterns(".git", "__pycache__", "*.rrd", "*.egg-info", ".pytest_cache",
                                 "build", "dist", ".venv")


@dataclasses.dataclass(frozen=True)
class Mutant:
    """One change: the text between two (line, column) positions replaced."""

    line: int
    start: tuple[int, int]
    end: tuple[int, int]
    original: str
    replacement: str

    def describe(self) -> str:
        return f"line {self.line}: {self.original!r} -> {self.replacement!r}"


def _segment(node: ast.AST, text: str) -> str:
    return ast.get_source_segment(text, node) or ast.unparse(node)


def _variants(node: ast.AST, text: str) -> list[str]:
    """The mutated source texts of ``node`` (only the node itself changes)."""
    if isinstance(node, ast.BinOp):
        left, right = _segment(node.left, text), _segment(node.right, text)
        # operands in parentheses: the source may have had them outside the operand's span
        left, right = f"({left})", f"({right})"
        if isinstance(node.op, ast.Add):
            return [f"{left} - {right}", left, right]
        if isinstance(node.op, ast.Sub):
            return [f"{left} + {right}", left, f"(-{right})"]
        if isinstance(node.op, ast.Mult):
            return [f"{left} / {right}"]
        if isinstance(node.op, ast.Div):
            return [f"{left} * {right}"]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return [f"({_segment(node.operand, text)})"]
    if (isinstance(node, ast.Constant) and type(node.value) is float and node.value != 0.0
            and node.value not in (1e-300,)):
        return [repr(node.value / 2)]
    return []


def _is_index(node: ast.AST, parents: dict) -> bool:
    """Whether ``node`` is (inside) a subscript's index: indices are not formula terms."""
    while node in parents:
        parent = parents[node]
        if isinstance(parent, ast.Subscript) and node is parent.slice:
            return True
        node = parent
    return False


def mutants(path: Path, lines: list[tuple[int, int]] | None) -> list[Mutant]:
    """Every mutant of the file at ``path`` on the given line ranges (all lines if None),
    docstrings and annotations left out."""
    text = path.read_text()
    tree = ast.parse(text)
    parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
    found = []
    for node in ast.walk(tree):
        if not hasattr(node, "lineno") or _is_index(node, parents):
            continue
        if lines is not None and not any(a <= node.lineno <= b for a, b in lines):
            continue
        if isinstance(node, ast.AugAssign) and isinstance(node.op, (ast.Add, ast.Sub)):
            target, value = _segment(node.target, text), _segment(node.value, text)
            op = "-=" if isinstance(node.op, ast.Add) else "+="
            variants = [f"{target} {op} ({value})"]
        else:
            variants = _variants(node, text)
        original = _segment(node, text)
        for variant in variants:
            found.append(Mutant(node.lineno, (node.lineno, node.col_offset),
                                (node.end_lineno, node.end_col_offset), original, variant))
    return sorted(set(found), key=lambda m: (m.start, m.end, m.replacement))


def apply(text: str, mutant: Mutant) -> str:
    """``text`` with the mutant's span replaced (columns are UTF-8 byte offsets, as ast's)."""
    lines = text.splitlines(keepends=True)
    (l0, c0), (l1, c1) = mutant.start, mutant.end
    head = lines[l0 - 1].encode()[:c0].decode()
    tail = lines[l1 - 1].encode()[c1:].decode()
    return "".join(lines[:l0 - 1]) + head + mutant.replacement + tail + "".join(lines[l1:])


def _pytest(copy: Path, args: list[str], compiled: bool, timeout: float):
    """The completed pytest run in ``copy`` (None when it timed out)."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    if compiled:
        env["NUMBA_CACHE_DIR"] = str(copy / ".numba-cache")
    else:
        env["NUMBA_DISABLE_JIT"] = "1"
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
               "-p", "no:randomly", "--no-header", *args]
    try:
        return subprocess.run(command, cwd=copy, env=env, capture_output=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None


def run_tests(copy: Path, tests: list[str], compiled: bool, timeout: float
              ) -> tuple[str, str | None]:
    """``("killed", the test that failed)`` when the tests fail (or time out: no test),
    else ``("survived", None)``; the run stops at the first failure."""
    done = _pytest(copy, ["-x", *tests], compiled, timeout)
    if done is None:
        return "killed", None  # a mutant that makes a loop run away is caught by the time limit
    if done.returncode == 0:
        return "survived", None
    failed = re.search(r"^(?:FAILED|ERROR) (.+?)(?: - .*)?$",
                       done.stdout.decode(errors="replace"), re.MULTILINE)
    return "killed", failed.group(1) if failed else None


def timed_tests(copy: Path, tests: list[str], compiled: bool, timeout: float
                ) -> list[str] | None:
    """The unchanged code's run: the node ids of ``tests``, quickest first (each mutant
    then runs them in that order, after the tests that killed the mutants before it, so
    that most mutants die in seconds), or None when the tests fail."""
    done = _pytest(copy, ["--durations=0", "--durations-min=0", *tests], compiled, timeout)
    if done is None or done.returncode != 0:
        return None
    seconds: dict[str, float] = {}
    for line in done.stdout.decode(errors="replace").splitlines():
        timed = re.match(r"^\s*([\d.]+)s (?:setup|call|teardown)\s+(\S.*)$", line)
        if timed:
            node = timed.group(2).strip()
            seconds[node] = seconds.get(node, 0.0) + float(timed.group(1))
    return sorted(seconds, key=seconds.get) or list(tests)


def scratch_copy(into: Path) -> Path:
    """A copy of the working tree in ``into/repo``; a copy left there by an earlier run is
    replaced except for its kernel cache, which stays valid while the compiled core is
    unchanged (Numba checks each file's time stamp, which the copy keeps)."""
    copy = into / "repo"
    if copy.exists():
        for entry in copy.iterdir():
            if entry.name != ".numba-cache":
                shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
    shutil.copytree(REPO, copy, ignore=IGNORED, dirs_exist_ok=True)
    return copy


def _parse_lines(spec: str | None) -> list[tuple[int, int]] | None:
    if not spec:
        return None
    ranges = []
    for part in spec.split(","):
        a, _, b = part.partition("-")
        ranges.append((int(a), int(b or a)))
    return ranges


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("module", help="the file to mutate, relative to the repository root")
    parser.add_argument("--tests", nargs="+", required=True,
                        help="test files or node ids that should notice every mutant")
    parser.add_argument("--lines", help="line ranges to mutate, e.g. 398-430,494-515")
    parser.add_argument("--jobs", type=int, default=2, help="mutants run at once (default 2)")
    parser.add_argument("--timeout", type=float, default=600.0,
                        help="seconds one mutant's tests may take (default 600)")
    parser.add_argument("--compiled", action="store_true",
                        help="run the tests compiled (each mutant of a kernel recompiles)")
    parser.add_argument("--scratch", type=Path,
                        help="keep the copies in this folder (made if missing) to reuse their "
                             "kernel caches in later --compiled runs; default a temporary one")
    parser.add_argument("--list", action="store_true", help="list the mutants and stop")
    args = parser.parse_args(argv)
    target = REPO / args.module
    if not target.is_file():
        parser.error(f"no file {args.module} in {REPO}")
    found = mutants(target, _parse_lines(args.lines))
    if args.list:
        for mutant in found:
            print(mutant.describe())
        print(f"{len(found)} mutants")
        return 0
    text = target.read_text()
    start = time.monotonic()
    with (contextlib.nullcontext(args.scratch) if args.scratch
          else tempfile.TemporaryDirectory(prefix="mbd3d-mutate-")) as scratch:
        copies = [scratch_copy(Path(scratch) / f"job{k}") for k in range(max(1, args.jobs))]
        order = None
        for copy in copies:  # the unchanged tests must pass, or nothing can be judged
            # (given longer: compiled, this first run fills the copy's kernel cache)
            order = timed_tests(copy, args.tests, args.compiled, max(args.timeout, 1800.0))
            if order is None:
                print("the tests fail on the unchanged code: fix them first", file=sys.stderr)
                return 2
        free, killers = list(copies), []

        def judge(mutant: Mutant) -> str:
            copy = free.pop()
            try:
                (copy / args.module).write_text(apply(text, mutant))
                # neighbouring mutants tend to die by the same test: the latest killers first
                first = list(dict.fromkeys(killers[::-1]))
                tests = first + [node for node in order if node not in first]
                outcome, killer = run_tests(copy, tests, args.compiled, args.timeout)
                if killer is not None:
                    killers.append(killer)
                    del killers[:-20]
                return outcome
            finally:
                (copy / args.module).write_text(text)
                free.append(copy)

        survivors = []
        with concurrent.futures.ThreadPoolExecutor(len(copies)) as pool:
            # reported as they are judged, so an interrupted run has said what it found
            for done, (mutant, outcome) in enumerate(zip(found, pool.map(judge, found)), 1):
                if outcome == "survived":
                    survivors.append(mutant)
                    print(f"survived  {args.module}:{mutant.describe()}", flush=True)
                if done % 50 == 0:
                    print(f"  {done} of {len(found)} judged", file=sys.stderr, flush=True)
    killed = len(found) - len(survivors)
    print(f"{args.module}: {killed} of {len(found)} mutants killed, {len(survivors)} survived "
          f"({time.monotonic() - start:.0f} s)")
    return 1 if survivors else 0


if __name__ == "__main__":
    sys.exit(main())
