"""Bundle adjustment of stereo keyframes: poses and points that minimise the reprojection error in both cameras.

The parameters are, for every keyframe but the first `fixed` ones, a rotation increment φ (left-multiplied on the
keyframe's initial world→camera rotation, R = exp(φ)·R₀) and the world→camera translation t, and for every point
its world coordinates X. An observation of X by keyframe j gives p = R_j·X + t_j and the residuals

    left:  fx·p_x/p_z + cx − u,          fy·p_y/p_z + cy − v
    right: fx·(p_x − b)/p_z + cx + δ − u_r                  (b the baseline, δ the disparity offset)

(the right column only where the feature was matched in the right image; its row is the left one's on a rectified
pair, so the matcher's row carries nothing but its noise: fitting it too
gave KITTI 06 0.95 % drift against 0.89 %). Each residual pair
depends on one pose and one point (analytic blocks; ∂p/∂φ = −[R·X]ₓ·J_l(φ), J_l the left Jacobian of SO(3)).
Levenberg–Marquardt with a robust Huber loss (iteratively reweighted, `huber_px`) solves the normal equations with the
points eliminated (the Schur complement on the poses). scipy's sparse `least_squares` (trust-region reflective with
LSMR) was measured on the same problems first: 1121 points and 8 keyframes, with Huber and `x_scale='jac'` it left the
poses where they started after 30 evaluations, and without the robust loss it took 28 s; this solver brings the poses
from 0.1 m to 0.003 m in 0.13 s (one core). Stereo fixes the scale, so one fixed keyframe fixes the gauge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from perception_plugins.vo.errors import VoError

Array = NDArray[np.float64]


class BundleError(VoError):
    """Inconsistent bundle-adjustment input."""


@dataclass(frozen=True, eq=False)
class Observations:
    """M observations: which keyframe (0…P−1) saw which point (0…L−1), where, in the left and right images."""

    keyframe: NDArray[np.int_]
    point: NDArray[np.int_]
    uv_left: Array
    uv_right: Array
    """(M, 2); NaN where the feature has no right-image match."""

    def __len__(self) -> int:
        return int(self.keyframe.shape[0])


@dataclass(frozen=True, eq=False)
class Adjusted:
    """The adjusted keyframe poses (T_world_cam) and points (world), and the reprojection errors (px)."""

    T_world_cam: Array
    points: Array
    rms_before_px: float
    rms_after_px: float
    error_px: Array
    """(M,) each observation's largest image error (left or right) after the adjustment."""
    evaluations: int


def _skew(v: Array) -> Array:
    out = np.zeros((len(v), 3, 3))
    out[:, 0, 1], out[:, 0, 2], out[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    out[:, 1, 0], out[:, 2, 0], out[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return out


def _left_jacobian(phi: Array) -> Array:
    """J_l(φ) of SO(3) for each row of φ: I + (1 − cos θ)/θ²·[φ]ₓ + (θ − sin θ)/θ³·[φ]ₓ²."""
    theta = np.linalg.norm(phi, axis=1)
    small = theta < 1e-6
    t = np.where(small, 1.0, theta)
    a = np.where(small, 0.5, (1 - np.cos(t)) / t**2)
    b = np.where(small, 1.0 / 6.0, (t - np.sin(t)) / t**3)
    S = _skew(phi)
    return np.eye(3)[None] + a[:, None, None] * S + b[:, None, None] * (S @ S)


class _Problem:
    """The residuals and their sparse Jacobian for one adjustment (see the module docstring)."""

    def __init__(self, T_world_cam: Array, n_points: int, obs: Observations, K: Array, baseline: float,
                 doffs: float, fixed: int) -> None:
        T_cam_world = np.linalg.inv(T_world_cam)
        self.R0, self.t0 = T_cam_world[:, :3, :3], T_cam_world[:, :3, 3]
        self.P, self.L, self.fixed = len(T_world_cam), n_points, fixed
        self.free = self.P - fixed
        self.obs, self.K, self.b, self.doffs = obs, K, baseline, doffs
        self.right = np.flatnonzero(np.all(np.isfinite(obs.uv_right), axis=1))
        self.meas = np.concatenate([obs.uv_left.ravel(), obs.uv_right[self.right].ravel()])
        # Jacobian pattern: per observation row, 6 pose columns (free keyframes) and 3 point columns.
        M = len(obs)
        self.rows_obs = np.concatenate([np.arange(M), self.right])  # the observation behind each residual pair
        self.has_pose = obs.keyframe[self.rows_obs] >= fixed

    def unpack(self, x: Array) -> tuple[Array, Array, Array, Array]:
        pose = x[:6 * self.free].reshape(-1, 6)
        phi = np.zeros((self.P, 3))
        t = np.array(self.t0, dtype=np.float64)
        phi[self.fixed:], t[self.fixed:] = pose[:, :3], pose[:, 3:]
        R = np.asarray(Rotation.from_rotvec(phi).as_matrix() @ self.R0, dtype=np.float64)
        return phi, R, t, np.asarray(x[6 * self.free:], dtype=np.float64).reshape(-1, 3)

    def x0(self, points: Array) -> Array:
        return np.concatenate([np.column_stack([np.zeros((self.free, 3)), self.t0[self.fixed:]]).ravel(),
                               points.ravel()])

    def _camera_points(self, x: Array) -> tuple[Array, Array, Array, Array]:
        phi, R, t, X = self.unpack(x)
        k, j = self.obs.keyframe[self.rows_obs], self.obs.point[self.rows_obs]
        RX = np.einsum("nij,nj->ni", R[k], X[j])
        return phi, R, RX, RX + t[k]

    def residuals(self, x: Array) -> Array:
        _, _, _, p = self._camera_points(x)
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        z = np.maximum(p[:, 2], 1e-3)
        M = len(self.obs)
        shift = np.zeros(len(p))
        shift[M:] = self.b
        u = fx * (p[:, 0] - shift) / z + cx + np.where(shift > 0, self.doffs, 0.0)
        v = fy * p[:, 1] / z + cy
        r = np.column_stack([u, v]) - self.meas.reshape(-1, 2)
        r[M:, 1] = 0.0  # the right image's row is the left one's (rectified): no information, only LK's noise
        return np.asarray(r.ravel(), dtype=np.float64)

    def blocks(self, x: Array) -> tuple[Array, Array]:
        """The Jacobian's blocks per residual pair: ∂r/∂pose (n, 2, 6; zero for fixed keyframes), ∂r/∂X (n, 2, 3)."""
        phi, R, RX, p = self._camera_points(x)
        fx, fy = self.K[0, 0], self.K[1, 1]
        n, M = len(p), len(self.obs)
        z = np.maximum(p[:, 2], 1e-3)
        px = p[:, 0] - np.where(np.arange(n) >= M, self.b, 0.0)
        dproj = np.zeros((n, 2, 3))  # ∂(u, v)/∂p
        dproj[:, 0, 0], dproj[:, 0, 2] = fx / z, -fx * px / z**2
        dproj[:, 1, 1], dproj[:, 1, 2] = fy / z, -fy * p[:, 1] / z**2
        k = self.obs.keyframe[self.rows_obs]
        d_point = dproj @ R[k]
        d_pose = np.concatenate([-dproj @ _skew(RX) @ _left_jacobian(phi)[k], dproj], axis=2)
        d_pose[~self.has_pose] = 0.0
        d_pose[M:, 1], d_point[M:, 1] = 0.0, 0.0
        return d_pose, d_point

    def per_observation_error(self, r: Array) -> Array:
        M = len(self.obs)
        e = np.linalg.norm(r.reshape(-1, 2), axis=1)
        out = e[:M].copy()
        out[self.right] = np.maximum(out[self.right], e[M:])
        return np.asarray(out, dtype=np.float64)


def _huber_weights(r: Array, c: float) -> tuple[Array, float]:
    """IRLS weights per residual pair (Huber on the pair's norm at `c` px) and the robust cost."""
    e = np.linalg.norm(r.reshape(-1, 2), axis=1)
    w = np.where(e <= c, 1.0, c / np.maximum(e, 1e-12))
    cost = float(np.sum(np.where(e <= c, 0.5 * e**2, c * (e - 0.5 * c))))
    return np.repeat(w, 2), cost


def _sum_blocks(index: NDArray[np.int_], values: Array, count: int) -> Array:
    """Σ values[i] over the rows i with index[i] = c, for c in 0…count−1 (blocks of any shape)."""
    shape = values.shape[1:]
    size = int(np.prod(shape))
    flat = (index[:, None] * size + np.arange(size)[None]).ravel()
    return np.bincount(flat, weights=values.reshape(len(values), -1).ravel(), minlength=count * size).reshape(
        (count, *shape))


def _levenberg_marquardt(problem: _Problem, x0: Array, huber_px: float, iterations: int) -> tuple[Array, int]:
    """Robust (IRLS Huber) Levenberg–Marquardt with the points eliminated: the normal equations' pose block minus
    the points' 3×3 blocks (the Schur complement, dense: a window has at most a few dozen pose parameters)."""
    x, lam, evaluations = x0.copy(), 1e-3, 1
    r = problem.residuals(x)
    w, cost = _huber_weights(r, huber_px)
    F, L = problem.free, problem.L
    k = np.maximum(problem.obs.keyframe[problem.rows_obs] - problem.fixed, 0)
    j = problem.obs.point[problem.rows_obs]
    for _ in range(iterations):
        A, B = problem.blocks(x)
        wr = (w * r).reshape(-1, 2)
        wA = A * w.reshape(-1, 2)[:, :, None]
        wB = B * w.reshape(-1, 2)[:, :, None]
        AtA, BtB, AtB = (np.matmul(a.transpose(0, 2, 1), c) for a, c in ((wA, A), (wB, B), (wA, B)))
        U = _sum_blocks(k, AtA, F)
        V = _sum_blocks(j, BtB, L)
        Wd = _sum_blocks(k * L + j, AtB, F * L).reshape(F, L, 6, 3).transpose(0, 2, 1, 3)
        gp = _sum_blocks(k, np.matmul(A.transpose(0, 2, 1), wr[:, :, None])[:, :, 0], F)
        gx = _sum_blocks(j, np.matmul(B.transpose(0, 2, 1), wr[:, :, None])[:, :, 0], L)
        Ufull = np.zeros((6 * F, 6 * F))
        for f in range(F):
            Ufull[6 * f:6 * f + 6, 6 * f:6 * f + 6] = U[f]
        Wm = Wd.reshape(6 * F, L, 3)
        converged = False
        while True:
            Vd = V.copy()
            Vd[:, [0, 1, 2], [0, 1, 2]] *= 1.0 + lam
            Vd[:, [0, 1, 2], [0, 1, 2]] += 1e-9
            Vinv = np.linalg.inv(Vd)
            WV = np.matmul(Wm.transpose(1, 0, 2), Vinv).transpose(1, 0, 2)
            S = Ufull + lam * np.diag(np.diag(Ufull)) + 1e-9 * np.eye(6 * F) \
                - WV.reshape(6 * F, -1) @ Wm.reshape(6 * F, -1).T
            dp = np.linalg.solve(S, -(gp.ravel() - WV.reshape(6 * F, -1) @ gx.ravel())) if F else np.zeros(0)
            dx = -np.matmul(Vinv, (gx + np.tensordot(dp, Wm, axes=(0, 0)))[:, :, None])[:, :, 0]
            step = np.concatenate([dp, dx.ravel()])
            x_new = x + step
            r_new = problem.residuals(x_new)
            evaluations += 1
            w_new, cost_new = _huber_weights(r_new, huber_px)
            if cost_new < cost:
                converged = cost - cost_new < 1e-6 * cost
                x, r, w, cost, lam = x_new, r_new, w_new, cost_new, max(lam / 3.0, 1e-7)
                break
            lam *= 4.0
            if lam > 1e6:
                return x, evaluations
        if converged or float(np.max(np.abs(step))) < 1e-8:
            break
    return x, evaluations


def bundle_adjust(T_world_cam: Array, points: Array, obs: Observations, K: Array, baseline: float, *,
                  doffs: float = 0.0, fixed: int = 1, huber_px: float = 1.0, iterations: int = 10) -> Adjusted:
    """Adjust keyframe poses (P, 4, 4) T_world_cam (the first `fixed` held) and points (L, 3) in the world frame to
    the observations (see the module docstring)."""
    P, L = len(T_world_cam), len(points)
    if not 1 <= fixed <= P:
        raise BundleError(f"fixed must be within 1…{P} keyframes, not {fixed}")
    if len(obs) and (obs.keyframe.max() >= P or obs.point.max() >= L or obs.keyframe.min() < 0):
        raise BundleError("an observation names a keyframe or point the adjustment does not have")
    problem = _Problem(np.asarray(T_world_cam, dtype=float), L, obs, K, baseline, doffs, fixed)
    x0 = problem.x0(np.asarray(points, dtype=float))
    r0 = problem.residuals(x0)
    rms0 = float(np.sqrt(np.mean(r0**2))) if len(r0) else 0.0
    if len(r0) <= len(x0):
        return Adjusted(np.asarray(T_world_cam, dtype=float).copy(), np.asarray(points, dtype=float).copy(), rms0,
                        rms0, problem.per_observation_error(r0), 0)
    x, evaluations = _levenberg_marquardt(problem, x0, huber_px, iterations)
    _, R, t, X = problem.unpack(x)
    T_cam_world = np.tile(np.eye(4), (P, 1, 1))
    T_cam_world[:, :3, :3], T_cam_world[:, :3, 3] = R, t
    r = problem.residuals(x)
    T_world_cam = np.asarray(np.linalg.inv(T_cam_world), dtype=np.float64)
    return Adjusted(T_world_cam, X.copy(), rms0, float(np.sqrt(np.mean(r**2))), problem.per_observation_error(r),
                    evaluations)


__all__ = ["Adjusted", "BundleError", "Observations", "bundle_adjust"]
