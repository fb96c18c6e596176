"""The stereo camera's mount (`sensors.stereo.mount`): a tilt from horizontal-forward, straight down by default."""

from __future__ import annotations

import numpy as np
import pydantic
import pytest

from mission.frames import R_BODY_CAM
from mission.language.models import Stereo


def test_a_stereo_entry_without_a_mount_looks_straight_down():
    assert Stereo().mount.looks_down and np.array_equal(Stereo().mount.R_body_cam(), R_BODY_CAM)


def test_a_tilted_mount_points_the_optical_axis_forward_and_down_with_image_x_to_starboard():
    R = Stereo.model_validate({"mount": {"tilt_deg": 45}}).mount.R_body_cam()
    assert np.allclose(R[:, 2], [np.sqrt(0.5), 0.0, np.sqrt(0.5)]) and np.allclose(R[:, 0], [0.0, 1.0, 0.0])
    assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)


@pytest.mark.parametrize("bad", [{"tilt_deg": 120}, {"tilt_deg": -5}, {"pan_deg": 10}])
def test_a_mount_out_of_range_or_with_unknown_keys_is_refused(bad):
    with pytest.raises(pydantic.ValidationError):
        Stereo.model_validate({"mount": bad})
