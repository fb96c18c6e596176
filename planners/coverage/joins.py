"""Turns between consecutive survey lines (seed 002 §2.1), pulled back from no-go zones when needed.

A turn leaves one line and enters the next in the opposite direction; it is the Dubins path between the two
poses (U-turn or Ω-turn, see `turns`). When it would touch a zone, both line ends are pulled back in small steps
until it clears; a pair that cannot be joined that way is not joined (the cell is split there, the baseline
transits instead). The contour passes fill the swath the pulled-back ends leave.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .runs import Run
from .scene import Scene
from .sweep import Sweep
from .turns import dubins, dubins_points

Array = NDArray[np.float64]
PULL_STEPS = 8


@dataclass(frozen=True)
class Join:
    path: Array        # from the (pulled-back) end of the first line to the (pulled-back) start of the second
    cut_a: float       # how far the first line's end was pulled back
    cut_b: float       # how far the second line's start was pulled back


class Joiner:
    """Turns and meanders over the lines of one sweep."""

    def __init__(self, scene: Scene, sweep: Sweep):
        self.scene = scene
        self.sweep = sweep
        self.step = max(0.5, 0.5 * scene.radius)

    def _end_u(self, pid: int, direction: int) -> float:
        p = self.sweep.pieces[pid]
        return p.u1 if direction > 0 else p.u0

    def join_many(self, requests: Sequence[tuple[int, int, int]]) -> list[Join | None]:
        """Turns for (a, side, b): line a flown towards `side` (±1 along u), then line b flown back."""
        out: list[Join | None] = [None] * len(requests)
        pending = list(range(len(requests)))
        pieces = self.sweep.pieces
        for level in range(PULL_STEPS + 1):
            cut = level * self.step
            todo = [k for k in pending        # no end is pulled back into a detour
                    if cut <= min(pieces[requests[k][0]].room(requests[k][1]),
                                  pieces[requests[k][2]].room(-requests[k][1])) + 1e-9]
            if not todo:
                break
            a = np.array([requests[k][0] for k in todo])
            side = np.array([requests[k][1] for k in todo], dtype=float)
            b = np.array([requests[k][2] for k in todo])
            ua = np.array([self._end_u(int(i), int(s)) for i, s in zip(a, side, strict=True)]) - side * cut
            ub = np.array([self._end_u(int(i), int(s)) for i, s in zip(b, side, strict=True)]) - side * cut
            va = np.array([pieces[int(i)].v for i in a])
            vb = np.array([pieces[int(i)].v for i in b])
            p0 = self.sweep.points(ua, va)
            p1 = self.sweep.points(ub, vb)
            t0 = np.where(side > 0, self.sweep.angle(1), self.sweep.angle(-1))
            t1 = np.where(side > 0, self.sweep.angle(-1), self.sweep.angle(1))
            _, word, params = dubins(p0, t0, p1, t1, self.scene.radius)
            paths = []
            for i in range(len(todo)):
                pts = dubins_points(p0[i], float(t0[i]), int(word[i]), params[i], self.scene.radius)
                pts[-1] = p1[i]
                paths.append(pts)
            ok = self.scene.valid(paths)
            done = set()
            for i, k in enumerate(todo):
                if ok[i]:
                    out[k] = Join(paths[i], cut, cut)
                    done.add(k)
            pending = [k for k in pending if k not in done]
            if not pending:
                break
        return out

    def run(self, items: Sequence[tuple[int, int]], joins: Sequence[Join]) -> Run:
        """The run flying pieces `items` ((piece id, direction) in order) joined by the given turns."""
        k = len(items)
        cut_start = [0.0] * k
        cut_end = [0.0] * k
        for j, join in enumerate(joins):
            cut_end[j] = join.cut_a
            cut_start[j + 1] = join.cut_b
        parts: list[Array] = []
        lines: list[Array] = []
        for j, (pid, d) in enumerate(items):
            p = self.sweep.pieces[pid]
            u_start = (p.u0 if d > 0 else p.u1) + d * cut_start[j]
            u_end = (p.u1 if d > 0 else p.u0) - d * cut_end[j]
            uv = p.uv(u_start, u_end)
            pts = self.sweep.points(uv[:, 0], uv[:, 1])
            lines.extend(pts[k : k + 2] for k in range(len(pts) - 1))     # a detour's every straight is a pass
            parts.append(pts[:1] if j == 0 else joins[j - 1].path[1:])
            parts.append(pts[1:])
        return Run(np.concatenate(parts), tuple(lines), self.sweep.angle(items[0][1]),
                   self.sweep.angle(items[-1][1]), k - 1)

    def meander(self, cell: Sequence[int], d0: int, table: dict[tuple[int, int, int], Join | None]) -> Run:
        """A cell flown as a meander starting towards `d0`, with the turns from `table` (all must exist)."""
        items = [(pid, d0 if j % 2 == 0 else -d0) for j, pid in enumerate(cell)]
        joins = []
        for j in range(len(items) - 1):
            join = table[(items[j][0], items[j][1], items[j + 1][0])]
            assert join is not None
            joins.append(join)
        return self.run(items, joins)

    def sequence(self, items: Sequence[tuple[int, int]]) -> list[Run]:
        """Runs flying `items` in the given order: consecutive lines of adjacent rows flown in opposite
        directions are joined by a turn where one clears the zones; anything else starts a new run."""
        pieces = self.sweep.pieces
        requests = []
        where = []
        for j in range(len(items) - 1):
            (a, da), (b, db) = items[j], items[j + 1]
            if abs(pieces[a].row - pieces[b].row) == 1 and db == -da:
                requests.append((a, da, b))
                where.append(j)
        joins = dict(zip(where, self.join_many(requests), strict=True))
        runs = []
        start = 0
        current: list[Join] = []
        for j in range(len(items) - 1):
            join = joins.get(j)
            if join is not None:
                current.append(join)
                continue
            runs.append(self.run(items[start : j + 1], current))
            start, current = j + 1, []
        runs.append(self.run(items[start:], current))
        return runs
