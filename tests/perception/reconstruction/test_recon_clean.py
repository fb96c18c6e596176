"""Artefact removal (seed 003 "3D reconstruction"): small disconnected components and grazing-only triangles."""

from __future__ import annotations

import numpy as np

from perception_plugins.reconstruction import CleanSettings, Mesh, clean_mesh
from perception_plugins.reconstruction.clean import drop_grazing, drop_small_components


def _grid(n: int, size: float, z: float = 0.0, cos: float = 1.0) -> Mesh:
    """A flat n×n-cell square of `size` metres at depth z, every vertex seen with incidence cosine `cos`."""
    xs = np.linspace(0.0, size, n + 1)
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, z)])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return Mesh(vertices, faces, np.full(len(vertices), 100, np.float32), np.full(len(vertices), cos, np.float32))


def _join(*meshes: Mesh) -> Mesh:
    starts = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    return Mesh(np.vstack([m.vertices for m in meshes]),
                np.vstack([m.faces + s for m, s in zip(meshes, starts, strict=True)]),
                np.concatenate([m.grey for m in meshes]), np.concatenate([m.best_cos for m in meshes]))


def test_a_small_floating_blob_is_removed_and_the_surface_kept() -> None:
    surface, blob = _grid(10, 2.0), _grid(2, 0.1, z=-1.0)
    cleaned = drop_small_components(_join(surface, blob), 0.02)
    assert len(cleaned.faces) == len(surface.faces)
    assert cleaned.vertices[:, 2].min() == 0.0


def test_triangles_seen_only_at_grazing_angles_are_removed() -> None:
    seen, grazed = _grid(4, 1.0, cos=0.9), _grid(4, 1.0, z=2.0, cos=np.cos(np.radians(85.0)))
    cleaned = drop_grazing(_join(seen, grazed), 80.0)
    assert len(cleaned.faces) == len(seen.faces)
    assert np.all(cleaned.vertices[:, 2] == 0.0)


def test_cleaning_keeps_a_well_seen_surface_whole() -> None:
    surface = _grid(8, 1.5, cos=0.5)
    cleaned = clean_mesh(surface, CleanSettings())
    assert len(cleaned.faces) == len(surface.faces)
    assert np.isclose(cleaned.face_areas().sum(), 1.5**2)
