"""What the vehicle has learnt during a mission, kept at the strategic level (seed 002 §1: the onboard database
holds the objects; route elements add to it): objects detected by surveys, maps built by agents.

Agents write here and later agents read from here (a survey's unknown detections feed `explore: detected`).
Everything in it is estimated: it is built from the navigation estimate and sensor data, never from the truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class DetectedObject:
    """An object found by a survey, in world coordinates (NED metres, degrees)."""

    id: str
    north: float
    east: float
    length: float
    width: float
    height: float
    heading_deg: float
    depth: float
    database_id: str | None
    element: str


@dataclass
class Knowledge:
    detections: list[DetectedObject] = field(default_factory=list)
    maps: dict[str, dict[str, Any]] = field(default_factory=dict)

    def unknown_objects(self) -> list[DetectedObject]:
        """Detected objects the database lacks (the `explore: {object: detected}` targets)."""
        return [d for d in self.detections if d.database_id is None]
