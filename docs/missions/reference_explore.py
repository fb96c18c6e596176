"""The reference mission's `explore` element, measured (issue 6): missions/sps_field_inspection.yaml without its two
perception plug-ins (not installed yet) and without its inspect element — to-field, field-survey (which finds
wellhead-x, the object the database lacks), scan-unknown (explore, 15 min, safe distance 6 m), home.

    .venv/bin/python docs/missions/reference_explore.py [RUN_DIR]
"""

import json
import sys
import time
from pathlib import Path

import yaml

from mission.language.models import Mission
from mission.sim.run import simulate

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    data = yaml.safe_load((ROOT / "missions" / "sps_field_inspection.yaml").read_text(encoding="utf-8"))
    data.pop("plugins")
    data["route"] = [e for e in data["route"] if "inspect" not in e]
    data["world"] = str(ROOT / "worlds" / "sps_field.yaml")
    t0 = time.perf_counter()
    result = simulate(Mission.model_validate(data), out=sys.argv[1] if len(sys.argv) > 1 else None)
    m = result.metrics
    print(f"wall {time.perf_counter() - t0:.1f} s, completed {m['completed']}, "
          f"safety violations {len(m['safety_violations'])}")
    element = next(e for e in m["elements"] if e["kind"] == "explore")
    keys = ("status", "duration_s", "views", "path_length_m", "surface_observed_percent", "map_surface_percent",
            "min_distance_to_object_m", "safe_distance_breached", "iteration_time_ms")
    print(json.dumps({k: element.get(k) for k in keys}, indent=1))


if __name__ == "__main__":
    main()
