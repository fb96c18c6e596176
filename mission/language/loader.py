"""Load and validate mission and world files, reporting every problem at once as FILE:LINE:COL: message."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from mission.errors import Diagnostic, MissionError, PluginError
from mission.language.checks import Parts, cross_check
from mission.language.limits import MAX_DIAGNOSTICS
from mission.language.mesh_file import mesh_file_problem
from mission.language.models import (
    Home,
    KnownObject,
    Mission,
    Plugins,
    RouteElement,
    Safety,
    Sensors,
    VehicleSettings,
)
from mission.language.reading import UnreadableFile, read_bounded
from mission.language.source import Located, parse_yaml, read_yaml
from mission.language.timing import duration_warning
from mission.language.validation import validate_as
from mission.language.world import World
from mission.plugins import describe_installed, installed_plugins

T = TypeVar("T")
_NOTHING: tuple[Any, list[Diagnostic]] = (None, [])


def _guarded(doc: Located, check: Callable[[], T], fallback: T) -> T:
    """Run a check; an arithmetic error in it (a number too large or too small for the computation, which the
    schema's bounds should have refused) becomes a diagnostic of the file, never a traceback."""
    try:
        return check()
    except (ArithmeticError, ValueError) as exc:
        doc.problems.append(Diagnostic(doc.file, 1, 1, f"a number in this file cannot be used in the checks "
                                                       f"({type(exc).__name__}); check the values' magnitudes"))
        return fallback


def _capped(diags: list[Diagnostic]) -> list[Diagnostic]:
    """Every problem, sorted; past `MAX_DIAGNOSTICS`, the rest are counted in a last line."""
    ordered = sorted(set(diags), key=lambda d: (d.file, d.line, d.col, d.message))
    if len(ordered) <= MAX_DIAGNOSTICS:
        return ordered
    last = ordered[MAX_DIAGNOSTICS - 1]
    more = len(ordered) - MAX_DIAGNOSTICS
    return ordered[:MAX_DIAGNOSTICS] + [Diagnostic(last.file, last.line, last.col,
                                                   f"... and {more} more problem(s) not shown")]


def _mapping_document(doc: Located, what: str) -> list[Diagnostic]:
    if doc.problems and doc.data is None:
        return []
    if not isinstance(doc.data, dict):
        kind = type(doc.data).__name__ if doc.data is not None else "nothing"
        kind = {"list": "a list", "str": "a string", "int": "a number", "float": "a number"}.get(kind, kind)
        return [doc.diagnostic((), f"a {what} file must be a mapping of keys, but this document is {kind}")]
    return []


def _salvage(doc: Located, model: type[BaseModel], base: tuple[str | int, ...]) -> Any:
    """Validate a section; if some of its keys are bad, validate it again without them (using defaults), so
    that one mistake does not hide the cross-checks the rest of the section allows. None if even that fails."""
    value, _ = validate_as(doc, model, base)
    if value is not None:
        return value
    node = doc.data
    for part in base:
        node = node[part]
    if not isinstance(node, dict):
        return None
    try:
        model.model_validate(node)
    except ValidationError as exc:
        bad = {e["loc"][0] for e in exc.errors() if e["loc"]}
    else:  # pragma: no cover - validate_as just failed on the same input
        return None
    try:
        return model.model_validate({k: v for k, v in node.items() if k not in bad})
    except ValidationError:
        return None


def _parts(doc: Located) -> Parts:
    """Validate each section on its own, silently, so that cross-checks run on whatever is well-formed."""
    data: dict[str, Any] = doc.data
    parts = Parts()
    sections: tuple[tuple[str, type[BaseModel]], ...] = (
        ("safety", Safety), ("sensors", Sensors), ("plugins", Plugins), ("home", Home),
        ("vehicle", VehicleSettings))
    for key, model in sections:
        if key in data:
            setattr(parts, key, _salvage(doc, model, (key,)))
        else:
            setattr(parts, key, model())
    raw_objects = data.get("objects")
    if isinstance(raw_objects, list):
        parts.raw_object_ids = {str(o["id"]) for o in raw_objects if isinstance(o, dict) and "id" in o}
    lists: tuple[tuple[str, type[BaseModel], list[Any]], ...] = (
        ("objects", KnownObject, parts.objects), ("route", RouteElement, parts.route))
    for key, item_model, store in lists:
        items = data.get(key)
        if isinstance(items, list):
            for i in range(len(items)):
                value = _salvage(doc, item_model, (key, i))
                if value is not None:
                    store.append((i, value))
    return parts


def _check_plugins(doc: Located, plugins: Plugins | None) -> list[Diagnostic]:
    if plugins is None:
        return []
    try:
        installed = installed_plugins()
    except PluginError as exc:
        return [doc.diagnostic(("plugins",), str(exc))]
    out = []
    for role, name in plugins.model_dump().items():
        if name is not None and name not in installed:
            out.append(doc.diagnostic(("plugins", role), f"perception plug-in '{name}' ({role}) is not installed "
                                                         f"(installed: {describe_installed()})"))
    return out


def resolve_world_path(mission_file: Path, world: str) -> Path:
    path = Path(world).expanduser()
    return path if path.is_absolute() else (mission_file.parent / path).resolve()


def _validate_world_doc(doc: Located) -> tuple[World | None, list[Diagnostic]]:
    diags = list(doc.problems) + _mapping_document(doc, "world")
    if diags:
        return None, diags
    world, errs = _guarded(doc, lambda: validate_as(doc, World), _NOTHING)
    diags += errs + doc.problems
    if world is not None:
        ids = [o.id for o in world.objects]
        for i, obj in enumerate(world.objects):
            if ids.index(obj.id) != i:
                diags.append(doc.diagnostic(("objects", i, "id"), f"duplicate world object id '{obj.id}'"))
    return (world if not diags else None), diags


def validate_world_file(path: Path) -> tuple[World | None, list[Diagnostic]]:
    """Validate a world file."""
    return _validate_world_doc(read_yaml(path))


def _looks_like_world(doc: Located) -> bool:
    """Whether a parsed document is meant as a world: a mapping whose keys are mostly a world's. A file that
    does not parse counts as one (its syntax diagnostics quote none of it)."""
    if doc.data is None:
        return True
    if not isinstance(doc.data, dict) or not doc.data:
        return False
    known = sum(1 for key in doc.data if key in World.model_fields)
    return known > 0 and 2 * known >= len(doc.data)


def _check_world(doc: Located, path: Path, world: str) -> tuple[Path | None, list[Diagnostic]]:
    """The world file a mission names: its absolute path if it is usable, and its problems. A file that is not
    a world gets one diagnostic at the mission's `world:` key naming its path, never quoting its content."""
    world_path = resolve_world_path(path, world)
    if not world_path.exists() and not world_path.is_symlink():
        return None, [doc.diagnostic(("world",), f"world file '{world}' not found (looked at {world_path})")]
    try:
        text = read_bounded(world_path)
    except UnreadableFile as exc:
        return None, [doc.diagnostic(("world",), f"world file '{world}' cannot be used: {exc}")]
    world_doc = parse_yaml(text, str(world_path))
    if not _looks_like_world(world_doc):
        return None, [doc.diagnostic(("world",), f"'{world}' is not a world file (expected a mapping with "
                                                 f"`name` and `seabed`; looked at {world_path})")]
    _, diags = _validate_world_doc(world_doc)
    return world_path, diags


def _check_models(doc: Located, path: Path, environment: bool, field: str = "model"
                  ) -> tuple[dict[int, str], list[Diagnostic]]:
    """Files named by database objects (`objects[i].model`, a multi-view model, or `objects[i].mesh`, a surface
    mesh), resolved like `world`: the absolute paths by object index, and a located problem for each file that is
    missing or not of its kind."""
    objects = doc.data.get("objects")
    if not isinstance(objects, list):
        return {}, []
    kind, problem_of = ("mesh", mesh_file_problem) if field == "mesh" else ("model", model_file_problem)
    paths: dict[int, str] = {}
    diags: list[Diagnostic] = []
    for i, obj in enumerate(objects):
        model = obj.get(field) if isinstance(obj, dict) else None
        if not isinstance(model, str):
            continue
        model_path = resolve_world_path(path, model)
        if not environment:
            paths[i] = str(model_path)
        elif not model_path.exists() and not model_path.is_symlink():
            diags.append(doc.diagnostic(("objects", i, field),
                                        f"{kind} file '{model}' not found (looked at {model_path})"))
        else:
            problem = problem_of(model_path)
            if problem:
                diags.append(doc.diagnostic(("objects", i, field), f"{kind} file '{model}' is not usable: "
                                                                   f"{problem}"))
            paths[i] = str(model_path)
    return paths, diags


def model_file_problem(path: Path) -> str:
    """Why a multi-view model file cannot be used ('' when it can): unreadable, not YAML, or not a model; read
    under the same bounds as missions, and never quoting the file. Only the file's header is checked here; its
    views are read when a plug-in loads it."""
    try:
        model_doc = parse_yaml(read_bounded(path), str(path))
    except UnreadableFile as exc:
        return str(exc)
    if model_doc.data is None and model_doc.problems:
        first = model_doc.problems[0]
        return f"it is not a valid YAML document (line {first.line}, column {first.col})"
    data = model_doc.data
    expected = "auv-multiview-model/1"
    if not isinstance(data, dict) or data.get("format") != expected:
        return f"not a multi-view model (expected `format: {expected}`)"
    if not isinstance(data.get("views"), list) or not data["views"]:
        return "the model has no views"
    return ""


def validate_mission_file(path: str | Path, environment: bool = True) -> tuple[Mission | None, list[Diagnostic]]:
    """Validate a mission file completely; (the mission if it is valid, every problem found).

    With `environment=False` the checks of this machine (installed plug-ins, the world file) are skipped, as
    when a finished run's mission is read back.
    """
    path = Path(path)
    doc = read_yaml(path)
    diags = list(doc.problems) + _mapping_document(doc, "mission")
    if doc.data is None or not isinstance(doc.data, dict):
        return None, _capped(diags)
    parsed = len(doc.problems)
    mission, errs = _guarded(doc, lambda: validate_as(doc, Mission), _NOTHING)
    diags += errs
    parts = _guarded(doc, lambda: _parts(doc), Parts()) if mission is None else Parts(
        mission.safety, mission.sensors, mission.plugins, mission.home,
        list(enumerate(mission.objects)), list(enumerate(mission.route)), vehicle=mission.vehicle)
    diags += _guarded(doc, lambda: cross_check(doc, parts), list[Diagnostic]())
    diags += doc.problems[parsed:]
    if environment:
        diags += _check_plugins(doc, parts.plugins)
    world = doc.data.get("world")
    if isinstance(world, str) and environment:
        world_path, world_errs = _check_world(doc, path, world)
        diags += world_errs
        if mission is not None and world_path is not None:
            mission = mission.model_copy(update={"world": str(world_path)})
    elif isinstance(world, str) and mission is not None:
        world_path = resolve_world_path(path, world)
        mission = mission.model_copy(update={"world": str(world_path) if world_path.is_file() else None})
    for field in ("model", "mesh"):
        model_paths, model_diags = _check_models(doc, path, environment, field)
        diags += model_diags
        if mission is not None and model_paths:
            mission = mission.model_copy(update={"objects": [
                o.model_copy(update={field: model_paths[i]}) if i in model_paths else o
                for i, o in enumerate(mission.objects)]})
    if mission is not None:
        mission._source = str(path)
    errors = [d for d in diags if not d.warning]
    if mission is not None and not errors:
        valid = mission
        diags += _guarded(doc, lambda: duration_warning(doc, valid), list[Diagnostic]())
    return (mission if not errors else None), _capped(diags)


def load_mission(path: str | Path, environment: bool = True) -> Mission:
    """Load a mission, raising MissionError with every problem if it is not valid (warnings alone do not stop
    it: `validate_mission_file` reports them)."""
    mission, diags = validate_mission_file(path, environment)
    if mission is None:
        raise MissionError([d for d in diags if not d.warning])
    return mission


def load_world(path: str | Path) -> World:
    world, diags = validate_world_file(Path(path))
    if diags or world is None:
        raise MissionError(diags)
    return world


def mission_schema() -> dict[str, Any]:
    """JSON Schema of mission language v1, for editors."""
    schema = Mission.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "auv-mission: mission language v1"
    return schema


def mission_schema_json() -> str:
    return json.dumps(mission_schema(), indent=2)
