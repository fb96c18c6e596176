"""How complete the scan of one object is, from the explorer's own voxel map (seed 002 §2.2.2: the scan ends
when the object's model is complete, which the vehicle must judge without the truth).

The argument is that of a closed surface. An object's solid, seen from outside, is a region the scanner never
enters: its voxels stay unknown. When the whole surface has been observed, that unknown region is enclosed by
occupied voxels (the observed shell) and the seabed; wherever a part of the surface has not been observed, the
unknown region instead meets known-free space (a frontier) somewhere in front of it. So, within the object's
region (`region`: a mask the caller gives, without the seabed):

* `observed`: occupied voxels (or, given them, the voxels where beams ended) with a known-free face neighbour:
  the surface seen from outside, one voxel per 0.25 m patch (voxels behind them, which navigation error between
  views smears in, do not count);
* `hidden`: frontier voxels — unknown, with a known-free face neighbour, or running out of the region sideways
  or upwards — of the unknown space that is joined to the occupied shell (26-connected through unknown voxels of
  the region, or next to it): the boundary of what may still hide surface. Isolated unknown specks in swept
  water (between diverging beams) touch no shell and do not count;
* `fraction` = observed / (observed + hidden).

While whole sides are unseen the fraction leans high (their unknown pockets are only partly bounded by swept
water inside the region: ~14 points on the tests' L-shape); once only gaps, undersides and strips are left it
tracks the truth within a few points, which is where a stopping rule reads it. Surface that navigation error
between views has the map hold as free water is beyond any count of this map.

>>> import numpy as np
>>> s = np.zeros((7, 7, 7), dtype=np.int8)
>>> s[2:5, 2:5, 2:5] = 1; s[3, 3, 3] = -1          # a fully seen cube with its unknown inside
>>> region = np.ones(s.shape, dtype=bool)
>>> surface_completeness(s, region).fraction
1.0
>>> s[2:5, 2:5, 4] = -1; s[2:5, 2:5, 5] = -1        # its top layer not seen, and the water above it unknown
>>> c = surface_completeness(s, region); (c.observed, c.hidden, round(c.fraction, 3))   # the truth: 17 of 26
(17, 17, 0.5)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planners.nbv.derived import _dilate
from planners.nbv.grid import FREE, OCCUPIED, UNKNOWN

BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Completeness:
    """Voxel counts of an object's observed surface and of the frontier that may hide more, and their ratio."""

    observed: int
    hidden: int

    @property
    def fraction(self) -> float:
        """observed / (observed + hidden); 0 before anything is observed."""
        total = self.observed + self.hidden
        return self.observed / total if total else 0.0


def surface_completeness(states: NDArray[np.int8], region: BoolArray,
                         returns: BoolArray | None = None) -> Completeness:
    """The completeness of the surface inside `region` (a mask over `states`: 1 occupied, 0 free, −1 unknown).

    With `returns` (a mask of the voxels in which a beam has ended), the observed surface is those voxels rather
    than the occupied ones: a face seen at a grazing angle holds its returns in voxels that later beams, passing
    just above it on their way to the rest of the face, partly clear to free."""
    from scipy import ndimage

    if not region.any():
        return Completeness(0, 0)
    # Only the region's bounding box (and one voxel around it, for the free neighbours) matters.
    where = np.argwhere(region)
    lo, hi = np.maximum(where.min(axis=0) - 1, 0), where.max(axis=0) + 2
    box = tuple(slice(int(a), int(b)) for a, b in zip(lo, hi, strict=True))
    states, region = states[box], region[box]
    occupied = (states == OCCUPIED) & region
    seen = occupied if returns is None else returns[box] & region
    unknown = (states == UNKNOWN) & region
    beside_free = _dilate(states == FREE, faces_only=True)
    if not occupied.any():
        return Completeness(0, 0)
    labels, _ = ndimage.label(unknown, structure=np.ones((3, 3, 3), dtype=bool))
    touching = np.unique(labels[_dilate(occupied, faces_only=False) & unknown])
    joined = np.isin(labels, touching[touching > 0])
    open_ = beside_free | _leaves_region(region, states != OCCUPIED)
    return Completeness(int((seen & beside_free).sum()), int((unknown & open_ & joined).sum()))


def _leaves_region(region: BoolArray, passable: BoolArray) -> BoolArray:
    """Voxels with a face neighbour outside `region`, not occupied, sideways or above (axis 2 is depth; below the
    region lies the seabed): unknown space running out of the region there is open, as at a frontier, since a
    side no beam has reached yet has its frontier outside the region."""
    out = np.zeros_like(region)
    leave = ~region & passable
    for axis in (0, 1):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        out[tuple(lo)] |= leave[tuple(hi)]
        out[tuple(hi)] |= leave[tuple(lo)]
    out[:, :, 1:] |= leave[:, :, :-1]  # the neighbour above (smaller depth)
    return out


__all__ = ["Completeness", "surface_completeness"]
