"""The fused surface as a triangle mesh: marching cubes on the TSDF's zero level, coloured from the images (seed
003 "3D reconstruction": iso-surface extraction after voxel fusion).

`extract_mesh` copies the hashed volume chunk by chunk into dense boxes (`HashedTsdf.chunks`: 64³ voxels sharing
a layer with their neighbours), runs scikit-image's Lewiner marching cubes on the cubes whose eight corners were all
observed, and welds the pieces. Zero crossings between a voxel just
behind one view's surface (−1, truncated) and a voxel another view saw empty (+1) are not surfaces: vertices whose
edge joins two saturated values are dropped with their triangles. Each vertex takes the fused grey level and the
best viewing incidence of the voxel nearest to it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception_plugins.reconstruction.tsdf import DenseVolume, HashedTsdf

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh in the world frame with per-vertex grey level and best viewing incidence."""

    vertices: Array
    """(V, 3) world coordinates (m)."""
    faces: NDArray[np.int64]
    """(F, 3) vertex indices."""
    grey: NDArray[np.float32]
    """(V,) fused grey level (0–255)."""
    best_cos: NDArray[np.float32]
    """(V,) largest |cos| of the viewing incidence among the views that saw the vertex."""

    def subset(self, keep_faces: NDArray[np.bool_]) -> Mesh:
        """The mesh with only the kept faces and the vertices they use."""
        faces = self.faces[keep_faces]
        used, inverse = np.unique(faces.reshape(-1), return_inverse=True)
        return Mesh(self.vertices[used], inverse.reshape(-1, 3).astype(np.int64), self.grey[used],
                    self.best_cos[used])

    def face_areas(self) -> Array:
        a, b, c = (self.vertices[self.faces[:, k]] for k in range(3))
        return np.asarray(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1))

    def sample(self, count: int, seed: int = 0) -> Array:
        """(count, 3) points spread uniformly over the surface (area-weighted)."""
        rng = np.random.default_rng(seed)
        areas = self.face_areas()
        if len(areas) == 0 or areas.sum() <= 0:
            return np.zeros((0, 3))
        f = rng.choice(len(areas), size=count, p=areas / areas.sum())
        r1, r2 = rng.random(count), rng.random(count)
        s = np.sqrt(r1)
        a, b, c = (self.vertices[self.faces[f, k]] for k in range(3))
        return np.asarray((1 - s)[:, None] * a + (s * (1 - r2))[:, None] * b + (s * r2)[:, None] * c)


def _observed_cubes(weight: NDArray[np.float32], min_weight: float) -> NDArray[np.bool_]:
    """True at (i, j, k) when all eight corners of the cube starting there were observed."""
    seen = weight > min_weight
    cube = seen.copy()
    for di in (0, 1):
        for dj in (0, 1):
            for dk in (0, 1):
                if di or dj or dk:
                    cube[:seen.shape[0] - di, :seen.shape[1] - dj, :seen.shape[2] - dk] &= seen[di:, dj:, dk:]
    cube[-1, :, :] = cube[:, -1, :] = cube[:, :, -1] = False
    return cube


def mesh_from_volume(vol: DenseVolume, min_weight: float = 0.0) -> Mesh:
    """Marching cubes on a dense volume (see the module docstring)."""
    from skimage.measure import marching_cubes

    cubes = _observed_cubes(vol.weight, min_weight)
    # scikit-image gates the cube starting at (i, j, k) by mask[i + 1, j + 1, k + 1] (its far corner).
    mask = np.zeros_like(cubes)
    mask[1:, 1:, 1:] = cubes[:-1, :-1, :-1]
    empty = Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0, np.float32), np.zeros(0, np.float32))
    if not cubes.any() or vol.tsdf[cubes].min() >= 0 or vol.tsdf[cubes].max() <= 0:
        return empty
    try:
        verts, faces, _, _ = marching_cubes(  # type: ignore[no-untyped-call,unused-ignore]
            vol.tsdf, level=0.0, mask=mask, allow_degenerate=False)
    except RuntimeError:  # scikit-image: "No surface found" when no meshed cube's corners change sign
        return empty
    # Each vertex lies on one grid edge: the axis with a fractional coordinate; read both ends' values.
    lo = np.floor(verts).astype(np.int64)
    frac = verts - lo
    axis = np.argmax(frac, axis=1)
    hi = lo.copy()
    hi[np.arange(len(hi)), axis] += 1
    shape = np.array(vol.tsdf.shape) - 1
    lo, hi = np.clip(lo, 0, shape), np.clip(hi, 0, shape)
    a = vol.tsdf[lo[:, 0], lo[:, 1], lo[:, 2]]
    b = vol.tsdf[hi[:, 0], hi[:, 1], hi[:, 2]]
    spurious = np.minimum(np.abs(a), np.abs(b)) > 0.95
    nearest = np.clip(np.rint(verts).astype(np.int64), 0, shape)
    grey = vol.grey[nearest[:, 0], nearest[:, 1], nearest[:, 2]]
    best = np.maximum(vol.best_cos[lo[:, 0], lo[:, 1], lo[:, 2]], vol.best_cos[hi[:, 0], hi[:, 1], hi[:, 2]])
    mesh = Mesh(vol.origin + vol.voxel * verts.astype(float), faces.astype(np.int64), grey.astype(np.float32),
                best.astype(np.float32))
    return mesh.subset(~spurious[faces].any(axis=1))


def weld(meshes: list[Mesh], tolerance: float = 1e-6) -> Mesh:
    """One mesh from pieces, with vertices closer than `tolerance` (m) merged (pieces of neighbouring chunks
    share their boundary vertices)."""
    meshes = [m for m in meshes if len(m.faces)]
    if not meshes:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0, np.float32),
                    np.zeros(0, np.float32))
    starts = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    vertices = np.vstack([m.vertices for m in meshes])
    faces = np.vstack([m.faces + s for m, s in zip(meshes, starts, strict=True)])
    keys = np.rint(vertices / tolerance).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    grey = np.concatenate([m.grey for m in meshes])[first]
    best = np.concatenate([m.best_cos for m in meshes])
    best_merged = np.zeros(len(first), np.float32)
    np.maximum.at(best_merged, inverse.reshape(-1), best)
    faces = inverse.reshape(-1)[faces]
    return Mesh(vertices[first], faces.astype(np.int64), grey, best_merged)


def extract_mesh(volume: HashedTsdf, min_weight: float = 0.0) -> Mesh:
    """The zero level of a hashed TSDF as a coloured mesh, extracted chunk by chunk (memory stays that of one
    chunk beyond the mesh) and welded."""
    return weld([mesh_from_volume(chunk, min_weight) for chunk in volume.chunks()])


__all__ = ["Mesh", "extract_mesh", "mesh_from_volume"]
