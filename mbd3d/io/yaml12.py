"""Reading YAML as YAML 1.2 (its core schema), strictly and in linear time, with the line of
every value: the reader model files use (:mod:`mbd3d.io.model_file`).

PyYAML parses (with libyaml where installed) but resolves plain scalars by YAML 1.1, in which
``010`` is 8, ``1:30`` is 90, ``no`` is False and ``1e-10`` a string. Here the composed node
tree is turned into Python values by the YAML 1.2 core schema instead: ``true``/``false``,
``null``/``~``, decimal, ``0o`` and ``0x`` integers, floats with or without a dot
(``1e-10``), ``.inf`` and ``.nan``; everything else is a string. Duplicate keys are refused
(a later one silently replacing an earlier is a typo that changes a model), and so are anchors
and aliases (``&a``/``*a``: a handful of nested aliases expand to gigabytes) and tags other
than YAML's own (``!!python/object`` and the like). The tree is walked once, so time and memory
grow with the file's size.
"""

from __future__ import annotations

import math
import re
from typing import Any

__all__ = ["YamlError", "load_yaml", "load_value", "MAX_DEPTH"]

#: nesting deeper than this is refused (a model file nests five or six levels)
MAX_DEPTH = 64

_STANDARD = "tag:yaml.org,2002:"
#: tags PyYAML's YAML 1.1 resolver gives plain scalars by itself (re-resolved here by 1.2)
_IMPLICIT = {_STANDARD + name for name in
             ("bool", "int", "float", "null", "timestamp", "merge", "value", "str", "yaml")}
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")
_TRUE = re.compile(r"^(?:true|True|TRUE)$")
_FALSE = re.compile(r"^(?:false|False|FALSE)$")
_INT = re.compile(r"^[-+]?[0-9]+$")
_OCT = re.compile(r"^0o[0-7]+$")
_HEX = re.compile(r"^0x[0-9a-fA-F]+$")
_FLOAT = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?$")
_INF = re.compile(r"^([-+]?)(?:\.inf|\.Inf|\.INF)$")
_NAN = re.compile(r"^(?:\.nan|\.NaN|\.NAN)$")


class YamlError(ValueError):
    """Text that is not YAML, or YAML a model file does not take; ``line`` is 1-based (or
    None)."""

    def __init__(self, message: str, line: int | None = None):
        super().__init__(message)
        self.line = line


def _scalar(text: str) -> Any:
    """A plain scalar's value by the YAML 1.2 core schema."""
    if _NULL.match(text):
        return None
    if _TRUE.match(text):
        return True
    if _FALSE.match(text):
        return False
    if _INT.match(text):
        return int(text)
    if _OCT.match(text):
        return int(text[2:], 8)
    if _HEX.match(text):
        return int(text[2:], 16)
    if _FLOAT.match(text):
        return float(text)
    inf = _INF.match(text)
    if inf:
        return -math.inf if inf.group(1) == "-" else math.inf
    if _NAN.match(text):
        return math.nan
    return text


def load_yaml(text: str) -> tuple[Any, dict[tuple, int]]:
    """``(data, lines)``: the document's value and the line (1-based) of every value by its
    field path (keys and list indices), e.g. ``lines[("bodies", 0, "mass")]``.

    Raises
    ------
    YamlError
        Not YAML, or a duplicate key, an alias, a foreign tag, a key that is not a scalar,
        nesting deeper than :data:`MAX_DEPTH`.
    """
    import yaml  # noqa: PLC0415

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when installed
    try:
        node = yaml.compose(text, Loader=loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise YamlError(f"not valid YAML: {getattr(exc, 'problem', None) or exc}",
                        None if mark is None else mark.line + 1) from None
    except RecursionError:
        raise YamlError(f"nested more than {MAX_DEPTH} levels deep") from None
    lines: dict[tuple, int] = {}
    if node is None:
        return None, lines
    try:
        return _Walk(lines).value(node, ()), lines
    except _Alias:
        raise YamlError("anchors and aliases (&name, *name) are not read in model files: write "
                        "the value out where it is used", _first_alias_line(text, loader)) from None


class _Alias(Exception):
    """A node met a second time: an alias (its line is found from the events)."""


def _first_alias_line(text: str, loader) -> int | None:
    import yaml  # noqa: PLC0415

    for event in yaml.parse(text, Loader=loader):
        if isinstance(event, yaml.AliasEvent):
            return event.start_mark.line + 1
    return None


class _Walk:
    """The node tree to Python values, each node once (a node met twice is an alias)."""

    def __init__(self, lines: dict[tuple, int]):
        self.lines = lines
        self.seen: set[int] = set()

    def value(self, node, path: tuple) -> Any:
        import yaml  # noqa: PLC0415

        line = node.start_mark.line + 1
        self.lines.setdefault(path, line)
        if id(node) in self.seen:
            raise _Alias()
        self.seen.add(id(node))
        if len(path) > MAX_DEPTH:
            raise YamlError(f"nested more than {MAX_DEPTH} levels deep", line)
        if isinstance(node, yaml.ScalarNode):
            plain = not node.style  # None (pure-Python parser) or "" (libyaml)
            if not (node.tag in _IMPLICIT if plain else node.tag == _STANDARD + "str"):
                if not plain and node.tag in _IMPLICIT:  # an explicit !!int, !!float, ...
                    return _scalar(node.value)
                raise YamlError(f"the tag {node.tag!r} is not read in model files (only plain "
                                "values, lists and mappings)", line)
            return _scalar(node.value) if plain else node.value
        if isinstance(node, yaml.SequenceNode):
            self._check_tag(node, "seq", line)
            return [self.value(item, path + (k,)) for k, item in enumerate(node.value)]
        self._check_tag(node, "map", line)
        out: dict = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                raise YamlError("a key must be a plain name or number, not a list or mapping",
                                key_node.start_mark.line + 1)
            key = self.value(key_node, path + ("<key>",))
            key_line = key_node.start_mark.line + 1
            if key in out:
                raise YamlError(f"the key {key!r} appears twice in this mapping (lines "
                                f"{self.lines[path + (key,)]} and {key_line}); a later one "
                                "would silently replace the first", key_line)
            self.lines[path + (key,)] = key_line
            out[key] = self.value(value_node, path + (key,))
        self.lines.pop(path + ("<key>",), None)
        return out

    @staticmethod
    def _check_tag(node, kind: str, line: int) -> None:
        if node.tag != _STANDARD + kind:
            raise YamlError(f"the tag {node.tag!r} is not read in model files (only plain "
                            "values, lists and mappings)", line)


def load_value(text: str) -> Any:
    """One value written as in a model file (``2``, ``1e-10``, ``[1, 2]``, ``crank``), read
    the same way: what the command line's ``--set`` and ``--grid`` take."""
    return load_yaml(text)[0]
