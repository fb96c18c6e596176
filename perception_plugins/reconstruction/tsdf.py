"""Fusion of range maps into a truncated signed-distance volume in a hashed block layout (seed 003
"3D reconstruction", second stage: the voxel method after Curless and Levoy, seed 003 refs. [11], [17]).

The volume is a dict from block coordinates to rows of flat per-voxel arrays; a block holds 4³ voxels, so memory
follows the observed surface, not its bounding box. Integrating a range map taken at `T_world_cam`:

1. allocation: every valid pixel (on a sparse grid) is back-projected, and the blocks within the truncation
   distance of it along its ray are created;
2. update: every voxel of those blocks is projected into the map; where the map has a depth, the projective
   signed distance sdf = depth − z_voxel (positive in front of the surface) is truncated to [−1, 1]·trunc and
   averaged with weight (σ_ref / σ_Z)² (close, well-textured measurements count more); voxels more than `trunc`
   behind the surface are left alone. The grey level and the best (largest) |cos| of the viewing incidence
   fuse alongside: the first colours the mesh, the second lets `clean` drop triangles seen only at grazing angles.

Everything is vectorised per frame (numpy, float32); no voxel loop runs in Python. With `bounds`, only the blocks
in that box are created (the object to reconstruct, not the seabed to the horizon).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception_plugins.reconstruction.depth import RangeMap, incidence_cosines

Array = NDArray[np.float64]
BLOCK = 4
_SHIFT = 6
"""log2(BLOCK³): a flat voxel index >> _SHIFT is its block's row, & (BLOCK³ − 1) the voxel in it."""
_OFFSETS = np.stack(np.meshgrid(np.arange(BLOCK), np.arange(BLOCK), np.arange(BLOCK), indexing="ij"),
                    axis=-1).reshape(-1, 3)


@dataclass(frozen=True, eq=False)
class DenseVolume:
    """The fused volume copied into a dense box: voxel (i, j, k) has its centre at origin + voxel·(i, j, k)."""

    origin: Array
    voxel: float
    tsdf: NDArray[np.float32]
    weight: NDArray[np.float32]
    grey: NDArray[np.float32]
    best_cos: NDArray[np.float32]


class HashedTsdf:
    """A sparse TSDF of `voxel` metres with truncation `trunc` metres (default four voxels)."""

    def __init__(self, voxel: float = 0.02, trunc: float | None = None, sigma_ref: float = 0.01,
                 max_weight: float = 64.0, bounds: tuple[Array, Array] | None = None) -> None:
        """`bounds`: (lo, hi) world corners of the region to reconstruct; blocks outside are never created."""
        self.voxel = float(voxel)
        self.bounds = None if bounds is None else (np.asarray(bounds[0], float), np.asarray(bounds[1], float))
        self.trunc = float(trunc if trunc is not None else 4.0 * voxel)
        self.sigma_ref = sigma_ref
        self.max_weight = max_weight
        self.index: dict[tuple[int, int, int], int] = {}
        capacity = 256
        self.coords = np.zeros((capacity, 3), dtype=np.int64)
        self.tsdf = np.ones((capacity, BLOCK**3), dtype=np.float32)
        self.weight = np.zeros((capacity, BLOCK**3), dtype=np.float32)
        self.grey = np.zeros((capacity, BLOCK**3), dtype=np.float32)
        self.best_cos = np.zeros((capacity, BLOCK**3), dtype=np.float32)

    @property
    def blocks(self) -> int:
        return len(self.index)

    @property
    def nbytes(self) -> int:
        """Bytes held by the allocated blocks (four float32 per voxel, plus coordinates)."""
        return self.blocks * (4 * 4 * BLOCK**3 + 3 * 8)

    def _grow(self, needed: int) -> None:
        capacity = len(self.coords)
        if needed <= capacity:
            return
        new = max(needed, 2 * capacity)
        self.coords = np.concatenate([self.coords, np.zeros((new - capacity, 3), dtype=np.int64)])
        for name, fill in (("tsdf", 1.0), ("weight", 0.0), ("grey", 0.0), ("best_cos", 0.0)):
            old = getattr(self, name)
            setattr(self, name, np.concatenate([old, np.full((new - capacity, BLOCK**3), fill, dtype=np.float32)]))

    def _rows_for(self, keys: NDArray[np.int64]) -> NDArray[np.int64]:
        """Rows of these block coordinates, allocating the missing ones."""
        rows = np.empty(len(keys), dtype=np.int64)
        fresh = []
        for n, (i, j, k) in enumerate(keys.tolist()):
            key = (i, j, k)
            row = self.index.get(key)
            if row is None:
                row = len(self.index)
                self.index[key] = row
                fresh.append(n)
            rows[n] = row
        self._grow(len(self.index))
        if fresh:
            self.coords[rows[fresh]] = keys[fresh]
        return rows

    def touched_blocks(self, rmap: RangeMap, T_world_cam: Array, stride: int = 4) -> NDArray[np.int64]:
        """Unique coordinates of the blocks within `trunc` of the map's surface points along their rays."""
        depth = rmap.depth[::stride, ::stride]
        v, u = np.nonzero(np.isfinite(depth))
        z = depth[v, u].astype(float)
        K = rmap.K
        rays = np.column_stack([(u * stride - K[0, 2]) / K[0, 0], (v * stride - K[1, 2]) / K[1, 1], np.ones(len(u))])
        R, t = T_world_cam[:3, :3], T_world_cam[:3, 3]
        size = BLOCK * self.voxel
        steps = np.linspace(-self.trunc, self.trunc, max(int(np.ceil(2 * self.trunc / size)) + 1, 3))
        keys = []
        norm = np.linalg.norm(rays, axis=1)
        for s in steps:
            pts = (rays * (z + s / norm * 1.0)[:, None]) @ R.T + t
            keys.append(np.floor(pts / size).astype(np.int64))
        return np.unique(np.concatenate(keys), axis=0)

    def integrate(self, rmap: RangeMap, T_world_cam: Array) -> None:
        """Fuse one range map taken with the camera at `T_world_cam` (4×4, camera → world)."""
        keys = self.touched_blocks(rmap, T_world_cam)
        if self.bounds is not None:
            size = BLOCK * self.voxel
            lo, hi = np.floor(self.bounds[0] / size), np.floor(self.bounds[1] / size)
            keys = keys[np.all((keys >= lo) & (keys <= hi), axis=1)]
        if len(keys) == 0:
            return
        rows = self._rows_for(keys)
        R = T_world_cam[:3, :3].astype(np.float32)
        t = T_world_cam[:3, 3]
        # Voxel centres in the camera frame: block origins (float64, exact) then float32 offsets.
        origins = ((keys * BLOCK * self.voxel - t) @ T_world_cam[:3, :3]).astype(np.float32)
        offsets = (_OFFSETS * self.voxel).astype(np.float32) @ R
        p_cam = (origins[:, None, :] + offsets[None]).reshape(-1, 3)
        z = p_cam[:, 2]
        K = rmap.K.astype(np.float32)
        h, w = rmap.depth.shape
        with np.errstate(divide="ignore", invalid="ignore"):
            inv_z = np.float32(1.0) / z
            u = np.rint(K[0, 0] * p_cam[:, 0] * inv_z + K[0, 2])
            v = np.rint(K[1, 1] * p_cam[:, 1] * inv_z + K[1, 2])
        inside = (z > 0) & (u >= 0) & (u < w) & (v >= 0) & (v < h)
        flat = np.flatnonzero(inside)
        pix = v[flat].astype(np.int64) * w + u[flat].astype(np.int64)
        d = rmap.depth.reshape(-1)[pix]
        sdf = d - z[flat]
        keep = sdf > -self.trunc  # NaN depths compare False
        flat, pix, sdf = flat[keep], pix[keep], sdf[keep]
        sigma = rmap.sigma.reshape(-1)[pix]
        w_new = np.minimum((np.float32(self.sigma_ref) / np.maximum(sigma, np.float32(1e-4))) ** 2, np.float32(4.0))
        value = np.clip(sdf * np.float32(1.0 / self.trunc), -1.0, 1.0)
        at = rows[flat >> _SHIFT] * BLOCK**3 + (flat & (BLOCK**3 - 1))  # index into the flattened pool arrays
        tsdf, weight, grey, best = (a.reshape(-1) for a in (self.tsdf, self.weight, self.grey, self.best_cos))
        w_old = weight[at]
        total = w_old + w_new
        share = w_new / total
        tsdf[at] += (value - tsdf[at]) * share
        grey[at] += (rmap.image.reshape(-1)[pix] - grey[at]) * share
        weight[at] = np.minimum(total, self.max_weight)
        near = np.abs(value) < 1.0  # the incidence only means something near the surface
        cosines = np.nan_to_num(incidence_cosines(rmap).reshape(-1)[pix[near]], nan=0.0)
        best[at[near]] = np.maximum(best[at[near]], cosines)

    def dense(self, margin: int = 1) -> DenseVolume:
        """The allocated blocks copied into the smallest dense box holding them (plus `margin` empty voxels)."""
        n = self.blocks
        if n == 0:
            raise ValueError("the volume is empty: nothing was integrated")
        coords = self.coords[:n]
        lo = coords.min(axis=0) * BLOCK - margin
        shape = tuple(int(s) for s in (coords.max(axis=0) + 1) * BLOCK + margin - lo)
        return self._box(np.arange(n), lo, shape)

    def chunks(self, blocks_per_chunk: int = 64 // BLOCK) -> list[DenseVolume]:
        """The volume as dense chunks of `blocks_per_chunk`³ blocks, each one voxel larger along every axis than
        its blocks so that neighbouring chunks share a layer of voxels (their meshes meet without a gap)."""
        n = self.blocks
        coords = self.coords[:n]
        chunk_keys = np.unique(np.floor_divide(coords, blocks_per_chunk), axis=0)
        out = []
        side = blocks_per_chunk * BLOCK + 1
        for key in chunk_keys:
            lo_b = key * blocks_per_chunk
            near = np.flatnonzero(np.all((coords >= lo_b) & (coords <= lo_b + blocks_per_chunk), axis=1))
            out.append(self._box(near, lo_b * BLOCK, (side, side, side)))
        return out

    def _box(self, rows: NDArray[np.int64], lo: NDArray[np.int64], shape: tuple[int, ...]) -> DenseVolume:
        """Blocks `rows` scattered into a dense box of `shape` voxels whose first voxel is `lo` (clipped)."""
        grids = {name: np.full(shape, fill, dtype=np.float32)
                 for name, fill in (("tsdf", 1.0), ("weight", 0.0), ("grey", 0.0), ("best_cos", 0.0))}
        idx = (self.coords[rows][:, None, :] * BLOCK + _OFFSETS[None] - lo).reshape(-1, 3)
        ok = np.all((idx >= 0) & (idx < np.array(shape)), axis=1)
        idx = idx[ok]
        for name, grid in grids.items():
            grid[idx[:, 0], idx[:, 1], idx[:, 2]] = getattr(self, name)[rows].reshape(-1)[ok]
        return DenseVolume(np.asarray(lo, dtype=float) * self.voxel, self.voxel, grids["tsdf"], grids["weight"],
                           grids["grey"], grids["best_cos"])


__all__ = ["BLOCK", "DenseVolume", "HashedTsdf"]
