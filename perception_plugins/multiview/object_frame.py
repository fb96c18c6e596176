"""The object's intrinsic frame from a base segment (seed 000 §3.1 step 4, Figure 2).

The segment [P1, P2] is given in a camera frame, with the external (world) z-axis expressed in that camera frame
(from the navigation attitude: roll and pitch are what an INS measures well). P1 is the origin; Z' is the world z;
X' is the direction of [P1, P2'], P2' being P2 projected on the plane through P1 perpendicular to Z'; Y' = Z' × X'
(right-handed). The result is `T_view_object` (object → camera coordinates); the seed's H_{CS^view, CS^object},
which maps camera coordinates into the object frame, is its inverse `T_object_view`.

>>> import numpy as np
>>> T = object_frame(np.array([1.0, 0, 5]), np.array([3.0, 0, 4]), np.array([0.0, 0, 1]))
>>> T[:3, :3].round(6).tolist(), T[:3, 3].tolist()
([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [1.0, 0.0, 5.0])
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception_plugins.multiview.errors import MultiviewError

Array = NDArray[np.float64]


def object_frame(p1: ArrayLike, p2: ArrayLike, z_world_cam: ArrayLike) -> Array:
    """T_view_object of the frame built on the base segment [p1, p2] (camera coordinates) with Z' along
    `z_world_cam` (the world z-axis in camera coordinates). Raises when the segment is (nearly) vertical."""
    a, b = np.asarray(p1, dtype=float).reshape(3), np.asarray(p2, dtype=float).reshape(3)
    z = np.asarray(z_world_cam, dtype=float).reshape(3)
    z = z / np.linalg.norm(z)
    d = b - a
    horizontal = d - (d @ z) * z                     # [P1, P2'] : the projection on the plane ⊥ Z'
    length = float(np.linalg.norm(horizontal))
    if length < 1e-3 * max(float(np.linalg.norm(d)), 1e-9) or length < 1e-6:
        raise MultiviewError("the base segment is vertical: it cannot give the object's x-axis")
    x = horizontal / length
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, a
    return T


__all__ = ["object_frame"]
