"""Where agents keep what a mission produces besides events and metrics: photographs and their records.

The executive hands agents an `Artifacts` store. The simulator's store writes into the run folder as things
happen (nothing waits for the end of the run); without a folder it only counts, so tests and benchmarks run
without disk traffic. A vehicle adapter can supply any store with the same two calls.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray


class Artifacts:
    """A folder-backed store (or a counting one when `root` is None)."""

    def __init__(self, root: Path | str | None = None):
        self.root = Path(root) if root is not None else None
        self.images = 0
        self.records = 0

    def save_image(self, relpath: str, image: NDArray[np.uint8]) -> str:
        """Write an 8-bit image (PNG by the name's suffix) under the root; returns the relative path."""
        self.images += 1
        if self.root is not None:
            import cv2

            path = self.root / relpath
            path.parent.mkdir(parents=True, exist_ok=True)
            if not cv2.imwrite(str(path), image):
                raise OSError(f"could not write {path}")
        return relpath

    def append_record(self, relpath: str, record: dict[str, Any]) -> None:
        """Append one JSON line to a file under the root (flushed at once)."""
        self.records += 1
        if self.root is not None:
            path = self.root / relpath
            path.parent.mkdir(parents=True, exist_ok=True)
            with path.open("a", encoding="utf-8") as f:
                f.write(json.dumps(record, default=_plain) + "\n")


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
