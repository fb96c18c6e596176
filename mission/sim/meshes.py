"""Triangle meshes of the object parts' textured twins (boxes and cylinders) for the simulated cameras.

Texture coordinates run in metres, so one texture has the same scale on every face; big faces are cut into
cells so that MuJoCo's per-vertex lighting varies across them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mission.frames import Array

MESH_CELL_M = 0.25
"""Largest cell of the visual meshes: MuJoCo lights per vertex, so big faces are cut up for the lamp's cone and
fall-off to vary across them."""

Mesh = tuple[Array, Array, Array, NDArray[np.int_]]
"""Vertices, normals, texture coordinates (metres) and triangles (counter-clockwise seen from outside)."""


def _grid_faces(start: int, n_b: int, n_c: int) -> list[tuple[int, int, int]]:
    """Two triangles per cell of an (n_b + 1) × (n_c + 1) vertex grid stored c-major, counter-clockwise when
    the grid's b × c points outwards."""
    faces = []
    for j in range(n_c):
        for i in range(n_b):
            a, b = start + j * (n_b + 1) + i, start + j * (n_b + 1) + i + 1
            c, d = b + n_b + 1, a + n_b + 1
            faces += [(a, b, c), (a, c, d)]
    return faces


def box_mesh(half: Array, offset: Array, cell: float = MESH_CELL_M) -> Mesh:
    """A box as six gridded faces; texture coordinates run in metres, shifted per face by `offset`."""
    verts: list[Array] = []
    normals: list[Array] = []
    uvs: list[Array] = []
    faces: list[tuple[int, int, int]] = []
    for a in range(3):
        for sign in (1.0, -1.0):
            b, c = ((a + 1) % 3, (a + 2) % 3) if sign > 0 else ((a + 2) % 3, (a + 1) % 3)  # b × c = outward
            n_b, n_c = (max(1, math.ceil(2.0 * half[k] / cell)) for k in (b, c))
            sb, sc = np.meshgrid(np.linspace(-half[b], half[b], n_b + 1), np.linspace(-half[c], half[c], n_c + 1))
            v = np.zeros((sb.size, 3))
            v[:, a], v[:, b], v[:, c] = sign * half[a], sb.ravel(), sc.ravel()
            faces += _grid_faces(sum(len(x) for x in verts), n_b, n_c)
            verts.append(v)
            normals.append(np.tile(sign * np.eye(3)[a], (len(v), 1)))
            uvs.append(v[:, [b, c]] + offset[2 * a + (sign < 0)])
    return np.vstack(verts), np.vstack(normals), np.vstack(uvs), np.array(faces)


def cylinder_mesh(radius: float, half: float, offset: Array, segments: int = 48, cell: float = MESH_CELL_M) -> Mesh:
    """A cylinder along local z: a gridded side whose u is arc length (seam duplicated) and two flat caps."""
    theta = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    ring = np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=1)
    m, n_z = segments + 1, max(1, math.ceil(2.0 * half / cell))
    z = np.repeat(np.linspace(-half, half, n_z + 1), m)
    verts = [np.column_stack([np.tile(ring, (n_z + 1, 1)), z])]
    normals = [np.tile(np.column_stack([np.cos(theta), np.sin(theta), np.zeros(m)]), (n_z + 1, 1))]
    uvs = [np.column_stack([np.tile(radius * theta, n_z + 1), z]) + offset[0]]
    faces = _grid_faces(0, segments, n_z)
    for k, zc in enumerate((-half, half)):  # caps: a centre and their own ring, normals along ±z
        c0 = sum(len(x) for x in verts)
        verts.append(np.vstack([[0.0, 0.0, zc], np.column_stack([ring[:-1], np.full(segments, zc)])]))
        normals.append(np.tile([0.0, 0.0, 1.0 if zc > 0 else -1.0], (segments + 1, 1)))
        uvs.append(np.vstack([[0.0, 0.0], ring[:-1]]) + offset[1 + k])
        for i in range(segments):
            j = (i + 1) % segments
            faces.append((c0, c0 + 1 + i, c0 + 1 + j) if zc > 0 else (c0, c0 + 1 + j, c0 + 1 + i))
    return np.vstack(verts), np.vstack(normals), np.vstack(uvs), np.array(faces)


__all__ = ["MESH_CELL_M", "Mesh", "box_mesh", "cylinder_mesh"]
