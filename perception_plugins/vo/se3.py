"""Rigid transforms for visual odometry: rotation vectors, interpolation and the constant-velocity model (the
inverse and the point transform are `mission.geometry`'s).

`T_a_b` is a 4×4 homogeneous matrix mapping coordinates in frame b to frame a (camera frames follow OpenCV).

>>> T = from_rotvec_translation([0.0, 0.0, np.pi / 2], [1.0, 0.0, 0.0])
>>> mid = interpolate(np.eye(4), T, 0.5)
>>> round(float(np.degrees(np.linalg.norm(to_rotvec(mid[:3, :3])))), 6), mid[:3, 3].round(6).tolist()
(45.0, [0.5, 0.0, 0.0])
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation, Slerp

Matrix = NDArray[np.float64]


def from_rotvec_translation(rotvec: ArrayLike, translation: ArrayLike) -> Matrix:
    """A transform from a rotation vector (rad) and a translation."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(np.asarray(rotvec, dtype=float).reshape(3)).as_matrix()
    T[:3, 3] = np.asarray(translation, dtype=float).reshape(3)
    return T


def to_rotvec(R: Matrix) -> NDArray[np.float64]:
    """The rotation vector (rad) of a rotation matrix."""
    return np.asarray(Rotation.from_matrix(R).as_rotvec(), dtype=float)


def interpolate(T_w_a: Matrix, T_w_b: Matrix, s: float) -> Matrix:
    """The pose a fraction `s` of the way from a to b: slerp of the rotation, linear in the position."""
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([T_w_a[:3, :3], T_w_b[:3, :3]])))
    T = np.eye(4)
    T[:3, :3] = slerp([s]).as_matrix()[0]
    T[:3, 3] = (1.0 - s) * T_w_a[:3, 3] + s * T_w_b[:3, 3]
    return T


def power(T_a_b: Matrix, s: float) -> Matrix:
    """T_a_b scaled along its own screw-free path: rotation angle × s, translation × s (constant velocity)."""
    return from_rotvec_translation(s * to_rotvec(T_a_b[:3, :3]), s * T_a_b[:3, 3])


def fill_poses(known: dict[int, Matrix], count: int) -> NDArray[np.float64]:
    """(count, 4, 4) poses: the known ones as they are, the others interpolated between their known neighbours
    (held at the nearest known pose beyond the first or last).

    >>> P = fill_poses({0: np.eye(4), 2: from_rotvec_translation([0, 0, 0], [2.0, 0, 0])}, 4)
    >>> P[:, 0, 3].tolist()
    [0.0, 1.0, 2.0, 2.0]
    """
    if not known:
        raise ValueError("no known pose to fill from")
    keys = sorted(known)
    out = np.empty((count, 4, 4))
    for i in range(count):
        j = int(np.searchsorted(keys, i))
        if j < len(keys) and keys[j] == i:
            out[i] = known[i]
        elif j == 0:
            out[i] = known[keys[0]]
        elif j == len(keys):
            out[i] = known[keys[-1]]
        else:
            a, b = keys[j - 1], keys[j]
            out[i] = interpolate(known[a], known[b], (i - a) / (b - a))
    return out


__all__ = ["Matrix", "fill_poses", "from_rotvec_translation", "interpolate", "power", "to_rotvec"]
