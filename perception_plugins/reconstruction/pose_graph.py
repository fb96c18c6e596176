"""Camera poses of a recording held together by visual odometry and anchored to navigation: a pose graph.

A recording's navigation poses carry the navigation's fast errors (a USBL fix moves the estimate by decimetres
between two frames, the heading is noisy by a few tenths of a degree a frame); fused at those poses, a surface seen
twice is placed twice. Stereo motion between two frames is good to millimetres and hundredths of a degree but
drifts when chained. The graph takes both: the unknowns are every frame's T_world_cam; each measured relative
motion (`Edge`, consecutive frames and revisits) pulls a pair of poses together, each navigation pose pulls its
frame towards itself with the navigation's σ. The weighted least squares (`anchor_poses`, scipy's sparse
trust-region solver with a robust loss, so that a wrong edge is outvoted) keeps the shape of what stereo saw and
the place where navigation put it.

Residuals (T = (R, t) camera → world; log is the rotation vector):

* edge i→j with measured T_ij = (R_ij, t_ij): log(R_ijᵀ·R_iᵀ·R_j) / σ_rot and (R_iᵀ·(t_j − t_i) − t_ij) / σ_step,
  σ_step = `edge_sigma_m` + `edge_sigma_per_m` · |t_ij|;
* prior i, navigation pose (R_nᵢ, t_nᵢ): log(R_nᵢᵀ·R_i) / `nav_sigma_rad` and (t_i − t_nᵢ) / `nav_sigma_m`
  (per axis: horizontal and depth differ).

>>> rng = np.random.default_rng(1)
>>> truth = np.stack([np.eye(4)] * 20)
>>> truth[:, 0, 3] = np.arange(20) * 0.5
>>> nav = truth.copy()
>>> nav[:, :2, 3] += rng.normal(0.0, 0.3, (20, 2))
>>> edges = [Edge(i, i + 1, np.linalg.inv(truth[i]) @ truth[i + 1]) for i in range(19)]
>>> fitted = anchor_poses(nav, edges)
>>> steps = np.diff(fitted[:, :3, 3], axis=0)
>>> bool(np.abs(steps - [0.5, 0.0, 0.0]).max() < 0.005)
True
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix
from scipy.spatial.transform import Rotation

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Edge:
    """A measured relative motion: T_i_j (frame j's camera in frame i's), supported by `inliers` features."""

    i: int
    j: int
    T_i_j: Array
    inliers: int = 0


@dataclass(frozen=True)
class GraphSettings:
    """The σ of each kind of residual (see the module docstring)."""

    nav_sigma_m: tuple[float, float, float] = (0.5, 0.5, 0.05)
    """Navigation position σ per world axis (north, east, depth): USBL-aided horizontally, a pressure depth."""
    nav_sigma_rad: float = float(np.radians(0.5))
    edge_sigma_m: float = 0.004
    edge_sigma_per_m: float = 0.005
    edge_sigma_rad: float = float(np.radians(0.1))
    loss_scale: float = 3.0
    """The robust loss (soft L1) turns linear beyond this many σ: a wrong edge pulls with a bounded force."""


def _unpack(x: Array, nav_R: Rotation, nav_t: Array) -> tuple[Rotation, Array]:
    """The poses of the unknowns: each frame's rotation and position as a small change of its navigation pose
    (R = R_nav·exp(δ), t = t_nav + d), so that no rotation vector comes near π whatever the heading."""
    p = x.reshape(len(nav_t), 6)
    return nav_R * Rotation.from_rotvec(p[:, :3]), nav_t + p[:, 3:]


def _residuals(x: Array, n: int, nav_R: Rotation, nav_t: Array, ei: NDArray[np.int_], ej: NDArray[np.int_],
               edge_R: Rotation, edge_t: Array, step_sigma: Array, s: GraphSettings) -> Array:
    R, t = _unpack(x, nav_R, nav_t)
    change = x.reshape(n, 6)
    prior_rot = change[:, :3] / s.nav_sigma_rad
    prior_pos = change[:, 3:] / np.asarray(s.nav_sigma_m)
    Ri, Rj = R[ei], R[ej]
    edge_rot = (edge_R.inv() * Ri.inv() * Rj).as_rotvec() / s.edge_sigma_rad
    edge_pos = (Ri.inv().apply(t[ej] - t[ei]) - edge_t) / step_sigma[:, None]
    return np.concatenate([prior_rot.ravel(), prior_pos.ravel(), edge_rot.ravel(), edge_pos.ravel()])


def _sparsity(n: int, ei: NDArray[np.int_], ej: NDArray[np.int_]) -> lil_matrix:
    m = 6 * n + 6 * len(ei)
    A = lil_matrix((m, 6 * n), dtype=np.int8)
    for k in range(n):  # priors: rotation rows on the rotation columns, position rows on the position columns
        A[3 * k:3 * k + 3, 6 * k:6 * k + 3] = 1
        A[3 * n + 3 * k:3 * n + 3 * k + 3, 6 * k + 3:6 * k + 6] = 1
    base = 6 * n
    for e, (i, j) in enumerate(zip(ei, ej, strict=True)):
        for frame in (i, j):
            A[base + 3 * e:base + 3 * e + 3, 6 * frame:6 * frame + 3] = 1
        row = base + 3 * len(ei) + 3 * e
        for frame in (i, j):
            A[row:row + 3, 6 * frame:6 * frame + 6] = 1
    return A


def anchor_poses(nav: Array, edges: Sequence[Edge], settings: GraphSettings | None = None,
                 max_evaluations: int = 200) -> Array:
    """(N, 4, 4) T_world_cam: the poses that best agree with the navigation poses `nav` (N, 4, 4) and the
    measured relative motions `edges`, in the weighted least-squares sense (module docstring). Frames no edge
    reaches keep their navigation pose."""
    s = settings or GraphSettings()
    nav = np.asarray(nav, dtype=float)
    n = len(nav)
    if n == 0 or not edges:
        return nav.copy()
    nav_R, nav_t = Rotation.from_matrix(nav[:, :3, :3]), nav[:, :3, 3]
    ei = np.array([e.i for e in edges], dtype=int)
    ej = np.array([e.j for e in edges], dtype=int)
    T = np.stack([np.asarray(e.T_i_j, dtype=float) for e in edges])
    edge_R, edge_t = Rotation.from_matrix(T[:, :3, :3]), T[:, :3, 3]
    step_sigma = s.edge_sigma_m + s.edge_sigma_per_m * np.linalg.norm(edge_t, axis=1)
    x0 = np.zeros(6 * n)
    args = (n, nav_R, nav_t, ei, ej, edge_R, edge_t, step_sigma, s)
    solution = least_squares(_residuals, x0, jac_sparsity=_sparsity(n, ei, ej), args=args, method="trf",
                             loss="soft_l1", f_scale=s.loss_scale, x_scale="jac", max_nfev=max_evaluations)
    R, t = _unpack(solution.x, nav_R, nav_t)
    out = np.tile(np.eye(4), (n, 1, 1))
    out[:, :3, :3] = R.as_matrix()
    out[:, :3, 3] = t
    return out


__all__ = ["Edge", "GraphSettings", "anchor_poses"]
