"""The stereo plug-in's pipeline against ground truth: rendered depth of the reference world (seed 000's virtual
scene, 1200×900 at 3.6 m), Middlebury's Motorcycle disparities (real pixels), and a KITTI clip (real motion)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import cv2  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from perception_plugins.stereo import (  # noqa: E402
    DETECTORS,
    RectifiedStereo,
    StereoCalibration,
    detect,
    epipolar_inliers,
    match_stereo,
    project,
    stereo_cloud,
    triangulate,
)

ROOT = Path(__file__).resolve().parents[2]
REFERENCE_WORLD = ROOT / "worlds" / "sps_field.yaml"
KITTI = ROOT.parent / "shared" / "data" / "kitti06_0-50"

# Middlebury 2014 "Motorcycle", downsampled 4× as scikit-image ships it (from `skimage.data.stereo_motorcycle`).
MIDDLEBURY_F, MIDDLEBURY_CX, MIDDLEBURY_CY = 994.978, 311.193, 254.877
MIDDLEBURY_DOFFS, MIDDLEBURY_BASELINE = 31.086, 0.193001


class SimPair:
    """A rendered pair with its ground truth (depth exists for tests only)."""

    def __init__(self, left: np.ndarray, right: np.ndarray, K: np.ndarray, baseline: float,
                 depth: np.ndarray) -> None:
        self.left, self.right, self.depth = left, right, depth
        self.geometry = RectifiedStereo.from_K(K, baseline, (left.shape[1], left.shape[0]))

    def true_depth(self, uv: np.ndarray) -> np.ndarray:
        u = np.clip(np.rint(uv[:, 0]).astype(int), 0, self.depth.shape[1] - 1)
        v = np.clip(np.rint(uv[:, 1]).astype(int), 0, self.depth.shape[0] - 1)
        return np.asarray(self.depth[v, u], dtype=float)


@pytest.fixture(scope="module")
def sim() -> Iterator[SimPair]:
    from mission.frames import transform_points
    from mission.language.loader import load_world
    from mission.language.models import Stereo
    from mission.sim.camera import RenderError, StereoCamera

    try:
        camera = StereoCamera(load_world(REFERENCE_WORLD), Stereo(width=1200, height=900, fx=1000.0, baseline=0.25))
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    # Textured sand with the manifold's skid edge in view: the stereo code is tested on texture and depth steps;
    # the painted object faces themselves are kept plain on purpose (their corners are the referencing features).
    manifold = next(o for o in camera.world.scene.objects if o.id == "manifold-1")
    corner = transform_points(manifold.T_world_object, np.array([[-1.5, 2.5, 0.0]]))[0]
    seabed = camera.world.scene.seabed.depth_at(corner[0], corner[1])
    frame = camera.render_at(corner[0], corner[1], seabed - 3.6, 40.0)
    camera.close()
    yield SimPair(frame.left, frame.right, frame.K, frame.baseline, frame.depth_left)


@pytest.fixture(scope="module")
def motorcycle() -> tuple[np.ndarray, np.ndarray, np.ndarray, RectifiedStereo]:
    skimage_data = pytest.importorskip("skimage.data")
    left, right, disparity = skimage_data.stereo_motorcycle()
    geometry = RectifiedStereo(MIDDLEBURY_F, MIDDLEBURY_F, MIDDLEBURY_CX, MIDDLEBURY_CY, MIDDLEBURY_BASELINE,
                               (left.shape[1], left.shape[0]), MIDDLEBURY_DOFFS)
    grey = [cv2.cvtColor(im, cv2.COLOR_RGB2GRAY) for im in (left, right)]
    return grey[0], grey[1], np.where(np.isfinite(disparity), disparity, np.nan), geometry


@pytest.mark.parametrize("detector", DETECTORS)
def test_triangulated_points_agree_with_the_rendered_depth(sim: SimPair, detector: str) -> None:
    cloud = stereo_cloud(sim.left, sim.right, sim.geometry, detector, 2000, max_range=8.0)  # type: ignore[arg-type]
    assert len(cloud) >= 400
    truth = sim.true_depth(cloud.uv_left)
    z = cloud.points_cam[:, 2]
    rel = np.abs(z - truth) / truth
    assert np.median(rel) < 0.01
    # σ_Z explains the spread: 95 % of the points within 2 σ_Z (stragglers sit on depth edges).
    assert np.percentile(np.abs(z - truth) / cloud.sigma_z, 95) < 2.0
    assert (z > 0).all() and (z <= 8.0 + 1e-9).all()
    np.testing.assert_allclose(cloud.points_cam[:, :2] / z[:, None],
                               (cloud.uv_left - [599.5, 449.5]) / 1000.0, atol=1e-12)  # on the left rays


def test_the_epipolar_check_rejects_wrong_matches(sim: SimPair) -> None:
    left, right = detect(sim.left, "sift", 2000), detect(sim.right, "sift", 2000)
    # An unconstrained matcher (cross-checked nearest neighbours over the whole image) makes wrong matches ...
    pairs = cv2.BFMatcher(cv2.NORM_L2, crossCheck=True).match(left.descriptors, right.descriptors)
    uv_l = np.array([left.xy[m.queryIdx] for m in pairs])
    uv_r = np.array([right.xy[m.trainIdx] for m in pairs])
    true_d = sim.geometry.disparity(sim.true_depth(uv_l))
    wrong = np.abs((uv_l[:, 0] - uv_r[:, 0]) - true_d) > 3.0
    assert wrong.sum() >= 10
    d_min, d_max = sim.geometry.disparity_range(0.3, 8.0)
    passed = epipolar_inliers(uv_l, uv_r, 1.5, d_min, d_max)
    assert (passed & wrong).sum() <= 0.1 * wrong.sum()  # a wrong partner on the same row cannot be told apart
    assert passed[~wrong].mean() > 0.95
    # ... and shuffled partners almost never pass.
    rng = np.random.default_rng(1)
    shuffled = uv_r[rng.permutation(len(uv_r))]
    assert epipolar_inliers(uv_l, shuffled, 1.5, d_min, d_max).mean() < 0.02
    # Matching among epipolar candidates keeps the geometry by construction, with few wrong matches left.
    matches = match_stereo(left, right, 1.5, d_min, d_max)
    assert epipolar_inliers(matches.uv_left, matches.uv_right, 1.5, d_min, d_max).all()
    bad = np.abs(matches.disparity - sim.geometry.disparity(sim.true_depth(matches.uv_left))) > 3.0
    assert len(matches) > 0.5 * len(pairs) and bad.mean() < 0.02


def test_surf_is_not_offered() -> None:
    with pytest.raises(ValueError, match="SURF is patented"):
        detect(np.zeros((64, 64), np.uint8), "surf")  # type: ignore[arg-type]


@pytest.mark.parametrize("detector", ["sift", "harris"])
def test_disparities_on_middlebury_motorcycle_match_the_ground_truth(motorcycle: tuple, detector: str) -> None:
    left, right, disparity, geometry = motorcycle
    cloud = stereo_cloud(left, right, geometry, detector, 2000)  # type: ignore[arg-type]
    u = np.rint(cloud.uv_left).astype(int)
    truth = disparity[u[:, 1], u[:, 0]]
    known = np.isfinite(truth)
    assert known.sum() >= 300
    error = np.abs(cloud.disparity[known] - truth[known])
    assert np.median(error) <= 1.0
    z_true = geometry.depth(truth[known])
    rel = np.abs(cloud.points_cam[known, 2] - z_true) / z_true
    assert np.median(rel) < 0.01  # about 0.2 % here


def test_rectification_puts_matches_on_the_same_row() -> None:
    K = np.array([[800.0, 0, 320], [0, 805.0, 240], [0, 0, 1]])
    R = np.asarray(cv2.Rodrigues(np.array([0.01, -0.02, 0.015]))[0], dtype=float)
    calib = StereoCalibration(K, K * [[1.01], [1.0], [1.0]], np.array([-0.05, 0.01, 0.0, 0.0, 0.0]), R,
                              np.array([-0.2, 0.005, 0.002]), (640, 480))
    assert not calib.is_rectified()
    rng = np.random.default_rng(0)
    points_l = np.column_stack([rng.uniform(-1, 1, 200), rng.uniform(-0.8, 0.8, 200), rng.uniform(2, 6, 200)])
    raw_l = project(K, points_l, calib.dist)
    raw_r = project(calib.K_right, points_l @ R.T + calib.T, calib.dist)
    rect = calib.rectification
    rect_l = cv2.undistortPoints(raw_l.reshape(-1, 1, 2), K, calib.dist, R=rect.R_left, P=rect.P_left)
    rect_r = cv2.undistortPoints(raw_r.reshape(-1, 1, 2), calib.K_right, calib.dist, R=rect.R_right,
                                 P=rect.P_right)
    rect_l, rect_r = rect_l.reshape(-1, 2), rect_r.reshape(-1, 2)
    assert np.abs(rect_l[:, 1] - rect_r[:, 1]).max() < 0.05
    cloud = triangulate(rect.geometry, rect_l, rect_r, R_cam_rect=rect.R_left.T)
    np.testing.assert_allclose(cloud.points_cam, points_l, rtol=2e-3, atol=2e-3)
    left, right = rect.apply(np.zeros((480, 640), np.uint8), np.zeros((480, 640), np.uint8))
    assert left.shape == right.shape == (480, 640)


def test_an_ideal_calibration_needs_no_remapping() -> None:
    K = np.array([[1000.0, 0, 599.5], [0, 1000.0, 449.5], [0, 0, 1]])
    calib = StereoCalibration.ideal(K, 0.25, (1200, 900))
    assert calib.is_rectified()
    geometry = calib.rectified_geometry()
    assert geometry.baseline == 0.25 and geometry.doffs == 0.0 and geometry.fB == 250.0


def _kitti_frames(index: int) -> tuple[np.ndarray, np.ndarray]:
    return tuple(cv2.imread(str(KITTI / f"image_{cam}" / f"{index:06d}.png"), cv2.IMREAD_GRAYSCALE)
                 for cam in (0, 1))  # type: ignore[return-value]


@pytest.mark.skipif(not KITTI.is_dir(), reason="the KITTI clip (../shared/data/kitti06_0-50) is absent")
def test_kitti_depths_are_positive_in_range_and_consistent_between_frames() -> None:
    calib = {line.split(":")[0]: np.array(line.split(":")[1].split(), dtype=float).reshape(3, 4)
             for line in (KITTI / "calib.txt").read_text().splitlines() if line[:2] in ("P0", "P1")}
    poses = np.loadtxt(KITTI / "poses.txt").reshape(-1, 3, 4)
    geometry = RectifiedStereo.from_projections(calib["P0"], calib["P1"], (1226, 370))
    assert geometry.baseline == pytest.approx(0.537, abs=0.001)
    max_range = 60.0
    for k in (0, 30):
        clouds = []
        for index in (k, k + 1):
            left, right = _kitti_frames(index)
            geometry = RectifiedStereo.from_projections(calib["P0"], calib["P1"], (left.shape[1], left.shape[0]))
            clouds.append(stereo_cloud(left, right, geometry, "orb", 2000, max_range=max_range))
        for cloud in clouds:
            assert len(cloud) >= 300
            assert (cloud.points_cam[:, 2] > 0).all() and (cloud.points_cam[:, 2] <= max_range + 1e-9).all()
        # Carry frame k's points into frame k+1 with the true motion; where they land next to a point of k+1,
        # the two depths agree.
        T0, T1 = np.eye(4), np.eye(4)
        T0[:3], T1[:3] = poses[k], poses[k + 1]
        T_10 = np.linalg.inv(T1) @ T0
        moved = clouds[0].points_cam @ T_10[:3, :3].T + T_10[:3, 3]
        uv = project(geometry.K, moved)
        dist, nearest = cKDTree(clouds[1].uv_left).query(uv, distance_upper_bound=2.0)
        close = np.isfinite(dist) & (moved[:, 2] < 30.0)
        assert close.sum() >= 50
        rel = np.abs(clouds[1].points_cam[nearest[close], 2] - moved[close, 2]) / moved[close, 2]
        assert np.median(rel) < 0.05
