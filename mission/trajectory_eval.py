"""Trajectory files (KITTI, TUM) and trajectory error metrics: ATE, RPE, end-point drift (seed 003 evaluation).

Pure numpy. The metrics follow the definitions evo uses (Sturm et al., TUM RGB-D benchmark), so that the two agree:

- ATE: the estimated positions are aligned to the ground truth by a rigid motion (Umeyama, no scale); the error is
  the distance between corresponding positions after alignment.
- RPE over ``delta`` frames: E_i = (Q_i⁻¹ Q_{i+δ})⁻¹ (P_i⁻¹ P_{i+δ}) for ground truth Q and estimate P; its
  translation norm (m) and rotation angle (deg), for every i (overlapping pairs). Independent of any alignment.
- End-point drift: the estimate is anchored at the ground truth's first pose (what a VO run starting from a known
  pose gives), and the drift is the distance between the last positions, also as a percentage of the ground-truth
  path length.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from mission.errors import AuvError
from mission.geometry import invert

Array = NDArray[np.float64]

KITTI_FIELDS = 12
TUM_FIELDS = 8
FORMATS = ("kitti", "tum")
_ROTATION_TOLERANCE = 1e-3  # files round to ~7 digits; anything worse than this is not a rotation


class TrajectoryError(AuvError):
    """A trajectory file is unreadable or two trajectories cannot be compared."""


@dataclass(frozen=True)
class Trajectory:
    """Poses T_world_cam (N, 4, 4) with optional times (N,) in seconds (TUM files carry them, KITTI files do not)."""

    poses: Array
    times: Array | None = None

    def __len__(self) -> int:
        return int(self.poses.shape[0])

    @property
    def positions(self) -> Array:
        return self.poses[:, :3, 3]


@dataclass(frozen=True)
class TrajectoryErrors:
    """Errors of an estimated trajectory against ground truth (see the module docstring for definitions)."""

    ate_rmse_m: float
    ate_mean_m: float
    ate_max_m: float
    rpe_trans_rmse_m: float
    rpe_rot_rmse_deg: float
    rpe_per_frame: Array  # (N - delta, 2): translation error m, rotation error deg, for pairs (i, i + delta)
    endpoint_drift_m: float
    endpoint_drift_percent: float  # of the ground-truth path length
    path_length_m: float
    delta: int = 1
    pairs: int = 0  # poses compared after association

    def as_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values; the per-frame RPE as a list of [translation m, rotation deg] pairs."""
        d = asdict(self)
        d["rpe_per_frame"] = self.rpe_per_frame.tolist()
        return d


# --------------------------------------------------------------------------------------------- reading and writing


def read_trajectory(path: str | Path) -> Trajectory:
    """Read a KITTI (12 numbers a line, row-major 3×4 T_world_cam) or TUM (``t x y z qx qy qz qw``) file.

    The format is detected from the first data line; blank lines and ``#`` comments are skipped. Every bad line
    raises a TrajectoryError naming the file and line.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise TrajectoryError(f"{path}: cannot read trajectory: {e.strerror or e}") from e
    rows: list[tuple[int, list[float]]] = []
    width: int | None = None
    for lineno, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        fields = stripped.replace(",", " ").split()
        if width is None:
            if len(fields) not in (KITTI_FIELDS, TUM_FIELDS):
                raise TrajectoryError(
                    f"{path}:{lineno}: expected 12 numbers (KITTI 3×4 pose) or 8 (TUM: t x y z qx qy qz qw), "
                    f"got {len(fields)}"
                )
            width = len(fields)
        elif len(fields) != width:
            kind = "KITTI" if width == KITTI_FIELDS else "TUM"
            raise TrajectoryError(f"{path}:{lineno}: expected {width} numbers ({kind}, as above), got {len(fields)}")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            bad = next(f for f in fields if not _is_float(f))
            raise TrajectoryError(f"{path}:{lineno}: not a number: {bad!r}") from None
        if not all(math.isfinite(v) for v in values):
            raise TrajectoryError(f"{path}:{lineno}: non-finite number")
        rows.append((lineno, values))
    if not rows:
        raise TrajectoryError(f"{path}: no poses")
    if width == KITTI_FIELDS:
        return Trajectory(poses=np.stack([_kitti_pose(path, n, v) for n, v in rows]))
    times = np.array([v[0] for _, v in rows])
    if np.any(np.diff(times) <= 0):
        lineno = rows[int(np.argmax(np.diff(times) <= 0)) + 1][0]
        raise TrajectoryError(f"{path}:{lineno}: timestamps must increase")
    return Trajectory(poses=np.stack([_tum_pose(path, n, v) for n, v in rows]), times=times)


def write_trajectory(path: str | Path, poses: ArrayLike, times: ArrayLike | None = None, fmt: str = "kitti") -> None:
    """Write poses T_world_cam (N, 4, 4) as KITTI (times ignored) or TUM (times, else the frame index)."""
    T = _as_poses(poses, "poses")
    if fmt == "kitti":
        lines = [" ".join(f"{x:.9e}" for x in p[:3, :4].reshape(-1)) for p in T]
    elif fmt == "tum":
        t = np.arange(len(T), dtype=float) if times is None else np.asarray(times, dtype=float).reshape(-1)
        if len(t) != len(T):
            raise TrajectoryError(f"{len(T)} poses but {len(t)} times")
        q = quaternions_from_rotations(T[:, :3, :3])
        lines = [
            f"{ti:.9f} " + " ".join(f"{x:.9e}" for x in (*p[:3, 3], *qi)) for ti, p, qi in zip(t, T, q, strict=True)
        ]
    else:
        raise TrajectoryError(f"unknown trajectory format {fmt!r} (expected one of {', '.join(FORMATS)})")
    try:
        Path(path).write_text("\n".join(lines) + "\n")
    except OSError as e:
        raise TrajectoryError(f"{path}: cannot write trajectory: {e.strerror or e}") from e


def _is_float(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def _kitti_pose(path: Path, lineno: int, values: list[float]) -> Array:
    T = np.eye(4)
    T[:3, :4] = np.reshape(values, (3, 4))
    R = T[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=_ROTATION_TOLERANCE) or np.linalg.det(R) < 0:
        raise TrajectoryError(f"{path}:{lineno}: the 3×3 part is not a rotation matrix")
    return T


def _tum_pose(path: Path, lineno: int, values: list[float]) -> Array:
    q = np.array(values[4:8])
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > 1e-2:  # renormalise rounding, refuse nonsense
        raise TrajectoryError(f"{path}:{lineno}: quaternion qx qy qz qw has norm {norm:.4g}, expected 1")
    T = np.eye(4)
    T[:3, :3] = rotation_from_quaternion(q / norm)
    T[:3, 3] = values[1:4]
    return T


def rotation_from_quaternion(q_xyzw: ArrayLike) -> Array:
    """Rotation matrix of a unit quaternion given as (x, y, z, w), TUM's order."""
    x, y, z, w = np.asarray(q_xyzw, dtype=float)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def quaternions_from_rotations(R: Array) -> Array:
    """Unit quaternions (N, 4) as (x, y, z, w) with w ≥ 0 of rotation matrices (N, 3, 3)."""
    q: Array = Rotation.from_matrix(R).as_quat()
    q[q[:, 3] < 0] *= -1
    return q


# ------------------------------------------------------------------------------------------------------- metrics


def align_se3(gt_positions: ArrayLike, est_positions: ArrayLike) -> tuple[Array, Array]:
    """Rigid motion (R, t) minimising Σ‖gt_i − (R·est_i + t)‖² (Umeyama 1991 without scale).

    >>> R, t = align_se3([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 0, 0], [-1, 1, 0], [-1, 0, 1]])
    >>> np.allclose(R, np.eye(3)), np.allclose(t, [1, 0, 0])
    (True, True)
    """
    gt = np.asarray(gt_positions, dtype=float)
    est = np.asarray(est_positions, dtype=float)
    if gt.ndim != 2 or gt.shape[1] != 3 or gt.shape != est.shape or len(gt) == 0:
        raise TrajectoryError(f"need two equal non-empty (N, 3) position arrays, got {gt.shape} and {est.shape}")
    mu_gt, mu_est = gt.mean(axis=0), est.mean(axis=0)
    cov = (gt - mu_gt).T @ (est - mu_est) / len(gt)
    U, _, Vt = np.linalg.svd(cov)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:  # a reflection would fit better; the best rotation flips one axis
        S[2, 2] = -1.0
    R = U @ S @ Vt
    return R, mu_gt - R @ mu_est


def associate(
    gt_times: ArrayLike, est_times: ArrayLike, max_dt: float = 0.01
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Index pairs (gt, est) of the nearest timestamps within max_dt, one per pose of the shorter trajectory."""
    tg, te = np.asarray(gt_times, dtype=float).reshape(-1), np.asarray(est_times, dtype=float).reshape(-1)
    if np.any(np.diff(tg) <= 0) or np.any(np.diff(te) <= 0):
        raise TrajectoryError("timestamps must increase to associate trajectories by time")
    swap = len(te) < len(tg)
    short, long_ = (te, tg) if swap else (tg, te)
    j = np.clip(np.searchsorted(long_, short), 1, max(len(long_) - 1, 1))
    before = np.abs(short - long_[j - 1])
    after = np.abs(long_[np.minimum(j, len(long_) - 1)] - short)
    nearest = np.where(after < before, j, j - 1) if len(long_) > 1 else np.zeros_like(j)
    ok = np.abs(long_[nearest] - short) <= max_dt
    i_short = np.flatnonzero(ok)
    i_long = nearest[ok]
    return (i_long, i_short) if swap else (i_short, i_long)


def evaluate(
    gt_poses: ArrayLike | Trajectory,
    est_poses: ArrayLike | Trajectory,
    delta: int = 1,
    *,
    gt_times: ArrayLike | None = None,
    est_times: ArrayLike | None = None,
    max_dt: float = 0.01,
) -> TrajectoryErrors:
    """ATE after SE(3) alignment, RPE over ``delta`` frames, and end-point drift of an estimate against ground truth.

    Poses are T_world_cam (N, 4, 4), or Trajectory objects (whose times are used). Equal lengths are associated by
    index; otherwise by nearest timestamp within ``max_dt`` s (both need times, as TUM files have).
    """
    if isinstance(gt_poses, Trajectory):
        gt_times = gt_poses.times if gt_times is None else gt_times
        gt_poses = gt_poses.poses
    if isinstance(est_poses, Trajectory):
        est_times = est_poses.times if est_times is None else est_times
        est_poses = est_poses.poses
    Q = _as_poses(gt_poses, "ground truth")
    P = _as_poses(est_poses, "estimate")
    if len(Q) != len(P):
        if gt_times is None or est_times is None:
            raise TrajectoryError(
                f"ground truth has {len(Q)} poses and the estimate {len(P)}: equal lengths are compared frame by "
                "frame, different ones need timestamps in both (TUM files)"
            )
        i_gt, i_est = associate(gt_times, est_times, max_dt)
        if len(i_gt) == 0:
            raise TrajectoryError(f"no timestamps of the two trajectories are within {max_dt} s of each other")
        Q, P = Q[i_gt], P[i_est]
    if len(Q) < 2:
        raise TrajectoryError(f"need at least 2 poses to compare, got {len(Q)}")
    delta = int(delta)
    if delta < 1 or delta >= len(Q):
        raise TrajectoryError(f"delta must be between 1 and {len(Q) - 1} (poses compared: {len(Q)}), got {delta}")

    R, t = align_se3(Q[:, :3, 3], P[:, :3, 3])
    ate = np.linalg.norm(Q[:, :3, 3] - (P[:, :3, 3] @ R.T + t), axis=1)

    rpe = relative_pose_errors(Q, P, delta)

    path_length = float(np.linalg.norm(np.diff(Q[:, :3, 3], axis=0), axis=1).sum())
    T_anchor = Q[0] @ invert(P[0])
    end_est = T_anchor[:3, :3] @ P[-1, :3, 3] + T_anchor[:3, 3]
    drift = float(np.linalg.norm(end_est - Q[-1, :3, 3]))
    return TrajectoryErrors(
        ate_rmse_m=float(np.sqrt(np.mean(ate**2))),
        ate_mean_m=float(ate.mean()),
        ate_max_m=float(ate.max()),
        rpe_trans_rmse_m=float(np.sqrt(np.mean(rpe[:, 0] ** 2))),
        rpe_rot_rmse_deg=float(np.sqrt(np.mean(rpe[:, 1] ** 2))),
        rpe_per_frame=rpe,
        endpoint_drift_m=drift,
        endpoint_drift_percent=100.0 * drift / path_length if path_length > 0 else math.nan,
        path_length_m=path_length,
        delta=delta,
        pairs=len(Q),
    )


def relative_pose_errors(gt_poses: Array, est_poses: Array, delta: int = 1) -> Array:
    """(N − delta, 2) translation (m) and rotation (deg) of E_i = (Q_i⁻¹Q_{i+δ})⁻¹(P_i⁻¹P_{i+δ})."""
    Q, P = gt_poses, est_poses
    dQ = invert(Q[:-delta]) @ Q[delta:]
    dP = invert(P[:-delta]) @ P[delta:]
    E = invert(dQ) @ dP
    trans = np.linalg.norm(E[:, :3, 3], axis=1)
    # scipy's quaternion fit absorbs the rounding of stored rotations, as evo's (which uses it) does
    rot = np.degrees(Rotation.from_matrix(E[:, :3, :3]).magnitude())
    return np.column_stack([trans, rot])


def _as_poses(poses: ArrayLike, name: str) -> Array:
    T = np.asarray(poses, dtype=float)
    if T.ndim != 3 or T.shape[1:] != (4, 4) or len(T) == 0:
        raise TrajectoryError(f"{name}: expected poses of shape (N, 4, 4), got {T.shape}")
    if not np.all(np.isfinite(T)):
        raise TrajectoryError(f"{name}: poses contain non-finite numbers")
    return T


# ------------------------------------------------------------------------------------------------------- reports


def summary_text(errors: TrajectoryErrors) -> str:
    """The headline figures, one per line (what `auv eval-traj` and `auv vo` print)."""
    return "\n".join([
        f"ATE after SE(3) alignment: rmse {errors.ate_rmse_m:.4f} m, mean {errors.ate_mean_m:.4f} m, "
        f"max {errors.ate_max_m:.4f} m ({errors.pairs} poses)",
        f"RPE over {errors.delta} frame(s): translation rmse {errors.rpe_trans_rmse_m:.4f} m, "
        f"rotation rmse {errors.rpe_rot_rmse_deg:.4f} deg",
        f"end-point drift: {errors.endpoint_drift_m:.4f} m = {errors.endpoint_drift_percent:.3f} % of "
        f"the {errors.path_length_m:.2f} m path",
    ])


def rpe_table(errors: TrajectoryErrors) -> str:
    """The relative pose error of every pair (i, i + delta) as an aligned text table."""
    rows = [f"{'from':>6} {'to':>6} {'trans_m':>10} {'rot_deg':>10}"]
    rows += [f"{i:>6d} {i + errors.delta:>6d} {t:>10.4f} {r:>10.4f}" for i, (t, r) in enumerate(errors.rpe_per_frame)]
    return "\n".join(rows)
