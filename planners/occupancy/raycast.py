"""Exact voxel traversal of sonar beams for the occupancy map of seed 002 §2.1, vectorised across beams.

A beam from the transducer to its return passes through a chain of voxels; the seed's Bayes update marks all of
them free and the last one occupied. Amanatides and Woo step through that chain one voxel at a time; here the
same set is found without a loop: the beam enters a new voxel exactly where it crosses a grid plane, and the
planes it crosses along one axis are consecutive integers. So for each axis and beam the crossings are an
arithmetic sequence in the ray parameter t, every crossing names the voxel it enters (the crossed axis by
counting, the other two by flooring the point at t), and all crossings of all beams are laid out in one ragged
array with `np.repeat`. The crossing with the largest t enters the endpoint voxel and is left out (OctoMap's
`computeRayKeys` also excludes it). The voxels come out in no particular order, each beam's without repeats.

Ties (a beam through a voxel edge or corner) are measure-zero; there the voxel chain may differ from a
step-by-step walk by which of the touching voxels it names.

>>> beam, keys = ray_voxels([0.5, 0.5, 0.5], [[3.5, 0.5, 0.5]], 1.0)
>>> sorted(map(tuple, keys.tolist()))
[(0, 0, 0), (1, 0, 0), (2, 0, 0)]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

KeyArray = NDArray[np.int32]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Crossings:
    """Voxels entered where beams cross the grid planes normal to one `axis`.

    `counts[i]` crossings belong to beam i, and they come first for beam 0, then beam 1, …; `keys` holds the
    three integer coordinates of each entered voxel.
    """

    axis: int
    counts: NDArray[np.int64]
    keys: tuple[KeyArray, KeyArray, KeyArray]

    def beams(self) -> NDArray[np.intp]:
        """The beam index of each crossing."""
        return np.repeat(np.arange(len(self.counts)), self.counts)


def traverse(origin: ArrayLike, ends: ArrayLike, offset: ArrayLike = (0, 0, 0)) -> tuple[
        list[Crossings], NDArray[np.bool_]]:
    """The voxels beams pass through, origin voxel and endpoint voxel excluded, per crossed axis.

    `origin` (3,) and `ends` (N, 3) are in voxel units (voxel k spans [k, k + 1), k = floor(coordinate)); the keys
    returned are k − `offset` and must fit int32. Returns the crossings of each axis and, per beam, whether it
    leaves the origin voxel at all (if so, it passes the origin voxel too).
    """
    o = np.asarray(origin, dtype=float).reshape(3)
    e = np.asarray(ends, dtype=float).reshape(-1, 3)
    shift = np.asarray(offset, dtype=np.int64).reshape(3)
    k0 = np.floor(o).astype(np.int64)
    k1 = np.floor(e).astype(np.int64)
    d = e - o
    step = np.sign(k1 - k0)
    counts = np.abs(k1 - k0)
    # Crossing j (0, 1, …) along axis a enters voxel k0 + step·(1 + j) through the plane k0 + (step > 0) + step·j.
    first_plane = k0 + (step > 0)
    inv = np.divide(1.0, d, out=np.zeros_like(d), where=counts > 0)  # only axes a beam crosses are used
    first_t = (first_plane - o) * inv
    dt = np.abs(inv)
    # The last crossing along each axis enters the endpoint voxel's slab; the latest of them enters the endpoint
    # voxel itself and is dropped by shortening that axis' sequence by one.
    t_last = np.where(counts > 0, first_t + (counts - 1) * dt, -np.inf)
    moves = counts.sum(axis=1) > 0
    rows = np.flatnonzero(moves)
    counts[rows, np.argmax(t_last[rows], axis=1)] -= 1
    out = []
    for a in range(3):
        n = counts[:, a]
        total = int(n.sum())
        if total == 0:
            continue
        # Per-beam values are spread over that beam's crossings with np.repeat, which is cheaper than a gather.
        j = np.arange(total, dtype=np.int32) - np.repeat((np.cumsum(n) - n).astype(np.int32), n)
        entered = np.repeat((k0[a] - shift[a] + step[:, a]).astype(np.int32), n)
        entered += np.repeat(step[:, a].astype(np.int32), n) * j
        jf = j.astype(float)
        keys: list[KeyArray] = []
        for b in range(3):
            if b == a:
                keys.append(entered)
                continue
            position = np.repeat(o[b] + first_t[:, a] * d[:, b], n)
            position += np.repeat(dt[:, a] * d[:, b], n) * jf
            # Floor in absolute voxel units, then shift as integers: the keys agree exactly with floor(p / res).
            key = np.floor(position, out=position).astype(np.int32)
            key -= np.int32(shift[b])
            keys.append(key)
        out.append(Crossings(a, n, (keys[0], keys[1], keys[2])))
    return out, moves


def ray_voxels(origin: ArrayLike, endpoints: ArrayLike, resolution: float) -> tuple[NDArray[np.intp], IntArray]:
    """Keys (floor(p / resolution)) of the voxels each beam passes through, endpoint voxel excluded.

    `origin` (3,) is shared by the `endpoints` (N, 3), in metres. Returns (beam index (M,), keys (M, 3)); the
    origin voxel is listed for every beam that leaves it.
    """
    o = np.asarray(origin, dtype=float).reshape(3) / resolution
    e = np.asarray(endpoints, dtype=float).reshape(-1, 3) / resolution
    offset = np.floor(o).astype(np.int64)  # keys relative to the origin voxel fit int32 for any sensible beam
    segments, moves = traverse(o, e, offset)
    starts = np.flatnonzero(moves)
    beams = [starts] + [s.beams() for s in segments]
    keys = [np.broadcast_to(offset, (len(starts), 3))]
    keys += [np.stack(s.keys, axis=1).astype(np.int64) + offset for s in segments]
    return np.concatenate(beams), np.concatenate(keys)
