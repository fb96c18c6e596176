"""Candidate viewpoints for next-best-view scanning (seed 002 §2.2.2).

The seed places the next viewpoint near the safe trajectory around the object generated at the start, inside
the safe limits near occupied voxels, and inside free voxels. Here the safe trajectory is the shell of points
`safe_distance` to `safe_distance + band` from the known structure: candidates are drawn on it around randomly
chosen occupied voxels — half of them on the open contour of the known structure within the scanner's range of
the vehicle (continuing where it is), a quarter on the contour anywhere, a quarter on any structure — and kept
when they

* lie in known-free voxels inside the exploration box,
* pass the safety grid (`derived.DerivedMaps.safety`): every point of their block at least `safe_distance` from
  every block holding occupied voxels *or mostly unknown* — unknown space may hide structure — with the same
  criterion the RRT between views uses (`planners.rrt`), so a candidate is a valid start or goal for it, plus one
  cell
  (`is_safe_view`: what a later scan may reveal next to space already known to be unsafe),

and look at the voxel they were drawn around (heading and pitch towards it, pitch limited, heading jittered by
up to a third of the horizontal field of view so that views also face past the known structure). Before any
structure is known they are drawn around the vehicle with random headings.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.grid import FREE, StateGrid
from planners.nbv.views import Scanner, Views, heading_pitch_towards
from planners.rrt import ClearanceGrid

Array = NDArray[np.float64]
EDGE_SHARE = 0.75
"""Share of anchors drawn from the open contour of the known structure (the rest: any occupied voxel)."""
LOCAL_SHARE = 0.5
"""Share of anchors drawn from the contour within the scanner's range of the vehicle (continuing where it is)."""


def required_clearance(safety: ClearanceGrid, safe_distance: float) -> float:
    """The clearance bound a voxel needs: the safety distance plus half the RRT's motion-checking step (the
    default step is a quarter of the grid cell; see `planners.rrt.planning`)."""
    return safe_distance + safety.cell / 8.0


def is_safe(safety: ClearanceGrid, points: ArrayLike, safe_distance: float) -> NDArray[np.bool_]:
    """(N,) True where points pass the safety grid with the RRT's criterion."""
    return safety.safe(points, required_clearance(safety, safe_distance))


def is_safe_view(safety: ClearanceGrid, points: ArrayLike, safe_distance: float) -> NDArray[np.bool_]:
    """(N,) `is_safe` with one more cell of clearance: structure a scan reveals in a block that was mostly known
    free (so not an obstacle yet) sits next to blocks that were, and would otherwise leave the vehicle, still
    truly safe, below the RRT's threshold at its own position."""
    return is_safe(safety, points, safe_distance + safety.cell)


def candidate_views(grid: StateGrid, safety: ClearanceGrid, current: ArrayLike, scanner: Scanner, *, count: int,
                    safe_distance: float, band: float | None = None, rng: np.random.Generator | None = None,
                    max_pitch_deg: float = 30.0, contour: ArrayLike | None = None, max_rounds: int = 20) -> Views:
    """Up to `count` safe candidate views on the shell around the known structure (see the module docstring).

    `contour` (flat grid ids, as `visibility.contour_voxels`) are the open-contour voxels to favour; `band`
    defaults to half the scanner's range.
    """
    rng = np.random.default_rng() if rng is None else rng
    band = scanner.max_range / 2.0 if band is None else float(band)
    occ = grid.occupied_centres()
    edge = np.zeros((0, 3)) if contour is None else grid.centres(
        np.stack(np.unravel_index(np.asarray(contour, dtype=np.int64), grid.shape), axis=1))
    here = np.asarray(current, dtype=float).reshape(3)
    lo, hi = grid.origin + grid.resolution, grid.upper - grid.resolution
    kept: list[Array] = []
    aims: list[Array] = []
    total = 0
    batch = max(8 * count, 64)
    for _ in range(max_rounds):
        u = rng.normal(size=(batch, 3))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        if len(occ):
            anchor = occ[rng.integers(len(occ), size=batch)]
            if len(edge):
                pick = rng.random(batch)
                on_edge = pick < EDGE_SHARE
                anchor[on_edge] = edge[rng.integers(len(edge), size=int(on_edge.sum()))]
                local = edge[np.linalg.norm(edge - here, axis=1) < scanner.max_range]
                if len(local):
                    mine = pick < LOCAL_SHARE
                    anchor[mine] = local[rng.integers(len(local), size=int(mine.sum()))]
            near = safe_distance + safety.cell  # nothing nearer passes `is_safe_view`
            r = rng.uniform(near, near + band, size=batch)
        else:
            anchor = np.broadcast_to(here, (batch, 3))
            r = rng.uniform(0.0, scanner.max_range / 2.0, size=batch)
        p = anchor + r[:, None] * u
        ok: NDArray[np.bool_] = np.asarray(((p > lo) & (p < hi)).all(axis=1))
        ok[ok] = grid.state(p[ok]) == FREE
        ok[ok] = is_safe_view(safety, p[ok], safe_distance)
        kept.append(p[ok])
        aims.append(anchor[ok] if len(occ) else p[ok] + u[ok])
        total += int(ok.sum())
        if total >= count:
            break
    positions = np.concatenate(kept)[:count]
    heading, pitch = heading_pitch_towards(positions, np.concatenate(aims)[:count])
    if not len(occ):
        heading = rng.uniform(0.0, 360.0, size=len(positions))
        pitch = np.zeros(len(positions))
    jitter = rng.uniform(-1.0, 1.0, size=len(positions)) * scanner.fov_deg[0] / 3.0
    return Views(positions, (heading + jitter) % 360.0, np.clip(pitch, -max_pitch_deg, max_pitch_deg))
