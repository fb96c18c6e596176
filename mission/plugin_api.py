"""The perception plug-in contract (core types only: plug-ins import this module and nothing else of `mission`).

A plug-in is a class registered under the entry-point group `auv.perception`. The executive's plug-in host
makes one instance per mission and calls, in this order:

- `configure(settings)`: once, before the route starts; `settings` holds the mission's sensor settings and
  anything the plug-in needs (a mapping; unknown keys are to be ignored).
- `process(frame, request) -> result`: for each stereo frame an agent hands over; must return within the
  host's time budget. Raise on failure: the host turns exceptions and overruns into a logged fault and a
  "not recognised" result, and the mission goes on.
- `reset()`: between route elements (drop per-element state such as VO chains).
- `close()`: once, at the end (optional; the default does nothing).

Frames follow OpenCV: camera x right, y down, z along the optical axis; the left camera is the stereo frame.
`T_a_b` maps coordinates in frame b to frame a.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

Matrix = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class StereoImages:
    """A rectified stereo pair as the vehicle's cameras deliver it (no depth: perception never sees the truth)."""

    time: float
    left: NDArray[np.uint8]
    right: NDArray[np.uint8]
    K: Matrix  # 3×3 intrinsics of both rectified cameras
    baseline: float  # metres; the right camera sits at +baseline along the left camera's x-axis


@dataclass(frozen=True, eq=False)
class PointSetModel:
    """A characteristic-point set of a known object, in the object frame."""

    object_id: str
    set_id: str
    points: Matrix  # (N, 3)


@dataclass(frozen=True, eq=False)
class ReferencingRequest:
    """What an agent asks of a referencing plug-in: find one of these sets; the prior says where it should be."""

    sets: tuple[PointSetModel, ...]
    prior_T_cam_object: Matrix | None = None  # from the database pose and the navigation estimate
    tolerance: float = 0.05  # metres, pairwise-distance consistency
    prior_radius: float | None = None  # metres: how far the prior may be off; cloud points farther are ignored


@dataclass(frozen=True, eq=False)
class ReferencingResult:
    """The vehicle's camera referenced to an object, or not (fewer than 3 points identified)."""

    recognised: bool
    set_id: str | None = None
    T_cam_object: Matrix | None = None
    matched: int = 0
    residual_rms: float = float("nan")
    ambiguous: bool = False
    cloud_points: int = 0
    details: dict[str, Any] = field(default_factory=dict)
    model_points: Matrix | None = None  # (k, 3) identified characteristic points, object frame
    points_cam: Matrix | None = None  # (k, 3) the cloud points they were identified with, camera frame

    @staticmethod
    def not_recognised(reason: str = "", **details: Any) -> ReferencingResult:
        return ReferencingResult(False, details={"reason": reason, **details})


@dataclass(frozen=True)
class OdometryRequest:
    """What an agent asks of a visual-odometry plug-in with each frame.

    `set_origin` makes this frame the origin of a new chain (an agent does it on the frame it was referenced
    on, so that poses chain from that fix); the plug-in's first frame after `configure`/`reset` is an origin
    too. `altitude` and `speed` (when known, from the navigation estimate) let an adaptive method choose its
    step."""

    set_origin: bool = False
    altitude: float | None = None
    speed: float | None = None


@dataclass(frozen=True, eq=False)
class OdometryResult:
    """The left camera's pose relative to the chain's origin frame: `T_origin_cam` maps the current camera
    frame into the origin camera frame. `ok` is False while the plug-in has no estimate for this frame (tracking
    lost, or the frame skipped by an adaptive step); the last good pose then stays the agent's business."""

    ok: bool
    T_origin_cam: Matrix | None = None
    tracked: int = 0  # features supporting the estimate
    frames_processed: int = 0  # since the origin
    details: dict[str, Any] = field(default_factory=dict)

    @staticmethod
    def lost(reason: str = "", **details: Any) -> OdometryResult:
        return OdometryResult(False, details={"reason": reason, **details})


@runtime_checkable
class PerceptionPlugin(Protocol):
    """The four calls a perception plug-in implements (see the module docstring)."""

    def configure(self, settings: Mapping[str, Any]) -> None: ...

    def process(self, frame: StereoImages, request: Any) -> Any: ...

    def reset(self) -> None: ...

    def close(self) -> None: ...
