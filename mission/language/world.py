"""World files, as a language: the seabed, the subsea objects as they truly are, and the water current.

The simulator builds its worlds from these models (`mission.world`); the mission language only validates the
files, so they live here and the language never imports the simulator's side.

Each world object has a charted `pose` (what a database would hold) and an optional `offset` (shift, rotation,
tilt) by which the truth differs from it: databases are "off by metres", and the world says by how much. The
truth belongs to the world alone; `database` names the mission-database object it is, for matching in metrics.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from mission.language.models import Identifier, NonNegative, Positive, Strict, Vec3


class Roughness(Strict):
    amplitude: NonNegative = 0.3
    wavelength: Positive = 20.0
    seed: int = 0


class Texture(Strict):
    """Procedural seabed texture for the cameras."""

    kind: Literal["sand", "mud", "gravel", "rock"] = "sand"
    seed: int = 0
    scale: Positive = 1.0


class Slope(Strict):
    """Depth gradient in metres of depth per metre travelled north / east."""

    north: float = 0.0
    east: float = 0.0


class Seabed(Strict):
    north: tuple[float, float]
    east: tuple[float, float]
    resolution: Positive = 1.0
    mean_depth: Positive
    slope: Slope = Slope()
    roughness: Roughness = Roughness()
    texture: Texture = Texture()

    @model_validator(mode="after")
    def _extent_ordered(self) -> Seabed:
        if self.north[0] >= self.north[1] or self.east[0] >= self.east[1]:
            raise ValueError("seabed extents must be [min, max] with min < max")
        cells = (self.north[1] - self.north[0]) * (self.east[1] - self.east[0]) / self.resolution**2
        if cells > 25e6:
            raise ValueError(f"seabed grid of {cells:.0f} cells is too large; use a coarser resolution")
        return self


class Current(Strict):
    north: float = 0.0
    east: float = 0.0


class TruePose(Strict):
    north: float
    east: float
    depth: float
    heading: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0


class Offset(Strict):
    """How the truth differs from the database pose: a shift (m), a rotation about z and a tilt (deg)."""

    north: float = 0.0
    east: float = 0.0
    depth: float = 0.0
    heading: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0


class Box(Strict):
    shape: Literal["box"]
    size: tuple[Positive, Positive, Positive]
    at: Vec3 = (0.0, 0.0, 0.0)
    heading: float = 0.0
    color: tuple[float, float, float] = (0.6, 0.55, 0.2)


class Cylinder(Strict):
    shape: Literal["cylinder"]
    radius: Positive
    height: Positive
    at: Vec3 = (0.0, 0.0, 0.0)
    axis: Literal["x", "y", "z"] = "z"
    color: tuple[float, float, float] = (0.5, 0.5, 0.55)


Part = Annotated[Box | Cylinder, Field(discriminator="shape")]


class WorldObject(Strict):
    """An object as it truly lies. Parts are centred at `at` in the object frame (z down)."""

    id: Identifier
    database: Identifier | None = None
    pose: TruePose
    offset: Offset = Offset()
    parts: Annotated[list[Part], Field(min_length=1)]


class World(Strict):
    name: Identifier
    description: str = ""
    seabed: Seabed
    current: Current = Current()
    objects: list[WorldObject] = []
