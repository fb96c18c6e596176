"""The photographs of a photo survey (seed 002 §2.2.1) written into the run folder, with their poses.

    DIR/photos/ELEMENT_NNN_left.png, ..._right.png   the rectified stereo pair
    DIR/photos/index.csv                              element, photo, file names, time, the vehicle's estimated
                                                      pose (what the agent tagged it with) and its true pose

The pairs come from `Knowledge.maps[ELEMENT]` (`photo_left`, `photo_right`, `photo_index`), where the explore
agent leaves them; they are taken out of it here, so that `maps/ELEMENT.npz` keeps only the plan and the index.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from mission.knowledge import Knowledge
from mission.sim.vehicle import SimulatedVehicle

COLUMNS = ("element", "photo", "left", "right", "time", "north_est", "east_est", "depth_est", "heading_est",
           "north", "east", "depth", "heading")


def write_photos(out: Path, knowledge: Knowledge, vehicle: SimulatedVehicle) -> int:
    """Write every element's photographs and the index; returns how many pairs were written."""
    import cv2  # opencv-python-headless, a dependency of the perception plug-ins

    rows = np.array([r[:5] for r in vehicle.log.rows], dtype=float) if vehicle.log.rows else np.zeros((0, 5))
    written = []
    for element, products in knowledge.maps.items():
        left = products.pop("photo_left", None)
        right = products.pop("photo_right", None)
        if left is None or right is None:
            continue
        (out / "photos").mkdir(exist_ok=True)
        for k, (index, a, b) in enumerate(zip(products["photo_index"], left, right, strict=True)):
            names = (f"{element}_{k:03d}_left.png", f"{element}_{k:03d}_right.png")
            cv2.imwrite(str(out / "photos" / names[0]), a)
            cv2.imwrite(str(out / "photos" / names[1]), b)
            i = int(np.argmin(np.abs(rows[:, 0] - index[0]))) if len(rows) else -1
            truth = rows[i, 1:5] if i >= 0 else np.full(4, np.nan)
            written.append((element, k, *names, *(f"{v:.4f}" for v in index), *(f"{v:.4f}" for v in truth)))
    if written:
        with (out / "photos" / "index.csv").open("w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(COLUMNS)
            w.writerows(written)
    return len(written)
