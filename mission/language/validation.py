"""Turn pydantic's validation errors into located, readable diagnostics with "did you mean" hints."""

from __future__ import annotations

import difflib
import re
import types
import typing
from typing import Any

from pydantic import BaseModel, ValidationError

from mission.errors import Diagnostic
from mission.language.source import Located, PathKey


def dotted(path: PathKey) -> str:
    """`route[2].transit.depth` from ('route', 2, 'transit', 'depth')."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "the document"


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    origin = typing.get_origin(annotation)
    if origin is not None or isinstance(annotation, types.UnionType):
        for arg in typing.get_args(annotation):
            found.extend(_models_in(arg))
    return found


def _model_at(root: type[BaseModel], loc: tuple[Any, ...]) -> type[BaseModel] | None:
    """The model class whose fields apply at `loc` (union tags in `loc` pick the branch)."""
    current: list[type[BaseModel]] = [root]
    for part in loc:
        if isinstance(part, int):
            continue
        named = [m for m in current if m.__name__ == part]
        if named:
            current = named
            continue
        nxt: list[type[BaseModel]] = []
        for model in current:
            field = model.model_fields.get(str(part))
            if field is not None:
                nxt.extend(_models_in(field.annotation))
        if not nxt:
            return current[0] if len(current) == 1 else None
        current = nxt
    return current[0] if current else None


def _split_loc(data: Any, loc: tuple[Any, ...], error_type: str) -> tuple[PathKey, int | None, int, tuple[Any, ...]]:
    """Data path of an error location, where in it the last union tag stood (None: no tag), the depth reached
    after that tag (deeper means the branch that matched the value's shape), and the branch (`loc` up to the
    tag)."""
    path: list[str | int] = []
    site: int | None = None
    branch: tuple[Any, ...] = ()
    node = data
    for k, part in enumerate(loc):
        last = k == len(loc) - 1
        if isinstance(node, dict) and isinstance(part, str) and part in node:
            path.append(part)
            node = node[part]
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            path.append(part)
            node = node[part]
        elif last and error_type == "missing":
            path.append(part)
        else:
            site, branch = len(path), loc[:k + 1]
    depth = len(path) - site if site is not None else 0
    return tuple(path), site, depth, branch


def _message(error: dict[str, Any]) -> str:
    msg = str(error["msg"])
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix):]
    msg = re.sub(r"a valid dictionary or instance of \w+", "a mapping", msg)
    msg = msg.replace(" after validation", "")
    msg = msg[:1].lower() + msg[1:]
    if error["type"] not in ("missing", "extra_forbidden", "value_error") and "input" in error:
        value = error["input"]
        if not isinstance(value, (dict, list)):
            msg += f" (got {value!r})"
    return msg


def _literal_hint(errors: list[dict[str, Any]]) -> str:
    for err in errors:
        if err["type"] == "literal_error" and isinstance(err.get("input"), str):
            choices = re.findall(r"'([^']*)'", str(err.get("ctx", {}).get("expected", "")))
            close = difflib.get_close_matches(err["input"], choices, n=1, cutoff=0.6)
            if close:
                return f"; did you mean '{close[0]}'?"
    return ""


def _unknown_key(doc: Located, model: type[BaseModel], err: dict[str, Any], full: PathKey) -> Diagnostic:
    key = str(full[-1])
    parent = _model_at(model, tuple(err["loc"])[:-1])
    hint = ""
    if parent is not None:
        close = difflib.get_close_matches(key, list(parent.model_fields), n=1, cutoff=0.6)
        hint = f"; did you mean '{close[0]}'?" if close else f" (allowed: {', '.join(parent.model_fields)})"
    return doc.diagnostic(full, f"unknown key '{key}' in {dotted(full[:-1])}{hint}", key=True)


def diagnostics_from(exc: ValidationError, doc: Located, model: type[BaseModel],
                     base: PathKey = ()) -> list[Diagnostic]:
    """Located diagnostics for every error of a validation of `doc.data` at `base` against `model`."""
    data = doc.data
    for part in base:
        data = data[part]
    entries = []
    for raw in exc.errors():
        err: dict[str, Any] = dict(raw)
        path, site, depth, branch = _split_loc(data, tuple(err["loc"]), err["type"])
        entries.append((err, path, site, depth, branch))
    # Of a union's branches, keep the one that got furthest into the value (the shape the author meant), with
    # every error of that branch.
    deepest: dict[PathKey, int] = {}
    for _, path, site, depth, _ in entries:
        if site is not None:
            deepest[path[:site]] = max(deepest.get(path[:site], 0), depth)
    best = {(path[:site], branch) for _, path, site, depth, branch in entries
            if site is not None and depth == deepest[path[:site]]}
    grouped: dict[PathKey, list[dict[str, Any]]] = {}
    for err, path, site, _, branch in entries:
        if site is None or (path[:site], branch) in best:
            grouped.setdefault(path, []).append(err)
    out: list[Diagnostic] = []
    short: dict[PathKey, int] = {}
    for path, errs in grouped.items():
        full = base + path
        if len(errs) > 1 and all(e["type"] not in ("missing", "extra_forbidden") for e in errs):
            msgs = sorted({_message(e) for e in errs})
            out.append(doc.diagnostic(full, f"{dotted(full)}: {' or '.join(msgs)}{_literal_hint(errs)}"))
            continue
        for err in errs:
            if err["type"] == "extra_forbidden":
                out.append(_unknown_key(doc, model, err, full))
            elif err["type"] == "missing" and isinstance(path[-1], int):
                short[full[:-1]] = max(short.get(full[:-1], 0), path[-1] + 1)
            elif err["type"] == "missing":
                out.append(doc.diagnostic(full[:-1], f"missing required key '{path[-1]}' in {dotted(full[:-1])}"))
            else:
                out.append(doc.diagnostic(full, f"{dotted(full)}: {_message(err)}{_literal_hint([err])}"))
    for parent, needed in short.items():
        node = doc.data
        for part in parent:
            node = node[part]
        out.append(doc.diagnostic(parent, f"{dotted(parent)}: expected {needed} values, got {len(node)}"))
    return out


def validate_as(doc: Located, model: type[BaseModel], base: PathKey = ()) -> tuple[Any, list[Diagnostic]]:
    """Validate the part of a document at `base` against `model`; (instance or None, diagnostics)."""
    data = doc.data
    for part in base:
        data = data[part]
    try:
        return model.model_validate(data), []
    except ValidationError as exc:
        return None, diagnostics_from(exc, doc, model, base)
