"""Every world in worlds/ is built as its missions' databases describe it: characteristic points on part corners,
objects resting on the seabed."""

import functools
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import MISSIONS, ROOT

from mission.frames import transform_points
from mission.language.loader import load_world
from mission.language.world import Box, Cylinder, World
from mission.world.scene import true_pose
from mission.world.terrain import generate_seabed

WORLDS = sorted((ROOT / "worlds").glob("*.yaml"))
MISSION_FILES = sorted(MISSIONS.glob("*.yaml")) + sorted((ROOT / "docs" / "missions").glob("*.yaml"))
CORNER_TOLERANCE_M = 0.01


@functools.cache
def _world(path: Path) -> World:
    return load_world(path)


def _box_corners(box: Box) -> np.ndarray:
    """The box's eight corners in its object's frame, top four (smallest z) first."""
    length, width, height = box.size
    c, s = math.cos(math.radians(box.heading)), math.sin(math.radians(box.heading))
    corners = []
    for sz in (-1, 1):
        for sx in (-1, 1):
            for sy in (-1, 1):
                x, y = sx * length / 2, sy * width / 2
                corners.append([box.at[0] + c * x - s * y, box.at[1] + s * x + c * y, box.at[2] + sz * height / 2])
    return np.array(corners)


def _hull_corners(part: Box | Cylinder) -> np.ndarray:
    """A box's corners, or the corners of a cylinder's bounding box, in the object's frame."""
    if isinstance(part, Box):
        return _box_corners(part)
    half = [part.radius, part.radius, part.radius]
    half["xyz".index(part.axis)] = part.height / 2
    return _box_corners(Box(shape="box", size=(2 * half[0], 2 * half[1], 2 * half[2]), at=part.at))


def _databases() -> list[tuple[Path, Path, str]]:
    """(mission file, world file, object id) of every database object of a mission that its world places."""
    out = []
    for path in MISSION_FILES:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
        if not doc.get("world"):
            continue
        world_path = (path.parent / doc["world"]).resolve()
        charted = {o["database"] for o in yaml.safe_load(world_path.read_text(encoding="utf-8"))["objects"]
                   if o.get("database")}
        out += [(path, world_path, o["id"]) for o in doc.get("objects", []) if o["id"] in charted]
    return out


DATABASES = _databases()


def test_every_world_has_a_mission_whose_database_it_places() -> None:
    assert {w.resolve() for w in WORLDS} <= {world for _, world, _ in DATABASES}


@pytest.mark.parametrize(("mission_path", "world_path", "object_id"), DATABASES,
                         ids=[f"{m.name}:{o}" for m, _, o in DATABASES])
def test_characteristic_points_lie_on_top_corners_of_the_objects_parts(mission_path: Path, world_path: Path,
                                                                        object_id: str) -> None:
    # Seed 002 §3.1: characteristic points are corners a Harris detector finds; the worlds put a box's top corner
    # under each point of the database, in the object's own frame.
    obj = next(o for o in _world(world_path).objects if o.database == object_id)
    tops = np.vstack([_box_corners(p)[:4] for p in obj.parts if isinstance(p, Box)])
    doc = yaml.safe_load(mission_path.read_text(encoding="utf-8"))
    database = next(o for o in doc["objects"] if o["id"] == object_id)
    for pset in database.get("characteristic_points", []):
        for point in np.asarray(pset["points"], dtype=float):
            gap = float(np.min(np.linalg.norm(tops - point, axis=1)))
            assert gap <= CORNER_TOLERANCE_M, (pset["id"], point.tolist(), gap)


@pytest.mark.parametrize("world_path", WORLDS, ids=[w.name for w in WORLDS])
def test_every_object_rests_on_the_seabed(world_path: Path) -> None:
    # The seabed under an object's lowest part (mean over its hull's corners) lies between its bottom and top:
    # nothing floats above the seabed, nothing is buried under it.
    world = _world(world_path)
    seabed = generate_seabed(world.seabed)
    for obj in world.objects:
        hulls = [transform_points(true_pose(obj), _hull_corners(p)) for p in obj.parts]
        lowest = max(hulls, key=lambda corners: float(corners[:, 2].max()))
        under = float(np.mean(seabed.depths_at(lowest[:, 0], lowest[:, 1])))
        assert lowest[:, 2].min() <= under <= lowest[:, 2].max(), (obj.id, under, lowest[:, 2].min())
