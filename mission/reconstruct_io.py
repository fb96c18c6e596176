"""Files of `auv reconstruct`: the mesh as PLY and glTF binary (trimesh), the point cloud as PLY, and a shaded
picture of the mesh (matplotlib, orthographic, painter's algorithm)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mission.extras import require

if TYPE_CHECKING:
    from perception_plugins.reconstruction import Mesh

# NED (north, east, down) → glTF's y-up frame: x = east, y = up, z = south (right-handed).
R_GLTF_NED = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])


def _trimesh(mesh: Mesh, R: NDArray[np.float64] | None = None) -> Any:
    import trimesh  # the `recon` extra; `auv reconstruct` checks it is installed

    grey = np.clip(mesh.grey, 0, 255).astype(np.uint8)
    colours = np.column_stack([grey, grey, grey, np.full(len(grey), 255, np.uint8)])
    vertices = mesh.vertices if R is None else mesh.vertices @ R.T
    return trimesh.Trimesh(vertices, mesh.faces, vertex_colors=colours, process=False)


def write_mesh(mesh: Mesh, out: Path) -> None:
    """`mesh.ply` in the world (NED) frame and `mesh.glb` in glTF's y-up frame (x east, y up, z south)."""
    _trimesh(mesh).export(out / "mesh.ply")
    _trimesh(mesh, R_GLTF_NED).export(out / "mesh.glb")


def write_points(points: NDArray[np.float64], grey: NDArray[np.floating[Any]], path: Path) -> None:
    """A binary little-endian PLY of points (world frame) with grey colours."""
    g = np.clip(np.asarray(grey), 0, 255).astype(np.uint8)
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")])
    data = np.empty(len(points), dtype=record)
    data["x"], data["y"], data["z"] = points[:, 0], points[:, 1], points[:, 2]
    data["red"] = data["green"] = data["blue"] = g
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(points)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
    with path.open("wb") as f:
        f.write(header.encode("ascii"))
        f.write(data.tobytes())


def render_picture(mesh: Mesh, path: Path, title: str = "", azimuth_deg: float = 210.0,
                   elevation_deg: float = 35.0, width: int = 960) -> None:
    """A shaded orthographic picture of the mesh seen from `azimuth` (from north, clockwise) and `elevation`.

    Rasterised with numpy (a z-buffer of points spread over every triangle, about three a pixel, nearest kept)
    and saved through matplotlib: drawing hundreds of thousands of polygons with matplotlib takes minutes."""
    require("matplotlib", "the mesh picture (`auv reconstruct`)")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a, e = math.radians(azimuth_deg), math.radians(elevation_deg)
    view = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), -math.sin(e)])  # towards the viewer
    right = np.array([-math.sin(a), math.cos(a), 0.0])
    up = np.cross(right, view)  # world up on the picture
    v = mesh.vertices - mesh.vertices.mean(axis=0)
    xy = np.column_stack([v @ right, v @ up])
    lo, span = xy.min(axis=0), np.ptp(xy, axis=0) + 1e-9
    scale = (width - 1) / span[0]
    height = max(int(span[1] * scale) + 1, 2)
    px = (xy - lo) * scale
    tri = mesh.faces
    n = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    light = (view + 0.5 * up) / np.linalg.norm(view + 0.5 * up)
    shade = 0.25 + 0.75 * np.abs(n @ light)
    colour = np.clip((0.35 + 0.65 * mesh.grey[tri].mean(axis=1) / 255.0) * shade, 0.0, 1.0)
    p0, p1, p2 = px[tri[:, 0]], px[tri[:, 1]], px[tri[:, 2]]
    d1, d2 = p1 - p0, p2 - p0
    area_px = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1])
    count = np.minimum(np.ceil(3.0 * area_px).astype(np.int64) + 2, 600)
    face = np.repeat(np.arange(len(tri)), count)
    rng = np.random.default_rng(0)
    r1, r2 = np.sqrt(rng.random(len(face))), rng.random(len(face))
    w0, w1, w2 = 1.0 - r1, r1 * (1.0 - r2), r1 * r2
    pts = w0[:, None] * p0[face] + w1[:, None] * p1[face] + w2[:, None] * p2[face]
    depth = (w0 * (v[tri[face, 0]] @ view) + w1 * (v[tri[face, 1]] @ view) + w2 * (v[tri[face, 2]] @ view))
    order = np.argsort(depth)  # far first: the nearest sample of a pixel is written last and stays
    cols = np.clip(np.rint(pts[order, 0]).astype(np.int64), 0, width - 1)
    rows = np.clip(height - 1 - np.rint(pts[order, 1]).astype(np.int64), 0, height - 1)
    image = np.ones((height, width))
    image[rows, cols] = colour[face[order]]
    fig, ax = plt.subplots(figsize=(width / 120, height / 120 + 0.4), dpi=120)
    ax.imshow(image, cmap="gray", vmin=0.0, vmax=1.0, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


__all__ = ["R_GLTF_NED", "render_picture", "write_mesh", "write_points"]
