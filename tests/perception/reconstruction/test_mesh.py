"""Marching cubes on the fused volume (`perception_plugins.reconstruction.mesh`)."""

from __future__ import annotations

import numpy as np

from perception_plugins.reconstruction.mesh import mesh_from_volume
from perception_plugins.reconstruction.tsdf import DenseVolume


def _volume(tsdf: np.ndarray, weight: np.ndarray) -> DenseVolume:
    shape = tsdf.shape
    return DenseVolume(np.zeros(3), 0.1, tsdf.astype(np.float32), weight.astype(np.float32),
                       np.full(shape, 100.0, np.float32), np.ones(shape, np.float32))


def test_meshed_cubes_without_a_sign_change_give_an_empty_mesh_not_an_error() -> None:
    tsdf = np.full((8, 8, 8), 0.5)
    tsdf[5:, 5:, 5:] = -0.5  # inside, but only where no meshed cube reaches the outside's values
    weight = np.zeros((8, 8, 8))
    weight[0:2, 0:2, 0:2] = 1.0  # one observed cube, all outside
    weight[6:8, 6:8, 6:8] = 1.0  # one observed cube, all inside
    mesh = mesh_from_volume(_volume(tsdf, weight))
    assert len(mesh.faces) == 0 and len(mesh.vertices) == 0


def test_a_plane_is_meshed_where_its_cubes_are_sure_enough_and_not_elsewhere() -> None:
    z = np.arange(8)[None, None, :] * 0.1
    tsdf = np.broadcast_to((0.35 - z) / 0.4, (8, 8, 8)).copy()  # a plane at z = 0.35 m
    weight = np.full((8, 8, 8), 1.0)
    weight[:4] = 0.01  # half the plane seen from far
    everything = mesh_from_volume(_volume(tsdf, weight))
    sure = mesh_from_volume(_volume(tsdf, weight), min_weight=0.1)
    assert len(everything.faces) > 0 and 0 < len(sure.faces) < len(everything.faces)
    assert np.allclose(sure.vertices[:, 2], 0.35, atol=0.01)
    assert sure.vertices[:, 0].min() >= 0.4 - 1e-6  # nothing where the weight stays under the threshold
