"""`auv bench photo-survey`'s worlds and one seed of its comparison."""

import numpy as np
import pytest

pytest.importorskip("ompl")

from mission.bench.photo_survey import BUDGET_M, SAFETY_M, run_seed  # noqa: E402
from mission.bench.photo_survey_maps import DEPTH_M, survey_world  # noqa: E402


def test_odd_seeds_put_a_pillar_through_the_survey_depth_and_even_seeds_leave_it_clear():
    for seed, pillar in ((2, False), (3, True)):
        w = survey_world(seed)
        n, e = np.meshgrid(np.arange(0.25, 40.0, 0.5), np.arange(0.25, 40.0, 0.5), indexing="ij")
        points = np.stack([n.ravel(), e.ravel(), np.full(n.size, DEPTH_M)], axis=1)
        assert bool((~w.grid.safe(points, SAFETY_M)).any()) is pillar
        assert w.objects == 1 + seed % 5 and w.field.normalised().max() == 1.0


def test_one_seed_scores_the_rig_above_both_lawnmowers_within_the_budget_and_clear_of_the_pillar():
    row = run_seed(3, BUDGET_M)
    rig, lawn, cover = row["rig"], row["lawnmower"], row["coverage"]
    assert rig["length_m"] <= BUDGET_M and lawn["length_m"] == pytest.approx(BUDGET_M, abs=0.5)
    assert rig["unsafe_samples"] == 0
    assert rig["info_per_m"] >= 1.5 * max(lawn["info_per_m"], cover["info_per_m"])
    assert rig["high_info_share"] >= lawn["high_info_share"]
