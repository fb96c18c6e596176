"""Claiming a run folder: what `--out` may name, `--force`, and the lock a run holds for its lifetime.

A run folder (`auv simulate`, `auv run`) or a campaign folder (`auv simulate --seeds`) carries the file `.auv-run`:
it says what wrote the folder, and a run holds an exclusive `fcntl.flock` on it while it writes there, so that a
second run into the same folder is refused. `claim_run_folder` refuses
- an existing path that is not a folder (a file, or a path below a file);
- a folder that holds the mission or its world (or one of their ancestors): a run would overwrite them;
- a folder in use by another run (its lock is held);
- a non-empty folder that is not a run folder, always; a run folder unless `force`, which then replaces the
  folder whole (removed, then created afresh: no stale files of the earlier run remain).
Every `OSError` on the way becomes a `RunFolderError` naming the path.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import IO

from mission.errors import RunFolderError

MARKER = ".auv-run"


def is_run_folder(folder: Path) -> bool:
    """A folder written by auv: the marker, or the files of an older run or campaign folder."""
    return (folder / MARKER).is_file() or (folder / "campaign.json").is_file() or (
        (folder / "mission.yaml").is_file() and (folder / "events.jsonl").is_file())


class RunLock:
    """The exclusive lock on a run folder's marker, held until `release` (or the process ends, even by kill -9)."""

    def __init__(self, folder: Path, file: IO[str]):
        self.folder = folder
        self._file: IO[str] | None = file

    def release(self) -> None:
        if self._file is not None:
            self._file.close()  # closing the descriptor releases the flock
            self._file = None

    def __enter__(self) -> RunLock:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _try_lock(folder: Path) -> IO[str] | None:
    """Open (creating) the folder's marker and lock it; None when another process holds the lock."""
    f = (folder / MARKER).open("a+", encoding="utf-8")
    try:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        f.close()
        return None
    return f


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def _refuse_protected(out: Path, resolved_out: Path, protected: Sequence[tuple[str, Path]]) -> None:
    for what, path in protected:
        if _inside(path.resolve().parent, resolved_out):
            raise RunFolderError(f"{out}: holds the {what} ({path}); a run folder must be a folder of its own")


def claim_run_folder(out: str | Path, kind: str, protected: Sequence[tuple[str, Path]] = (),
                     force: bool = False) -> RunLock:
    """Create (or, with `force`, replace) the run folder `out` and lock it for this run; see the module docstring.

    `protected` names files the run must never overwrite, e.g. `[("mission", mission_path)]`."""
    out = Path(out)
    try:
        return _claim(out, out.resolve(), kind, protected, force)
    except RunFolderError:
        raise
    except OSError as exc:
        raise RunFolderError(f"{out}: cannot be used as a run folder ({exc.strerror or exc})") from exc


def _claim(out: Path, resolved: Path, kind: str, protected: Sequence[tuple[str, Path]], force: bool) -> RunLock:
    _refuse_protected(out, resolved, protected)
    for parent in resolved.parents:
        if parent.exists() and not parent.is_dir():
            raise RunFolderError(f"{out}: {parent} is a file, not a folder")
    if out.exists() and not out.is_dir():
        raise RunFolderError(f"{out}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    lock = _try_lock(out) if (out / MARKER).exists() or not any(out.iterdir()) else None
    if lock is None and (out / MARKER).exists():
        raise RunFolderError(f"{out}: in use by another run (its lock is held); wait for it or choose another --out")
    others = [p for p in out.iterdir() if p.name != MARKER]
    if others and not is_run_folder(out):
        if lock is not None:
            lock.close()
        raise RunFolderError(f"{out}: not empty and not a run folder; choose a new or empty folder")
    if others and not force:
        if lock is not None:
            lock.close()
        raise RunFolderError(f"{out}: holds an earlier run; pass --force to replace it, or choose another --out")
    if others:
        if lock is None:  # an older run folder without a marker: nobody can be writing it under our lock
            lock = _try_lock(out)
            if lock is None:
                raise RunFolderError(f"{out}: in use by another run (its lock is held)")
        try:  # replaced whole, under the old lock: a racing claim finds the old lock held or the new one
            shutil.rmtree(out)
            out.mkdir()
        finally:
            lock.close()
        lock = _try_lock(out)
        if lock is None:
            raise RunFolderError(f"{out}: in use by another run (its lock is held)")
    assert lock is not None
    lock.seek(0)
    lock.truncate()
    lock.write(json.dumps({"written_by": kind, "pid": os.getpid()}) + "\n")
    lock.flush()
    return RunLock(out, lock)
