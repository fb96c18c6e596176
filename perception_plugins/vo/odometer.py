"""The odometer: a front end (classic or long KLT), a step policy (fixed or adaptive), the chain of local transforms
and, optionally, the virtual reference network — fed one frame at a time, online or offline alike.

Frames are pushed in order; the odometer buffers the frames since its last processed position and processes one
when the buffer reaches the current step (fixed, or `adaptive.step_time`'s T·fps). A step that too few features
support is halved (adaptive mode, down to one frame; seed 003's second mechanism); a step that fails outright is a
tracking loss: the position is dead-reckoned at the median velocity of the last tracked steps (`_bridge`) and a
new fragment starts there (the loss is counted, the odometer carries on). Positions relative to the origin come out
as `Estimate`s, possibly several per push (a halved step emits the shorter position and then the rest of the buffer
as it becomes due).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert
from mission.plugin_api import StereoImages
from perception_plugins.vo.adaptive import (
    common_view_mask,
    field_of_view_along,
    overlap_displacement,
    step_frames,
    step_time,
)
from perception_plugins.vo.chain import Chain
from perception_plugins.vo.classic import ClassicMatcher
from perception_plugins.vo.errors import VoError
from perception_plugins.vo.frontend import Array, Frontend, Step, geometry_of, prepare
from perception_plugins.vo.klt import KltTracker
from perception_plugins.vo.network import NetworkSettings, ReferenceNetwork
from perception_plugins.vo.se3 import from_rotvec_translation, to_rotvec
from perception_plugins.vo.window import KeyframeWindow, WindowSettings

_BRIDGE_STEPS = 7
"""Tracked steps whose median velocity bridges a tracking loss."""


@dataclass(frozen=True)
class OdometerSettings:
    """How the odometer works; `methods.settings_for` builds these for the named methods."""

    frontend: Literal["klt", "classic"] = "klt"
    step: int = 1
    """Frames per step (fixed step); the first step of the adaptive mode."""
    fragment_steps: int = 4
    """Steps per KLT fragment (a fragment also ends early when its survivors fall below `refresh_features`)."""
    adaptive: bool = False
    overlap_percent: float = 90.0
    """P: the share of the view two processed positions keep in common (adaptive mode). The seed gives no value;
    on the 240 s rendered seabed pass (`auv bench vo`) 85 % processed 8.2× fewer frames than KLT at step 2 at
    1.57× its mean error, 90 % 5.3× fewer at 0.91× (the seed's claim is fewer frames at equal accuracy)."""
    max_step: int = 32
    min_features: int = 50
    """Features a step needs; below it the adaptive step is halved (30–100 in the seed's experiments)."""
    min_track: int = 12
    """Fewer inliers than this is a tracking loss."""
    refresh_features: int = 120
    """A KLT fragment ends early when fewer features survive."""
    fragment_rotation_deg: float = 10.0
    """A KLT fragment also ends early once the view has turned this much since its start (LK's windows do not
    rotate: long tracks across a turn drift, and the check against the start image rejects good ones)."""
    features: int = 500
    crop: bool = True
    """Adaptive mode: generate features only where the next position is predicted to see too (third mechanism)."""
    threshold_px: float = 1.5
    calibrate_offset: bool = True
    """KLT: estimate the pair's disparity offset from the fragments' motion (self-calibration), from the fragments
    whose depths can tell it from the translation's scale (`klt.offset_observable`)."""
    max_motion_depths: float = 1.0
    """A step moving farther than this many scene depths is rejected as a failure (the views could not overlap)."""
    max_turn_deg: float = 30.0
    """A step turning more than this is rejected as a failure."""
    fps: float | None = None
    """Frame rate for the adaptive step; from the frames' times when None."""
    altitude: float | None = None
    """R for the adaptive step; the keyframe's median depth when None."""
    network: NetworkSettings | None = None
    flat_field_px: float | None = 40.0
    """The front end sees each image divided by its Gaussian blur of this σ (px) (`frontend.flat_field`): a lamp
    moving with the vehicle breaks LK's brightness constancy otherwise (measured on the rendered seabed: long KLT's
    pitch drift per fragment −0.015° → +0.002°). The reference network binds on the images as pushed (its
    descriptor matching bound 1.7 cm off on flat-fielded ones, 0.2 cm on the originals). None: no flat field."""
    prefilter_px: float | None = 0.7
    """A Gaussian low-pass of this σ (px) on the front ends' images after the flat field (`frontend.prepare`):
    against sensor noise, which the flat field amplifies in dim areas, and against aliased texture, on which LK's
    sub-pixel estimates lock toward whole pixels. Measured with σ 0.7 against none: KITTI 06 KLT end-point drift
    0.84 → 0.77 %; rendered seabed 240 s, mean error at steps 2/4/8/16, KLT 67/98/70/32 → 60/83/57/33 cm and
    classic 100/66/66/85 → 66/54/47/63 cm; degraded mud run tracking losses KLT 16 → 1.8 %, adaptive 32 → 0 %.
    Stronger is not better on sharp real images (σ 1.0: KITTI 1.14 %). None: no low-pass."""
    bundle_window: int | None = None
    """Keyframes (fragment ends) in a local bundle adjustment (`window.KeyframeWindow`); None: none. Off by default:
    with 8 keyframes (KLT, tracks carried) the end-point drift was KITTI 06 0.69 → 0.89 %, rendered turns (`auv bench
    vo`) forward 90° 0.41 → 0.26 %, forward S 0.20 → 0.17 %, down 90° 0.19 → 0.05 %, down S 0.10 → 0.20 %: no
    consistent gain, for 10–50 % of the frame rate (`benchmarks/results/vo_turns.json`)."""
    carry_tracks: bool = True
    """KLT: a fragment's start continues the previous fragment's survivors as features and detects new corners only
    away from them (`KltTracker.carry`). End-point drift against fresh corners at every start: KITTI 06 0.85 →
    0.69 % (0.71 → 0.63 % on average over four start frames), rendered turns forward 90° 0.24 → 0.41 %, forward S
    0.32 → 0.20 %, down 90° 0.13 → 0.19 %, down S 0.17 → 0.10 %."""
    tracking_lowpass_px: float | None = 1.5
    """KLT: the images LK tracks across time (step to step, and back to the fragment's start) are low-passed to
    this total σ (px), the prefilter's included; corners and the stereo matching keep the prefiltered images. LK's
    sub-pixel estimates lock toward whole pixels on sharp texture, and along a steady flow the lock is systematic:
    the motion fit trades it into pitch (on the rendered seabed +1.9° over 240 s at step 8 with the offset
    calibration off). Its 21-px windows lose little precision to the blur: KITTI 06 drift 0.77 → 0.65 %.
    None: track on the prefiltered images."""


@dataclass(frozen=True, eq=False)
class Estimate:
    """The pose of a processed frame relative to the origin (frame index as pushed)."""

    index: int
    T_origin_cam: Array
    tracked: int
    lost: bool = False
    bound_to: int | None = None
    """The frame index of the reference frame this position was bound to, if it was."""


@dataclass
class _Position:
    index: int
    time: float
    T_origin: Array


@dataclass
class OdometerStats:
    positions: int = 0
    losses: int = 0
    halvings: int = 0
    fragments: int = 0
    bindings: int = 0
    steps: list[int] = field(default_factory=list)


def _extra_blur(total_px: float | None, applied_px: float | None) -> float:
    """σ of the Gaussian that takes an image low-passed by σ `applied_px` to σ `total_px` (variances add)."""
    total, applied = total_px or 0.0, applied_px or 0.0
    return math.sqrt(max(total * total - applied * applied, 0.0))


class Odometer:
    """Stereo visual odometry over a stream of frames (see the module docstring)."""

    def __init__(self, settings: OdometerSettings | None = None) -> None:
        self.settings = s = settings or OdometerSettings()
        if s.step < 1 or s.max_step < 1 or s.fragment_steps < 1:
            raise VoError("step, max_step and fragment_steps must be at least 1")
        self.frontend: Frontend = (KltTracker(s.features, s.threshold_px, calibrate_offset=s.calibrate_offset,
                                              track_blur_px=_extra_blur(s.tracking_lowpass_px, s.prefilter_px),
                                              carry=s.carry_tracks)
                                   if s.frontend == "klt"
                                   else ClassicMatcher(2 * s.features, s.threshold_px))
        self.network = ReferenceNetwork(s.network) if s.network is not None else None
        self.window = KeyframeWindow(WindowSettings(size=s.bundle_window)) if s.bundle_window else None
        self.stats = OdometerStats()
        self._buffer: list[tuple[int, StereoImages, StereoImages]] = []  # (index, prepared, as pushed)
        self._key: _Position | None = None
        self._last: _Position | None = None
        self._chain = Chain.origin()
        self._in_fragment = 0
        self._velocity: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None  # (rad/s, m/s) in camera
        self._speeds: list[float] = []
        self._recent: list[NDArray[np.float64]] = []  # the last tracked steps' (rad/s, m/s), for dead reckoning
        self._last_dt = 0.0
        self._target = s.step
        self._depth: float | None = None
        self._fps = s.fps
        self._K: Array = np.eye(3)
        self._size = (0, 0)

    # ---- public -------------------------------------------------------------------------------------------------
    def push(self, index: int, frame: StereoImages, altitude: float | None = None) -> list[Estimate]:
        """Feed the next frame; returns the positions this frame made due (none when the step skips it)."""
        if altitude is not None:
            self._depth = altitude
        raw, frame = frame, self._prepared(frame)
        if self._key is None:
            return [self._start(index, frame, raw)]
        if self._fps is None and self._last is not None and frame.time > self._last.time and index > self._last.index:
            self._fps = (index - self._last.index) / (frame.time - self._last.time)
        self._buffer.append((index, frame, raw))
        out: list[Estimate] = []
        while self._buffer and len(self._buffer) >= self._target:
            out.append(self._advance(self._target))
        return out

    def finish(self) -> list[Estimate]:
        """Process what is left in the buffer (its last frame becomes a position)."""
        out: list[Estimate] = []
        while self._buffer:
            out.append(self._advance(min(self._target, len(self._buffer))))
        return out

    def pending(self) -> int:
        return len(self._buffer)

    def _prepared(self, frame: StereoImages) -> StereoImages:
        flat, low = self.settings.flat_field_px, self.settings.prefilter_px
        if flat is None and low is None:
            return frame
        return replace(frame, left=prepare(frame.left, flat, low), right=prepare(frame.right, flat, low))

    # ---- steps --------------------------------------------------------------------------------------------------
    def _start(self, index: int, frame: StereoImages, raw: StereoImages) -> Estimate:
        self.frontend.start(frame)
        self._adjusted(np.eye(4), frame, linked=False)
        self._K, self._size = frame.K, (frame.left.shape[1], frame.left.shape[0])
        self._key = self._last = _Position(index, frame.time, np.eye(4))
        self._chain = Chain.origin()
        self.stats.positions += 1
        self._update_depth()
        if self.network is not None:
            self.network.offer(index, raw, self._chain, self.frontend.key_points)
        return Estimate(index, np.eye(4), len(self.frontend.key_points))

    def _predict(self, dt: float) -> Array:
        if self._velocity is None:
            return np.eye(4)
        w, v = self._velocity
        return from_rotvec_translation(w * dt, v * dt)

    def _advance(self, n: int) -> Estimate:
        s = self.settings
        assert self._key is not None and self._last is not None
        key, last = self._key, self._last
        while True:
            index, frame, raw = self._buffer[n - 1]
            dt = self._dt(last, index, frame)
            T_last_b_pred = self._predict(dt)
            T_key_pred = invert(key.T_origin) @ last.T_origin @ T_last_b_pred
            step = self._plausible(self.frontend.track(frame, T_key_pred))
            if (step is None or step.count < s.min_features) and self._velocity is not None:
                # The prediction itself may be what failed (a turn, a stop): try again without it.
                retry = self._plausible(self.frontend.track(frame, None))
                if retry is not None and (step is None or retry.count > step.count):
                    step = retry
            if step is not None and step.count >= s.min_features:
                break
            if s.adaptive and n > 1:
                n //= 2
                self.stats.halvings += 1
                continue
            break
        del self._buffer[:n]
        self.stats.positions += 1
        self.stats.steps.append(index - last.index)
        if step is None or step.count < s.min_track:
            # Tracking lost: dead-reckon this position and start a new fragment from it.
            self.stats.losses += 1
            T_origin_b = last.T_origin @ self._bridge(dt)
            self._chain = self._chain.append(invert(key.T_origin) @ T_origin_b)
            self._restart(index, frame, T_origin_b)
            self._target = max(1, min(self._target, s.step))
            return Estimate(index, T_origin_b, 0, lost=True)
        self._in_fragment += 1
        turned = np.degrees(np.linalg.norm(to_rotvec(step.T_key_b[:3, :3])))
        end = (s.frontend == "classic" or s.adaptive or self._in_fragment >= s.fragment_steps
               or step.count < s.refresh_features or turned >= s.fragment_rotation_deg)
        T_key_b = self.frontend.commit(frame, step, end)
        T_origin_b = key.T_origin @ T_key_b
        self._remember_motion(invert(last.T_origin) @ T_origin_b, dt)
        bound = None
        if end:
            self._next_target()
            mask = self._crop_mask(frame) if s.adaptive and s.crop else None
            self.frontend.start(frame, mask)
            T_origin_b = self._adjusted(T_origin_b, frame, linked=True)
            self._chain = self._chain.append(invert(key.T_origin) @ T_origin_b)
            self._update_depth()
            self._in_fragment = 0
            self.stats.fragments += 1
            if self.network is not None:
                binding = self.network.offer(index, raw, self._chain, self.frontend.key_points)
                if binding is not None:
                    self._chain, bound = binding.chain, binding.reference
                    T_origin_b = self._adjusted(self._chain.pose(), frame, linked=False)
                    self.stats.bindings += 1
            self._key = _Position(index, frame.time, T_origin_b)
        else:
            self._next_target()
        self._last = _Position(index, frame.time, T_origin_b)
        return Estimate(index, T_origin_b, step.count, bound_to=bound)

    def _plausible(self, step: Step | None) -> Step | None:
        """None for a motion no tracker could have followed: farther than `max_motion_depths` times the scene's
        depth, or turned by more than `max_turn_deg` — what a wrong RANSAC consensus on a few features gives."""
        if step is None:
            return None
        s = self.settings
        reach = s.max_motion_depths * (self._depth if self._depth is not None else math.inf)
        turn = float(np.degrees(np.linalg.norm(to_rotvec(step.T_key_b[:3, :3]))))
        if float(np.linalg.norm(step.T_key_b[:3, 3])) > reach or turn > s.max_turn_deg:
            return None
        return step

    def _bridge(self, dt: float) -> Array:
        """The motion over a lost step: the median of the last tracked steps' velocities, not the last one alone —
        on poor images the step before a loss is often the worst estimated, and a lost stretch repeats it."""
        if not self._recent:
            return self._predict(dt)
        w, v = np.split(np.median(np.stack(self._recent), axis=0), 2)
        return from_rotvec_translation(w * dt, v * dt)

    def _restart(self, index: int, frame: StereoImages, T_origin_b: Array) -> None:
        self.frontend.start(frame)
        self._adjusted(T_origin_b, frame, linked=False)
        self._update_depth()
        self._in_fragment = 0
        self._key = self._last = _Position(index, frame.time, T_origin_b)

    def _adjusted(self, T_origin_b: Array, frame: StereoImages, linked: bool) -> Array:
        """A new keyframe's pose after the window's bundle adjustment (as given without a window). Unlinked (the
        first keyframe, after a loss or a binding to a reference): the window starts again from it."""
        if self.window is None:
            return T_origin_b
        if not linked:
            self.window.reset()
        doffs = geometry_of(frame).doffs + float(getattr(self.frontend, "doffs", 0.0))
        matches = self.frontend.key_matches() if linked else None
        return self.window.add(T_origin_b, self.frontend.key_features(), matches, frame.K, frame.baseline, doffs)

    def _dt(self, last: _Position, index: int, frame: StereoImages) -> float:
        if frame.time > last.time:
            return frame.time - last.time
        return (index - last.index) / (self._fps or 10.0)

    def _remember_motion(self, T_last_b: Array, dt: float) -> None:
        if dt <= 0:
            return
        self._velocity = (to_rotvec(T_last_b[:3, :3]) / dt, T_last_b[:3, 3] / dt)
        self._recent = [*self._recent[-(_BRIDGE_STEPS - 1):], np.concatenate(self._velocity)]
        self._speeds.append(float(np.linalg.norm(T_last_b[:3, 3])) / dt)
        self._speeds = self._speeds[-2:]
        self._last_dt = dt

    def _update_depth(self) -> None:
        if self.settings.altitude is not None:
            self._depth = self.settings.altitude
        elif len(self.frontend.key_points) >= 8:
            self._depth = float(np.median(self.frontend.key_points[:, 2]))

    # ---- the adaptive step ----------------------------------------------------------------------------------------
    def _next_target(self) -> None:
        s = self.settings
        if not s.adaptive:
            self._target = s.step
            return
        if self._velocity is None or self._depth is None or not self._speeds or self._fps is None:
            self._target = s.step
            return
        K, size = self._K_size()
        alpha, axial = field_of_view_along(K, size, self._velocity[1])
        S = overlap_displacement(alpha, self._depth, s.overlap_percent, axial)
        V = self._speeds[-1]
        A = (self._speeds[-1] - self._speeds[-2]) / self._last_dt if len(self._speeds) == 2 and self._last_dt > 0 \
            else 0.0
        self._target = step_frames(step_time(S, V, A), self._fps, s.max_step)

    def _K_size(self) -> tuple[Array, tuple[int, int]]:
        return self._K, self._size

    def _crop_mask(self, frame: StereoImages) -> NDArray[np.uint8] | None:
        if self._velocity is None or self._depth is None:
            return None
        h, w = frame.left.shape[:2]
        dt = self._target / (self._fps or 10.0)
        return common_view_mask(frame.K, (w, h), self._predict(dt), self._depth)


__all__ = ["Estimate", "Odometer", "OdometerSettings", "OdometerStats"]
