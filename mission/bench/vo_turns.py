"""Rendered turning sequences for the VO benchmark: a ~90° turn and an S-turn, seen by a forward-looking camera
(KITTI-like: 1226×370, fx 707, baseline 0.54 m, tilted 20° down, 2 m above the seabed, 4 m/s turning at 30°/s at
10 Hz, as a car turns at a junction) and by the down-looking seabed camera (600×400, fx 500, baseline 0.3 m, 4 m
altitude, 1 m/s turning at 20°/s at 10 Hz).

Sequences are rendered once into the KITTI odometry layout (`StereoRecorder`) under a cache folder
(`AUV_VO_CACHE`, default the system temp folder's `auv-vo-turns/`), keyed by the sequence's parameters, and read
back with `read_kitti_sequence` (so `auv vo` runs on them too); nothing is stored in the repository.

`python -m mission.bench.vo_turns FILE` runs the before / now / with-BA comparison of every method on the shared
KITTI clip and every turning sequence alone (`study`; `benchmarks/results/vo_turns.json`), without the benchmark's
other studies.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mission.bench.vo_runs import lockstep, relative, summarise

METHODS = ("classic", "klt", "adaptive", "network")


@dataclass(frozen=True)
class Turning:
    """A turning run: straight, a turn of `turns_deg` (one entry per turn, at `rate_deg_s`), straight."""

    name: str
    camera: str  # "forward" or "down"
    turns_deg: tuple[float, ...]
    speed_m_s: float
    rate_deg_s: float = 15.0
    straight_s: float = 2.0
    fps: float = 10.0
    seed: int = 5


SEQUENCES = (Turning("forward_turn90", "forward", (90.0,), 4.0, rate_deg_s=30.0),
             Turning("forward_s_turn", "forward", (60.0, -120.0, 60.0), 4.0, rate_deg_s=30.0),
             Turning("down_turn90", "down", (90.0,), 1.0, rate_deg_s=20.0),
             Turning("down_s_turn", "down", (60.0, -120.0, 60.0), 1.0, rate_deg_s=20.0))


def heading_profile(spec: Turning) -> tuple[np.ndarray, np.ndarray]:
    """Times and headings (deg): straight, each turn at the constant rate, straight."""
    rates = [0.0] * int(spec.straight_s * spec.fps)
    for turn in spec.turns_deg:
        rates += [math.copysign(spec.rate_deg_s, turn)] * int(round(abs(turn) / spec.rate_deg_s * spec.fps))
    rates += [0.0] * int(spec.straight_s * spec.fps)
    heading = np.concatenate([[0.0], np.cumsum(rates[:-1]) / spec.fps])
    return np.arange(len(rates)) / spec.fps, heading


def _forward_pose(north: float, east: float, depth: float, heading_deg: float, tilt_deg: float) -> np.ndarray:
    """T_world_cam of a camera looking along the heading, tilted down (NED world, OpenCV camera axes)."""
    h, t = math.radians(heading_deg), math.radians(tilt_deg)
    z = np.array([math.cos(t) * math.cos(h), math.cos(t) * math.sin(h), math.sin(t)])
    x = np.array([-math.sin(h), math.cos(h), 0.0])
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, (north, east, depth)
    return T


def _render(spec: Turning, folder: Path) -> None:
    from mission.language.models import Stereo
    from mission.plugin_api import StereoImages
    from mission.sim.camera import StereoCamera
    from mission.sim.stereo_record import StereoRecorder
    from mission.sim.stereo_sequence import seabed_world
    from mission.world.scene import build_scene

    world = seabed_world(seed=spec.seed)
    scene = build_scene(world)
    times, heading = heading_profile(spec)
    hd = np.radians(heading)
    north = np.concatenate([[0.0], np.cumsum(spec.speed_m_s * np.cos(hd[:-1]) / spec.fps)])
    east = np.concatenate([[0.0], np.cumsum(spec.speed_m_s * np.sin(hd[:-1]) / spec.fps)])
    north -= 0.5 * (north.min() + north.max())
    east -= 0.5 * (east.min() + east.max())
    if spec.camera == "forward":
        settings = Stereo(width=1226, height=370, fx=707.0912, baseline=0.537, rate_hz=spec.fps)
        poses = [_forward_pose(n, e, scene.seabed.depth_at(float(n), float(e)) - 2.0, hdg, 20.0)
                 for n, e, hdg in zip(north, east, heading, strict=True)]
    else:
        from mission.frames import camera_pose

        settings = Stereo(width=600, height=400, fx=500.0, baseline=0.3, rate_hz=spec.fps)
        poses = [camera_pose(float(n), float(e), scene.seabed.depth_at(float(n), float(e)) - 4.0, float(hdg),
                             baseline=0.3) for n, e, hdg in zip(north, east, heading, strict=True)]
    partial = folder.with_name(folder.name + ".partial")
    with StereoCamera(scene, settings, texture=world.seabed.texture) as camera, StereoRecorder(partial) as rec:
        for t, T in zip(times, poses, strict=True):
            f = camera.render(T)
            rec.write(StereoImages(float(t), f.left, f.right, f.K, f.baseline), T, T)
    partial.rename(folder)


def sequence_folder(spec: Turning) -> Path:
    """The cached KITTI-layout folder of a turning sequence, rendered first when absent."""
    root = Path(os.environ.get("AUV_VO_CACHE", Path(tempfile.gettempdir()) / "auv-vo-turns"))
    key = hashlib.sha256(json.dumps(asdict(spec), sort_keys=True).encode()).hexdigest()[:10]
    folder = root / f"{spec.name}-{key}"
    if not (folder / "poses.txt").exists():
        root.mkdir(parents=True, exist_ok=True)
        _render(spec, folder)
    return folder


BEFORE: dict[str, Any] = {"bundle_window": None, "carry_tracks": False}
"""The seed's odometer: no bundle adjustment, every KLT fragment starts from fresh corners."""


BUNDLE: dict[str, Any] = {"bundle_window": 8}
"""The defaults with the local bundle adjustment over 8 keyframes."""


def specs_before_after(fps: float, methods: tuple[str, ...] = METHODS) -> dict[str, tuple[str, dict[str, Any]]]:
    """Each method as the seed had it (`_before`: `BEFORE`), as it is now (its defaults) and with the bundle
    adjustment (`_ba`: `BUNDLE`)."""
    specs: dict[str, tuple[str, dict[str, Any]]] = {}
    for m in methods:
        extra: dict[str, Any] = {"fps": fps, "max_step": 64} if m == "adaptive" else {}
        specs[f"{m}_before"] = (m, {**extra, **BEFORE})
        specs[m] = (m, extra)
        specs[f"{m}_ba"] = (m, {**extra, **BUNDLE})
    return specs


def run_sequence(folder: Path, methods: tuple[str, ...] = METHODS) -> dict[str, Any]:
    """Every method before and after on one KITTI-layout sequence: drift %, ATE, frames per CPU second."""
    from perception_plugins.vo import read_kitti_sequence

    seq = read_kitti_sequence(folder)
    assert seq.gt_poses is not None
    frames = list(seq)
    fps = float(1.0 / np.median(np.diff(seq.times)))
    runs = lockstep(frames, specs_before_after(fps, methods))
    table = summarise(runs, relative(seq.gt_poses), len(frames))
    for name in table:
        table[name]["fps_cpu"] = round(len(frames) / max(runs[name]["cpu_s"], 1e-9), 1)
    h, w = frames[0].left.shape[:2]
    return {"frames": len(frames), "image": [w, h], "methods": table}


def turns(quick: bool) -> dict[str, Any]:
    """The turning sequences, every method before and after (with --quick the down-looking 90° turn and the KLT
    method only: the forward-looking sequences take a minute each to render, the classic matcher's runs longer)."""
    out: dict[str, Any] = {}
    for spec in SEQUENCES:
        if quick and spec.name != "down_turn90":
            continue
        result = run_sequence(sequence_folder(spec), ("klt",) if quick else METHODS)
        out[spec.name] = {"turns_deg": list(spec.turns_deg), "camera": spec.camera,
                          "speed_m_s": spec.speed_m_s, "rate_deg_s": spec.rate_deg_s, **result}
    return out


__all__ = ["BEFORE", "BUNDLE", "METHODS", "SEQUENCES", "Turning", "heading_profile", "run_sequence", "sequence_folder",
           "turns"]


def study(out: Path) -> dict[str, Any]:
    """Every method before / now / with the bundle adjustment on the shared KITTI clip (when present) and on every
    turning sequence, written to `out` as JSON: the turning part of `auv bench vo` without its other studies."""
    import cv2

    from mission.bench import REPO, machine

    cv2.setNumThreads(1)
    results: dict[str, Any] = {"machine": machine(), "before": BEFORE, "bundle": BUNDLE}
    kitti = Path(os.environ.get("AUV_VO_KITTI", REPO.parent / "shared" / "data" / "kitti06_0-50"))
    results["turns"] = {}
    jobs: list[tuple[str, Turning | None]] = [(s.name, s) for s in SEQUENCES]
    if (kitti / "poses.txt").exists():
        jobs.insert(0, ("kitti", None))
    for name, spec in jobs:  # written after each sequence: a long study shows what it has
        if spec is None:
            results["kitti"] = {"sequence": str(kitti), **run_sequence(kitti)}
        else:
            results["turns"][name] = {"turns_deg": list(spec.turns_deg), "camera": spec.camera,
                                      "speed_m_s": spec.speed_m_s, "rate_deg_s": spec.rate_deg_s,
                                      **run_sequence(sequence_folder(spec))}
        out.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    return results


if __name__ == "__main__":
    import sys

    study(Path(sys.argv[1]))
