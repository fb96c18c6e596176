"""Run folders: one writer and one reader for the files `auv simulate` and `auv run` leave behind.

    DIR/mission.yaml      the mission as run (seed filled in, world pointing at the copy beside it)
    DIR/world.yaml        the world the run used
    DIR/trajectory.csv    time, true and estimated pose, altitude, per control step (`auv run` knows no truth:
                          its true columns stay empty until `auv score` fills them from the simulator's)
    DIR/usbl.csv          acoustic fixes: time, north, east, used, accepted
    DIR/events.jsonl      events, flushed as they happened
    DIR/metrics.json      the run's metrics, written last: the folder's end marker (`check_complete`)
    DIR/maps/ELEMENT.npz  maps an element with the `map` action built (survey: depth, info, north0, east0, cell,
                          lines)
    DIR/photos/           photographs of photo surveys (`mission.sim.photos`); inspections' under their element
    DIR/stereo/ELEMENT/   stereo pairs of an element with the `record` or `model` action (KITTI layout, estimated
                          poses: `mission.stereo_recording`)
    DIR/plots/*.png       figures (`auv plot DIR` redraws them)
    DIR/.auv-run          the marker, locked while a run writes the folder (`mission.runlock`)

Files written at the end are written whole or not at all (`write_atomic`); an `OSError` becomes `RunFolderError`.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import time
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
import yaml

from mission.errors import MissionError, RunFolderError
from mission.events import read_events
from mission.knowledge import Knowledge
from mission.language.loader import load_mission
from mission.language.models import Mission
from mission.runlock import RunLock, claim_run_folder

TRAJECTORY_COLUMNS = (
    "time", "north", "east", "depth", "heading", "altitude",
    "north_est", "east_est", "depth_est", "heading_est", "altitude_est",
    "position_sigma", "speed", "energy_wh", "element",
)
FLUSH_S = 1.0  # a streamed file is flushed at least this often (wall time): a killed run loses at most this


def _cell(value: object) -> object:
    if isinstance(value, float):
        return f"{value:.4f}" if math.isfinite(value) else ""
    return "" if value is None else value


class TrajectoryWriter:
    """trajectory.csv written as the run goes: a row per control tick, flushed at least every `FLUSH_S`."""

    def __init__(self, path: Path, columns: Sequence[str] = TRAJECTORY_COLUMNS):
        self.path = path
        try:
            self._file: IO[str] | None = path.open("w", newline="", encoding="utf-8")
            self._csv = csv.writer(self._file)
            self._csv.writerow(columns)
            self._file.flush()
        except OSError as exc:
            raise RunFolderError(f"{path}: cannot write ({exc.strerror or exc})") from exc
        self._flushed = time.monotonic()

    def write(self, row: Iterable[object]) -> None:
        if self._file is None:
            return
        try:
            self._csv.writerow([_cell(v) for v in row])
            if time.monotonic() - self._flushed >= FLUSH_S:
                self._file.flush()
                self._flushed = time.monotonic()
        except OSError as exc:
            raise RunFolderError(f"{self.path}: cannot write ({exc.strerror or exc})") from exc

    def close(self) -> None:
        if self._file is not None:
            try:
                self._file.close()
            except OSError as exc:
                raise RunFolderError(f"{self.path}: cannot write ({exc.strerror or exc})") from exc
            finally:
                self._file = None


def write_atomic(path: Path, data: str | bytes) -> None:
    """Write a file whole or not at all: a temporary file beside it, renamed over it (`RunFolderError` on failure)."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        if isinstance(data, bytes):
            tmp.write_bytes(data)
        else:
            tmp.write_text(data, encoding="utf-8")
        os.replace(tmp, path)
    except OSError as exc:
        raise RunFolderError(f"{path}: cannot write ({exc.strerror or exc})") from exc


def prepare_run_folder(out: Path, mission: Mission, seed: int, force: bool = False,
                       kind: str = "auv simulate") -> RunLock:
    """Claim the folder for this run (`mission.runlock`: refusals, `force`, the lock, returned to be held for the
    run's lifetime) and write the mission as run and its world, before the run starts."""
    protected = [("mission", Path(mission.source))] if mission.source else []
    if mission.world is not None:
        protected.append(("world", Path(mission.world)))
    lock = claim_run_folder(out, kind, protected, force)
    try:
        as_run = mission.model_dump(mode="json")
        as_run["seed"] = seed
        if mission.world is not None:
            try:
                world_text = Path(mission.world).read_bytes()
            except OSError as exc:
                raise RunFolderError(f"{mission.world}: cannot read the world ({exc.strerror or exc})") from exc
            write_atomic(out / "world.yaml", world_text)
            as_run["world"] = "world.yaml"
        header = f"# The mission as run (seed {seed}), from {mission.source or 'memory'}.\n"
        write_atomic(out / "mission.yaml", header + yaml.safe_dump(as_run, sort_keys=False))
    except BaseException:
        lock.release()
        raise
    return lock


def write_trajectory(out: Path, rows: Iterable[Sequence[object]]) -> None:
    """trajectory.csv written whole (a temporary file renamed over it)."""
    tmp = out / "trajectory.csv.tmp"
    writer = TrajectoryWriter(tmp)
    for row in rows:
        writer.write(row)
    writer.close()
    try:
        os.replace(tmp, out / "trajectory.csv")
    except OSError as exc:
        raise RunFolderError(f"{out / 'trajectory.csv'}: cannot write ({exc.strerror or exc})") from exc


def write_usbl(out: Path, fixes: Iterable[Any]) -> None:
    """usbl.csv from fixes with time, north, east, used, accepted (written whole or not at all)."""
    text = io.StringIO(newline="")
    w = csv.writer(text)
    w.writerow(("time", "north", "east", "used", "accepted"))
    for fix in fixes:
        w.writerow((f"{fix.time:.2f}", f"{fix.north:.3f}", f"{fix.east:.3f}", int(fix.used), int(fix.accepted)))
    write_atomic(out / "usbl.csv", text.getvalue())


def write_metrics(out: Path, metrics: dict[str, Any]) -> None:
    """metrics.json, written whole or not at all (a temporary file renamed over the old one)."""
    write_atomic(out / "metrics.json", json.dumps(metrics, indent=2) + "\n")


def write_run_results(out: Path, metrics: dict[str, Any], rows: Iterable[Sequence[object]] | None, fixes: Iterable[Any],
                      knowledge: Knowledge | None = None, maps_for: Collection[str] | None = None) -> None:
    """The results of a run at its end; `metrics.json`, written last, marks the folder complete (`rows`: the
    trajectory when it was not streamed as the run went, None when it was). The maps of the elements in
    `maps_for` (those with the `map` action; every element's when None) go to `maps/ELEMENT.npz`."""
    if rows is not None:
        write_trajectory(out, rows)
    write_usbl(out, fixes)
    if knowledge is not None and knowledge.maps:
        for element, products in knowledge.maps.items():
            if maps_for is not None and element not in maps_for:
                continue
            arrays = {k: np.asarray(v) for k, v in products.items() if k != "lines"}
            lines = np.asarray(products.get("lines", []), dtype=float).reshape(-1, 2, 2)
            arrays["lines"] = lines
            buffer = io.BytesIO()
            np.savez_compressed(buffer, **arrays)  # type: ignore[arg-type]
            try:
                (out / "maps").mkdir(exist_ok=True)
            except OSError as exc:
                raise RunFolderError(f"{out / 'maps'}: cannot create ({exc.strerror or exc})") from exc
            write_atomic(out / "maps" / f"{element}.npz", buffer.getvalue())
    write_metrics(out, metrics)


@dataclass
class RunData:
    """A run folder read back: everything the plots need."""

    folder: Path
    mission: Mission
    trajectory: dict[str, np.ndarray]
    elements: list[str]
    fixes: dict[str, np.ndarray]
    events: list[dict[str, Any]]
    metrics: dict[str, Any]
    maps: dict[str, dict[str, np.ndarray]]


def read_csv(path: Path, text_columns: tuple[str, ...] = ()) -> tuple[dict[str, np.ndarray], dict[str, list[str]]]:
    """A CSV file with a header line: numeric columns as arrays (empty cells NaN), `text_columns` as strings."""
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except OSError as exc:
        raise RunFolderError(f"{path}: cannot read ({exc.strerror})") from exc
    if not rows:
        raise RunFolderError(f"{path}: empty; expected a header line")
    header, body = rows[0], rows[1:]
    numeric, text = {}, {}
    for k, name in enumerate(header):
        values = [r[k] if k < len(r) else "" for r in body]
        if name in text_columns:
            text[name] = values
            continue
        try:
            numeric[name] = np.array([float(v) if v != "" else np.nan for v in values])
        except ValueError as exc:
            raise RunFolderError(f"{path}: column '{name}' holds a non-number ({exc})") from exc
    return numeric, text


def check_complete(folder: Path) -> None:
    """Raise `RunFolderError` in one line unless the folder holds a finished (or cleanly interrupted) run: its
    `metrics.json`, written last, is the end marker."""
    if not folder.is_dir():
        raise RunFolderError(f"{folder}: not a run folder (no such directory)")
    if not (folder / "metrics.json").is_file():
        if (folder / "events.jsonl").is_file() or (folder / "trajectory.csv").is_file():
            raise RunFolderError(f"{folder}: incomplete run folder (no metrics.json: the run was killed, or is still "
                                 "running)")
        raise RunFolderError(f"{folder}: not a complete run folder (missing metrics.json)")


def read_run_folder(folder: str | Path) -> RunData:
    """Read a run folder written by `auv simulate` (RunFolderError says what is missing or malformed)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise RunFolderError(f"{folder}: not a run folder (no such directory)")
    check_complete(folder)
    for name in ("mission.yaml", "trajectory.csv", "events.jsonl"):
        if not (folder / name).is_file():
            raise RunFolderError(f"{folder}: not a complete run folder (missing {name})")
    try:  # a finished run is read as it was: installed plug-ins and the world file no longer matter
        mission = load_mission(folder / "mission.yaml", environment=False)
    except MissionError as exc:
        raise RunFolderError(f"{folder}/mission.yaml is not a valid mission:\n{exc}") from exc
    traj, text = read_csv(folder / "trajectory.csv", ("element",))
    missing = [c for c in TRAJECTORY_COLUMNS if c not in traj and c not in text]
    if missing:
        raise RunFolderError(f"{folder}/trajectory.csv lacks column(s) {', '.join(missing)}")
    fixes: dict[str, np.ndarray] = {}
    if (folder / "usbl.csv").is_file():
        fixes, _ = read_csv(folder / "usbl.csv")
    try:
        metrics = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise RunFolderError(f"{folder}/metrics.json: not JSON ({exc})") from exc
    maps: dict[str, dict[str, np.ndarray]] = {}
    for path in sorted((folder / "maps").glob("*.npz")):
        try:
            with np.load(path) as data:
                maps[path.stem] = {k: data[k] for k in data.files}
        except (OSError, ValueError) as exc:
            raise RunFolderError(f"{path}: not a map archive ({exc})") from exc
    return RunData(folder, mission, traj, text["element"], fixes, read_events(folder / "events.jsonl"), metrics,
                   maps)
