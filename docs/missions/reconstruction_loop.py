"""Issue 22's loop end to end, measured (README, "3D reconstruction of explored objects"):

1. `docs/missions/sps_explore_model_near.yaml`: a survey finds wellhead-x (the database lacks it), the reference
   mission's explore element scans it with `actions: [map, model]` and records the stereo pairs (RUN/explore);
2. `auv reconstruct RUN/explore --object wellhead-x --element scan-unknown`: the poses anchored by stereo odometry,
   the mesh, the multi-view model, then the database entry with three named targets (RUN/explore/recon/object.yaml).
   A designer names a target where the mesh shows it, in the mesh's frame (the explore run's navigation frame);
   the script does so by moving each target's true position by the mesh's offset from the true geometry
   (`mission.reconstruct_loop.mesh_offset`), the navigation error the reconstruction inherited;
3. a follow-up mission that knows wellhead-x only from that entry and the multi-view model `auv reconstruct` built
   beside the mesh (`follow_up_mission`: transit, inspect all its targets with the `multiview-referencing` plug-in,
   home; no truth) is simulated for each seed (RUN/inspect-seed-N), and each photograph's true camera
   is compared with the viewpoint placed on its target's true position (`mission.reconstruct_loop`).

    .venv/bin/python docs/missions/reconstruction_loop.py RUN_DIR [SEEDS]     # SEEDS like 1,2,3 (default)

Steps whose outputs exist are not run again (delete the folder to redo one).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from mission.bench.reconstruction_scenes import part_sdf, truth_parts
from mission.language.loader import load_mission
from mission.language.world import World
from mission.reconstruct import (
    database_entry,
    parse_target,
    reconstruct_run,
)
from mission.reconstruct_loop import mesh_offset, photo_errors, recognitions
from mission.sim.run import simulate
from perception_plugins.reconstruction.keypoints import PointSetProposal

ROOT = Path(__file__).resolve().parents[2]
TARGETS = {  # true world positions (local NED, m) on worlds/sps_field.yaml's wellhead-x, standoff 3 m
    "tree-cap": (215.000, 110.000, 56.000),  # the top of the tree body
    "flowline-end": (216.597, 110.581, 56.600),  # the top of the flowline stub's end
    "frame-corner": (217.307, 108.924, 58.600),  # the base frame's top, 0.2 m in from a corner
}
STANDOFF_M = 3.0


def follow_up_mission(entry: dict[str, Any], recon: Path, seed: int, referencing: str = "multiview-referencing"
                      ) -> dict[str, Any]:
    """The second mission: wellhead-x from the entry only (its mesh and multi-view model in `recon`), approached by
    USBL, its targets photographed; the object recognised by `referencing` (the multi-view model by default)."""
    template = yaml.safe_load((ROOT / "docs" / "missions" / "sps_explore_model.yaml").read_text(encoding="utf-8"))
    north, east = entry["pose"]["north"] + entry["size"][0] / 2, entry["pose"]["east"] + entry["size"][1] / 2
    return {
        "name": "wellhead-inspect-reconstructed",
        "description": "Photograph wellhead-x's named targets, knowing it only from `auv reconstruct`'s entry.",
        "origin": template["origin"], "world": str(ROOT / "worlds" / "sps_field.yaml"), "seed": seed,
        "vehicle": template["vehicle"],
        "sensors": {**{k: template["sensors"][k] for k in ("usbl", "dvl")},
                    "stereo": {**template["sensors"]["stereo"], "rate_hz": 10}},
        "plugins": {"referencing": referencing, "odometry": "stereo-vo"},
        "safety": {**template["safety"], "max_duration": "1h"},
        "objects": [{**entry, "mesh": str((recon / "mesh.ply").resolve())}
                    | ({"model": str((recon / entry["model"]).resolve())} if "model" in entry else {})],
        "route": [
            {"id": "approach", "transit": {"to": {"north": round(north, 2), "east": round(east, 2)}, "depth": 45,
                                           "navigation": "usbl"}},
            {"id": "photograph-wellhead", "inspect": {"object": entry["id"], "targets": "all", "order": "auto",
                                                      "search": {"pattern": "expanding-square", "budget": "5min"}},
             "actions": ["photograph"]},
            {"id": "home", "transit": {"to": "home", "depth": 0}},
        ],
    }


def true_surface() -> Callable[[np.ndarray], np.ndarray]:
    """Signed distance to wellhead-x's true parts in worlds/sps_field.yaml (the seabed left out)."""
    data = yaml.safe_load((ROOT / "worlds" / "sps_field.yaml").read_text(encoding="utf-8"))
    data["objects"] = [o for o in data["objects"] if o["id"] == "wellhead-x"]
    parts = truth_parts(World.model_validate(data))
    return lambda points: np.min([part_sdf(part, points) for part in parts], axis=0)


def name_targets(recon: Path) -> np.ndarray:
    """Write the entry with the named targets where the mesh shows them; returns the mesh's offset from the truth."""
    import trimesh

    report = json.loads((recon / "report.json").read_text(encoding="utf-8"))
    plane = np.array([report["seabed_plane"][k] for k in "abc"])
    vertices = np.asarray(trimesh.load(recon / "mesh.ply", process=False).vertices, dtype=float)
    height = plane[0] * vertices[:, 0] + plane[1] * vertices[:, 1] + plane[2] - vertices[:, 2]
    surface = true_surface()
    offset = mesh_offset(vertices[height > 0.2], surface)
    errors = np.abs(surface(vertices[height > 0.2])), np.abs(surface(vertices[height > 0.2] - offset))
    targets = tuple(parse_target(f"{k}={n + offset[0]},{e + offset[1]},{d + offset[2]}:{STANDOFF_M}")
                    for k, (n, e, d) in TARGETS.items())
    # The sets `auv reconstruct` wrote (from the detector's views, else the mesh's corners), back in the world frame.
    written = yaml.safe_load((recon / "object.yaml").read_text(encoding="utf-8"))["objects"][0]
    origin = np.array([written["pose"][k] for k in ("north", "east", "depth")])
    proposals = [PointSetProposal(np.asarray(s["points"], dtype=float) + origin, False)
                 for s in written["characteristic_points"]]
    entry = database_entry("wellhead-x", vertices, plane, targets, "mesh.ply", proposals)
    assert entry is not None
    if "model" in written:  # the multi-view model `auv reconstruct` built beside the mesh
        entry["model"] = written["model"]
    (recon / "object.yaml").write_text(yaml.safe_dump({"objects": [entry]}, sort_keys=False), encoding="utf-8")
    figures = {"mesh_offset_m": offset.round(4).tolist()} | {
        f"mesh_error_{name}_m": {"median": round(float(np.median(e)), 4), "p90": round(float(np.percentile(e, 90)), 4)}
        for name, e in zip(("as_fused", "after_offset"), errors, strict=True)}
    (recon / "offset.json").write_text(json.dumps(figures) + "\n", encoding="utf-8")
    return offset


def main() -> None:
    run = Path(sys.argv[1] if len(sys.argv) > 1 else "runs/reconstruction-loop")
    seeds = [int(s) for s in (sys.argv[2] if len(sys.argv) > 2 else "1,2,3").split(",")]
    explore, recon = run / "explore", run / "explore" / "recon"
    if not (explore / "metrics.json").is_file():
        simulate(load_mission(ROOT / "docs" / "missions" / "sps_explore_model_near.yaml"), out=explore, force=True)
    if not (recon / "report.json").is_file():
        reconstruct_run(explore, "wellhead-x", recon, element="scan-unknown")
    offset = name_targets(recon)
    entry = yaml.safe_load((recon / "object.yaml").read_text(encoding="utf-8"))["objects"][0]
    summary = []
    for seed in seeds:
        path = run / f"inspect-seed-{seed}.yaml"
        path.write_text(yaml.safe_dump(follow_up_mission(entry, recon, seed),
                                       sort_keys=False), encoding="utf-8")
        out = run / f"inspect-seed-{seed}"
        if not (out / "metrics.json").is_file():
            simulate(load_mission(path), out=out, force=True, plots=False)
        errors = photo_errors(out, "photograph-wellhead", entry, TARGETS, 0.25)
        metrics = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
        element = next(e for e in metrics["elements"] if e["id"] == "photograph-wellhead")
        summary.append({"seed": seed, "mesh_offset_m": offset.round(3).tolist(), "completed": metrics["completed"],
                        "status": element["status"],
                        "photos": len(errors), "worst_error_m": max((e["error_m"] for e in errors), default=None),
                        "errors_m": {t: max(e["error_m"] for e in errors if e["target"] == t)
                                     for t in sorted({e["target"] for e in errors})},
                        "recognitions": recognitions(out, "photograph-wellhead")})
        print(json.dumps(summary[-1]))
    (run / "loop.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
