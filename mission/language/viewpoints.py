"""Viewpoints checked at planning time (issue 21, item 4): a target is photographed from `standoff` metres above
it (`mission.agents.inspect.targets`), and the vehicle may not come closer than `safety.min_altitude` to whatever
lies under it. A viewpoint that the database itself shows to be too low is a warning at its target's line, so that
the designer learns it before the dive, not from a photo taken from the altitude floor.

What the database says lies under a viewpoint: the target's own point, and the characteristic points of the
object within `FOOTPRINT_M` horizontally of it (the vehicle's footprint, where its altimeter looks). The object's
`size` box is not used: it bounds the whole object, and a low part (a skid) beside a tall one (a module) would
always look forbidden. Objects are taken level, as the database poses give them.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

from mission.language.models import KnownObject

FOOTPRINT_M = 1.0  # horizontal radius under the vehicle in which a higher point forbids the viewpoint


def forbidden_viewpoints(obj: KnownObject, min_altitude: float) -> Iterator[tuple[int, str]]:
    """(target index, message) for each target of `obj` whose viewpoint is less than `min_altitude` above the
    highest database point under it (object frame: x, y horizontal, z down)."""
    for k, target in enumerate(obj.targets):
        vx, vy, vz = target.at[0], target.at[1], target.at[2] - target.standoff
        under = [("the target itself", target.at[2])]
        for point_set in obj.characteristic_points:
            for p in point_set.points:
                if math.hypot(p[0] - vx, p[1] - vy) <= FOOTPRINT_M:
                    under.append((f"point set '{point_set.id}'", p[2]))
        name, top = min(under, key=lambda u: u[1])  # z down: the highest point has the smallest z
        clearance = top - vz
        if clearance < min_altitude:
            yield k, (f"the viewpoint of target '{target.id}' ({target.standoff:g} m above it) is {clearance:.2f} m "
                      f"above {name}, below safety.min_altitude {min_altitude:g} m: the vehicle will photograph it "
                      f"from higher, {min_altitude - clearance:.2f} m or more off the viewpoint; raise its standoff")
