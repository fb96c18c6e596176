"""Transits around no-go zones (seed 002 §2.1: the survey avoids the forbidden zones between its passes too).

A visibility graph over the corners of the zones grown by the standoff gives the shortest polyline between two
points that keeps out of the zones; all-pairs distances between the corners are computed once per request
(Floyd–Warshall), so a batch of transit lengths costs a few array operations.

The graph is kept as numpy arrays, not a networkx graph: measured (`benchmarks/networkx_timing.py`) over the
coverage benchmark's 47 seeded scenes with zones (4–28 corners), `networkx.all_pairs_dijkstra` into the same
distance and next-hop arrays took 4.5–4.8× as long as the vectorised Floyd–Warshall (median of two runs; 1.8–10×).
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry.base import BaseGeometry

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _ring_vertices(geom: BaseGeometry) -> Array:
    rings = []
    for poly in shapely.get_parts(geom):
        if poly.geom_type != "Polygon":
            continue
        rings.append(np.asarray(poly.exterior.coords)[:-1])
        rings.extend(np.asarray(r.coords)[:-1] for r in poly.interiors)
    return np.concatenate(rings) if rings else np.zeros((0, 2))


class Router:
    """Shortest polylines that do not enter `blocking`, through the vertices of `obstacles` (which contain it).

    >>> from shapely.geometry import box
    >>> router = Router(box(-1.0, -1.0, 1.0, 1.0), box(-0.9, -0.9, 0.9, 0.9))
    >>> router.route([-2.0, -0.5], [2.0, -0.5]).tolist()       # round the square by its nearer side
    [[-2.0, -0.5], [-1.0, -1.0], [1.0, -1.0], [2.0, -0.5]]
    >>> round(float(router.lengths([[-2.0, -0.5]], [[2.0, -0.5]])[0, 0]), 4)
    4.2361
    """

    def __init__(self, obstacles: BaseGeometry, blocking: BaseGeometry):
        self.blocking = blocking
        self.empty = bool(blocking.is_empty)
        self._seen: dict[bytes, Array] = {}
        # the zones one by one behind a tree of their extents: most segments pass far from all of them
        self._parts = shapely.get_parts(blocking)
        shapely.prepare(self._parts)
        self._tree = shapely.STRtree(self._parts)
        self.nodes = _ring_vertices(obstacles) if not self.empty else np.zeros((0, 2))
        n = len(self.nodes)
        dist = np.full((n, n), np.inf)
        nxt = np.full((n, n), -1, dtype=np.int64)
        if n:
            i, j = np.triu_indices(n, 1)
            ok = self.clear(self.nodes[i], self.nodes[j])
            d = np.linalg.norm(self.nodes[i] - self.nodes[j], axis=1)
            dist[i[ok], j[ok]] = dist[j[ok], i[ok]] = d[ok]
            nxt[i[ok], j[ok]] = j[ok]
            nxt[j[ok], i[ok]] = i[ok]
            np.fill_diagonal(dist, 0.0)
            np.fill_diagonal(nxt, np.arange(n))
            for k in range(n):
                alt = dist[:, k : k + 1] + dist[k : k + 1, :]
                better = alt < dist
                if better.any():
                    dist = np.where(better, alt, dist)
                    nxt = np.where(better, nxt[:, k : k + 1], nxt)
        self.dist = dist
        self.next = nxt

    def clear(self, a: ArrayLike, b: ArrayLike) -> BoolArray:
        """Whether each straight segment a[i] → b[i] keeps out of the blocking zones."""
        pa = np.atleast_2d(np.asarray(a, dtype=float))
        pb = np.atleast_2d(np.asarray(b, dtype=float))
        pa, pb = np.broadcast_arrays(pa, pb)
        if self.empty or len(pa) == 0:
            return np.ones(len(pa), dtype=bool)
        segs = shapely.linestrings(np.stack([pa, pb], axis=1))
        seg, part = self._tree.query(segs)                 # extents that overlap
        out = np.ones(len(segs), dtype=bool)
        out[seg[shapely.intersects(self._parts[part], segs[seg])]] = False
        return out

    def _reach(self, pts: Array) -> Array:
        """Straight distance from each point to each graph node it sees (inf where hidden); remembered per point,
        since the ends of lines are asked about again and again."""
        keys = [p.tobytes() for p in np.ascontiguousarray(pts, dtype=float)]
        todo = [i for i, k in enumerate(keys) if k not in self._seen]
        if todo:
            v = len(self.nodes)
            a = np.repeat(pts[todo], v, axis=0)
            b = np.tile(self.nodes, (len(todo), 1))
            d = np.where(self.clear(a, b), np.linalg.norm(a - b, axis=1), np.inf).reshape(len(todo), v)
            for i, row in zip(todo, d, strict=True):
                self._seen[keys[i]] = row
        return np.array([self._seen[k] for k in keys]).reshape(len(keys), len(self.nodes))

    def lengths(self, p: ArrayLike, q: ArrayLike) -> Array:
        """Lengths of the shortest zone-avoiding polylines from each p[i] to each q[j] (inf if there is none)."""
        pp = np.atleast_2d(np.asarray(p, dtype=float))
        qq = np.atleast_2d(np.asarray(q, dtype=float))
        n, m = len(pp), len(qq)
        direct = np.linalg.norm(pp[:, None, :] - qq[None, :, :], axis=2)
        if self.empty:
            return np.asarray(direct, dtype=float)
        clear = self.clear(np.repeat(pp, m, axis=0), np.tile(qq, (n, 1))).reshape(n, m)
        if clear.all() or len(self.nodes) == 0:
            return np.where(clear, direct, np.inf)
        rows = np.flatnonzero(~clear.all(axis=1))
        cols = np.flatnonzero(~clear.all(axis=0))
        via = (self._reach(pp[rows])[:, :, None] + self.dist[None, :, :]).min(axis=1)
        routed = (via[:, None, :] + self._reach(qq[cols])[None, :, :]).min(axis=2)
        out = np.where(clear, direct, np.inf)
        block = out[np.ix_(rows, cols)]
        out[np.ix_(rows, cols)] = np.where(clear[np.ix_(rows, cols)], block, routed)
        return out

    def pair_lengths(self, p: ArrayLike, q: ArrayLike) -> Array:
        """Lengths of the shortest zone-avoiding polylines from p[i] to q[i]."""
        pp = np.atleast_2d(np.asarray(p, dtype=float))
        qq = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.linalg.norm(pp - qq, axis=1)
        if self.empty:
            return np.asarray(out, dtype=float)
        blocked = np.flatnonzero(~self.clear(pp, qq))
        if blocked.size == 0:
            return np.asarray(out, dtype=float)
        if len(self.nodes) == 0:
            out[blocked] = np.inf
            return np.asarray(out, dtype=float)
        via = (self._reach(pp[blocked])[:, :, None] + self.dist[None, :, :]).min(axis=1)
        out[blocked] = (via + self._reach(qq[blocked])).min(axis=1)
        return np.asarray(out, dtype=float)

    def route(self, p: ArrayLike, q: ArrayLike) -> Array:
        """The shortest zone-avoiding polyline from p to q; the straight segment if none exists."""
        a = np.asarray(p, dtype=float).reshape(2)
        b = np.asarray(q, dtype=float).reshape(2)
        if self.empty or bool(self.clear(a, b)[0]) or len(self.nodes) == 0:
            return np.array([a, b])
        ra = self._reach(a[None])[0]
        rb = self._reach(b[None])[0]
        total = ra[:, None] + self.dist + rb[None, :]
        i, j = np.unravel_index(int(np.argmin(total)), total.shape)
        if not np.isfinite(total[i, j]):
            return np.array([a, b])
        path = [a, self.nodes[i]]
        k = int(i)
        while k != j:
            k = int(self.next[k, j])
            path.append(self.nodes[k])
        path.append(b)
        return np.array(path)
