"""The README's table of estimates against simulation: `auv plan`'s duration and energy for each mission in
`missions/`, beside what `auv simulate` measured in run folders (one per mission, `RUNS/NAME/metrics.json`).

    python benchmarks/estimate_table.py RUNS_DIR        # e.g. after: for m in missions/*.yaml; do
                                                        #   auv simulate $m --out RUNS_DIR/$(basename $m .yaml) --no-plots -q; done
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from mission.cli_plan import mission_estimate
from mission.language import load_mission

ROOT = Path(__file__).resolve().parents[1]


def main(runs: Path) -> None:
    print("| mission | duration: estimate / simulated | energy: estimate / simulated | per element (duration) |")
    print("|---|---|---|---|")
    for path in sorted((ROOT / "missions").glob("*.yaml")):
        metrics_file = runs / path.stem / "metrics.json"
        if not metrics_file.is_file():
            continue
        m = json.loads(metrics_file.read_text())
        estimate, _ = mission_estimate(load_mission(path))
        flown = {e["id"]: e for e in m["elements"]}
        parts = []
        for e in estimate.elements:
            sim = flown.get(e.id, {}).get("duration_s")
            if sim:
                parts.append(f"{e.id} {e.duration_s:.0f}/{sim:.0f} s")
        d_ratio = estimate.duration_s / m["mission_time_s"] - 1.0
        e_ratio = estimate.energy_wh / m["energy_wh"] - 1.0
        note = " (aborted)" if m.get("aborted") else ""
        print(f"| `{path.name}`{note} | {estimate.duration_s:.0f} / {m['mission_time_s']:.0f} s ({100 * d_ratio:+.0f} %) "
              f"| {estimate.energy_wh:.1f} / {m['energy_wh']:.1f} Wh ({100 * e_ratio:+.0f} %) | {'; '.join(parts)} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
