"""Boustrophedon cell decomposition of the free area (seed 002 §2.1; Choset's decomposition, found on the swath
grid).

Sweeping across the line direction, a cell continues while each band has exactly one slice linked to exactly one
slice of the next band; where the number of slices changes (a zone or a bay of the boundary splits or merges the
lines) the cell ends and new ones begin. Each cell is then one meander. Lines that the vehicle cannot join by a
turn without touching a zone split a cell further, and each cell offers the meanders it can be flown by (start
side, and either end) so that the cells can be ordered.
"""

from __future__ import annotations

from collections import defaultdict

from .joins import Join, Joiner
from .runs import Run
from .sweep import Sweep


def decompose(sweep: Sweep) -> list[list[int]]:
    """Cells as chains of piece ids, one piece per row, rows increasing.

    A piece continues into the one above when that is its only upper neighbour and it is that one's only lower
    neighbour (no split or merge between the two rows).

    >>> from shapely.geometry import box
    >>> from .sweep import build_sweep
    >>> zone = box(150, 30, 250, 70)
    >>> decompose(build_sweep(box(0, 0, 400, 100).difference(zone), zone, 90.0, 30.0))   # below, left, right, above
    [[0], [1, 3], [2, 4], [5]]
    """
    up: dict[int, list[int]] = defaultdict(list)
    down: dict[int, list[int]] = defaultdict(list)
    for p, q in sweep.links:
        up[p].append(q)
        down[q].append(p)
    nxt: dict[int, int] = {}
    has_prev: set[int] = set()
    for p in range(len(sweep.pieces)):
        if len(up[p]) == 1 and len(down[up[p][0]]) == 1:
            nxt[p] = up[p][0]
            has_prev.add(up[p][0])
    chains = []
    for p in range(len(sweep.pieces)):
        if p in has_prev:
            continue
        chain = [p]
        while chain[-1] in nxt:
            chain.append(nxt[chain[-1]])
        chains.append(chain)
    return chains


def cell_variants(joiner: Joiner, chains: list[list[int]]) -> list[list[Run]]:
    """For each cell the meanders it can be flown by: one per feasible start side, each forwards and backwards.

    Consecutive lines of a cell alternate direction; the turn between lines j and j+1 happens on the side where
    line j ends. Both sides are tried for every pair; a cell whose pair cannot be turned on the side either start
    direction needs is split there.
    """
    pairs = [(c[j], c[j + 1]) for c in chains for j in range(len(c) - 1)]
    requests = [(a, side, b) for a, b in pairs for side in (1, -1)]
    joins = joiner.join_many(requests)
    table = {(a, side, b): joins[k] for k, (a, side, b) in enumerate(requests)}
    tasks: list[list[Run]] = []
    for chain in chains:
        start = 0
        feasible = {1, -1}                 # start directions still possible for the cell begun at `start`
        for j in range(len(chain) - 1):
            keep = set()
            for d0 in feasible:
                side = d0 if (j - start) % 2 == 0 else -d0
                if table[(chain[j], side, chain[j + 1])] is not None:
                    keep.add(d0)
            if keep:
                feasible = keep
                continue
            tasks.append(_variants(joiner, chain[start : j + 1], feasible, table))
            start, feasible = j + 1, {1, -1}
        tasks.append(_variants(joiner, chain[start:], feasible, table))
    return tasks


def _variants(joiner: Joiner, cell: list[int], starts: set[int],
              table: dict[tuple[int, int, int], Join | None]) -> list[Run]:
    out = []
    if len(cell) == 1:                     # one line: the other start side is the same line flown backwards
        starts = {max(starts)}
    for d0 in sorted(starts, reverse=True):
        run = joiner.meander(cell, d0, table)
        out.extend([run, run.reversed()])
    return out
