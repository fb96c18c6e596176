"""`safety.max_duration` is a hard stop: the route stops there, and the abort that follows ends within
`safety.abort_time` of it whatever the legs' own timeouts would allow."""

from __future__ import annotations

import pytest

from mission import load_mission, simulate

ROUTE = """
  - id: far
    transit: {to: {north: 300, east: 400}, depth: 20}
"""


def test_an_abort_after_max_duration_ends_within_abort_time(write_mission):
    path = write_mission("deadline", ROUTE)
    path.write_text(path.read_text().replace("min_altitude: 1.5",
                                             "min_altitude: 1.5\n  max_duration: 1min\n  abort_time: 20s"))
    m = simulate(load_mission(path), seed=1).metrics
    assert [v["monitor"] for v in m["safety_violations"]] == ["max_duration"]
    statuses = {e["id"]: e["status"] for e in m["elements"]}
    assert statuses["far"] == "aborted"
    assert statuses["abort-return"] == "timeout"  # 20 s cannot bring it home from ~80 m out
    assert m["mission_time_s"] == pytest.approx(80.0, abs=0.5)  # 60 s + 20 s, and not a tick more


def test_an_abort_with_time_to_spare_returns_home_and_surfaces(write_mission):
    path = write_mission("spare", ROUTE)
    path.write_text(path.read_text().replace("min_altitude: 1.5",
                                             "min_altitude: 1.5\n  max_duration: 1min\n  abort_time: 10min"))
    m = simulate(load_mission(path), seed=1).metrics
    statuses = {e["id"]: e["status"] for e in m["elements"]}
    assert statuses["abort-return"] == "succeeded" and statuses["abort-surface"] == "succeeded"
    assert m["mission_time_s"] < 60.0 + 600.0
