"""Scoring a run against the truth, from arrays: the navigation error of the estimate, and each element's true
track (path length, lowest altitude, where a transit truly ended). `auv simulate` scores with the simulator's log;
`auv score RUN_DIR --truth DIR` scores an `auv run` against what `auv sim serve --out DIR` kept, with these same
functions and under the same `metrics.json` keys.

>>> t = np.array([0.0, 1.0, 2.0])
>>> nav = navigation_errors(np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 3.0, 4.0]), np.zeros(3),
...                         np.zeros(3))
>>> nav["position_error_rms_m"], nav["position_error_max_m"], nav["position_error_final_m"]
(2.887, 4.0, 4.0)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ElementSpan:
    """Where an element ran on the vehicle's clock, and the transit goal (north, east) if it had one."""

    id: str
    start_time: float
    end_time: float
    goal: tuple[float, float] | None = None


def navigation_errors(north: Array, east: Array, depth: Array, north_est: Array, east_est: Array,
                      depth_est: Array) -> dict[str, float]:
    """RMS, maximum and final horizontal error of the estimate, and the depth error's RMS (metres)."""
    err = np.hypot(north_est - north, east_est - east)
    if not len(err):
        return {"position_error_rms_m": 0.0, "position_error_max_m": 0.0, "position_error_final_m": 0.0,
                "depth_error_rms_m": 0.0}
    return {
        "position_error_rms_m": round(float(np.sqrt(np.mean(err**2))), 3),
        "position_error_max_m": round(float(err.max()), 3),
        "position_error_final_m": round(float(err[-1]), 3),
        "depth_error_rms_m": round(float(np.sqrt(np.mean((depth_est - depth) ** 2))), 3),
    }


def track_metrics(span: ElementSpan, times: Array, north: Array, east: Array, altitude: Array) -> dict[str, Any]:
    """An element's true track: path length, lowest true altitude, and for a transit the end position error."""
    item: dict[str, Any] = {}
    if not len(times) or not math.isfinite(span.end_time):
        return item
    if span.goal is not None:
        k = min(int(np.searchsorted(times, span.end_time)), len(times) - 1)
        item["goal"] = [round(span.goal[0], 3), round(span.goal[1], 3)]
        item["end_position_error_m"] = round(math.hypot(north[k] - span.goal[0], east[k] - span.goal[1]), 3)
    step = np.hypot(np.diff(north, prepend=north[:1]), np.diff(east, prepend=east[:1]))
    window = (times > span.start_time) & (times <= span.end_time)
    item["path_length_m"] = round(float(step[window].sum()), 2)
    finite = window & np.isfinite(altitude)
    if finite.any():  # the true altitude above whatever lies below (seabed or object)
        item["min_altitude_m"] = round(float(altitude[finite].min()), 3)
    return item


def resample(times: Array, at: Array, values: Array, angle: bool = False) -> Array:
    """`values` sampled at `times`, linearly interpolated at `at` (headings in degrees unwrapped first).

    >>> resample(np.array([0.0, 1.0]), np.array([0.5]), np.array([350.0, 10.0]), angle=True).tolist()
    [0.0]
    """
    if angle:
        return np.asarray(np.interp(at, times, np.degrees(np.unwrap(np.radians(values)))) % 360.0)
    return np.interp(at, times, values)


def path_length(north: Sequence[float], east: Sequence[float], depth: Sequence[float]) -> float:
    """3-D length of a sampled track (metres)."""
    n, e, d = (np.asarray(v, dtype=float) for v in (north, east, depth))
    return float(np.sqrt(np.diff(n) ** 2 + np.diff(e) ** 2 + np.diff(d) ** 2).sum()) if len(n) > 1 else 0.0
