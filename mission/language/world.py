"""World files, as a language: the seabed, the subsea objects as they truly are, and the water current.

The simulator builds its worlds from these models (`mission.world`); the mission language only validates the
files, so they live here and the language never imports the simulator's side.

Each world object has a charted `pose` (what a database would hold) and an optional `offset` (shift, rotation,
tilt) by which the truth differs from it: databases are "off by metres", and the world says by how much. The
truth belongs to the world alone; `database` names the mission-database object it is, for matching in metrics.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from mission.language import limits as L
from mission.language.models import Angle, Coordinate, Identifier, ObjectDepth, Seed, Size, Strict, Vec3, between

Fraction = Annotated[float, between(0.0, 1.0)]
Color = tuple[Fraction, Fraction, Fraction]


class Roughness(Strict):
    amplitude: Annotated[float, between(0.0, 100.0)] = 0.3
    wavelength: Annotated[float, between(0.01, 1.0e5)] = 20.0
    seed: Seed = 0


class Texture(Strict):
    """Procedural seabed texture for the cameras."""

    kind: Literal["sand", "mud", "gravel", "rock"] = "sand"
    seed: Seed = 0
    scale: Annotated[float, between(0.001, 1000.0)] = 1.0


class Slope(Strict):
    """Depth gradient in metres of depth per metre travelled north / east."""

    north: Annotated[float, between(-10.0, 10.0)] = 0.0
    east: Annotated[float, between(-10.0, 10.0)] = 0.0


class Seabed(Strict):
    north: tuple[Coordinate, Coordinate]
    east: tuple[Coordinate, Coordinate]
    resolution: Annotated[float, between(L.MIN_RESOLUTION, L.MAX_RESOLUTION)] = 1.0
    mean_depth: Annotated[float, between(0.1, L.MAX_DEPTH_M)]
    slope: Slope = Slope()
    roughness: Roughness = Roughness()
    texture: Texture = Texture()

    @model_validator(mode="after")
    def _extent_ordered(self) -> Seabed:
        if self.north[0] >= self.north[1] or self.east[0] >= self.east[1]:
            raise ValueError("seabed extents must be [min, max] with min < max")
        rows = (self.north[1] - self.north[0]) / self.resolution + 1
        cols = (self.east[1] - self.east[0]) / self.resolution + 1
        cells = rows * cols
        if cells > L.MAX_SEABED_CELLS:
            raise ValueError(f"a seabed grid of {cells:.3g} cells is too large (at most {L.MAX_SEABED_CELLS:,}); "
                             "use a coarser resolution or a smaller extent")
        taps = 8.0 * self.roughness.wavelength / (2.0 * math.pi * self.resolution) + 1.0  # the roughness filter
        if self.roughness.amplitude > 0 and cells * taps > L.MAX_ROUGHNESS_WORK:
            raise ValueError(f"roughness.wavelength {self.roughness.wavelength:g} m is too long for a grid of "
                             f"{cells:.3g} cells at {self.resolution:g} m (filtering it would take too long)")
        return self


class Current(Strict):
    """The water current (m/s), uniform over the world."""

    north: Annotated[float, between(-L.MAX_CURRENT, L.MAX_CURRENT)] = 0.0
    east: Annotated[float, between(-L.MAX_CURRENT, L.MAX_CURRENT)] = 0.0


class TruePose(Strict):
    north: Coordinate
    east: Coordinate
    depth: ObjectDepth
    heading: Angle = 0.0
    pitch: Angle = 0.0
    roll: Angle = 0.0


class Offset(Strict):
    """How the truth differs from the database pose: a shift (m), a rotation about z and a tilt (deg)."""

    north: Annotated[float, between(-L.MAX_SIZE, L.MAX_SIZE)] = 0.0
    east: Annotated[float, between(-L.MAX_SIZE, L.MAX_SIZE)] = 0.0
    depth: Annotated[float, between(-L.MAX_SIZE, L.MAX_SIZE)] = 0.0
    heading: Angle = 0.0
    pitch: Angle = 0.0
    roll: Angle = 0.0


class Box(Strict):
    shape: Literal["box"]
    size: tuple[Size, Size, Size]
    at: Vec3 = (0.0, 0.0, 0.0)
    heading: Angle = 0.0
    color: Color = (0.6, 0.55, 0.2)


class Cylinder(Strict):
    shape: Literal["cylinder"]
    radius: Size
    height: Size
    at: Vec3 = (0.0, 0.0, 0.0)
    axis: Literal["x", "y", "z"] = "z"
    color: Color = (0.5, 0.5, 0.55)


Part = Annotated[Box | Cylinder, Field(discriminator="shape")]


class WorldObject(Strict):
    """An object as it truly lies. Parts are centred at `at` in the object frame (z down)."""

    id: Identifier
    database: Identifier | None = None
    pose: TruePose
    offset: Offset = Offset()
    parts: Annotated[list[Part], Field(min_length=1, max_length=L.MAX_WORLD_PARTS)]


class World(Strict):
    name: Identifier
    description: str = ""
    seabed: Seabed
    current: Current = Current()
    objects: Annotated[list[WorldObject], Field(max_length=L.MAX_OBJECTS)] = []
