"""Turns and transits the vehicle can fly: shortest paths of bounded curvature between two poses (seed 002 §2.1,
meanders flown by an AUV with a turning radius R).

These are Dubins paths. Between two survey lines at least 2R apart the shortest turn is a quarter circle, a
straight and a quarter circle (the U-turn, Dubins' LSL or RSR words); closer than 2R it is a bulb of three arcs
(the Ω-turn, Dubins' RLR or LRL). The same solver joins the end of one cell to the start of the next. Poses are
(x, y) points with math angles (radians, counter-clockwise from +x); any proper rotation of the plane works.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

TWO_PI = 2.0 * math.pi
# Each word is three segments: +1 a left (counter-clockwise) arc, -1 a right arc, 0 a straight.
WORDS: tuple[tuple[int, int, int], ...] = ((1, 0, 1), (-1, 0, -1), (1, 0, -1), (-1, 0, 1), (-1, 1, -1), (1, -1, 1))
ARC_STEP = math.radians(10.0)


def _mod(a: Array) -> Array:
    return np.mod(a, TWO_PI)


def dubins(
    p0: ArrayLike, theta0: ArrayLike, p1: ArrayLike, theta1: ArrayLike, radius: float
) -> tuple[Array, IntArray, Array]:
    """Shortest bounded-curvature paths for arrays of pose pairs: (lengths, word index, segment parameters).

    Segment parameters are arc angles (radians) or straight lengths divided by the radius. With radius 0 the
    path is the straight segment (word 0, parameters (0, length, 0)).

    >>> length, word, _ = dubins([[0, 0]], [0.0], [[0, 50]], [math.pi], 6.0)   # U-turn, lines 50 m apart
    >>> round(float(length[0]), 2), WORDS[int(word[0])]
    (56.85, (1, 0, 1))
    >>> length, word, _ = dubins([[0, 0]], [0.0], [[0, 10]], [math.pi], 6.0)   # Ω-turn, lines 10 m apart
    >>> round(float(length[0]), 2), WORDS[int(word[0])]
    (28.72, (-1, 1, -1))
    """
    a = np.atleast_2d(np.asarray(p0, dtype=float))
    b = np.atleast_2d(np.asarray(p1, dtype=float))
    t0 = np.atleast_1d(np.asarray(theta0, dtype=float))
    t1 = np.atleast_1d(np.asarray(theta1, dtype=float))
    n = max(len(a), len(b), len(t0), len(t1))
    dx = np.broadcast_to(b[:, 0] - a[:, 0], (n,))
    dy = np.broadcast_to(b[:, 1] - a[:, 1], (n,))
    dist = np.hypot(dx, dy)
    if radius <= 0.0:
        params = np.zeros((n, 3))
        params[:, 1] = dist
        return dist.copy(), np.zeros(n, dtype=np.int64), params
    d = dist / radius
    phi = np.arctan2(dy, dx)
    al = _mod(np.broadcast_to(t0, (n,)) - phi)
    be = _mod(np.broadcast_to(t1, (n,)) - phi)
    sa, sb, ca, cb = np.sin(al), np.sin(be), np.cos(al), np.cos(be)
    cab = np.cos(al - be)
    inf = np.full(n, np.inf)
    cand = np.full((6, n, 3), np.nan)
    with np.errstate(invalid="ignore"):
        # LSL
        psq = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)
        tmp = np.arctan2(cb - ca, d + sa - sb)
        cand[0] = np.stack([_mod(tmp - al), np.sqrt(psq), _mod(be - tmp)], axis=1)
        cand[0][psq < 0] = np.nan
        # RSR
        psq = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)
        tmp = np.arctan2(ca - cb, d - sa + sb)
        cand[1] = np.stack([_mod(al - tmp), np.sqrt(psq), _mod(tmp - be)], axis=1)
        cand[1][psq < 0] = np.nan
        # LSR
        psq = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)
        p = np.sqrt(psq)
        tmp = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        cand[2] = np.stack([_mod(tmp - al), p, _mod(tmp - be)], axis=1)
        cand[2][psq < 0] = np.nan
        # RSL
        psq = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)
        p = np.sqrt(psq)
        tmp = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        cand[3] = np.stack([_mod(al - tmp), p, _mod(be - tmp)], axis=1)
        cand[3][psq < 0] = np.nan
        # RLR
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0
        tmp = np.arctan2(ca - cb, d - sa + sb)
        p = _mod(TWO_PI - np.arccos(c))
        t = _mod(al - tmp + p / 2.0)
        cand[4] = np.stack([t, p, _mod(al - be - t + p)], axis=1)
        cand[4][np.abs(c) > 1.0] = np.nan
        # LRL
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0
        tmp = np.arctan2(ca - cb, d + sa - sb)
        p = _mod(TWO_PI - np.arccos(c))
        t = _mod(-al - tmp + p / 2.0)
        cand[5] = np.stack([t, p, _mod(be - al - t + p)], axis=1)
        cand[5][np.abs(c) > 1.0] = np.nan
    total = np.where(np.isnan(cand).any(axis=2), inf, np.nansum(cand, axis=2))
    word = np.argmin(total, axis=0)
    idx = np.arange(n)
    return total[word, idx] * radius, word.astype(np.int64), cand[word, idx]


def dubins_points(
    p0: ArrayLike, theta0: float, word: int, params: ArrayLike, radius: float, step: float = ARC_STEP
) -> Array:
    """Points along one Dubins path (arcs sampled every `step` radians), from its start to its end."""
    pos = np.asarray(p0, dtype=float).reshape(2).copy()
    heading = float(theta0)
    out = [pos.copy()]
    prm = np.asarray(params, dtype=float)
    if radius <= 0.0:
        out.append(pos + prm[1] * np.array([math.cos(heading), math.sin(heading)]))
        return np.array(out)
    for kind, value in zip(WORDS[word], prm, strict=True):
        if value <= 1e-12:
            continue
        if kind == 0:
            pos = pos + value * radius * np.array([math.cos(heading), math.sin(heading)])
            out.append(pos.copy())
            continue
        centre = pos + kind * radius * np.array([-math.sin(heading), math.cos(heading)])
        start = heading - kind * math.pi / 2.0      # angle of pos seen from the centre
        k = max(1, math.ceil(value / step))
        angles = start + kind * value * np.arange(1, k + 1) / k
        pts = centre + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        out.extend(pts)
        pos = pts[-1].copy()
        heading += kind * value
    return np.array(out)


def dubins_path(p0: ArrayLike, theta0: float, p1: ArrayLike, theta1: float, radius: float) -> Array:
    """Points of the shortest bounded-curvature path from pose (p0, theta0) to pose (p1, theta1).

    >>> pts = dubins_path([0, 0], 0.0, [0, 50], math.pi, 6.0)
    >>> pts[0].tolist(), pts[-1].round(6).tolist(), round(float(pts[:, 0].max()), 6)
    ([0.0, 0.0], [0.0, 50.0], 6.0)
    """
    a = np.asarray(p0, dtype=float).reshape(1, 2)
    b = np.asarray(p1, dtype=float).reshape(1, 2)
    turn = (theta1 - theta0) % (2.0 * math.pi)
    if np.linalg.norm(b - a) < 1e-9 and min(turn, 2.0 * math.pi - turn) < 1e-9:    # the poses coincide
        return np.concatenate([a, b])
    _, word, params = dubins(a, [theta0], b, [theta1], radius)
    pts = dubins_points(p0, theta0, int(word[0]), params[0], radius)
    if len(pts) < 2:
        return np.concatenate([a, b])
    pts[-1] = np.asarray(p1, dtype=float)        # remove the rounding of the last arc
    return pts
