"""Range maps (seed 003 "3D reconstruction", first stage) against the renderer's true depth."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from recon_views import BASELINE, Views, render_views

from perception_plugins.reconstruction.depth import RangeSettings, incidence_cosines, range_map, scaled_intrinsics

FULL = RangeSettings(scale=1, min_range_m=1.5, max_range_m=8.0)


@pytest.fixture(scope="module")
def views() -> Views:
    return render_views(rings=((30.0, 2),))


def _errors(frame: Any) -> tuple[np.ndarray, np.ndarray, Any]:
    rmap = range_map(frame.left, frame.right, frame.K, BASELINE, FULL)
    ok = rmap.valid & np.isfinite(frame.depth_left)
    return (rmap.depth[ok] - frame.depth_left[ok]).astype(float), rmap.sigma[ok].astype(float), rmap


def test_range_map_depths_match_the_rendered_depth_within_a_few_centimetres(views: Views) -> None:
    for frame in views.frames:
        err, _, rmap = _errors(frame)
        assert rmap.valid.mean() > 0.3  # the object and the seabed within 8 m
        assert np.median(np.abs(err)) < 0.04  # fx 400: one pixel of disparity is ~0.25 m at 5 m
        assert np.percentile(np.abs(err), 90) < 0.15


def test_depth_sigma_covers_most_errors(views: Views) -> None:
    err, sigma, _ = _errors(views.frames[0])
    within = np.abs(err) <= 2.0 * sigma
    assert 0.7 < within.mean() <= 1.0


def test_nothing_beyond_the_maximum_range_is_kept(views: Views) -> None:
    frame = views.frames[0]
    rmap = range_map(frame.left, frame.right, frame.K, BASELINE, RangeSettings(scale=1, max_range_m=5.0))
    assert np.nanmax(rmap.depth) <= 5.0
    far = np.isfinite(frame.depth_left) & (frame.depth_left > 5.5)
    # Pixels truly beyond it get no depth, but for the few that SGBM fattens a nearer edge onto.
    assert far.sum() > 1000 and rmap.valid[far].mean() < 0.02


def test_textureless_images_give_no_depth() -> None:
    flat = np.full((120, 160), 128, dtype=np.uint8)
    K = np.array([[200.0, 0, 79.5], [0, 200.0, 59.5], [0, 0, 1]])
    assert not range_map(flat, flat, K, 0.25, RangeSettings(scale=1)).valid.any()


def test_half_resolution_maps_carry_the_intrinsics_of_their_grid(views: Views) -> None:
    frame = views.frames[0]
    rmap = range_map(frame.left, frame.right, frame.K, BASELINE, RangeSettings(scale=2))
    assert rmap.depth.shape == (frame.left.shape[0] // 2, frame.left.shape[1] // 2)
    assert np.allclose(rmap.K, scaled_intrinsics(frame.K, 2))


def test_a_plane_facing_the_camera_is_seen_head_on_and_a_tilted_one_obliquely() -> None:
    from perception_plugins.reconstruction.depth import RangeMap

    K = np.array([[100.0, 0, 49.5], [0, 100.0, 49.5], [0, 0, 1]])
    v = np.arange(100, dtype=np.float32)[:, None]
    facing = np.full((100, 100), 4.0, dtype=np.float32)
    # A plane tilted 60° about the camera's x axis: depth grows along image y.
    tilted = (4.0 / (1.0 - np.tan(np.radians(60.0)) * (v - 49.5) / 100.0)).astype(np.float32) * np.ones((1, 100))
    cos_facing = incidence_cosines(RangeMap(facing, facing, K, facing))[50, 50]
    cos_tilted = incidence_cosines(RangeMap(tilted.astype(np.float32), facing, K, facing))[50, 50]
    assert cos_facing == pytest.approx(1.0, abs=1e-4)
    assert cos_tilted == pytest.approx(np.cos(np.radians(60.0)), abs=0.02)
