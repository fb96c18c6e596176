"""Artefact removal on a fused mesh (seed 003 "3D reconstruction": the algorithm that removes artefacts of the
generated surface).

Two kinds of artefact are removed:

- small disconnected components: blobs of triangles that share no vertex with the rest of the surface and cover
  less than `min_component_area` m² (floating matches, speckle the range maps let through, spurious zero
  crossings);
- triangles seen only at grazing angles: if no view saw any of a triangle's vertices at an incidence better than
  `grazing_deg` from head-on, its position rests on depths the matcher measures worst (stretched windows, mixed
  foreground and background) and it is dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception_plugins.reconstruction.mesh import Mesh


@dataclass(frozen=True)
class CleanSettings:
    min_component_area: float = 0.02
    """Components smaller than this (m²) are dropped."""
    grazing_deg: float = 80.0
    """Triangles whose best view's incidence is above this angle from the normal are dropped."""


def component_labels(faces: NDArray[np.int64], vertex_count: int) -> NDArray[np.int64]:
    """(F,) label of the vertex-connected component each face belongs to.

    >>> component_labels(np.array([[0, 1, 2], [2, 3, 4], [5, 6, 7]]), 8).tolist()
    [0, 0, 1]
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if len(faces) == 0:
        return np.zeros(0, dtype=np.int64)
    rows = np.concatenate([faces[:, 0], faces[:, 1], faces[:, 2]])
    cols = np.concatenate([faces[:, 1], faces[:, 2], faces[:, 0]])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(vertex_count, vertex_count))
    _, labels = connected_components(graph, directed=False)
    face_labels = labels[faces[:, 0]]
    _, dense = np.unique(face_labels, return_inverse=True)
    return np.asarray(dense, dtype=np.int64)


def drop_small_components(mesh: Mesh, min_area: float) -> Mesh:
    """The mesh without the vertex-connected components smaller than `min_area` (m²)."""
    if len(mesh.faces) == 0:
        return mesh
    labels = component_labels(mesh.faces, len(mesh.vertices))
    area = np.bincount(labels, weights=mesh.face_areas())
    return mesh.subset(area[labels] >= min_area)


def drop_grazing(mesh: Mesh, grazing_deg: float) -> Mesh:
    """The mesh without the triangles none of whose vertices was seen within `grazing_deg` of head-on."""
    if len(mesh.faces) == 0:
        return mesh
    best = mesh.best_cos[mesh.faces].max(axis=1)
    return mesh.subset(best >= np.cos(np.radians(grazing_deg)))


def clean_mesh(mesh: Mesh, settings: CleanSettings | None = None) -> Mesh:
    """Grazing triangles first (they often bridge real parts), then small components."""
    s = settings or CleanSettings()
    return drop_small_components(drop_grazing(mesh, s.grazing_deg), s.min_component_area)


__all__ = ["CleanSettings", "clean_mesh", "component_labels", "drop_grazing", "drop_small_components"]
