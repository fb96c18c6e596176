"""Where the inspect agent views a set from, and its search pattern, against the camera's geometry."""

from __future__ import annotations

import math

import numpy as np

from mission.agents.inspect.placement import Placement
from mission.agents.inspect.search import expanding_square, meander_offsets, search_order
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.viewing import SetViewer
from mission.frames import pose_matrix
from mission.geometry import invert, transform_points
from mission.vehicle import NavState

SETS = {"module-top": np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]], dtype=float),
        "skid-west": np.array([[0, 0, 0], [0, 5, 0], [1, 1.2, -0.3], [1.2, 4, -0.35]], dtype=float)}
FIELD = (1.2, 0.9)  # 1200 × 900 pixels, fx = 1000
T_WORLD_OBJECT = pose_matrix(150.0, 200.0, 58.0, 30.0)


def pixels(goal, points_object, place):
    """Where the points fall in the image of the left camera with the vehicle at `goal`."""
    nav = NavState(0.0, goal.north, goal.east, goal.depth, goal.heading, 0.0, None, 0.1, 100.0)
    cam = transform_points(invert(place.camera_in_world(nav)), transform_points(place.T_wo, points_object))
    return np.column_stack([1000 * cam[:, 0] / cam[:, 2] + 600, 1000 * cam[:, 1] / cam[:, 2] + 450]), cam


def in_image(uv):
    return bool((uv[:, 0] > 0).all() and (uv[:, 0] < 1200).all() and (uv[:, 1] > 0).all() and (uv[:, 1] < 900).all())


def test_a_set_lies_wholly_in_the_image_from_its_search_view_and_inside_the_stereo_range():
    place = Placement(T_WORLD_OBJECT.copy(), 0.25)
    viewer = SetViewer(SETS, FIELD, 8.0, InspectSettings())
    goals = viewer.search_goals(place, "expanding-square")
    for set_id, first in (("module-top", 0), ("skid-west", 9)):  # each set's pattern starts over it
        uv, cam = pixels(goals[first], SETS[set_id], place)
        assert in_image(uv) and (cam[:, 2] > 0).all() and (cam[:, 2] < 8.0 - 0.5).all()


def test_the_fine_views_keep_a_compact_set_in_the_image():
    place = Placement(T_WORLD_OBJECT.copy(), 0.25)
    viewer = SetViewer(SETS, FIELD, 8.0, InspectSettings())
    for k in range(6):  # heights 3.6, 4.0, 4.4 m above the top, shifted ±0.15 m along the object
        uv, cam = pixels(viewer.fine_goal(place, "module-top", k), SETS["module-top"], place)
        assert in_image(uv) and (cam[:, 2] < 8.0).all()


def test_the_fine_views_keep_a_set_spread_across_the_skid_in_the_image():
    place = Placement(T_WORLD_OBJECT.copy(), 0.25)
    viewer = SetViewer(SETS, FIELD, 8.0, InspectSettings())
    for k in range(6):
        uv, cam = pixels(viewer.fine_goal(place, "skid-west", k), SETS["skid-west"], place)
        assert in_image(uv) and (cam[:, 2] < 8.0 - 0.5).all()


def test_fine_views_look_down_from_where_the_set_fills_the_image_with_the_image_along_the_object():
    place = Placement(T_WORLD_OBJECT.copy(), 0.25)
    viewer = SetViewer(SETS, FIELD, 8.0, InspectSettings())
    goal = viewer.fine_goal(place, "module-top", 0)
    _, cam = pixels(goal, SETS["module-top"], place)
    assert abs(cam[:, 2].min() - 4.0 / (0.9 * 1.2)) < 1e-9  # its 4 m side in 90 % of the image's 1.2 m/m width
    assert abs(math.remainder(goal.heading - (30.0 - 90.0), 360.0)) < 1e-9
    shifted = viewer.fine_goal(place, "module-top", 1)
    along = np.array([math.cos(math.radians(30)), math.sin(math.radians(30))])
    step = np.array([shifted.north - goal.north, shifted.east - goal.east])
    assert abs(abs(step @ along) - 0.15) < 1e-9


def test_the_search_flies_the_most_distinctive_set_first_around_its_placed_centroid():
    assert search_order(SETS) == ["module-top", "skid-west"]
    place = Placement(T_WORLD_OBJECT.copy(), 0.25)
    goals = SetViewer(SETS, FIELD, 8.0, InspectSettings()).search_goals(place, "meander")
    assert len(goals) == 2 * 9
    offsets = meander_offsets(1.5, 9)
    centre = transform_points(T_WORLD_OBJECT, SETS["module-top"]).mean(axis=0)
    first = goals[0]
    nav = NavState(0.0, first.north, first.east, first.depth, first.heading, 0.0, None, 0.1, 100.0)
    camera = place.camera_in_world(nav)[:3, 3]
    assert np.allclose(camera[:2], centre[:2] + np.array(offsets[0]), atol=1e-9)


def test_expanding_square_legs_grow_by_one_step_every_second_turn_and_never_revisit():
    offsets = np.array(expanding_square(1.5, 9))
    assert len({tuple(o) for o in offsets.tolist()}) == 9
    legs = np.linalg.norm(np.diff(offsets, axis=0), axis=1) / 1.5
    assert np.allclose(legs, [1, 1, 2, 2, 3, 3, 4, 4])
