"""The inspect agent's odometry chain: the object re-anchored in the drifting navigation frame so that the camera
sits, in the object's frame, where it truly is; late results applied with the estimate of their own frame."""

from __future__ import annotations

import numpy as np
import pytest
from doubles import ScriptedPlugin, frame_at, nav_at, scripted_host

from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.frames import pose_matrix
from mission.geometry import invert
from mission.plugin_api import OdometryResult

T_WORLD_OBJECT = pose_matrix(150.0, 200.0, 58.0, 30.0)
BASELINE = 0.25


def true_camera(nav):
    return Placement(T_WORLD_OBJECT.copy(), BASELINE).camera_in_world(nav)


def truthful_odometry(true_navs):
    """A plug-in that reports the true motion of the camera since the chain's origin (frames by time)."""
    origin = {}

    def answer(frame, request):
        T = true_camera(true_navs[frame.time])
        if request.set_origin or not origin:
            origin["T"] = T
            return OdometryResult(True, np.eye(4))
        return OdometryResult(True, invert(origin["T"]) @ T)

    return ScriptedPlugin(answer)


def chain_with(plugin, delays=None):
    place = Placement(T_WORLD_OBJECT.copy(), BASELINE)
    place.fix(T_WORLD_OBJECT.copy())
    return place, OdometryChain(scripted_host({"odometry": plugin}, delays), place, InspectSettings())


def test_odometry_moves_the_object_with_the_navigation_drift_so_the_camera_is_where_it_truly_is():
    true_navs = {0.0: nav_at(0.0, 152.0, 203.0, 54.0, 120.0), 0.5: nav_at(0.5, 152.3, 203.2, 54.0, 120.0)}
    place, chain = chain_with(truthful_odometry(true_navs))
    chain.start(frame_at(0.0), true_navs[0.0])
    drifted = nav_at(0.5, 152.3 + 0.2, 203.2 - 0.1, 54.0, 120.0)  # dead reckoning 22 cm off by now
    chain.feed(frame_at(0.5), drifted)
    true_object_cam = invert(T_WORLD_OBJECT) @ true_camera(true_navs[0.5])
    assert np.allclose(place.camera_in_object(drifted), true_object_cam, atol=1e-9)
    assert abs(chain.path_m - np.hypot(0.3, 0.2)) < 1e-9
    assert chain.report.frames == 1 and chain.report.chains == 1 and len(chain.report.track) == 1


def test_a_late_result_is_applied_with_the_estimate_of_its_own_frame():
    true_navs = {0.0: nav_at(0.0, 152.0, 203.0, 54.0, 120.0), 0.5: nav_at(0.5, 152.3, 203.2, 54.0, 120.0)}
    place, chain = chain_with(truthful_odometry(true_navs), delays={"odometry": 1.2})
    chain.start(frame_at(0.0), true_navs[0.0])
    chain.feed(frame_at(0.5), true_navs[0.5])
    before = place.T_wo.copy()
    chain.poll(1.5)  # the frame of 0.5 s is not answered yet
    assert np.array_equal(place.T_wo, before) and chain.report.frames == 0
    chain.poll(1.8)  # the vehicle has moved on; the result is applied at its frame's estimate
    true_object_cam = invert(T_WORLD_OBJECT) @ true_camera(true_navs[0.5])
    assert np.allclose(place.camera_in_object(true_navs[0.5]), true_object_cam, atol=1e-9)
    assert chain.report.track[0][0] == 0.5


def test_results_of_a_chain_that_a_new_fix_replaced_are_dropped():
    true_navs = {t: nav_at(t, 152.0 + t, 203.0, 54.0, 120.0) for t in (0.0, 0.5, 1.0, 1.5)}
    place, chain = chain_with(truthful_odometry(true_navs), delays={"odometry": 2.0})
    chain.start(frame_at(0.0), true_navs[0.0])
    chain.feed(frame_at(0.5), true_navs[0.5])
    chain.start(frame_at(1.0), true_navs[1.0])  # a new fix before the old chain's frame is answered
    chain.feed(frame_at(1.5), true_navs[1.5])
    chain.poll(10.0)
    assert [row[0] for row in chain.report.track] == [1.5]
    assert abs(chain.path_m - 0.5) < 1e-9


def test_lost_frames_and_impossible_jumps_break_the_chain():
    jumps = iter([OdometryResult(True, np.eye(4)), OdometryResult.lost("no features"),
                  OdometryResult(True, pose_matrix(0.9, 0.0, 0.0, 0.0)), OdometryResult.lost(),
                  OdometryResult.lost()])
    place, chain = chain_with(ScriptedPlugin(lambda frame, request: next(jumps)))
    nav = nav_at(0.0, 152.0, 203.0, 54.0, 120.0)
    chain.start(frame_at(0.0), nav)
    for t in (0.5, 1.0, 1.5, 2.0):
        assert not chain.broken
        chain.feed(frame_at(t), nav)
    assert chain.broken and chain.lost == 4 and chain.stats.lost == 4
    assert chain.needs_rereference()


def frozen_odometry():
    """A plug-in that tracks confidently and reports no motion at all (what a failed tracker that keeps answering
    looks like)."""
    return ScriptedPlugin(lambda frame, request: OdometryResult(True, np.eye(4), tracked=300))


def test_odometry_that_drags_the_object_beyond_what_navigation_can_drift_ends_the_chain():
    """The vehicle moves 0.1 m a frame; odometry says it stands still. Following it would carry the object (and
    the viewpoint the vehicle chases) along with the vehicle: the chain ends once the object would have moved
    more than the gate allows, and the object stays within the gate of its fix."""
    place, chain = chain_with(frozen_odometry())
    navs = [nav_at(0.1 * k, 152.0 - 0.1 * k, 203.0, 54.0, 120.0) for k in range(40)]
    chain.start(frame_at(0.0), navs[0])
    broke_at = None
    for k in range(1, 40):
        chain.feed(frame_at(0.1 * k), navs[k])
        if chain.broken and broke_at is None:
            broke_at = k
    assert chain.disagrees and broke_at is not None
    settings = InspectSettings()
    assert 0.1 * broke_at == pytest.approx(settings.vo_object_shift_m, abs=0.15)  # no odometry path: no allowance
    shift = np.linalg.norm(place.T_wo[:3, 3] - T_WORLD_OBJECT[:3, 3])
    assert settings.vo_object_shift_m - 0.15 <= shift <= settings.vo_object_shift_m
    chain.start(frame_at(4.0), navs[-1])  # a new fix starts a chain that agrees again
    assert not chain.broken


def test_navigation_jumps_of_a_usbl_fix_do_not_end_a_truthful_chain():
    """Navigation's estimate jumps 0.3 m (a USBL fix) while odometry reports the true motion: the object moves
    with the estimate, as it must, and the chain goes on."""
    true_navs = {round(0.1 * k, 1): nav_at(0.1 * k, 152.0 + 0.05 * k, 203.0, 54.0, 120.0) for k in range(30)}
    place, chain = chain_with(truthful_odometry(true_navs))
    chain.start(frame_at(0.0), true_navs[0.0])
    for k in range(1, 30):
        t = round(0.1 * k, 1)
        truth = true_navs[t]
        jump = 0.3 if k >= 10 else 0.0
        chain.feed(frame_at(t), nav_at(t, truth.north + jump, truth.east - jump, 54.0, 120.0))
    assert not chain.broken and chain.report.frames == 29
    assert np.linalg.norm(place.T_wo[:3, 3] - T_WORLD_OBJECT[:3, 3]) == pytest.approx(0.3 * np.sqrt(2), abs=1e-6)
