"""The plug-in host times every call with the clock it is given and turns an overrun into a fault."""

import itertools

import numpy as np

from mission.plugin_api import OdometryRequest, StereoImages
from mission.plugin_host import PluginHost


def _frame() -> StereoImages:
    blank = np.zeros((90, 120), np.uint8)
    return StereoImages(0.0, blank, blank, np.array([[100.0, 0, 60], [0, 100, 45], [0, 0, 1]]), 0.25)


def test_an_overrun_on_the_hosts_clock_is_a_fault_and_a_failed_result():
    events = []
    ticks = itertools.count(0.0, 6.0)  # every reading of this clock is 6 s after the last
    host = PluginHost({"odometry": "stereo-vo"}, {}, lambda e, t, **f: events.append((e, f)), budget_s=5.0,
                      clock=lambda: next(ticks))
    result = host.process("odometry", _frame(), OdometryRequest(set_origin=True), 12.0)
    assert not result.ok
    assert [e for e, _ in events] == ["plugin_fault"]
    assert "over its time budget (6000 ms > 5000 ms)" in events[0][1]["error"]


def test_a_call_within_budget_on_the_hosts_clock_passes_through():
    events = []
    host = PluginHost({"odometry": "stereo-vo"}, {}, lambda e, t, **f: events.append(e), budget_s=5.0,
                      clock=lambda: 0.0)
    host.process("odometry", _frame(), OdometryRequest(set_origin=True), 0.0)
    assert events == []
