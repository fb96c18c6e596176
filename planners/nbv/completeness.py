"""How complete the scan of one object is, from the explorer's own voxel map (seed 002 §2.2.2: the scan ends
when the object's model is complete, which the vehicle must judge without the truth).

The argument is that of a closed surface. An object's solid, seen from outside, is a region the scanner never
enters: its voxels stay unknown. When the whole surface has been observed, that unknown region is enclosed by
occupied voxels (the observed shell) and the seabed; wherever a part of the surface has not been observed, the
unknown region instead meets known-free space (a frontier) somewhere in front of it. So, within the object's
region (`region`: a mask the caller gives, without the seabed):

* `observed`: occupied voxels with a known-free face neighbour (the surface seen from outside, one voxel per
  0.25 m patch; occupied voxels behind them, which navigation error between views smears in, do not count);
* `hidden`: frontier voxels — unknown, with a known-free face neighbour — of the unknown space that is joined
  to the observed shell (26-connected through unknown voxels of the region, or next to it): the boundary of what
  may still hide surface. Isolated unknown specks in swept water (between diverging beams) touch no shell and do
  not count;
* `fraction` = observed / (observed + hidden).

A frontier in front of an unseen face has about the face's area (a thin pocket) or a little more (a deeper one),
so the fraction leans low while large faces are missing, and tracks the truth closely once only gaps, undersides
and strips are left, which is where a stopping rule reads it.

>>> import numpy as np
>>> s = np.zeros((7, 7, 7), dtype=np.int8)
>>> s[2:5, 2:5, 2:5] = 1; s[3, 3, 3] = -1          # a fully seen cube with its unknown inside
>>> region = np.ones(s.shape, dtype=bool)
>>> surface_completeness(s, region).fraction
1.0
>>> s[2:5, 2:5, 4] = -1; s[2:5, 2:5, 5] = -1        # its top layer not seen, and the water above it unknown
>>> c = surface_completeness(s, region); (c.observed, c.hidden, round(c.fraction, 3))
(17, 9, 0.654)
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


def surface_completeness(states: NDArray[np.int8], region: BoolArray) -> Completeness:
    """The completeness of the surface inside `region` (a mask over `states`: 1 occupied, 0 free, −1 unknown)."""
    from scipy import ndimage

    occupied = (states == OCCUPIED) & region
    unknown = (states == UNKNOWN) & region
    beside_free = _dilate(states == FREE, faces_only=True)
    if not occupied.any():
        return Completeness(0, 0)
    labels, _ = ndimage.label(unknown, structure=np.ones((3, 3, 3), dtype=bool))
    touching = np.unique(labels[_dilate(occupied, faces_only=False) & unknown])
    joined = np.isin(labels, touching[touching > 0])
    return Completeness(int((occupied & beside_free).sum()), int((unknown & beside_free & joined).sum()))


__all__ = ["Completeness", "surface_completeness"]
