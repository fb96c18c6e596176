"""Characteristic-point sets proposed from a mesh seen from above (seed 002 §3.1: Harris corners)."""

from __future__ import annotations

import numpy as np

from perception_plugins.reconstruction.keypoints import propose_point_sets


def _scene() -> np.ndarray:
    """Vertices of a flat seabed at 30 m with a 2 × 1 × 1 m box and a 0.5 m cube standing on it."""
    n, e = np.meshgrid(np.arange(0.0, 5.0, 0.02), np.arange(0.0, 4.0, 0.02), indexing="ij")
    depth = np.full(n.shape, 30.0)
    depth[(n >= 1.0) & (n < 3.0) & (e >= 1.0) & (e < 2.0)] = 29.0
    depth[(n >= 3.6) & (n < 4.1) & (e >= 2.6) & (e < 3.1)] = 29.5
    return np.column_stack([n.ravel(), e.ravel(), depth.ravel()])


def test_the_proposed_points_are_top_corners_of_the_parts() -> None:
    proposals = propose_point_sets(_scene(), np.array([0.0, 0.0, 30.0]), set_size=4, sets=2)
    corners = np.array([[1, 1, 29], [3, 1, 29], [3, 2, 29], [1, 2, 29],
                        [3.6, 2.6, 29.5], [4.1, 2.6, 29.5], [4.1, 3.1, 29.5], [3.6, 3.1, 29.5]], dtype=float)
    points = np.vstack([p.points for p in proposals])
    assert len(points) == 8
    gaps = np.linalg.norm(points[:, None, :] - corners[None], axis=2).min(axis=1)
    assert np.all(gaps < 0.1)  # within two cells of 5 cm of a true corner


def test_a_rectangle_s_corners_are_marked_symmetric_and_a_mixed_set_is_not() -> None:
    box_only = _scene()
    box_only[box_only[:, 2] == 29.5, 2] = 30.0  # flatten the cube
    rectangle = propose_point_sets(box_only, np.array([0.0, 0.0, 30.0]), set_size=4, sets=1)[0]
    assert rectangle.symmetric
    mixed = propose_point_sets(_scene(), np.array([0.0, 0.0, 30.0]), set_size=5, sets=1)[0]
    assert not mixed.symmetric
