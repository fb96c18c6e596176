"""YAML documents with the location of every node, so that each error can say FILE:LINE:COL.

PyYAML's safe composer gives nodes with marks; this module turns them into plain Python values and a table
from value paths (tuples of keys and indices) to 1-based (line, col) positions. Duplicate keys are reported,
not silently overwritten.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from mission.errors import Diagnostic
from mission.language.composer import LimitExceeded, compose_bounded
from mission.language.reading import UnreadableFile, read_bounded

PathKey = tuple[str | int, ...]


@dataclass
class Located:
    """A parsed YAML document: plain values plus where each path sits in the file."""

    file: str
    data: Any
    value_at: dict[PathKey, tuple[int, int]] = field(default_factory=dict)
    key_at: dict[PathKey, tuple[int, int]] = field(default_factory=dict)
    problems: list[Diagnostic] = field(default_factory=list)

    def where(self, path: PathKey, *, key: bool = False) -> tuple[int, int]:
        """Position of the node at `path` (its key if `key`), falling back to the nearest ancestor."""
        table = self.key_at if key else self.value_at
        probe = tuple(path)
        while probe:
            if probe in table:
                return table[probe]
            if probe in self.value_at:
                return self.value_at[probe]
            probe = probe[:-1]
        return self.value_at.get((), (1, 1))

    def diagnostic(self, path: PathKey, message: str, *, key: bool = False) -> Diagnostic:
        line, col = self.where(path, key=key)
        return Diagnostic(self.file, line, col, message)


def _position(node: yaml.Node) -> tuple[int, int]:
    return node.start_mark.line + 1, node.start_mark.column + 1


def _scalar(scalars: yaml.constructor.SafeConstructor, node: yaml.Node) -> Any:
    try:
        return scalars.construct_object(node)
    except (ValueError, OverflowError) as exc:  # e.g. a timestamp with a month 13
        raise yaml.constructor.ConstructorError(None, None, f"this value cannot be read ({type(exc).__name__})",
                                                node.start_mark) from None


def _build(doc: Located, node: yaml.Node, path: PathKey, scalars: yaml.constructor.SafeConstructor) -> Any:
    doc.value_at[path] = _position(node)
    if isinstance(node, yaml.MappingNode):
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = _build(doc, key_node, path + ("<key>",), scalars)
            if not isinstance(key, (str, int, float, bool)) or key is None:
                doc.problems.append(Diagnostic(doc.file, *_position(key_node),
                                               "a mapping key must be a string or a number"))
                continue
            key = str(key) if not isinstance(key, str) else key
            if key in out:
                first = doc.key_at[path + (key,)][0]
                doc.problems.append(
                    Diagnostic(doc.file, *_position(key_node), f"duplicate key '{key}' (first on line {first})"))
                continue
            doc.key_at[path + (key,)] = _position(key_node)
            out[key] = _build(doc, value_node, path + (key,), scalars)
        doc.value_at.pop(path + ("<key>",), None)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_build(doc, item, path + (i,), scalars) for i, item in enumerate(node.value)]
    return _scalar(scalars, node)


def _syntax_diagnostic(exc: yaml.MarkedYAMLError, file: str) -> Diagnostic:
    """Locate a syntax error where the reader can fix it: an unclosed bracket at the bracket itself."""
    problem, context = exc.problem or "", exc.context or ""
    pm, cm = exc.problem_mark, exc.context_mark
    if "flow" in context and cm is not None:
        opener = "{" if "mapping" in context else "["
        where = f" (line {pm.line + 1}, column {pm.column + 1})" if pm is not None else ""
        return Diagnostic(file, cm.line + 1, cm.column + 1,
                          f"YAML syntax error: this '{opener}' is never closed: {problem}{where}")
    message = f"YAML syntax error: {problem}"
    if context:
        message += f" ({context})"
    if "<block end>" in problem or "mapping values are not allowed" in problem:
        message += "; check the indentation"
    if "tab" in problem:
        message += "; indent with spaces, not tabs"
    mark = pm or cm
    line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
    return Diagnostic(file, line, col, message)


def _position_of(text: str, index: int) -> tuple[int, int]:
    """1-based line and column of a character index."""
    index = max(0, min(index, len(text)))
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def parse_yaml(text: str, file: str) -> Located:
    """Parse one YAML document under the limits of `mission.language.limits`; every failure becomes a located
    diagnostic, never an exception."""
    doc = Located(file=file, data=None)
    try:
        node = compose_bounded(text)
    except LimitExceeded as exc:
        mark = exc.problem_mark
        line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
        doc.problems.append(Diagnostic(file, line, col, f"document refused: {exc.problem}"))
        return doc
    except yaml.MarkedYAMLError as exc:
        doc.problems.append(_syntax_diagnostic(exc, file))
        return doc
    except yaml.reader.ReaderError as exc:
        line, col = _position_of(text, exc.position)
        doc.problems.append(Diagnostic(file, line, col, f"YAML error: character {exc.character!r} is not allowed "
                                                        f"in a YAML document ({exc.reason})"))
        return doc
    except yaml.YAMLError as exc:
        doc.problems.append(Diagnostic(file, 1, 1, f"YAML error: {type(exc).__name__}"))
        return doc
    if node is None:
        doc.problems.append(Diagnostic(file, 1, 1, "the document is empty; expected a mapping"))
        return doc
    try:
        doc.data = _build(doc, node, (), yaml.constructor.SafeConstructor())
    except yaml.constructor.ConstructorError as exc:
        mark = exc.problem_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        problem = str(exc.problem)
        if "merge" in problem:
            problem = "YAML merge keys (<<) are not supported in missions; write the keys out"
        doc.problems.append(Diagnostic(file, line, col, f"YAML error: {problem}"))
    return doc


def read_yaml(path: Path) -> Located:
    """Read (under `mission.language.reading`'s bounds) and parse a YAML file; a file that cannot or may not be
    read is one diagnostic at 1:1."""
    try:
        text = read_bounded(path)
    except UnreadableFile as exc:
        doc = Located(file=str(path), data=None)
        doc.problems.append(Diagnostic(str(path), 1, 1, f"cannot read the file: {exc}"))
        return doc
    return parse_yaml(text, str(path))
