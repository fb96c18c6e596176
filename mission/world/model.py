"""The world file's models (defined with the mission language in `mission.language.world`), for the simulator."""

from mission.language.world import (
    Box,
    Current,
    Cylinder,
    Offset,
    Part,
    Roughness,
    Seabed,
    Slope,
    Texture,
    TruePose,
    World,
    WorldObject,
)

__all__ = ["Box", "Current", "Cylinder", "Offset", "Part", "Roughness", "Seabed", "Slope", "Texture", "TruePose",
           "World", "WorldObject"]
