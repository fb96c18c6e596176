"""`auv export`: a mission or a run folder in the formats of the field's tools.

- `geojson`, `kml`: areas, planned paths, database objects; for a run also the tracks, detections, photos and
  safety events (`mission.export.features`);
- `mavlink`: a QGC WPL 110 mission of the plannable elements (`mission.export.mavlink_plan`);
- `imc`: an IMC PlanSpecification packet for LSTS vehicles (`mission.export.imc_plan`);
- `mcap`: a run folder as an MCAP log with ROS 2 messages for Foxglove (`mission.mcap_log`).

Every format but `mcap` places the local frame with the mission's `origin`; without one, the export is a located
error. MAVLink and IMC carry only transit and survey elements and refuse adaptive ones by name.
Importing this package is light (the `auv` parser reads `FORMATS`); each export imports what it needs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from mission.errors import AuvError

if TYPE_CHECKING:
    from mission.language.models import Mission

FORMATS = ("geojson", "kml", "mavlink", "imc", "mcap")
SUFFIX = {"geojson": ".geojson", "kml": ".kml", "mavlink": ".waypoints", "imc": ".imc", "mcap": ".mcap"}
TARGET = {"geojson": "a GeoJSON export", "kml": "a KML export", "mavlink": "a MAVLink mission",
          "imc": "an IMC plan"}


@dataclass(frozen=True)
class ExportResult:
    """What an export wrote: the file, the format and how many features, items or messages it holds."""

    out: Path
    format: str
    count: int
    what: str


def default_out(source: Path, fmt: str) -> Path:
    """FILE.FORMAT beside a mission file, or inside a run folder (`run.mcap` for MCAP)."""
    if source.is_dir():
        return source / ("run.mcap" if fmt == "mcap" else f"{source.name}{SUFFIX[fmt]}")
    return source.with_suffix(SUFFIX[fmt])


def export(source: str | Path, fmt: str, out: str | Path | None = None) -> ExportResult:
    """Export a mission file or a run folder (a directory) as `fmt` to `out` (default: `default_out`)."""
    from mission.export.plan import plan_legs
    from mission.geodesy import require_origin

    source = Path(source)
    if fmt not in FORMATS:
        raise AuvError(f"unknown export format '{fmt}' (known: {', '.join(FORMATS)})")
    target = Path(out) if out is not None else default_out(source, fmt)
    if fmt == "mcap":
        from mission.mcap_log import write_mcap

        if not source.is_dir():
            raise AuvError(f"{source}: an MCAP log is written from a run folder, not a mission file")
        return ExportResult(target, fmt, write_mcap(source, target), "messages")
    if source.is_dir():
        from mission.runfolder import read_run_folder

        run = read_run_folder(source)
        mission = run.mission
    else:
        from mission.language import load_mission

        run, mission = None, load_mission(source, environment=False)
    lat0, lon0 = require_origin(mission, TARGET[fmt])
    if fmt in ("geojson", "kml"):
        from mission.export.features import mission_features, run_features

        features = (run_features(mission, run.trajectory, run.events, run.metrics) if run is not None
                    else mission_features(mission))
        if fmt == "geojson":
            from mission.export.geojson import write_geojson

            write_geojson(features, lat0, lon0, mission.name, target)
        else:
            from mission.export.kml import write_kml

            write_kml(features, lat0, lon0, mission.name, target)
        return ExportResult(target, fmt, len(features), "features")
    legs = plan_legs(mission, strict=True, target=TARGET[fmt])
    if fmt == "mavlink":
        from mission.export.mavlink_plan import mission_items, write_wpl

        items = mission_items(legs, lat0, lon0, (mission.home.north, mission.home.east), _capture_radii(mission))
        write_wpl(items, target)
        return ExportResult(target, fmt, len(items), "mission items")
    from mission.export.imc_plan import imc_plan_bytes

    target.write_bytes(imc_plan_bytes(legs, lat0, lon0, mission.name, mission.description.strip()))
    return ExportResult(target, fmt, len(legs), "maneuvers")


def _capture_radii(mission: Mission) -> dict[str, float]:
    return {el.id: el.transit.capture_radius for el in mission.route if el.transit is not None}


__all__ = ["FORMATS", "ExportResult", "default_out", "export"]
