"""The simulated down-looking stereo camera: left/right grey images of the world rendered off-screen by MuJoCo.

Seed 002 §3.1–3.3 and seed 000 §4 reference the vehicle to an object from stereo pairs of a camera looking straight
down (seed 000's virtual scene: 1200×900 pixels, 3.6 m above the object). This module renders such pairs from the
world's MuJoCo model (`mission.sim.mjworld`, built with an `Appearance`: procedural seabed texture, textured object
parts), lit only by a spot lamp the vehicle carries (`castshadow` off: shadows cost ~4× on a software renderer).

Frames. Each camera frame follows OpenCV (x right, y down, z along the optical axis); the left camera is the stereo
frame, the right camera sits at +baseline along the left camera's x with the same orientation (rectified by
construction). Mounted on the vehicle (`left_camera_pose`): by default the optical axis is body z (down), image x
is body y (starboard), image y is −body x (the top of the image looks forward); a tilted mount
(`sensors.stereo.mount.tilt_deg`, `mission.language.mount`) pitches the optical axis up towards body x about body
y. The left camera sits at −baseline/2 on body y (port), the right at +baseline/2 (starboard), both at the body
origin otherwise; the lamp sits between them.

Intrinsics: fx from the `Stereo` settings, fy = fx, principal point at the image centre ((W − 1)/2, (H − 1)/2 in
OpenCV's pixel-centre convention, which is where a symmetric OpenGL frustum puts it); MuJoCo's vertical field of
view is 2·atan(H / (2·fy)).

Degradations (all off by default; `Degradations`): the lamp's fall-off with range (OpenGL quadratic attenuation),
turbidity from the rendered depth (I = J·exp(−c·d) + A·(1 − exp(−c·d)), d the range along each pixel's ray), then
Gaussian blur, then Gaussian sensor noise, then rounding to 8 bits.

Supersampling (`supersample=k`, off by default): each image is rendered at k× the width and height with the same
field of view, then every k×k block is averaged (as a real sensor integrates the light over each pixel's area);
the degradations apply to the averaged image. With the default 1, each pixel is one sample of the texture through
OpenGL's mipmapped filtering, which lets a seabed texture finer than the pixels alias.

`StereoFrame.depth_left` is the renderer's depth buffer: ground truth for tests and benchmarks only. Perception
plug-ins are handed the images, K, the baseline and the pose prior, never the depth. A camera built with
`depth=False` (the simulated vehicle's) neither reads the depth buffer back nor converts it, unless turbidity needs
it, and its frames carry an empty `depth_left`: the read-back and the conversion cost about a third of a pair's
post-processing.

Anti-aliasing (`antialias`, on by default): the off-screen buffer has 4 samples per pixel, so the edges of
geometry (object outlines) are averaged over the pixel as a sensor would; textures are filtered either way. Off,
a pair costs about half on a software renderer (llvmpipe: ~65 → ~30 ms per 1200×900 image here), and only pixels
on geometry edges change (~0.4 % of a view of the manifold, by up to a few tens of grey levels).

Off-screen GL: EGL, falling back to OSMesa (`MUJOCO_GL=osmesa` tries OSMesa first); `MESA_SHADER_CACHE_DIR` is
pointed at a temporary folder when unset, so that Mesa does not write under the user's home.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
from dataclasses import dataclass
from typing import Any, overload

import mujoco
import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import gaussian_filter

from mission.errors import AuvError
from mission.frames import R_BODY_CAM, Array, camera_pose
from mission.language.models import Stereo
from mission.language.world import Texture, World
from mission.sim.mjworld import HIDDEN_GROUP, R_MJ_NED, SEABED_TILE_GROUP, VISUAL_GROUP, MjWorld, ned_to_mj
from mission.sim.textures import Appearance
from mission.world.scene import Scene, build_scene


class RenderError(AuvError):
    """No off-screen OpenGL context could be created (neither EGL nor OSMesa)."""


@dataclass(frozen=True)
class Degradations:
    """Image degradations a user can switch on; the defaults leave the rendered images untouched."""

    noise_sigma: float = 0.0
    """Gaussian sensor noise, standard deviation in grey levels (0–255)."""
    blur_sigma_px: float = 0.0
    """Gaussian blur (defocus, scattering), standard deviation in pixels."""
    falloff_range_m: float = 0.0
    """0: the lamp lights every range alike; r0 > 0: intensity falls as (r0 / range)², unchanged at r0."""
    turbidity_per_m: float = 0.0
    """Attenuation coefficient c (1/m) of I = J·exp(−c·d) + A·(1 − exp(−c·d)); 0 for clear water."""
    veiling_light: float = 70.0
    """A: the grey level the water column tends to at long range (with turbidity only)."""
    seed: int = 0
    """Seed of the sensor-noise generator."""


@dataclass(frozen=True)
class Lamp:
    """The spot lamp between the cameras, along the optical axis (OpenGL light parameters)."""

    diffuse: float = 0.9
    ambient: float = 0.12
    specular: float = 0.15
    cutoff_deg: float = 80.0
    exponent: float = 1.0


@dataclass(frozen=True, eq=False)
class StereoFrame:
    """A rectified stereo pair as the camera delivers it, plus the rendered depth for tests."""

    left: NDArray[np.uint8]
    """(H, W) grey image of the left camera."""
    right: NDArray[np.uint8]
    """(H, W) grey image of the right camera (same orientation, +baseline along the left camera's x)."""
    K: Array
    """(3, 3) intrinsics of both cameras."""
    baseline: float
    """Distance between the optical centres (m)."""
    T_world_left: Array
    """(4, 4) left camera → world (NED); camera axes per OpenCV."""
    depth_left: NDArray[np.float32]
    """(H, W) rendered depth along the left camera's z (m), inf where nothing is seen; (0, 0) from a camera built
    with `depth=False`. FOR TESTS ONLY: ground truth that perception must never be given."""


def intrinsics(settings: Stereo) -> Array:
    """K of the camera: fx = fy from the settings, principal point at the image centre.

    >>> intrinsics(Stereo(width=1200, height=900, fx=1000.0)).tolist()
    [[1000.0, 0.0, 599.5], [0.0, 1000.0, 449.5], [0.0, 0.0, 1.0]]
    """
    return np.array([[settings.fx, 0.0, 0.5 * (settings.width - 1)],
                     [0.0, settings.fx, 0.5 * (settings.height - 1)],
                     [0.0, 0.0, 1.0]])


def fovy_deg(settings: Stereo) -> float:
    """MuJoCo's vertical field of view for the settings' height and focal length.

    >>> round(fovy_deg(Stereo(width=1200, height=900, fx=1000.0)), 3)
    48.455
    """
    return math.degrees(2.0 * math.atan(0.5 * settings.height / settings.fx))


def left_camera_pose(north: float, east: float, depth: float, heading: float, pitch: float = 0.0,
                     roll: float = 0.0, baseline: float = 0.25, R_body_cam: Array = R_BODY_CAM) -> Array:
    """T_world_left of the rig on a vehicle at this pose: `mission.frames.camera_pose`, the one mount definition
    agents use too (left camera at −baseline/2 on body y; looking down unless `R_body_cam` tilts it)."""
    return camera_pose(north, east, depth, heading, pitch, roll, baseline, R_body_cam)


def _gl_context(width: int, height: int) -> Any:
    """An off-screen GL context: EGL, else OSMesa (OSMesa first when MUJOCO_GL says so).

    PyOpenGL binds one platform per process (`PYOPENGL_PLATFORM`, which MuJoCo's backends set on import): the
    fallback works when the first backend failed before PyOpenGL was imported, e.g. for a missing libEGL.
    """
    os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))
    order = ["osmesa", "egl"] if os.environ.get("MUJOCO_GL", "").lower() == "osmesa" else ["egl", "osmesa"]
    errors = []
    for backend in order:
        platform_before = os.environ.get("PYOPENGL_PLATFORM")
        try:
            if backend == "egl":
                from mujoco.egl import GLContext
            else:
                from mujoco.osmesa import GLContext  # type: ignore[no-redef,unused-ignore]
            context = GLContext(width, height)
            context.make_current()
            return context
        except Exception as exc:  # noqa: BLE001 -- any failure means "try the next backend"
            errors.append(f"{backend}: {exc}")
            if platform_before is None and "OpenGL" not in sys.modules:
                os.environ.pop("PYOPENGL_PLATFORM", None)  # let the next backend choose its platform
    raise RenderError("no off-screen OpenGL context (" + "; ".join(errors) + "); install Mesa's EGL "
                      "(libegl1) or OSMesa (libosmesa6)")


def _block_mean(image: NDArray[np.float32], k: int) -> NDArray[np.float32]:
    """The mean of every k×k block (cv2.INTER_AREA for a whole factor); an infinite depth stays infinite.

    >>> _block_mean(np.arange(16, dtype=np.float32).reshape(4, 4), 2).tolist()
    [[2.5, 4.5], [10.5, 12.5]]
    """
    h, w = image.shape[0] // k, image.shape[1] // k
    return np.asarray(image.reshape(h, k, w, k).mean(axis=(1, 3), dtype=np.float32), dtype=np.float32)


_NO_DEPTH: NDArray[np.float32] = np.empty((0, 0), dtype=np.float32)
_NO_DEPTH.setflags(write=False)  # the `depth_left` of a camera built with `depth=False`


class StereoCamera:
    """Renders rectified stereo pairs of a world from poses of the left camera or of the vehicle.

    One camera owns one GL context and one MuJoCo model of the world with its appearance; use it from one
    thread. `close()` (or a `with` block) frees the GL resources. `degradations` may be replaced between renders
    (the noise generator carries on).
    """

    def __init__(self, world: World | Scene | MjWorld, settings: Stereo | None = None,
                 degradations: Degradations | None = None, *, texture: Texture | None = None,
                 appearance: Appearance | None = None, lamp: Lamp | None = None, near_m: float = 0.1,
                 far_m: float = 200.0, supersample: int = 1, depth: bool = True, antialias: bool = True) -> None:
        """`world`: a world file's model, a scene or a plain `MjWorld` (the seabed texture comes from `texture`,
        else the world's or scene's own). The camera compiles its own model with the appearance, sized for its
        images. `supersample`: render k× larger and average k×k blocks (see the module docstring). `depth`: read
        the depth buffer back into `StereoFrame.depth_left` (False: an empty array, and less work per pair).
        `antialias`: 4× multisampling of geometry edges (False: about half the cost of a pair; see the module
        docstring)."""
        if not isinstance(supersample, int) or supersample < 1:
            raise ValueError(f"supersample must be a whole number >= 1, got {supersample!r}")
        if isinstance(world, World):
            scene, texture = build_scene(world), texture or world.seabed.texture
        elif isinstance(world, MjWorld):
            scene = world.scene
            if appearance is None and world.appearance is not None:
                appearance = world.appearance
        else:
            scene = world
        self.settings = settings or Stereo()
        self.degradations = degradations or Degradations()
        self.lamp = lamp or Lamp()
        self.K = intrinsics(self.settings)
        self.near_m, self.far_m = near_m, far_m
        self.supersample = supersample
        self.depth = depth
        w, h = self.settings.width, self.settings.height
        # The rendered frustum is the images' (same fx/W ratio): only the number of samples per pixel changes.
        w_gl, h_gl = supersample * w, supersample * h
        self.world = MjWorld(scene, offscreen=(w_gl, h_gl), near_m=near_m, far_m=far_m,
                             appearance=appearance or Appearance(seabed=texture or scene.texture),
                             offsamples=4 if antialias else 0)
        self._rng = np.random.default_rng(self.degradations.seed)
        self._rect = mujoco.MjrRect(0, 0, w_gl, h_gl)
        self._gl = _gl_context(w_gl, h_gl)
        self._context: Any = mujoco.MjrContext(self.world.model, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(self.world.model, maxgeom=max(100, 2 * self.world.model.ngeom))
        self._option = mujoco.MjvOption()
        self._option.geomgroup[:] = 0
        self._option.geomgroup[SEABED_TILE_GROUP] = self._option.geomgroup[VISUAL_GROUP] = 1
        for flag in ("mjRND_SHADOW", "mjRND_SKYBOX", "mjRND_HAZE", "mjRND_REFLECTION", "mjRND_FOG"):
            self._scene.flags[getattr(mujoco.mjtRndFlag, flag)] = 0
        self._rgb = np.empty((h_gl, w_gl, 3), dtype=np.uint8)
        self._depth = np.empty((h_gl, w_gl), dtype=np.float32)
        # Range along each pixel's ray per metre of depth, for turbidity.
        u = (np.arange(w) - self.K[0, 2]) / self.K[0, 0]
        v = (np.arange(h) - self.K[1, 2]) / self.K[1, 1]
        self._ray_length = np.sqrt(1.0 + u[None, :] ** 2 + v[:, None] ** 2).astype(np.float32)

    @property
    def baseline(self) -> float:
        return float(self.settings.baseline)

    def render_at(self, north: float, east: float, depth: float, heading: float, pitch: float = 0.0,
                  roll: float = 0.0) -> StereoFrame:
        """The pair seen from a vehicle at this pose (camera mounted as `left_camera_pose` and the settings'
        `mount` say)."""
        return self.render(left_camera_pose(north, east, depth, heading, pitch, roll, self.baseline,
                                            self.settings.mount.R_body_cam()))

    @overload
    def render(self, pose: Array) -> StereoFrame: ...

    @overload
    def render(self, pose: float, east: float, depth: float, heading: float, pitch: float = 0.0,
               roll: float = 0.0) -> StereoFrame: ...

    def render(self, pose: Array | float, east: float | None = None, depth: float | None = None,
               heading: float | None = None, pitch: float = 0.0, roll: float = 0.0) -> StereoFrame:
        """The pair seen with the left camera at `T_world_left` (4×4, camera axes per OpenCV, world NED), or from
        a vehicle at (north, east, depth, heading[, pitch, roll]) as `render_at`."""
        if np.ndim(pose) == 0:
            if east is None or depth is None or heading is None:
                raise TypeError("render(north, east, depth, heading[, pitch, roll]) needs all four")
            return self.render_at(float(pose), east, depth, heading, pitch, roll)
        T_world_left = np.asarray(pose, dtype=float)
        if self._context is None:
            raise RenderError("render() after close()")
        self._gl.make_current()
        model, scene = self.world.model, self._scene
        self._cull_tiles(T_world_left)
        mujoco.mjv_updateScene(model, self.world.data, self._option, mujoco.MjvPerturb(), mujoco.MjvCamera(),
                               mujoco.mjtCatBit.mjCAT_ALL, scene)
        R = R_MJ_NED @ T_world_left[:3, :3]  # camera axes in MuJoCo's world
        centre = T_world_left[:3, 3] + 0.5 * self.baseline * T_world_left[:3, 0]
        self._set_lamp(ned_to_mj(centre), R[:, 2])
        images, depths = [], []
        with_depth = self.depth or self.degradations.turbidity_per_m > 0
        for offset in (0.0, self.baseline):
            self._set_camera(ned_to_mj(T_world_left[:3, 3] + offset * T_world_left[:3, 0]), R)
            mujoco.mjr_render(self._rect, scene, self._context)
            mujoco.mjr_readPixels(self._rgb, self._depth if with_depth else None, self._rect, self._context)
            rgb = self._rgb[::-1]  # OpenGL rows run bottom-up
            grey = np.asarray(rgb @ np.array([0.299, 0.587, 0.114], dtype=np.float32), dtype=np.float32)
            z = self._metric_depth(self._depth[::-1]) if with_depth else _NO_DEPTH
            if self.supersample > 1:
                grey = _block_mean(grey, self.supersample)
                z = _block_mean(z, self.supersample) if with_depth else z
            images.append(self._degrade(grey, z))
            depths.append(z if self.depth else _NO_DEPTH)
        return StereoFrame(images[0], images[1], self.K.copy(), self.baseline, T_world_left.copy(), depths[0])

    def _cull_tiles(self, T_world_left: Array) -> None:
        """Show only the seabed tiles whose bounding spheres reach into the pair's joint view frustum."""
        world = self.world
        T_mj = np.eye(4)
        T_mj[:3, :3] = R_MJ_NED @ T_world_left[:3, :3]
        T_mj[:3, 3] = ned_to_mj(T_world_left[:3, 3])
        p = (world.seabed_tile_centres - T_mj[:3, 3]) @ T_mj[:3, :3]  # tile centres in the left camera frame
        r = world.seabed_tile_radii
        w, h = self.settings.width, self.settings.height
        fx, cx, cy = self.K[0, 0], self.K[0, 2], self.K[1, 2]
        tan_left, tan_right = (cx + 0.5) / fx, (w - cx - 0.5) / fx
        tan_top, tan_bottom = (cy + 0.5) / fx, (h - cy - 0.5) / fx
        visible = (p[:, 2] > -r) & (p[:, 2] < self.far_m + r)
        # Outward side planes of the union of both views: the right camera sits at +baseline along x.
        for normal, x0 in (((-1.0, 0.0, -tan_left), 0.0), ((1.0, 0.0, -tan_right), self.baseline),
                           ((0.0, -1.0, -tan_top), 0.0), ((0.0, 1.0, -tan_bottom), 0.0)):
            n = np.asarray(normal) / np.linalg.norm(normal)
            visible &= (p - [x0, 0.0, 0.0]) @ n < r
        world.model.geom_group[world.seabed_tile_geoms] = np.where(visible, SEABED_TILE_GROUP, HIDDEN_GROUP)

    def _set_camera(self, pos_mj: Array, R_mj_cam: Array) -> None:
        n, (w, h) = self.near_m, (self.settings.width, self.settings.height)
        fx, cx, cy = self.K[0, 0], self.K[0, 2], self.K[1, 2]
        for cam in self._scene.camera:  # both eyes alike: mono rendering averages the two
            cam.pos[:] = pos_mj
            cam.forward[:] = R_mj_cam[:, 2]
            cam.up[:] = -R_mj_cam[:, 1]  # image y runs down
            cam.frustum_near, cam.frustum_far = n, self.far_m
            cam.frustum_top = n * (cy + 0.5) / fx
            cam.frustum_bottom = -n * (h - cy - 0.5) / fx
            cam.frustum_center = n * (0.5 * w - cx - 0.5) / fx
            cam.frustum_width = n * 0.5 * w / fx
            cam.orthographic = 0

    def _set_lamp(self, pos_mj: Array, axis_mj: Array) -> None:
        lamp, scene = self.lamp, self._scene
        scene.nlight = 1
        light = scene.lights[0]
        light.pos[:] = pos_mj
        light.dir[:] = axis_mj
        light.type = mujoco.mjtLightType.mjLIGHT_SPOT
        light.headlight = 0
        light.castshadow = 0
        light.cutoff, light.exponent = lamp.cutoff_deg, lamp.exponent
        r0 = self.degradations.falloff_range_m
        light.attenuation[:] = (0.0, 0.0, 1.0 / r0**2) if r0 > 0 else (1.0, 0.0, 0.0)
        light.ambient[:] = lamp.ambient
        light.diffuse[:] = lamp.diffuse
        light.specular[:] = lamp.specular
        light.range = 10.0 * self.far_m

    def _metric_depth(self, buf: NDArray[np.float32]) -> NDArray[np.float32]:
        """Reversed-Z depth buffer (1 at near, 0 at far) → metres along z; inf where nothing was drawn."""
        n, f = self.near_m, self.far_m
        z = (f * n) / (n + buf.astype(np.float64) * (f - n))
        z[buf <= 0.0] = np.inf
        return z.astype(np.float32)

    def _degrade(self, grey: NDArray[np.float32], z: NDArray[np.float32]) -> NDArray[np.uint8]:
        deg = self.degradations
        image: NDArray[np.floating[Any]] = grey
        if deg.turbidity_per_m > 0:
            transmission = np.exp(-deg.turbidity_per_m * np.where(np.isfinite(z), z * self._ray_length, 1e6))
            image = image * transmission + deg.veiling_light * (1.0 - transmission)
        if deg.blur_sigma_px > 0:
            image = gaussian_filter(image, deg.blur_sigma_px, mode="nearest")
        if deg.noise_sigma > 0:
            image = image + self._rng.normal(0.0, deg.noise_sigma, image.shape).astype(np.float32)
        return np.asarray(np.clip(np.rint(image), 0, 255), dtype=np.uint8)

    def close(self) -> None:
        """Free the GL resources (idempotent)."""
        if self._context is not None:
            self._gl.make_current()
            self._context.free()
            self._context = None
            self._gl.free()

    def __enter__(self) -> StereoCamera:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["Degradations", "Lamp", "R_BODY_CAM", "RenderError", "StereoCamera", "StereoFrame", "fovy_deg",
           "intrinsics", "left_camera_pose"]
