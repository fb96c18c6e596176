"""Stereo VO on rendered down-looking sequences with known poses (seed 003's model scenes): long KLT tracking,
the classic scheme, the adaptive step with halving, and the plug-in contract."""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Iterator

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mission.geometry import invert  # noqa: E402
from mission.plugin_api import OdometryRequest, OdometryResult, StereoImages  # noqa: E402
from perception_plugins.vo import Odometer, VoError, estimate_trajectory, run_odometer, settings_for  # noqa: E402
from perception_plugins.vo.plugin import StereoOdometryPlugin  # noqa: E402


class Sequence:
    def __init__(self, frames: list[StereoImages], poses: np.ndarray) -> None:
        self.frames = frames
        self.gt = np.stack([invert(poses[0]) @ P for P in poses])  # T_first_cam
        self.path = float(np.linalg.norm(np.diff(self.gt[:, :3, 3], axis=0), axis=1).sum())

    def end_error(self, poses: np.ndarray) -> float:
        return float(np.linalg.norm(poses[-1, :3, 3] - self.gt[-1, :3, 3]))

    def mean_error(self, poses: np.ndarray) -> float:
        return float(np.linalg.norm(poses[:, :3, 3] - self.gt[:, :3, 3], axis=1).mean())


@pytest.fixture(scope="module")
def survey() -> Iterator[Sequence]:
    """3.2 s of a meandering pass at 25 fps, 600×400, 3.5–5 m over rough sand (seed 003 Table 1 conditions)."""
    from mission.sim.camera import RenderError
    from mission.sim.stereo_sequence import SequenceRenderer, seabed_world, survey_trajectory

    path = survey_trajectory(duration=3.2, fps=25.0, speed=(0.8, 1.2), altitude=(3.5, 5.0), turn_rate_deg=8.0)
    try:
        seq = SequenceRenderer(seabed_world(), path)
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    frames = list(seq)
    seq.close()
    yield Sequence(frames, seq.poses)


def test_rendered_sequence_has_known_poses_and_textured_pairs(survey: Sequence) -> None:
    f = survey.frames[0]
    assert f.left.shape == (400, 600) and f.left.std() > 10 and f.baseline == pytest.approx(0.3)
    np.testing.assert_allclose(survey.gt[0], np.eye(4), atol=1e-12)
    assert 2.4 < survey.path < 4.0


def test_long_klt_tracking_follows_the_true_poses(survey: Sequence) -> None:
    odometer = Odometer(settings_for("klt", step=2, fragment_steps=4))
    n, estimates = run_odometer(survey.frames, odometer)
    poses = estimate_trajectory(survey.frames, "klt", step=2, fragment_steps=4)
    assert odometer.stats.fragments >= 8 and odometer.stats.losses == 0
    assert {e.index for e in estimates} == set(range(0, n, 2)) | {n - 1}
    assert survey.end_error(poses) < 0.01 * survey.path  # under 1 % of the path
    R_err = poses[-1, :3, :3].T @ survey.gt[-1, :3, :3]
    assert np.degrees(np.arccos(np.clip((np.trace(R_err) - 1) / 2, -1, 1))) < 0.3


@pytest.mark.parametrize("fragment_steps", [1, 2, 4])
def test_long_klt_fragments_span_the_steps_asked_for_while_features_survive(survey: Sequence,
                                                                           fragment_steps: int) -> None:
    # 80 frames at a step of 2: 40 positions after the origin, one fragment per `fragment_steps` of them (the
    # texture keeps well over `refresh_features` alive, so no fragment ends early).
    odometer = Odometer(settings_for("klt", step=2, fragment_steps=fragment_steps))
    run_odometer(survey.frames, odometer)
    assert odometer.stats.fragments == math.ceil(40 / fragment_steps)


def test_centred_survey_pass_keeps_its_views_over_the_seabed() -> None:
    from mission.sim.stereo_sequence import centred_start, seabed_world, survey_trajectory

    path = survey_trajectory(duration=240.0, fps=25.0)
    world = seabed_world()
    reach = 0.5 * 600 / 500.0 * float(path.states[:, 2].max())  # half the widest footprint at 8 m
    assert path.states[:, 0].max() + reach > world.seabed.north[1]  # from the origin it runs off the seabed
    centred = survey_trajectory(duration=240.0, fps=25.0, start=centred_start(path))
    np.testing.assert_allclose(np.diff(centred.states, axis=0), np.diff(path.states, axis=0), atol=1e-9)
    for k, (lo, hi) in enumerate((world.seabed.north, world.seabed.east)):
        assert lo < centred.states[:, k].min() - reach and centred.states[:, k].max() + reach < hi


def test_classic_scheme_follows_the_true_poses(survey: Sequence) -> None:
    poses = estimate_trajectory(survey.frames, "classic", step=4)
    assert survey.end_error(poses) < 0.02 * survey.path


def test_adaptive_step_processes_fewer_frames_at_similar_accuracy(survey: Sequence) -> None:
    odometer = Odometer(settings_for("adaptive", fps=25.0))
    n, estimates = run_odometer(survey.frames, odometer)
    poses = estimate_trajectory(survey.frames, "adaptive", fps=25.0)
    assert odometer.stats.positions <= n / 4  # the overlap allows steps of several frames here
    assert max(odometer.stats.steps) > 4
    assert survey.end_error(poses) < 0.02 * survey.path


def test_adaptive_step_halves_down_to_one_frame_when_features_are_short(survey: Sequence) -> None:
    # A threshold no step can meet: every step is halved down to a single frame and still accepted.
    odometer = Odometer(settings_for("adaptive", fps=25.0, min_features=100_000, max_step=8))
    frames = survey.frames[:20]
    n, estimates = run_odometer(frames, odometer)
    assert odometer.stats.halvings >= 3
    assert odometer.stats.steps[1:] == [1] * (len(odometer.stats.steps) - 1)
    assert odometer.stats.losses == 0


def test_plugin_answers_poses_in_the_origin_frame_and_restarts_on_request(survey: Sequence) -> None:
    plugin = StereoOdometryPlugin()
    plugin.configure({"method": "klt", "sensors": {"stereo": {"rate_hz": 25.0}}, "unrelated": 1})
    results = [plugin.process(f, OdometryRequest()) for f in survey.frames[:12]]
    assert all(isinstance(r, OdometryResult) and r.ok for r in results)
    assert results[0].T_origin_cam is not None and np.allclose(results[0].T_origin_cam, np.eye(4))
    last = results[-1].T_origin_cam
    assert last is not None and np.linalg.norm(last[:3, 3] - survey.gt[11, :3, 3]) < 0.01
    assert results[-1].tracked >= 50 and results[-1].frames_processed == 12
    restarted = plugin.process(survey.frames[12], OdometryRequest(set_origin=True))
    assert restarted.ok and restarted.T_origin_cam is not None and np.allclose(restarted.T_origin_cam, np.eye(4))
    after = plugin.process(survey.frames[13], OdometryRequest())
    truth = invert(survey.gt[12]) @ survey.gt[13]
    assert after.T_origin_cam is not None and np.linalg.norm(after.T_origin_cam[:3, 3] - truth[:3, 3]) < 0.005


def test_adaptive_plugin_reports_skipped_frames_as_not_ok(survey: Sequence) -> None:
    plugin = StereoOdometryPlugin()
    plugin.configure({"method": "adaptive", "fps": 25.0})
    results = [plugin.process(f, OdometryRequest(altitude=4.0)) for f in survey.frames[:30]]
    skipped = [r for r in results if not r.ok]
    assert skipped and all(r.details["reason"] == "skipped" for r in skipped)
    assert sum(r.ok for r in results) >= 2 and len(skipped) >= 10


def test_plugin_rejects_an_unknown_method() -> None:
    with pytest.raises(VoError):
        StereoOdometryPlugin().configure({"method": "sift-flow"})


def test_the_prefilter_option_reaches_the_odometer_and_tracking_stays_on_the_truth(survey: Sequence) -> None:
    plugin = StereoOdometryPlugin()
    plugin.configure({"method": "klt", "vo": {"prefilter_px": 1.5, "step": 2}})
    assert plugin.settings.prefilter_px == 1.5 and settings_for("klt").prefilter_px == 0.7
    results = [plugin.process(f, OdometryRequest()) for f in survey.frames]
    known = [k for k, r in enumerate(results) if r.ok and r.T_origin_cam is not None]
    assert len(known) >= len(results) // 2 - 1 and known[-1] >= len(results) - 3
    last = results[known[-1]].T_origin_cam
    assert last is not None and np.linalg.norm(last[:3, 3] - survey.gt[known[-1], :3, 3]) < 0.01 * survey.path


def test_the_disparity_offset_is_calibrated_only_where_depths_tell_it_from_scale(survey: Sequence) -> None:
    from perception_plugins.vo.klt import KltTracker

    # Over the seabed the depths span a factor well under 2.5: the offset would trade against the translation's
    # scale, so the pair keeps its calibrated offset (0, which is the truth for the renderer).
    odometer = Odometer(settings_for("klt", step=2, fragment_steps=4))
    run_odometer(survey.frames, odometer)
    assert isinstance(odometer.frontend, KltTracker)
    assert odometer.frontend.offsets == [] and odometer.frontend.doffs == 0.0
    # Asked to calibrate from any depth spread, the fragments do estimate offsets, each small against the truth.
    eager = Odometer(settings_for("klt", step=2, fragment_steps=4))
    assert isinstance(eager.frontend, KltTracker)
    eager.frontend.offset_depth_ratio = 1.0
    run_odometer(survey.frames, eager)
    assert len(eager.frontend.offsets) >= 8 and abs(float(np.median(eager.frontend.offsets))) < 0.3


def test_lk_tracks_across_time_on_images_low_passed_to_the_setting(survey: Sequence) -> None:
    from perception_plugins.vo.klt import KltTracker

    default = Odometer(settings_for("klt"))
    assert isinstance(default.frontend, KltTracker)
    assert default.frontend.track_blur_px == pytest.approx(math.sqrt(1.5**2 - 0.7**2))  # variances add
    plugin = StereoOdometryPlugin()
    plugin.configure({"method": "klt", "vo": {"tracking_lowpass_px": None, "step": 2}})
    assert plugin.settings.tracking_lowpass_px is None
    # Without the extra low-pass the tracker still follows the truth over this short pass.
    results = [plugin.process(f, OdometryRequest()) for f in survey.frames]
    known = [k for k, r in enumerate(results) if r.ok and r.T_origin_cam is not None]
    assert known[-1] >= len(results) - 3
    last = results[known[-1]].T_origin_cam
    assert last is not None and np.linalg.norm(last[:3, 3] - survey.gt[known[-1], :3, 3]) < 0.01 * survey.path
