"""KML 2.2 of a mission or a run, written with the standard library: one folder per layer (the layers of
`mission.export.features`), placemarks clamped to the sea surface, coordinates `lon,lat,0` in WGS84 degrees, and
each feature's properties as ExtendedData."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from mission.export.features import Feature
from mission.geodesy import ring_to_geodetic

KML_NS = "http://www.opengis.net/kml/2.2"
STYLES = {  # layer: (line colour aabbggrr, fill colour aabbggrr)
    "geofence": ("ff0000ff", "00000000"), "survey_areas": ("ff00aa00", "3300aa00"),
    "no_go_zones": ("ff0000cc", "660000cc"), "planned_paths": ("ffff8800", "00000000"),
    "true_track": ("ff000000", "00000000"), "estimated_track": ("ff00a5ff", "00000000"),
}


def _coords(points_lonlat: list[tuple[float, float]]) -> str:
    return " ".join(f"{lon!r},{lat!r},0" for lon, lat in points_lonlat)


def _geometry(parent: ET.Element, feature: Feature, lat0: float, lon0: float) -> None:
    rings = [ring_to_geodetic(r, lat0, lon0) for r in feature.rings_ne]
    if feature.geometry == "Point":
        ET.SubElement(ET.SubElement(parent, "Point"), "coordinates").text = _coords(rings[0][:1])
    elif feature.geometry == "LineString":
        ET.SubElement(ET.SubElement(parent, "LineString"), "coordinates").text = _coords(rings[0])
    else:
        poly = ET.SubElement(parent, "Polygon")
        for k, ring in enumerate(rings):
            closed = ring + ring[:1] if ring[0] != ring[-1] else ring
            boundary = ET.SubElement(poly, "outerBoundaryIs" if k == 0 else "innerBoundaryIs")
            ET.SubElement(ET.SubElement(boundary, "LinearRing"), "coordinates").text = _coords(closed)


def to_kml(features: Sequence[Feature], lat0: float, lon0: float, name: str) -> ET.Element:
    """The KML document of `features`, placed with the origin (lat0, lon0)."""
    root = ET.Element("kml", xmlns=KML_NS)
    doc = ET.SubElement(root, "Document")
    ET.SubElement(doc, "name").text = name
    for layer, (line, fill) in STYLES.items():
        style = ET.SubElement(doc, "Style", id=layer)
        ET.SubElement(ET.SubElement(style, "LineStyle"), "color").text = line
        ET.SubElement(ET.SubElement(style, "PolyStyle"), "color").text = fill
    folders: dict[str, ET.Element] = {}
    for f in features:
        if f.layer not in folders:
            folders[f.layer] = ET.SubElement(doc, "Folder")
            ET.SubElement(folders[f.layer], "name").text = f.layer
        mark = ET.SubElement(folders[f.layer], "Placemark")
        ET.SubElement(mark, "name").text = f.name
        if f.layer in STYLES:
            ET.SubElement(mark, "styleUrl").text = f"#{f.layer}"
        data = ET.SubElement(mark, "ExtendedData")
        for key, value in {"layer": f.layer, **f.properties}.items():
            ET.SubElement(ET.SubElement(data, "Data", name=key), "value").text = "" if value is None else str(value)
        _geometry(mark, f, lat0, lon0)
    return root


def write_kml(features: Sequence[Feature], lat0: float, lon0: float, name: str, out: Path) -> None:
    tree = ET.ElementTree(to_kml(features, lat0, lon0, name))
    ET.indent(tree)
    tree.write(out, encoding="utf-8", xml_declaration=True)
