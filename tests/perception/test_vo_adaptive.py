"""The adaptive step of seed 003 (H = 2·tan(α/2)·R, S = H·(1 − P/100), A·T² + 2·V·T − S = 0) against hand-computed
cases, and the common field of view that features are generated in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception_plugins.vo import (
    common_view_mask,
    field_of_view_along,
    footprint,
    overlap_displacement,
    step_frames,
    step_time,
)
from perception_plugins.vo.se3 import from_rotvec_translation

K = np.array([[500.0, 0.0, 299.5], [0.0, 500.0, 199.5], [0.0, 0.0, 1.0]])
SIZE = (600, 400)


def test_footprint_and_displacement_follow_the_seed() -> None:
    # α = 60°, R = 4 m: H = 2·tan 30°·4 = 4.6188 m; P = 75 %: S = H/4 = 1.1547 m.
    assert footprint(60.0, 4.0) == pytest.approx(8.0 / math.sqrt(3.0))
    assert overlap_displacement(60.0, 4.0, 75.0) == pytest.approx(2.0 / math.sqrt(3.0))
    # Straight along the optical axis the view of a plane at R shrinks instead: S = R·(1 − P/100).
    assert overlap_displacement(60.0, 4.0, 75.0, axial_fraction=1.0) == pytest.approx(1.0)


def test_step_time_without_acceleration_is_distance_over_speed() -> None:
    assert step_time(1.2, 0.4, 0.0) == pytest.approx(3.0)


def test_step_time_when_braking_to_a_stop_short_of_the_distance() -> None:
    # V = 0.5, A = −0.5, S = 1: D = 0.25 − 1 < 0, the vehicle stops after −V/A = 1 s.
    assert step_time(1.0, 0.5, -0.5) == pytest.approx(1.0)


@pytest.mark.parametrize(("S", "V", "A", "T"), [(1.0, 0.5, 0.25, 1.4641016), (1.0, 1.0, -0.25, 1.1715729),
                                                (2.0, 0.2, 0.1, 4.6332496)])
def test_step_time_covers_the_distance_at_the_mean_speed(S: float, V: float, A: float, T: float) -> None:
    # The seed's T = (−V + √D)/A with D = V² + 2·A·S: the distance at the mean speed V + A·T/2 is S.
    t = step_time(S, V, A)
    assert t == pytest.approx(T, abs=1e-6)
    assert (V + A * t / 2) * t == pytest.approx(S, abs=1e-9)


def test_step_time_of_a_vehicle_at_rest_is_unbounded() -> None:
    assert math.isinf(step_time(1.0, 0.0, 0.0))


def test_step_frames_multiplies_by_the_frame_rate_within_limits() -> None:
    assert step_frames(1.4641016, 25.0, 64) == 36
    assert step_frames(math.inf, 25.0, 64) == 64
    assert step_frames(0.01, 25.0, 64) == 1


def test_field_of_view_follows_the_motion_direction() -> None:
    along_y, axial = field_of_view_along(K, SIZE, np.array([0.0, -1.0, 0.0]))
    assert along_y == pytest.approx(math.degrees(2 * math.atan(200 / 500))) and axial == pytest.approx(0.0)
    along_x, _ = field_of_view_along(K, SIZE, np.array([2.0, 0.0, 0.0]))
    assert along_x == pytest.approx(math.degrees(2 * math.atan(300 / 500)))
    _, forward = field_of_view_along(K, SIZE, np.array([0.0, 0.0, 3.0]))
    assert forward == pytest.approx(1.0)


def test_common_view_is_the_part_the_next_position_still_sees() -> None:
    # Down-looking camera over a plane 4 m away moving 1.6 m along its x: the view shifts by 200 px.
    T_a_b = from_rotvec_translation([0, 0, 0], [1.6, 0.0, 0.0])
    mask = common_view_mask(K, SIZE, T_a_b, 4.0, margin=0.0)
    cols = np.flatnonzero(mask[200] > 0)
    assert cols.min() == pytest.approx(200, abs=1.5) and cols.max() == 599
    assert mask.mean() / 255 == pytest.approx(400 / 600, abs=0.01)
    # No motion: the whole image is common.
    assert common_view_mask(K, SIZE, np.eye(4), 4.0, margin=0.0).mean() == pytest.approx(255, abs=1)
