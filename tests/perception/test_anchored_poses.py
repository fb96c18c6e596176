"""Poses anchored to navigation by stereo odometry (`perception_plugins.reconstruction.motions` and `pose_graph`) on
a rendered trajectory that passes twice over the same seabed, with navigation errors of the simulator's kind: a
random walk (DVL drift), decimetre jumps (USBL fixes) and heading noise. The anchored poses must keep stereo's
geometry between frames, where navigation's do not."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mission.plugin_api import StereoImages  # noqa: E402
from perception_plugins.reconstruction.motions import candidate_pairs, measure_motions  # noqa: E402
from perception_plugins.reconstruction.pose_graph import Edge, anchor_poses  # noqa: E402
from perception_plugins.vo.se3 import from_rotvec_translation  # noqa: E402


@pytest.fixture(scope="module")
def laps() -> Iterator[tuple[list[StereoImages], np.ndarray, np.ndarray]]:
    """1.5 laps of a 2.5 m circle at 4 m over rough sand, a frame every 2 s (0.6 m apart)."""
    from mission.sim.camera import RenderError
    from mission.sim.stereo_sequence import SequenceRenderer, VehiclePath, loop_trajectory, seabed_world

    full = loop_trajectory(laps=1.5, radius=2.5, speed=0.3, altitude=4.0, fps=0.5, wobble=0.2)
    try:
        seq = SequenceRenderer(seabed_world(seed=11), VehiclePath(full.times, full.states))
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    frames = list(seq)
    seq.close()
    yield frames, seq.poses, full.times


def navigation_of(truth: np.ndarray, seed: int = 4) -> np.ndarray:
    """The truth with a random walk of 3 cm a frame, a USBL-like jump of 0.3 m every 8th frame, heading noise 0.3°."""
    rng = np.random.default_rng(seed)
    n = len(truth)
    walk = np.cumsum(rng.normal(0.0, 0.03, (n, 2)), axis=0)
    jumps = np.cumsum((np.arange(n) % 8 == 7)[:, None] * rng.normal(0.0, 0.3, (n, 2)), axis=0)
    nav = truth.copy()
    nav[:, :2, 3] += walk + jumps
    for k in range(n):
        turn = from_rotvec_translation([0.0, 0.0, np.radians(rng.normal(0.0, 0.3))], [0.0, 0.0, 0.0])[:3, :3]
        nav[k, :3, :3] = turn @ nav[k, :3, :3]  # about the world's down axis: a heading error
    return nav


def relative_error(poses: np.ndarray, truth: np.ndarray, i: int, j: int) -> float:
    measured = np.linalg.inv(poses[i]) @ poses[j]
    true = np.linalg.inv(truth[i]) @ truth[j]
    return float(np.linalg.norm(measured[:3, 3] - true[:3, 3]))


def test_the_anchored_poses_keep_the_geometry_between_passes_that_navigation_loses(
        laps: tuple[list[StereoImages], np.ndarray, np.ndarray]) -> None:
    frames, truth, times = laps
    nav = navigation_of(truth)
    pairs = candidate_pairs(nav, times)
    revisits = [(i, j) for i, j in pairs if j - i > 2]
    assert revisits, "the second lap passes over the first: revisit pairs expected"
    edges = measure_motions(lambda k: frames[k], nav, times, pairs)
    assert sum(1 for e in edges if e.j - e.i > 2) >= len(revisits) // 2  # most revisits are measured
    edge_errors = [relative_error(np.stack([np.eye(4), e.T_i_j]), np.stack([truth[e.i], truth[e.j]]), 0, 1)
                   for e in edges]
    assert np.median(edge_errors) < 0.01
    anchored = anchor_poses(nav, edges)
    for i, j in revisits:
        assert relative_error(anchored, truth, i, j) < 0.03
    nav_errors = [relative_error(nav, truth, i, j) for i, j in revisits]
    anchored_errors = [relative_error(anchored, truth, i, j) for i, j in revisits]
    assert np.median(nav_errors) > 0.15  # what the mesh would have inherited
    assert np.median(anchored_errors) < 0.2 * np.median(nav_errors)
    # Where navigation puts the whole: the anchored poses stay within its errors of the truth.
    assert np.sqrt(np.mean(np.sum((anchored[:, :3, 3] - truth[:, :3, 3]) ** 2, axis=1))) < 0.5


def test_a_wrong_edge_is_outvoted_by_the_chain_and_navigation() -> None:
    truth = np.tile(np.eye(4), (30, 1, 1))
    truth[:, 0, 3] = np.arange(30) * 0.5
    rng = np.random.default_rng(2)
    nav = truth.copy()
    nav[:, :2, 3] += rng.normal(0.0, 0.3, (30, 2))
    edges = [Edge(i, i + 1, np.linalg.inv(truth[i]) @ truth[i + 1]) for i in range(29)]
    wrong = np.linalg.inv(truth[5]) @ truth[20]
    wrong[:3, 3] += (1.5, 0.0, 0.0)  # a false match on repetitive texture, 1.5 m off
    anchored = anchor_poses(nav, [*edges, Edge(5, 20, wrong)])
    steps = np.diff(anchored[:, :3, 3], axis=0)
    assert np.abs(steps - (0.5, 0.0, 0.0)).max() < 0.02


def test_without_edges_the_navigation_poses_are_kept() -> None:
    nav = np.tile(np.eye(4), (3, 1, 1))
    nav[:, 0, 3] = (0.0, 1.0, 2.0)
    assert np.allclose(anchor_poses(nav, []), nav)
