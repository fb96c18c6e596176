"""Turn pydantic's validation errors into located, readable diagnostics with "did you mean" hints."""

from __future__ import annotations

import difflib
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


def _split_loc(data: Any, loc: tuple[Any, ...], error_type: str) -> tuple[PathKey, bool, int]:
    """Data path of an error location, whether a union tag was passed, and the depth after the last tag."""
    path: list[str | int] = []
    tagged, after_tag = False, 0
    node = data
    for k, part in enumerate(loc):
        last = k == len(loc) - 1
        if isinstance(node, dict) and isinstance(part, str) and part in node:
            path.append(part)
            node = node[part]
            after_tag += 1
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            path.append(part)
            node = node[part]
            after_tag += 1
        elif last and error_type == "missing":
            path.append(part)
            after_tag += 1
        else:
            tagged, after_tag = True, 0
    return tuple(path), tagged, after_tag


def _message(error: dict[str, Any]) -> str:
    msg = str(error["msg"])
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix):]
    msg = msg[:1].lower() + msg[1:]
    if error["type"] not in ("missing", "extra_forbidden", "value_error") and "input" in error:
        value = error["input"]
        if not isinstance(value, (dict, list)):
            msg += f" (got {value!r})"
    return msg


def diagnostics_from(exc: ValidationError, doc: Located, model: type[BaseModel],
                     base: PathKey = ()) -> list[Diagnostic]:
    """Located diagnostics for every error of a validation of `doc.data` at `base` against `model`."""
    data = doc.data
    for part in base:
        data = data[part]
    grouped: dict[PathKey, list[tuple[dict[str, Any], bool, int]]] = {}
    for raw in exc.errors():
        err: dict[str, Any] = dict(raw)
        path, tagged, depth = _split_loc(data, tuple(err["loc"]), err["type"])
        grouped.setdefault(path, []).append((err, tagged, depth))
    out: list[Diagnostic] = []
    for path, errs in grouped.items():
        deepest = max(depth for _, tagged, depth in errs if tagged) if any(t for _, t, _ in errs) else 0
        chosen = [e for e, tagged, depth in errs if not tagged or depth == deepest]
        if len(chosen) > 1 and all(t for _, t, _ in errs):
            msgs = sorted({_message(e) for e in chosen})
            chosen = [{**chosen[0], "msg": " or ".join(msgs), "type": "union"}]
        for err in chosen:
            full = base + path
            where = dotted(full)
            if err["type"] == "extra_forbidden":
                key = str(path[-1])
                parent = _model_at(model, tuple(err["loc"])[:-1])
                hint = ""
                if parent is not None:
                    close = difflib.get_close_matches(key, list(parent.model_fields), n=1, cutoff=0.6)
                    if close:
                        hint = f"; did you mean '{close[0]}'?"
                    else:
                        hint = f" (allowed: {', '.join(parent.model_fields)})"
                out.append(doc.diagnostic(full, f"unknown key '{key}' in {dotted(full[:-1])}{hint}", key=True))
            elif err["type"] == "missing":
                out.append(doc.diagnostic(full[:-1], f"missing required key '{path[-1]}' in {dotted(full[:-1])}"))
            else:
                msg = err["msg"] if err["type"] == "union" else _message(err)
                out.append(doc.diagnostic(full, f"{where}: {msg}"))
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
