"""The RIG tree's own logic (`planners.rrt.rig`) with straight-line motions, and the photo model's returns."""

import math

import numpy as np

from planners.rrt.information import InformationField
from planners.rrt.photo_gain import PhotoModel
from planners.rrt.rig import RigSettings, plan_rig

WALL = (10.0, 12.0, -1.0, 22.0)  # north 10–12, east up to 22: the way north is round its east end


def blocked(n, e):
    return WALL[0] <= n <= WALL[1] and WALL[2] <= e <= WALL[3]


def straight(pose, north, east, max_length):
    """Straight motions, sampled every 0.5 m, refused when a sample is in the wall."""
    d = math.hypot(north - pose[0], east - pose[1])
    if d < 1e-6:
        return None
    length = min(d, max_length)
    yaw = math.atan2(east - pose[1], north - pose[0])
    n = max(1, math.ceil(length / 0.5))
    out = [pose] + [(pose[0] + length * k / n * math.cos(yaw), pose[1] + length * k / n * math.sin(yaw), yaw)
                    for k in range(1, n + 1)]
    if any(blocked(p[0], p[1]) for p in out):
        return None
    return np.array(out)


def field():
    info = np.zeros((30, 30))  # 1 m cells, centres 0 … 29
    info[20:24, 4:8] = 1.0  # north of the wall
    return InformationField(info, north0=0.0, east0=0.0, cell=1.0)


def test_the_tree_finds_its_way_round_an_obstacle_to_the_information_within_the_budget():
    model = PhotoModel(field(), across=3.0, along=2.0)
    settings = RigSettings(budget=90.0, photo_spacing=1.0, horizon=40.0, iterations=150, step=4.0, seed=2)
    plan = plan_rig((2.0, 5.0, 0.0), model, straight, (0.0, 29.0, 0.0, 29.0), settings)
    assert plan.length <= 90.0 + 1e-6
    assert not any(blocked(n, e) for n, e in plan.samples[:, :2])
    assert model.high_share(plan.counts) >= 0.9  # the patch behind the wall, ≥ 27 m of detour away
    assert abs(model.revealed(plan.counts) - plan.information) < 1e-6


def test_a_second_photograph_of_a_cell_reveals_half_as_much_as_the_first():
    model = PhotoModel(field(), across=1.0, along=1.0, repeat=0.5)
    counts = model.zero_counts()
    cells = model.cells(21.0, 5.0, 0.0)
    first, second = model.add(counts, cells), model.add(counts, cells)
    assert first == 0.5 * len(cells) and second == 0.5 * first
