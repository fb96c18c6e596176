"""The survey plan of missions/field_survey.yaml exported as GeoJSON and drawn, in longitude and latitude, over its
chart: the world's seabed (worlds/sps_field.yaml, the objects on it included) placed on the globe with the
mission's origin. Everything drawn is read back from the exported file, not from the mission.

    .venv/bin/python docs/missions/export_chart.py [OUT.png]     # default docs/figures/export_chart.png
"""

import json
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mission.export import export  # noqa: E402
from mission.geodesy import ned_to_geodetic  # noqa: E402
from mission.language import load_mission, load_world  # noqa: E402
from mission.world.scene import build_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
STYLE = {"geofence": ("tab:red", "--", 1.2), "survey_areas": ("tab:green", "-", 1.5),
         "no_go_zones": ("darkred", "-", 1.5), "planned_paths": ("black", "-", 1.0)}


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "figures" / "export_chart.png"
    mission_file = ROOT / "missions" / "field_survey.yaml"
    mission = load_mission(mission_file, environment=False)
    assert mission.origin is not None and mission.world is not None
    with tempfile.TemporaryDirectory() as tmp:
        geojson = Path(tmp) / "field_survey.geojson"
        export(mission_file, "geojson", geojson)
        features = json.loads(geojson.read_text())["features"]
    surface = build_scene(load_world(mission.world)).surface
    north, east = surface.grid()
    nn, ee = np.meshgrid(north, east, indexing="ij")
    lat, lon = ned_to_geodetic(nn, ee, mission.origin.lat, mission.origin.lon)
    fig, ax = plt.subplots(figsize=(8.0, 7.0))
    chart = ax.pcolormesh(lon, lat, surface.depth, cmap="Blues", shading="auto")
    fig.colorbar(chart, ax=ax, label="chart depth [m]")
    drawn: set[str] = set()
    for f in features:
        layer, geom = f["properties"]["layer"], f["geometry"]
        if geom["type"] == "Polygon" or geom["type"] == "LineString":
            ring = np.asarray(geom["coordinates"][0] if geom["type"] == "Polygon" else geom["coordinates"])
            colour, dash, width = STYLE.get(layer, ("black", "-", 1.0))
            ax.plot(ring[:, 0], ring[:, 1], dash, color=colour, lw=width,
                    label=layer.replace("_", " ") if layer not in drawn else None)
        else:
            x, y = geom["coordinates"]
            ax.plot(x, y, "o" if layer == "objects" else "^", color="orange" if layer == "objects" else "tab:purple",
                    label=layer if layer not in drawn else None)
            ax.annotate(f["properties"]["name"], (x, y), textcoords="offset points", xytext=(5, 5), fontsize=8)
        drawn.add(layer)
    ax.set_xlabel("longitude [deg E]")
    ax.set_ylabel("latitude [deg N]")
    ax.set_aspect(1.0 / np.cos(np.radians(mission.origin.lat)))
    ax.ticklabel_format(useOffset=False)
    ax.set_title(f"{mission.name}: the exported GeoJSON over the chart (origin {mission.origin.lat}°N, "
                 f"{mission.origin.lon}°E)", fontsize=10)
    ax.legend(loc="lower right", fontsize=8, framealpha=0.8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
