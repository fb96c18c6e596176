"""Figures of the explore planner's `reconstruct` goal against `map` (README, "The loop", point 1) for run folders
of docs/missions/sps_explore_reconstruct.yaml and docs/missions/sps_explore_reconstruct_map.yaml:

* the truth's stereo coverage of wellhead-x along the element: the share of its true surface (5 cm samples) seen
  within the useful range at ≤ 60° incidence by a pair so far, from the TRUE track (trajectory.csv) at each
  pair's time (RUN/stereo/scan-unknown/times.txt), with the camera's mount (`mission.sim.stereo_coverage`);
* with `--mesh`, after `auv reconstruct RUN --object wellhead-x --element scan-unknown`: the mesh's completeness,
  the share of the same samples within 5 cm of a mesh vertex, as fused and after the mesh's best single shift
  (`mission.reconstruct_loop.mesh_offset`, the navigation error the mesh inherited).

    python docs/missions/reconstruct_goal_figures.py runs/rec [--mesh [RECONSTRUCTION_DIR]]

(RECONSTRUCTION_DIR: `auv reconstruct`'s output folder, default RUN/models/wellhead-x/reconstruction.)
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
MARKS_S = (120, 240, 360, 480, 600, 900)


def main() -> None:
    from mission.frames import camera_pose
    from mission.language.mount import mount_rotation
    from mission.sim.stereo_coverage import seen_by_view, surface_samples
    from mission.world.model import World
    from mission.world.scene import build_scene

    run = Path(sys.argv[1])
    mission = yaml.safe_load((run / "mission.yaml").read_text(encoding="utf-8"))
    stereo = mission["sensors"]["stereo"]
    tilt = float(stereo.get("mount", {}).get("tilt_deg", 90.0))
    fov = tuple(2.0 * np.degrees(np.arctan(0.5 * stereo[k] / stereo["fx"])) for k in ("width", "height"))
    useful = 0.75 * float(stereo["max_range"])
    data = yaml.safe_load((ROOT / "worlds" / "sps_field.yaml").read_text(encoding="utf-8"))
    scene = build_scene(World.model_validate(data))
    obj = next(o for o in scene.objects if o.id == "wellhead-x")
    points, normals = surface_samples(obj, scene)
    with (run / "trajectory.csv").open(encoding="utf-8") as f:
        rows = np.array([[float(r[k]) for k in ("time", "north", "east", "depth", "heading")]
                         for r in csv.DictReader(f)])
    times = np.loadtxt(run / "stereo" / "scan-unknown" / "times.txt").reshape(-1)
    seen = np.zeros(len(points), dtype=bool)
    at: dict[int, float] = {}
    for t in times:
        r = rows[int(np.argmin(np.abs(rows[:, 0] - t)))]
        T = camera_pose(r[1], r[2], r[3], r[4], baseline=float(stereo["baseline"]), R_body_cam=mount_rotation(tilt))
        seen |= seen_by_view(points, normals, T, (float(fov[0]), float(fov[1])), useful, 1.5)
        for mark in MARKS_S:
            if t - times[0] <= mark:
                at[mark] = float(seen.mean())
    print(f"{run}: {len(times)} pairs; stereo coverage (truth) "
          + " / ".join(f"{100 * at[m]:.1f} % at {m} s" for m in MARKS_S if m in at)
          + f"; {100 * seen.mean():.1f} % in all")
    if "--mesh" in sys.argv:
        after = sys.argv[sys.argv.index("--mesh") + 1:]
        folder = Path(after[0]) if after else run / "models" / "wellhead-x" / "reconstruction"
        mesh_completeness(folder, points, data)


def mesh_completeness(folder: Path, points: np.ndarray, data: dict) -> None:
    import trimesh
    from scipy.spatial import cKDTree

    from mission.bench.reconstruction_scenes import part_sdf, truth_parts
    from mission.language.world import World as WorldFile
    from mission.reconstruct_loop import mesh_offset

    only = dict(data, objects=[o for o in data["objects"] if o["id"] == "wellhead-x"])
    parts = truth_parts(WorldFile.model_validate(only))

    def sdf(p: np.ndarray) -> np.ndarray:
        return np.asarray(np.min([part_sdf(q, p) for q in parts], axis=0))

    mesh = trimesh.load(folder / "mesh.ply", process=False)
    vertices = np.asarray(mesh.vertices, dtype=float)
    offset = mesh_offset(vertices[np.abs(sdf(vertices)) < 0.5], sdf)
    raw = np.isfinite(cKDTree(vertices).query(points, distance_upper_bound=0.05)[0]).mean()
    shifted = np.isfinite(cKDTree(vertices - offset).query(points, distance_upper_bound=0.05)[0]).mean()
    print(f"{folder}: mesh completeness (5 cm) {100 * raw:.1f} %, {100 * shifted:.1f} % after the shift "
          f"{np.round(offset, 3).tolist()} m")


if __name__ == "__main__":
    main()
