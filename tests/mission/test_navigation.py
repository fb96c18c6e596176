"""The navigation filter against known inputs."""

import math
import random

import pytest

from mission.navigation import GATE_CHI2, NavigationFilter


def test_dead_reckoning_integrates_velocity_and_grows_sigma_with_distance():
    f = NavigationFilter(0.0, 0.0, sigma=1.0, drift_fraction=0.01, velocity_sigma=0.0)
    for _ in range(100):
        f.predict(1.0, 0.0, 1.0)
    assert (f.north, f.east) == pytest.approx((100.0, 0.0))
    assert f.sigma == pytest.approx(1.0 + 0.01 * 100.0)


def test_fixes_pull_the_estimate_and_shrink_the_variance():
    f = NavigationFilter(0.0, 0.0, sigma=3.0, drift_fraction=0.0, velocity_sigma=0.0)
    res = f.update(4.0, 0.0, fix_sigma=3.0)
    assert res.accepted
    assert f.north == pytest.approx(2.0)  # equal variances: half way
    assert f.sigma == pytest.approx(3.0 / math.sqrt(2.0))


def test_averaging_fixes_converges_below_the_fix_noise():
    rng = random.Random(1)
    f = NavigationFilter(10.0, -10.0, sigma=20.0, drift_fraction=0.0, velocity_sigma=0.0)
    for _ in range(400):
        f.update(rng.gauss(0.0, 1.5), rng.gauss(0.0, 1.5), 1.5)
    assert math.hypot(f.north, f.east) < 0.4
    assert f.sigma < 0.1


def test_outlier_fix_is_gated_and_a_run_of_them_resets_the_filter():
    f = NavigationFilter(0.0, 0.0, sigma=0.5, drift_fraction=0.0, velocity_sigma=0.0)
    far = math.sqrt(GATE_CHI2 * (0.25 + 1.0)) * 2.0
    assert not f.update(far, 0.0, 1.0).accepted
    assert (f.north, f.east) == (0.0, 0.0)
    results = [f.update(far, 0.0, 1.0).accepted for _ in range(6)]
    assert results[-1] and f.north == pytest.approx(far)
