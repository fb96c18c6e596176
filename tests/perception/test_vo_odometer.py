"""The odometer's loss handling with a scripted front end (a test double of `Frontend`): a lost step is bridged at
the median velocity of the last tracked steps, so one badly estimated step before a loss is not repeated."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from perception_plugins.vo import Odometer, settings_for
from perception_plugins.vo.frontend import Step
from perception_plugins.vo.se3 import from_rotvec_translation
from perception_plugins.vo.window import KeyFeatures, Matches


class ScriptedFrontend:
    """Answers each frame's motion relative to the previous one from a script (None: the step is lost)."""

    def __init__(self, script: dict[float, float | None]) -> None:
        self.script = script
        self.key_points = np.column_stack([np.zeros(20), np.zeros(20), np.full(20, 5.0)])  # a seabed 5 m below

    def start(self, frame: StereoImages, mask: NDArray[np.uint8] | None = None) -> int:
        return len(self.key_points)

    def track(self, frame: StereoImages, T_key_pred: NDArray[np.float64] | None) -> Step | None:
        dx = self.script[frame.time]
        return None if dx is None else Step(from_rotvec_translation(np.zeros(3), np.array([dx, 0.0, 0.0])), 200)

    def commit(self, frame: StereoImages, step: Step, end: bool) -> NDArray[np.float64]:
        return step.T_key_b

    def key_features(self) -> KeyFeatures:
        return KeyFeatures(np.zeros((20, 2)), np.zeros((20, 2)), self.key_points)

    def key_matches(self) -> Matches | None:
        return None


def _frame(t: float) -> StereoImages:
    image = np.zeros((4, 4), np.uint8)
    return StereoImages(t, image, image, np.eye(3), 0.3)


def test_a_lost_step_is_bridged_at_the_median_of_the_recent_velocities() -> None:
    # 0.1 s apart: five steps of 0.1 m, one badly estimated step of 0.3 m, then a lost step.
    steps: list[float | None] = [0.1, 0.1, 0.1, 0.1, 0.1, 0.3, None]
    times = [0.1 * k for k in range(len(steps) + 1)]
    odometer = Odometer(settings_for("classic", step=1))
    odometer.frontend = ScriptedFrontend(dict(zip(times[1:], steps, strict=True)))
    estimates = [e for k, t in enumerate(times) for e in odometer.push(k, _frame(t))]
    assert [e.lost for e in estimates] == [False] * 7 + [True]
    assert estimates[6].T_origin_cam[0, 3] == pytest.approx(0.8)
    # The median velocity is 1 m/s: 0.1 m over the lost step, not the last step's 0.3 m.
    assert estimates[7].T_origin_cam[0, 3] == pytest.approx(0.9)
    assert odometer.stats.losses == 1
