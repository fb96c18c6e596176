"""The `reconstruct` goal's stereo terms (`planners.nbv.stereo`): what a camera sees well (range, incidence,
frustum, occlusion), the per-voxel coverage record, and the utility term, on small scenes whose answer is known
by hand."""

from __future__ import annotations

import math

import numpy as np

from planners.nbv import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    Camera,
    DerivedMaps,
    StateGrid,
    StereoCoverage,
    camera_candidates,
    camera_rotations,
    reconstruct_utility,
    stereo_gain,
    surface_normals,
)

RES = 0.25
AHEAD = np.eye(3)[:, [1, 2, 0]]  # R_body_cam of a camera looking straight ahead (image x starboard, y down)
CAMERA = Camera.of_stereo(1200, 900, 1000.0, 8.0, AHEAD)  # useful to 6 m


def box_grid() -> tuple[StateGrid, np.ndarray, np.ndarray]:
    """A 2 × 2 × 2 m box (north 0–2, east −1–1, depth 10–12) in a free 20 m grid: its shell occupied, its inside
    unknown (as a scanner leaves it). Returns the grid, the shell's grid indices and their centres."""
    lo = np.array([-10.0, -10.0, 4.0])
    n = int(20 / RES)
    states = np.full((n, n, n), FREE, dtype=np.int8)
    key_lo = np.floor(lo / RES).astype(np.int64)
    grid = StateGrid(states, key_lo, RES)
    b0 = np.floor(np.array([0.0, -1.0, 10.0]) / RES).astype(np.int64) - key_lo
    b1 = b0 + int(2 / RES)
    states[b0[0]:b1[0], b0[1]:b1[1], b0[2]:b1[2]] = OCCUPIED
    states[b0[0] + 1:b1[0] - 1, b0[1] + 1:b1[1] - 1, b0[2] + 1:b1[2] - 1] = UNKNOWN
    grid = StateGrid(states, key_lo, RES)
    ijk = np.stack(np.unravel_index(grid.occupied_ids, grid.shape), axis=1)
    return grid, ijk, grid.centres(ijk)


def test_a_box_face_seen_head_on_from_four_metres_is_recorded_and_nothing_else_is() -> None:
    grid, ijk, centres = box_grid()
    record = StereoCoverage(CAMERA, grid.shape)
    # 4 m south of the box's south face (north = 0), at its mid-depth, looking north.
    record.add_pose((-4.0, 0.0, 11.0), camera_rotations([0.0], AHEAD)[0])
    share = record.update(grid, grid.occupied_ids)
    seen = record.well.reshape(-1)[grid.occupied_ids]
    south = centres[:, 0] < RES
    core = south & (np.abs(centres[:, 1]) < 1.0 - RES) & (centres[:, 2] > 10.0 + RES) & (centres[:, 2] < 12.0 - RES)
    assert core.sum() == 36
    assert seen[core].all()  # the face's inside, head-on at 4.1–4.2 m
    assert not seen[~south].any()  # the far face is hidden, the sides and top at ≥ 76° incidence
    assert math.isclose(share, seen.mean()) and 0.1 < share < 0.3
    normals = surface_normals(grid.states, ijk[core])
    assert np.allclose(normals, [[-1.0, 0.0, 0.0]], atol=1e-6)  # outward: towards the camera (south)


def test_the_record_checks_voxels_mapped_later_against_earlier_poses() -> None:
    grid, _, centres = box_grid()
    record = StereoCoverage(CAMERA, grid.shape)
    record.add_pose((-4.0, 0.0, 11.0), camera_rotations([0.0], AHEAD)[0])
    south = grid.occupied_ids[centres[:, 0] < RES]
    assert record.update(grid, south[: len(south) // 2]) > 0.5
    assert record.update(grid, south) > 0.6  # the second half, new to the record, is checked against that pose too


def test_the_stereo_gain_prefers_unseen_surface_in_range_over_beyond_range_or_grazing() -> None:
    grid, ijk, centres = box_grid()
    normals = surface_normals(grid.states, ijk)
    positions = np.array([
        [-4.0, 0.0, 11.0],   # head-on, 4 m: in the useful range
        [-8.0, 0.0, 11.0],   # head-on, 8 m: beyond 6 m
        [-0.6, -5.0, 11.0],  # beside the south face, looking along it (east): grazing, ~80°
    ])
    headings = np.array([0.0, 0.0, 90.0])
    gain = stereo_gain(grid, centres, normals, positions, camera_rotations(headings, AHEAD), CAMERA)
    assert gain[1] == 0
    assert gain[0] >= 36
    # From the side the camera sees the west face (its normal points at it), and of the south face only the
    # column on the corner, whose normal is diagonal; none of the south face's inside (grazing, ~80°).
    south = (centres[:, 0] < RES) & (centres[:, 1] > -1.0 + RES)
    side = stereo_gain(grid, centres[south], normals[south], positions[2:], camera_rotations(headings[2:], AHEAD),
                       CAMERA)
    assert side[0] == 0 and gain[2] > 0
    u = reconstruct_utility(np.full(3, 0.5), gain, 0.6)
    assert int(np.argmax(u)) == 0 and u[1] < u[0]


def test_surface_already_seen_well_adds_nothing() -> None:
    grid, ijk, centres = box_grid()
    normals = surface_normals(grid.states, ijk)
    R = camera_rotations([0.0], AHEAD)
    record = StereoCoverage(CAMERA, grid.shape)
    record.add_pose((-4.0, 0.0, 11.0), R[0])
    record.update(grid, grid.occupied_ids)
    unseen = ~record.well.reshape(-1)[grid.occupied_ids]
    again = stereo_gain(grid, centres[unseen], normals[unseen], np.array([[-4.5, 0.0, 11.0]]), R, CAMERA)
    assert again[0] <= 4  # at most a few edge voxels the first pose missed


def test_candidates_aimed_at_unseen_surface_see_it_well_and_keep_the_safe_distance() -> None:
    grid, ijk, centres = box_grid()
    normals = surface_normals(grid.states, ijk)
    safety = DerivedMaps(grid, 0.5).safety
    tilted = Camera.of_stereo(1200, 900, 1000.0, 8.0, np.array([[0.0, -0.7071, 0.7071], [1.0, 0.0, 0.0],
                                                                 [0.0, 0.7071, 0.7071]]))  # 45° down
    views = camera_candidates(grid, safety, centres, normals, tilted, count=40, near=3.5, safe_distance=3.0,
                              rng=np.random.default_rng(2))
    assert len(views) >= 20
    nearest = np.min(np.linalg.norm(views.positions[:, None, :] - centres[None], axis=2), axis=1)
    assert np.all(nearest >= 3.0)
    gain = stereo_gain(grid, centres, normals, views.positions, camera_rotations(views.heading_deg,
                                                                                 tilted.R_body_cam), tilted)
    assert np.mean(gain > 0) >= 0.9
