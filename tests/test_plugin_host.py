"""The plug-in host in use: the real plug-ins answer through their workers exactly as they do in-process, and an
executive ticking in wall-clock time keeps its rate while a plug-in hangs for 30 s or segfaults (issue 19's
done-when line)."""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Iterator
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from test_plugin_worker import plugin_workers  # noqa: E402

from mission import load_mission  # noqa: E402
from mission.agents import Agent, AgentContext  # noqa: E402
from mission.executive import Executive  # noqa: E402
from mission.plugin_api import OdometryRequest, PointSetModel, ReferencingRequest, StereoImages  # noqa: E402
from mission.plugin_calls import PluginCall  # noqa: E402
from mission.plugin_host import PluginHost  # noqa: E402
from mission.testing_plugins import FAULT  # noqa: E402
from mission.vehicle import Command, NavState, Observation  # noqa: E402

PERIOD_S = 0.2  # 5 Hz control


def _same(a: Any, b: Any) -> bool:
    """Two plug-in results agree field by field (arrays to 1e-9)."""
    for name, x in vars(a).items():
        y = getattr(b, name)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if x is None or y is None or not np.allclose(x, y, rtol=0.0, atol=1e-9):
                return False
        elif name != "details" and x != y and not (x != x and y != y):  # NaN equals NaN here
            return False
    return True


def test_stereo_vo_answers_through_its_worker_as_it_does_in_process():
    from mission.sim.camera import RenderError
    from mission.sim.stereo_sequence import SequenceRenderer, seabed_world, survey_trajectory
    from perception_plugins.vo.plugin import StereoOdometryPlugin

    path = survey_trajectory(duration=0.6, fps=25.0, speed=(0.8, 1.2), altitude=(3.5, 5.0), turn_rate_deg=8.0)
    try:
        renderer = SequenceRenderer(seabed_world(), path)
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    frames = list(renderer)
    renderer.close()
    in_process = StereoOdometryPlugin()
    in_process.configure({})
    expected = [in_process.process(f, OdometryRequest(set_origin=k == 0)) for k, f in enumerate(frames)]
    host = PluginHost({"odometry": "stereo-vo"}, {}, lambda *a, **k: None)
    calls = [host.submit("odometry", f, OdometryRequest(set_origin=k == 0), f.time) for k, f in enumerate(frames)]
    got = [_wait(c) for c in calls]
    host.close()
    assert sum(r.ok for r in expected) >= len(frames) - 1  # the scene is trackable: the comparison means something
    assert all(_same(a, b) for a, b in zip(expected, got, strict=True))
    assert [c.frame_time for c in calls] == [f.time for f in frames]


def test_stereo_referencing_answers_through_its_worker_as_it_does_in_process():
    from conftest import WORLD

    from mission.bench.referencing_images import MODULE_TOP
    from mission.frames import heading_of, invert, pose_matrix, transform_points
    from mission.language.loader import load_world
    from mission.language.models import Stereo
    from mission.sim.camera import RenderError, StereoCamera
    from perception_plugins.referencing.plugin import StereoReferencingPlugin

    try:
        camera = StereoCamera(load_world(WORLD), Stereo(width=1200, height=900, fx=1000.0, baseline=0.25))
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    manifold = next(o for o in camera.world.scene.objects if o.id == "manifold-1")
    placed = transform_points(manifold.T_world_object, MODULE_TOP)
    roof, top = placed[:4].mean(axis=0), float(placed[:, 2].min())
    heading = heading_of(manifold.T_world_object) - 90.0
    jobs = []
    for k, (dn, de, dh) in enumerate([(0.0, 0.0, 0.0), (0.15, -0.1, 1.5)]):
        rendered = camera.render_at(roof[0] + dn, roof[1] + de, top - 3.6, heading + dh)
        prior = invert(rendered.T_world_left) @ manifold.T_world_object @ pose_matrix(0.05, -0.05, 0.05, 0.5)
        request = ReferencingRequest((PointSetModel("manifold-1", "module-top", MODULE_TOP),), prior, 0.05, 0.4)
        jobs.append((StereoImages(float(k), rendered.left, rendered.right, rendered.K, rendered.baseline), request))
    camera.close()
    settings = {"sensors": {"stereo": {"max_range": 8.0}}}
    in_process = StereoReferencingPlugin()
    in_process.configure(settings)
    expected = [in_process.process(f, r) for f, r in jobs]
    host = PluginHost({"referencing": "stereo-referencing"}, settings, lambda *a, **k: None)
    got = [_wait(host.submit("referencing", f, r, f.time)) for f, r in jobs]
    host.close()
    assert all(r.recognised for r in expected)
    assert all(_same(a, b) for a, b in zip(expected, got, strict=True))


def _wait(call: PluginCall, within_s: float = 60.0) -> Any:
    end = time.monotonic() + within_s
    while (result := call.poll(1e9)) is None:
        assert time.monotonic() < end
        time.sleep(0.005)
    return result


# -- the done-when test: an executive in wall-clock time with a hanging or crashing plug-in ----------------------

class WallClockVehicle:
    """A vehicle double on the wall clock: `advance` waits for the next 5 Hz tick and counts the ticks missed
    (a tick is missed when the loop comes back after its slot has passed)."""

    control_period = PERIOD_S

    def __init__(self) -> None:
        self.t0 = time.monotonic()
        self.tick = 0
        self.missed = 0
        self.commands: list[Command] = []

    def observe(self) -> Observation:
        t = time.monotonic() - self.t0
        return Observation(NavState(t, 0.0, 0.0, 10.0, 0.0, 0.0, 20.0, 1.0, 1000.0))

    def apply(self, command: Command) -> None:
        self.commands.append(command)

    def set_aiding(self, usbl: bool) -> None:
        return None

    def set_payload(self, sensors: frozenset[str]) -> None:
        return None

    def set_frame_rate(self, rate_hz: float | None) -> None:
        return None

    def advance(self) -> None:
        now = time.monotonic() - self.t0
        late = int(now // PERIOD_S) - self.tick  # slots begun since the last tick's: 0 when on time
        self.missed += max(0, late)
        self.tick += 1 + max(0, late)
        time.sleep(max(0.0, self.tick * PERIOD_S - (time.monotonic() - self.t0)))


class FramePerTickAgent(Agent):
    """Submits a ~1 MB stereo frame every tick (a faulting one on tick 5), reads the results as they come, and
    succeeds once six frames submitted after the fault have been answered."""

    kind = "transit"

    def start(self, context: AgentContext) -> None:
        assert context.plugins is not None
        self.plugins = context.plugins
        self.calls: list[PluginCall] = []
        self.results: dict[float, Any] = {}
        self.ticks = 0
        pixels = np.random.default_rng(1).integers(0, 255, (600, 800), dtype=np.uint8)
        self.pixels = pixels

    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        frame = StereoImages(nav.time, self.pixels, self.pixels, np.eye(3), 0.25)
        self.calls.append(self.plugins.submit("referencing", frame, FAULT if self.ticks == 5 else None, nav.time))
        self.ticks += 1
        for call in self.calls:
            if call.frame_time not in self.results and (result := call.poll(nav.time)) is not None:
                self.results[call.frame_time] = result
        after_fault = [c.frame_time for c in self.calls[6:] if c.frame_time in self.results]
        if len(after_fault) >= 6:
            self.succeed()
        elif self.ticks > 150:
            self.fail("the plug-in never answered again")
        return Command.hold(nav)


@pytest.fixture
def transit_mission(write_mission: Any) -> Iterator[Any]:
    yield load_mission(write_mission("plugin-faults", "  - id: watch\n    transit: {to: {north: 0, east: 0}}\n"))


@pytest.mark.parametrize(("plugin", "fault"), [("SleepingPlugin", "no answer within 1 s"),
                                               ("SegfaultingPlugin", "killed by SIGSEGV")])
def test_control_ticks_go_on_at_their_rate_while_a_plugin_hangs_or_crashes(transit_mission, plugin, fault):
    events: list[tuple[str, dict[str, Any]]] = []
    host = PluginHost({"referencing": f"mission.testing_plugins:{plugin}"}, {}, lambda e, t, **f: events.append(
        (e, f)), budget_s=1.0)
    vehicle = WallClockVehicle()
    agents: list[FramePerTickAgent] = []

    def factory() -> FramePerTickAgent:
        agents.append(FramePerTickAgent())
        return agents[-1]

    t0 = time.monotonic()
    report = Executive(transit_mission, vehicle, lambda e, t, **f: events.append((e, f)),
                       agents={"transit": factory}, plugins=host).run()
    wall = time.monotonic() - t0
    host.close()
    agent = agents[0]
    assert report.completed, report.elements[0].reason
    assert vehicle.missed <= 1, f"{vehicle.missed} control ticks missed"
    faults = [f for e, f in events if e == "plugin_fault"]
    assert len(faults) == 1 and faults[0]["frame_time"] == agent.calls[5].frame_time
    assert fault in faults[0]["error"] and faults[0]["worker_restarted"] is True
    assert not agent.results[agent.calls[5].frame_time].recognised
    answered = [agent.results[c.frame_time] for c in agent.calls if c.frame_time in agent.results]
    assert sum(r.recognised for r in answered) >= 10  # before and after the fault
    assert wall < 15.0  # nowhere near the sleeper's 30 s
    assert plugin_workers() == []
