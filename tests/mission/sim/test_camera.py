"""The simulated stereo camera (seed 000 §4's virtual scene: 1200×900 at 3.6 m above the object), against the
world's geometry: ray casts, projected part corners, and the degradation formulas."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.ndimage import laplace  # noqa: E402

from mission.frames import invert, transform_points  # noqa: E402
from mission.language.loader import load_world  # noqa: E402
from mission.language.models import Stereo  # noqa: E402
from mission.sim.camera import (  # noqa: E402
    Degradations,
    RenderError,
    StereoCamera,
    StereoFrame,
    fovy_deg,
    intrinsics,
    left_camera_pose,
)
from mission.world.scene import PlacedObject  # noqa: E402

REFERENCE_WORLD = Path(__file__).resolve().parents[3] / "worlds" / "sps_field.yaml"
ALTITUDE = 3.6  # above the manifold's roof, as in seed 000's virtual scene
ROOF_Z = -2.0  # the module's top in the object frame (z down)
HEADING = 33.5  # manifold-1's true heading: image axes along the roof's edges


@pytest.fixture(scope="module")
def camera() -> Iterator[StereoCamera]:
    try:
        cam = StereoCamera(load_world(REFERENCE_WORLD), Stereo(width=1200, height=900, fx=1000.0, baseline=0.25))
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    yield cam
    cam.close()


def manifold(camera: StereoCamera) -> PlacedObject:
    return next(o for o in camera.world.scene.objects if o.id == "manifold-1")


def above_roof(camera: StereoCamera, x: float, y: float) -> tuple[float, float, float]:
    """(north, east, depth) of the vehicle ALTITUDE above the roof point (x, y) of the object frame."""
    p = transform_points(manifold(camera).T_world_object, np.array([[x, y, ROOF_Z]]))[0]
    return float(p[0]), float(p[1]), float(p[2] - ALTITUDE)


@pytest.fixture(scope="module")
def centred(camera: StereoCamera) -> StereoFrame:
    return camera.render_at(*above_roof(camera, 4.0, 2.5), HEADING)


def test_intrinsics_follow_the_settings() -> None:
    settings = Stereo(width=1200, height=900, fx=1000.0)
    K = intrinsics(settings)
    assert K[0, 0] == K[1, 1] == 1000.0 and (K[0, 2], K[1, 2]) == (599.5, 449.5)
    assert fovy_deg(settings) == pytest.approx(2 * np.degrees(np.arctan(450 / 1000)))


def test_vehicle_pose_puts_the_left_camera_to_port_looking_down() -> None:
    T = left_camera_pose(10.0, 20.0, 50.0, heading=0.0, baseline=0.3)
    np.testing.assert_allclose(T[:3, 3], [10.0, 19.85, 50.0])  # port of a vehicle heading north is west
    np.testing.assert_allclose(T[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)


def test_images_of_the_reference_world_are_textured(centred: StereoFrame) -> None:
    for image in (centred.left, centred.right):
        assert image.shape == (900, 1200) and image.dtype == np.uint8
        assert 40 < image.mean() < 200
        assert image.std() > 10
        assert laplace(image.astype(float)).std() > 4  # fine texture, not only shading
    assert np.abs(centred.left.astype(int) - centred.right.astype(int)).mean() > 5  # the views differ
    assert centred.depth_left.dtype == np.float32
    np.testing.assert_allclose(centred.K, intrinsics(Stereo()))


def test_render_takes_a_pose_matrix_or_a_vehicle_pose(camera: StereoCamera, centred: StereoFrame) -> None:
    north, east, depth = above_roof(camera, 4.0, 2.5)
    again = camera.render(north, east, depth, HEADING)
    np.testing.assert_array_equal(again.left, centred.left)  # rendering is deterministic
    np.testing.assert_allclose(again.T_world_left, left_camera_pose(north, east, depth, HEADING, baseline=0.25))
    same = camera.render(centred.T_world_left)
    np.testing.assert_array_equal(same.right, centred.right)


def test_rays_through_pixel_centres_hit_what_the_depth_buffer_says(camera: StereoCamera,
                                                                   centred: StereoFrame) -> None:
    u, v = np.meshgrid(np.arange(20, 1200, 59), np.arange(15, 900, 45))
    u, v = np.r_[599.5, u.ravel()], np.r_[449.5, v.ravel()]  # the principal ray first
    rays_cam = np.column_stack([(u - 599.5) / 1000.0, (v - 449.5) / 1000.0, np.ones_like(u)])
    unit = rays_cam / np.linalg.norm(rays_cam, axis=1, keepdims=True)
    T = centred.T_world_left
    dist, geom = camera.world.cast_fan(T[:3, 3], unit @ T[:3, :3].T, cutoff=50.0)
    assert (geom >= 0).all()
    ray_depth = dist * unit[:, 2]
    # The principal point lies between four pixel centres.
    principal = float(centred.depth_left[449:451, 599:601].mean())
    assert principal == pytest.approx(ray_depth[0], abs=0.002)
    rendered = centred.depth_left[v[1:].astype(int), u[1:].astype(int)]
    err = np.abs(rendered - ray_depth[1:])
    assert np.median(err) < 0.001
    assert np.percentile(err, 95) < 0.005  # a ray on a depth edge may hit either side


def test_a_projected_roof_corner_lands_on_the_rendered_edges(camera: StereoCamera) -> None:
    frame = camera.render_at(*above_roof(camera, 5.0, 3.0), HEADING)
    T_left_world = invert(frame.T_world_left)
    corner_obj = np.array([[6.0, 4.0, ROOF_Z]])  # forward-starboard corner of the module's roof
    corner_cam = transform_points(T_left_world @ manifold(camera).T_world_object, corner_obj)[0]
    uc, vc = (frame.K @ corner_cam)[:2] / corner_cam[2]
    assert 100 < uc < 1100 and 50 < vc < 850
    iu, iv = int(round(uc)), int(round(vc))
    # The roof lies down-left of this corner in the image; beyond it the skid, 2 m lower.
    assert frame.depth_left[iv + 6, iu - 6] == pytest.approx(corner_cam[2], abs=0.05)
    assert frame.depth_left[iv - 6, iu + 6] > corner_cam[2] + 1.5
    image = frame.left.astype(float)
    across_u = np.abs(np.diff(image[iv + 20:iv + 120, iu - 15:iu + 16].mean(axis=0)))
    across_v = np.abs(np.diff(image[iv - 15:iv + 16, iu - 120:iu - 20].mean(axis=1)))
    edge_u = iu - 15 + int(np.argmax(across_u)) + 0.5
    edge_v = iv - 15 + int(np.argmax(across_v)) + 0.5
    assert abs(edge_u - uc) <= 3.0 and abs(edge_v - vc) <= 3.0


def test_sensor_noise_has_the_asked_sigma(camera: StereoCamera, centred: StereoFrame) -> None:
    clean = camera.degradations
    camera.degradations = Degradations(noise_sigma=8.0, seed=3)
    try:
        noisy = camera.render(centred.T_world_left)
    finally:
        camera.degradations = clean
    diff = noisy.left.astype(float) - centred.left.astype(float)
    assert diff.std() == pytest.approx(8.0, rel=0.05)
    assert abs(diff.mean()) < 0.3
    assert noisy.left.astype(float).var() > centred.left.astype(float).var() + 50


def test_blur_removes_fine_detail(camera: StereoCamera, centred: StereoFrame) -> None:
    clean = camera.degradations
    camera.degradations = Degradations(blur_sigma_px=1.5)
    try:
        blurred = camera.render(centred.T_world_left)
    finally:
        camera.degradations = clean
    assert laplace(blurred.left.astype(float)).std() < 0.5 * laplace(centred.left.astype(float)).std()
    assert blurred.left.mean() == pytest.approx(centred.left.mean(), abs=1.0)


def test_turbidity_follows_the_formula_and_costs_contrast_with_range(camera: StereoCamera,
                                                                     centred: StereoFrame) -> None:
    clean = camera.degradations
    turbid = Degradations(turbidity_per_m=0.2, veiling_light=70.0)
    camera.degradations = turbid
    try:
        murky = camera.render(centred.T_world_left)
    finally:
        camera.degradations = clean
    v, u = np.mgrid[0:900, 0:1200]
    ray = np.sqrt(1 + ((u - 599.5) / 1000) ** 2 + ((v - 449.5) / 1000) ** 2)
    t = np.exp(-0.2 * centred.depth_left * ray)
    expected = centred.left * t + 70.0 * (1 - t)
    assert np.abs(murky.left - expected).mean() < 0.6  # rounding to grey levels
    near, far = centred.depth_left < 3.7, centred.depth_left > 6.0  # roof versus seabed
    assert near.sum() > 1e5 and far.sum() > 5e4
    ratio_near = murky.left[near].std() / centred.left[near].std()
    ratio_far = murky.left[far].std() / centred.left[far].std()
    assert ratio_far < ratio_near < 1.0
    assert ratio_near == pytest.approx(np.exp(-0.2 * 3.65), rel=0.05)


def test_light_fall_off_darkens_with_range(camera: StereoCamera) -> None:
    pose = above_roof(camera, 5.0, 3.0)
    clean = camera.render_at(*pose, HEADING)
    camera.degradations = replace(camera.degradations, falloff_range_m=ALTITUDE)
    try:
        dim = camera.render_at(*pose, HEADING)
    finally:
        camera.degradations = Degradations()
    ratio = (dim.left.astype(float) + 0.5) / (clean.left.astype(float) + 0.5)
    v, u = np.mgrid[0:900, 0:1200]
    lamp_range = clean.depth_left * np.sqrt(1 + ((u - 599.5 - 125) / 1000) ** 2 + ((v - 449.5) / 1000) ** 2)
    expected = (ALTITUDE / lamp_range) ** 2
    roof = np.abs(clean.depth_left - ALTITUDE) < 0.05
    seabed = clean.depth_left > 6.0
    assert np.median(ratio[roof]) == pytest.approx(np.median(expected[roof]), abs=0.05)
    assert np.median(ratio[seabed]) == pytest.approx(np.median(expected[seabed]), rel=0.2)
    assert np.median(ratio[seabed]) < 0.5


def test_supersampling_averages_samples_without_moving_the_image(centred: StereoFrame) -> None:
    import cv2

    with pytest.raises(ValueError, match="supersample"):
        StereoCamera(load_world(REFERENCE_WORLD), Stereo(width=120, height=90, fx=100.0), supersample=0)
    with StereoCamera(load_world(REFERENCE_WORLD), Stereo(width=1200, height=900, fx=1000.0, baseline=0.25),
                      supersample=2) as fine:
        frame = fine.render(centred.T_world_left)
    assert frame.left.shape == (900, 1200) and frame.left.dtype == np.uint8
    np.testing.assert_allclose(frame.K, centred.K)
    # Same frustum and pixel centres: the pictures and depths line up with the plain render to a small fraction
    # of a pixel; the 2×2 average removes aliased fine detail, so the picture gets no sharper.
    for ours, plain in ((frame.left, centred.left), (frame.right, centred.right)):
        shift, _ = cv2.phaseCorrelate(ours.astype(np.float64), plain.astype(np.float64))
        assert np.hypot(*shift) < 0.05
        assert abs(float(ours.mean()) - float(plain.mean())) < 1.0
        assert laplace(ours.astype(float)).std() < laplace(plain.astype(float)).std()
    flat = np.abs(laplace(centred.depth_left.astype(float))) < 1e-3  # away from depth edges
    assert np.median(np.abs(frame.depth_left - centred.depth_left)[flat]) < 0.001


def test_a_camera_without_depth_renders_the_same_images_and_an_empty_depth(camera: StereoCamera,
                                                                         centred: StereoFrame) -> None:
    with StereoCamera(load_world(REFERENCE_WORLD), Stereo(width=1200, height=900, fx=1000.0, baseline=0.25),
                      depth=False) as lean:
        frame = lean.render(centred.T_world_left)
        assert frame.depth_left.shape == (0, 0)
        np.testing.assert_array_equal(frame.left, centred.left)
        np.testing.assert_array_equal(frame.right, centred.right)
        # turbidity needs the depth: it is read back for it, and the picture is the one a camera with depth makes
        lean.degradations = camera.degradations = Degradations(turbidity_per_m=0.2)
        try:
            murky, reference = lean.render(centred.T_world_left), camera.render(centred.T_world_left)
        finally:
            camera.degradations = Degradations()
        assert murky.depth_left.shape == (0, 0)
        np.testing.assert_array_equal(murky.left, reference.left)
        assert float(murky.left.std()) < float(centred.left.std())
