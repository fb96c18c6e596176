"""Referencing a tracked object: the gate tells a wrong identification from a correction, and views taken while
odometry tracks the object are fused in its tracked frame (against a known true pose)."""

from __future__ import annotations

import numpy as np
from doubles import ScriptedPlugin, frame_at, nav_at, scripted_host

from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.referencer import Referencer
from mission.agents.inspect.settings import InspectSettings
from mission.frames import pose_matrix
from mission.geometry import invert, transform_points
from mission.plugin_api import ReferencingResult

SET = np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]], dtype=float)
T_TRUE = pose_matrix(150.0, 200.0, 58.0, 30.0)


def seeing(T_world_object_seen):
    """A referencing plug-in that recognises the set where `T_world_object_seen` puts it."""

    def answer(frame, request):
        T_cam_world = request.prior_T_cam_object @ invert(answer.T_world_object_est)
        T_cam_object = T_cam_world @ T_world_object_seen
        return ReferencingResult(True, "module-top", T_cam_object, matched=len(SET), residual_rms=0.01,
                                 model_points=SET, points_cam=transform_points(T_cam_object, SET))

    return answer


def referencer_for(T_seen, delays=None):
    place = Placement(T_TRUE.copy(), 0.25)
    place.fix(T_TRUE.copy())
    answer = seeing(T_seen)
    answer.T_world_object_est = place.T_wo  # type: ignore[attr-defined]
    odometry = ScriptedPlugin(lambda frame, request: None)
    host = scripted_host({"referencing": ScriptedPlugin(answer), "odometry": odometry}, delays)
    chain = OdometryChain(host, place, InspectSettings())
    return place, Referencer(host, "manifold-1", {"module-top": SET}, place, chain, InspectSettings())


def test_a_view_that_moves_a_tracked_set_half_a_metre_is_gated_out():
    _, referencer = referencer_for(pose_matrix(150.5, 200.0, 58.0, 30.0))
    referencer.submit(frame_at(1.0), nav_at(1.0, 152.0, 203.0, 52.0, 300.0), "module-top", ["module-top"], False)
    judged = referencer.poll(1.0)
    assert judged is not None and not judged.recognised
    assert judged.record["gated"] and "gate 0.15 m" in judged.record["reason"]


def test_a_small_correction_passes_the_gate_and_fused_views_recover_the_truth():
    T_seen = pose_matrix(150.03, 200.02, 58.0, 30.2)  # where the object truly is, 4 cm from the estimate
    place, referencer = referencer_for(T_seen, delays={"referencing": 2.0})
    for k in range(3):
        t = 1.0 + 3.0 * k
        nav = nav_at(t, 152.0 + 0.1 * k, 203.0, 52.0, 300.0)
        referencer.submit(frame_at(t), nav, "module-top", ["module-top"], False)
        assert referencer.busy and referencer.poll(t + 1.0) is None  # not ready before its delay
        judged = referencer.poll(t + 2.0)
        assert judged is not None and judged.recognised and judged.record["time"] == t
        referencer.add_view(judged)
    fused = referencer.fuse(agreement=0.05)
    assert fused is not None and fused.views == 3
    assert np.allclose(fused.T, T_seen, atol=1e-6)
