"""What a photograph reveals of the information map: the camera footprint's cells, with diminishing returns.

A down-looking camera at a pose (north, east, heading) images a rectangle `across` wide (to starboard) and
`along` long (fore–aft) centred under it. A cell of normalised information Î photographed n times has given

    Î · (1 − ρⁿ)          (ρ = `repeat` ∈ [0, 1): the share of a cell's information still unrevealed per photo)

so the first photograph of a cell reveals (1 − ρ) of it, each further one ρ times less than the one before: the
survey is rewarded for photographing informative ground more than once (the overlap photogrammetry needs), with
diminishing returns, and not at all for going over blank ground again. The footprint's cells are looked up from
offsets precomputed for 10° heading bins (cell centres inside the rotated rectangle centred on the photo's
cell), so a photograph costs one small integer-array gather.

>>> import numpy as np
>>> from planners.rrt.information import InformationField, resample
>>> f = InformationField(np.ones((5, 5)), north0=0.0, east0=0.0, cell=1.0)
>>> cam = PhotoModel(f, across=3.0, along=1.0, repeat=0.5)
>>> counts = cam.counts([[2.0, 2.0]], [0.0])
>>> int(counts.sum()), round(cam.revealed(counts), 2)   # 3 cells across track, 1 along; half of each revealed
(3, 1.5)
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.rrt.information import InformationField, resample

Array = NDArray[np.float64]
Counts = NDArray[np.int16]
HEADING_BINS = 36


class PhotoModel:
    """Footprint cells of photographs on an information field and the information they reveal."""

    def __init__(self, field: InformationField, across: float, along: float, repeat: float = 0.5) -> None:
        if not 0.0 <= repeat < 1.0:
            raise ValueError(f"repeat must lie in [0, 1), got {repeat}")
        if not (across > 0 and along > 0):
            raise ValueError(f"footprint must be positive, got {across} x {along}")
        self.field = field
        self.info = field.normalised()
        self.flat_info = self.info.ravel()
        self.info_list: list[float] = self.flat_info.tolist()
        self.shape = self.info.shape
        self.across, self.along, self.repeat = float(across), float(along), float(repeat)
        self.offsets = [self._offsets(2.0 * math.pi * k / HEADING_BINS) for k in range(HEADING_BINS)]

    def _offsets(self, heading: float) -> NDArray[np.int64]:
        """(K, 2) row/column offsets of the cells whose centres lie in the footprint at `heading` (radians)."""
        c = self.field.cell
        reach = int(math.ceil(0.5 * math.hypot(self.across, self.along) / c)) + 1
        di, dj = np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1), indexing="ij")
        n, e = di.ravel() * c, dj.ravel() * c
        fwd = n * math.cos(heading) + e * math.sin(heading)
        stb = -n * math.sin(heading) + e * math.cos(heading)
        inside = (np.abs(fwd) <= self.along / 2.0 + 1e-9) & (np.abs(stb) <= self.across / 2.0 + 1e-9)
        if not inside.any():  # a footprint smaller than a cell still images the cell under the camera
            inside = (di.ravel() == 0) & (dj.ravel() == 0)
        return np.stack([di.ravel()[inside], dj.ravel()[inside]], axis=1)

    def cells(self, north: float, east: float, heading: float) -> NDArray[np.int64]:
        """Flat indices of the on-map cells one photograph at (north, east, heading in radians) images."""
        f = self.field
        i = math.floor((north - f.north0) / f.cell + 0.5)
        j = math.floor((east - f.east0) / f.cell + 0.5)
        k = round(heading / (2.0 * math.pi) * HEADING_BINS) % HEADING_BINS
        off = self.offsets[k]
        rows, cols = off[:, 0] + i, off[:, 1] + j
        on = (rows >= 0) & (rows < self.shape[0]) & (cols >= 0) & (cols < self.shape[1])
        return np.asarray(rows[on] * self.shape[1] + cols[on])

    def info_at(self, north: float, east: float) -> float:
        """Î of the cell nearest (north, east); 0 off the map."""
        f = self.field
        i = math.floor((north - f.north0) / f.cell + 0.5)
        j = math.floor((east - f.east0) / f.cell + 0.5)
        if 0 <= i < self.shape[0] and 0 <= j < self.shape[1]:
            return float(self.info_list[i * self.shape[1] + j])
        return 0.0

    def zero_counts(self) -> Counts:
        return np.zeros(self.info.size, dtype=np.int16)

    def add(self, counts: Counts, cells: NDArray[np.int64]) -> float:
        """Count one photograph of `cells` into `counts` (in place); returns the information it revealed."""
        gain = float(np.sum(self.flat_info[cells] * self.repeat ** counts[cells].astype(float))) * (1.0 - self.repeat)
        counts[cells] += 1
        return gain

    def counts(self, points: ArrayLike, headings: ArrayLike) -> Counts:
        """How often each cell (flat) is photographed by photos at points (M, ≥2) with headings (M,) in radians."""
        out = self.zero_counts()
        p = np.atleast_2d(np.asarray(points, dtype=float))
        for (n, e), h in zip(p[:, :2], np.asarray(headings, dtype=float).reshape(-1), strict=True):
            np.add.at(out, self.cells(float(n), float(e), float(h)), 1)
        return out

    def revealed(self, counts: Counts) -> float:
        """Σ Î·(1 − ρⁿ): the information the photographs counted in `counts` revealed."""
        return float(np.sum(self.flat_info * (1.0 - self.repeat ** counts.astype(float))))

    def seen(self, counts: Counts) -> float:
        """Σ Î over cells photographed at least once (no credit for repeats)."""
        return float(np.sum(self.flat_info[counts > 0]))

    def high_share(self, counts: Counts, threshold: float = 0.5) -> float:
        """Share of the cells with Î ≥ threshold photographed at least once (1 when there is none)."""
        high = self.flat_info >= threshold
        return float(np.mean(counts[high] > 0)) if high.any() else 1.0


def path_headings(path: ArrayLike, points: ArrayLike) -> Array:
    """Heading (radians) of a polyline (K, ≥2) at the vertex nearest each point (M, ≥2): the camera's yaw there."""
    p = _dense(path)[:, :2]
    q = np.atleast_2d(np.asarray(points, dtype=float))[:, :2]
    d = np.diff(p, axis=0)
    seg = np.arctan2(d[:, 1], d[:, 0]) if len(d) else np.zeros(1)
    vertex = np.concatenate([seg, seg[-1:]])
    nearest = np.argmin(((q[:, None, :] - p[None, :, :]) ** 2).sum(axis=2), axis=1)
    return np.asarray(vertex[nearest])


def truncate(path: ArrayLike, points: ArrayLike, budget: float) -> tuple[Array, Array]:
    """The polyline (resampled every 0.5 m) cut at arc length `budget`, and the photo points whose nearest point
    of it lies before the cut."""
    p = _dense(path)
    q = np.atleast_2d(np.asarray(points, dtype=float))
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    if s[-1] <= budget:
        return p, q
    k = int(np.searchsorted(s, budget))
    t = (budget - s[k - 1]) / (s[k] - s[k - 1])
    cut = np.concatenate([p[:k], (p[k - 1] + t * (p[k] - p[k - 1]))[None]])
    nearest = np.argmin(((q[:, None, :2] - p[None, :, :2]) ** 2).sum(axis=2), axis=1)
    return cut, q[s[nearest] <= budget]


def _dense(path: ArrayLike) -> Array:
    p = np.asarray(path, dtype=float)
    return resample(p if p.shape[1] == 3 else np.column_stack([p[:, :2], np.zeros(len(p))]), 0.5)
