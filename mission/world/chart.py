"""A world as a chart for planning before the dive (`mission.estimate.Chart`): its seabed, without the objects,
and its current. A designer's chart of the site; the simulator's truth is `mission.world.scene`."""

from __future__ import annotations

from mission.estimate import Chart
from mission.language.loader import load_world
from mission.world.terrain import generate_seabed


def chart_of(world_path: str) -> Chart:
    world = load_world(world_path)
    seabed = generate_seabed(world.seabed)
    return Chart(lambda north, east: float(seabed.depth_at(north, east)), (world.current.north, world.current.east))
