"""Where the inspect agent views a point set from (seed 002 §3.3, seed 000's experiments): the altitudes at which
a set is wholly in view and inside the stereo range, the hover poses over it (image x along the object; a tilted
camera looks at the same point from the same range, from behind it), the fine views' heights and shifts, and how
closely views taken there must agree."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mission.agents.hover import Goal
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.search import pattern_offsets, search_order
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.viewpoint import optical_axis
from mission.frames import camera_pose
from mission.geometry import transform_points
from mission.language.mount import DOWN_DEG


def fit_altitude(points: np.ndarray, field: tuple[float, float], fill: float = 0.75) -> float:
    """The range from a down-looking camera at which a point set (object frame, z down) fits in `fill` of the
    image, its longer horizontal side along the image's width; `field` is the image's (width, height) at unit
    range. Seed 002's fine views need the whole set: a set cut by the image's edge is not recognised.

    >>> round(fit_altitude(np.array([[0, 0, 0], [5, 0, 0], [5, 1.5, 0]]), (1.2, 0.9)), 3)  # 5 m / (0.75 · 1.2)
    5.556
    """
    extent = np.sort(np.ptp(np.asarray(points, dtype=float)[:, :2], axis=0))[::-1]
    return float(max(extent[0] / (fill * field[0]), extent[1] / (fill * field[1])))


class SetViewer:
    """Views of an object's point sets (object frame, z down) for a down-looking stereo camera whose image spans
    `field` (width, height) at unit range and sees up to `max_range`."""

    def __init__(self, sets: Mapping[str, np.ndarray], field: tuple[float, float], max_range: float,
                 settings: InspectSettings):
        self.sets = sets
        self.field = field
        self.max_range = max_range
        self.settings = settings

    def range_ceiling(self, set_id: str) -> float:
        """The highest view above a set's top that keeps its deepest point inside the stereo range."""
        return self.max_range - float(np.ptp(self.sets[set_id][:, 2])) - self.settings.range_margin_m

    def fit_altitude(self, set_id: str, fill: float | None = None) -> float:
        """How high above a set's top the whole set is in view in `fill` of the image (`fit_altitude`; default
        the search's `view_fill`), no lower than the fine altitude, and its deepest point inside the stereo range."""
        s = self.settings
        fit = fit_altitude(self.sets[set_id], self.field, s.view_fill if fill is None else fill)
        return min(max(s.fine_altitude_m, fit), self.range_ceiling(set_id))

    def search_altitude(self, set_id: str) -> float:
        """Searching, a little above the fine view: a wider field for the larger position uncertainty."""
        s = self.settings
        return float(min(max(s.search_altitude_m, self.fit_altitude(set_id) + s.search_raise_m),
                         self.range_ceiling(set_id) - s.search_raise_m))

    def agreement(self, set_id: str) -> float:
        """How closely views of a set must agree: the view agreement at the seed's 3.6 m, growing with the fine
        views' range like the stereo depth error (σ_Z ∝ Z²), as the plug-in's own tolerance does."""
        s = self.settings
        pts = self.sets[set_id]
        reach = (self.fit_altitude(set_id, s.fine_view_fill) + s.fine_steps_m[len(s.fine_steps_m) // 2]
                 + float(np.ptp(pts[:, 2])))
        return s.view_agreement_m * max(1.0, (reach / s.fine_altitude_m) ** 2)

    @staticmethod
    def camera_goal(place: Placement, camera_world: np.ndarray, heading: float) -> Goal:
        """The hover pose that puts the left camera at `camera_world` with the vehicle at `heading`."""
        offset = camera_pose(0.0, 0.0, 0.0, heading, baseline=place.baseline)[:3, 3]
        body = camera_world - offset
        return Goal(float(body[0]), float(body[1]), float(body[2]), heading)

    def over_set(self, place: Placement, set_id: str, altitude: float, shift: tuple[float, float] = (0.0, 0.0),
                 along_set: bool = False) -> Goal:
        """Hover over a set's centroid (as placed now) at `altitude` above its top, aligned with the object
        (seed 002 §3.3): the image's long side (camera x) along the object's x-axis, or with `along_set` along the
        object's axis on which the set is longer (searching, so that the whole set fits)."""
        pts = transform_points(place.T_wo, self.sets[set_id])
        centre = pts.mean(axis=0)
        camera = np.array([centre[0] + shift[0], centre[1] + shift[1], float(pts[:, 2].min()) - altitude])
        extent = np.ptp(self.sets[set_id][:, :2], axis=0)
        along_x = extent[0] >= extent[1] or not along_set
        heading = (place.heading() - (90.0 if along_x else 0.0)) % 360.0
        if place.tilt_deg != DOWN_DEG:  # a tilted camera looks at the same point from the same range
            camera = camera + altitude * (np.array([0.0, 0.0, 1.0]) - optical_axis(heading, place.tilt_deg))
        return self.camera_goal(place, camera, heading)

    def fine_goal(self, place: Placement, set_id: str, k: int) -> Goal:
        """The `k`-th fine view over a set: from where the whole set is in view (`fit_altitude` with the fine
        views' fill, the image's long
        side along the set's longer axis: a skid set spans the skid's 5 m width, and seen at 3.6 m with the image
        across it, two of its five points were out of every fine view), its height cycling through the fine steps,
        moving the fine shift back and forth along the object's x-axis (fresh image noise and corners each time)."""
        s = self.settings
        shift = s.fine_shift_m * (1 if k % 2 else -1) if k else 0.0
        x_axis = place.T_wo[:3, 0]
        altitude = min(self.fit_altitude(set_id, s.fine_view_fill) + s.fine_steps_m[k % len(s.fine_steps_m)],
                       self.range_ceiling(set_id))
        return self.over_set(place, set_id, altitude, (shift * float(x_axis[0]), shift * float(x_axis[1])),
                             along_set=True)

    def search_goals(self, place: Placement, pattern: str) -> list[Goal]:
        """The whole pattern around the most distinctive set first, then around the next, every other position a
        little higher (recognition is sensitive to the range, and the database may be off in depth too)."""
        s = self.settings
        offsets = pattern_offsets(pattern, s.search_step_m, s.search_positions)
        return [self.over_set(place, set_id, self.search_altitude(set_id) + s.search_raise_m * (ring % 2), o, True)
                for set_id in search_order(self.sets) for ring, o in enumerate(offsets)]
