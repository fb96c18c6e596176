"""Typed, immutable models of mission language v1 (seed 002 §1, Fig. 1; §3.4, Fig. 11).

A mission is a list of route elements (`transit`, `survey`, `explore`, `inspect`), an onboard database of known
objects with characteristic-point sets and targets in object frames, the vehicle, its sensors, the perception
plug-ins and the safety envelope. Defaults live here, in code; unknown keys are rejected.
Frames: local NED in metres, headings in degrees clockwise from north.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import pydantic
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationInfo, field_validator, model_validator

from mission import geodesy
from mission.language import limits as L
from mission.language.fault_models import Fault
from mission.language.mount import Mounted, Streamed  # Streamed: mbes, scanner; Mounted: stereo
from mission.language.units import Duration, Percent


def between(low: float, high: float, *, open_low: bool = False) -> Any:
    """A field constraint `low ≤ x ≤ high` (`low < x` with `open_low`): every number of the language is finite
    and lies in a range a vehicle or a world can have (`mission.language.limits`)."""
    return Field(gt=low, le=high) if open_low else Field(ge=low, le=high)


Coordinate = Annotated[float, between(-L.MAX_EXTENT, L.MAX_EXTENT)]  # north, east (m) in the local frame
Vec2 = tuple[Coordinate, Coordinate]
Vec3 = tuple[Coordinate, Coordinate, Coordinate]


def _unplaced_geodetic(value: object) -> object:
    """A `{lat, lon}` point still here was not converted by `Mission` (see `mission.geodesy.localize`): say why."""
    if geodesy.is_geodetic(value):
        if not geodesy.valid_geodetic(value):
            raise ValueError("a geodetic point is {lat, lon} with lat in [-90, 90] and lon in [-180, 180] (degrees)")
        raise ValueError("a {lat, lon} point needs the mission's `origin: {lat, lon}` to place it in the local frame")
    return value


_GEODETIC_SCHEMA = {"type": "object", "additionalProperties": False, "required": ["lat", "lon"],
                    "properties": {"lat": {"type": "number", "minimum": -90, "maximum": 90},
                                   "lon": {"type": "number", "minimum": -180, "maximum": 180}}}


def _or_geodetic(schema: dict[str, Any]) -> None:
    local = dict(schema)
    schema.clear()
    schema["anyOf"] = [local, _GEODETIC_SCHEMA]


# A point of a polygon: [north, east] metres, or {lat, lon} degrees that `Mission` converts with its `origin`.
PlanePoint = Annotated[Vec2, pydantic.BeforeValidator(_unplaced_geodetic), pydantic.WithJsonSchema({"anyOf": [
    {"type": "array", "prefixItems": [{"type": "number"}, {"type": "number"}], "minItems": 2, "maxItems": 2},
    _GEODETIC_SCHEMA]})]
Polygon = Annotated[list[PlanePoint], Field(min_length=3, max_length=L.MAX_POLYGON_VERTICES,
                                            description="[[north, east], ...] in metres, or {lat, lon} points "
                                                        "(degrees, WGS84)")]
Identifier = Annotated[str, Field(min_length=1, max_length=200, pattern=r"^[A-Za-z0-9_.\-]+$")]
Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
Depth = Annotated[float, between(0.0, L.MAX_DEPTH_M)]  # below the surface (m)
ObjectDepth = Annotated[float, between(-L.MAX_DEPTH_M, L.MAX_DEPTH_M)]  # of an object frame's origin (m)
Altitude = Annotated[float, between(0.0, L.MAX_ALTITUDE)]
Angle = Annotated[float, between(-L.MAX_HEADING, L.MAX_HEADING)]  # degrees
Speed = Annotated[float, between(L.MIN_SPEED, L.MAX_SPEED)]  # m/s
Rate = Annotated[float, between(L.MIN_RATE_HZ, L.MAX_RATE_HZ)]  # Hz
Range = Annotated[float, between(0.1, L.MAX_RANGE)]  # of a sensor (m)
Size = Annotated[float, between(0.001, L.MAX_SIZE)]  # of an object or a part (m)
Distance = Annotated[float, between(0.1, L.MAX_SIZE)]  # a standoff, a capture radius (m)
Sigma = Annotated[float, between(0.0, 100.0)]
Seed = Annotated[int, between(0, L.MAX_SEED)]
Time = Annotated[Duration, Field(le=L.MAX_DURATION_S)]  # a duration of at most a week


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Origin(Strict):
    """Geodetic origin (WGS84 degrees) of the local NED frame: exports and `{lat, lon}` points need it."""

    lat: Annotated[float, between(-90, 90)]
    lon: Annotated[float, between(-180, 180)]


class Home(Strict):
    """The launch point, in the local frame. `transit: {to: home}` returns here."""

    north: Coordinate = 0.0
    east: Coordinate = 0.0
    depth: Depth = 0.0
    heading: Angle = 0.0


class VehicleSettings(Strict):
    """The mission's `vehicle:` section: the limits and energy of the vehicle (the vehicle itself, simulated or
    real, is `mission.vehicle.VehicleInterface`)."""

    max_speed: Speed = 2.0
    cruise_speed: Speed = 1.5
    max_acceleration: Annotated[float, between(0.001, L.MAX_ACCELERATION)] = 0.2
    max_yaw_rate: Annotated[float, between(L.MIN_YAW_RATE, L.MAX_YAW_RATE)] = 15.0
    max_vertical_speed: Annotated[float, between(L.MIN_VERTICAL_SPEED, L.MAX_VERTICAL_SPEED)] = 0.5
    turn_radius: Annotated[float, between(0.0, L.MAX_SIZE)] = 6.0
    energy_wh: Annotated[float, between(1.0, L.MAX_ENERGY_WH)] = 4000.0
    hotel_power_w: Annotated[float, between(0.0, L.MAX_POWER_W)] = 60.0
    propulsion_power_w: Annotated[float, between(0.0, L.MAX_POWER_W)] = 180.0

    @field_validator("cruise_speed")
    @classmethod
    def _cruise_within_max(cls, value: float, info: ValidationInfo) -> float:
        top = info.data.get("max_speed")
        if top is not None and value > top:
            raise ValueError(f"cruise_speed {value:g} exceeds max_speed {top:g}")
        return value


Vehicle = VehicleSettings  # the same model under its short name (`Mission.vehicle`)


class Mbes(Streamed):
    beams: Annotated[int, between(2, L.MAX_BEAMS)] = 256
    swath_deg: Annotated[float, Field(ge=1, lt=180)] = 120.0
    max_range: Range = 80.0
    rate_hz: Rate = 10.0
    range_sigma: Annotated[float, between(0.0, 10.0)] = 0.05


class Stereo(Mounted):
    width: Annotated[int, between(16, L.MAX_IMAGE_SIDE)] = 1200
    height: Annotated[int, between(16, L.MAX_IMAGE_SIDE)] = 900
    fx: Annotated[float, between(1.0, 1.0e5)] = 1000.0
    baseline: Annotated[float, between(0.001, 10.0)] = 0.25
    rate_hz: Rate = 10.0
    max_range: Range = 8.0


class Scanner(Streamed):
    fov_deg: tuple[Annotated[float, Field(ge=1, lt=180)], Annotated[float, Field(ge=1, lt=180)]] = (60.0, 45.0)
    max_range: Range = 12.0
    rate_hz: Rate = 2.0


class Usbl(Strict):
    sigma: Sigma = 1.5
    rate_hz: Rate = 0.5


class Dvl(Strict):
    drift_percent: Annotated[float, between(0.0, 100.0)] = 0.5
    velocity_sigma: Annotated[float, between(0.0, 10.0)] = 0.01
    max_altitude: Annotated[float, between(0.1, L.MAX_ALTITUDE)] = 100.0


class Sensors(Strict):
    mbes: Mbes | None = None
    stereo: Stereo | None = None
    scanner: Scanner | None = None
    usbl: Usbl | None = None
    dvl: Dvl = Dvl()


class Plugins(Strict):
    """Entry-point names (group `auv.perception`) of the perception plug-ins the mission uses."""

    referencing: str | None = None
    odometry: str | None = None


class AbortTo(Strict):
    north: Coordinate
    east: Coordinate
    depth: Depth = 0.0


class OnViolation(Strict):
    """What the executive does when a safety monitor trips: go to a point (or home) and surface there."""

    abort_to: Literal["home"] | AbortTo = "home"
    surface: bool = True


class Safety(Strict):
    geofence: Polygon | None = None
    max_depth: Annotated[float, between(0.0, L.MAX_DEPTH_M, open_low=True)] = 300.0
    min_altitude: Altitude = 1.0
    max_duration: Annotated[Time, Field(ge=1.0)] = 6 * 3600.0  # the route stops here (the abort then has abort_time)
    abort_time: Annotated[Time, Field(ge=1.0)] = 1800.0  # the longest an abort may run past max_duration
    energy_reserve: Percent = 20.0
    on_violation: OnViolation = OnViolation()
    link_timeout: Annotated[Duration, Field(ge=0.1, le=L.MAX_LINK_TIMEOUT_S)] = 3.0  # onboard: no heartbeat: lost


class Pose(Strict):
    """Pose of an object frame in the world: position of its origin and heading of its x-axis."""

    north: Coordinate
    east: Coordinate
    depth: ObjectDepth
    heading: Angle = 0.0


class PointSet(Strict):
    id: Identifier
    points: Annotated[list[Vec3], Field(max_length=L.MAX_POINTS_PER_SET)]


class Target(Strict):
    id: Identifier
    at: Vec3
    reference: Identifier
    standoff: Distance = 2.0
    photos: Annotated[int, between(1, L.MAX_PHOTOS)] = 1


class KnownObject(Strict):
    id: Identifier
    description: str = ""
    pose: Pose
    size: tuple[Size, Size, Size]
    characteristic_points: Annotated[list[PointSet], Field(max_length=L.MAX_POINT_SETS)] = []
    targets: Annotated[list[Target], Field(max_length=L.MAX_TARGETS)] = []
    model: str | None = Field(None, description="multi-view model file (`auv model build`), relative to the "
                                                "mission file; the loader resolves it to an absolute path")
    mesh: str | None = None  # surface mesh (`auv reconstruct`: .ply or .glb), relative to the mission file

    @model_validator(mode="after")
    def _points_within_limit(self) -> KnownObject:
        count = sum(len(s.points) for s in self.characteristic_points)
        if count > L.MAX_POINTS_PER_OBJECT:
            raise ValueError(f"object '{self.id}' has {count} characteristic points (at most "
                             f"{L.MAX_POINTS_PER_OBJECT} in all its sets)")
        return self


class Point(Strict):
    """A point in the local frame; `{lat, lon}` is accepted too and converted with the mission's `origin`."""

    model_config = ConfigDict(json_schema_extra=lambda schema: _or_geodetic(schema))

    north: Coordinate
    east: Coordinate

    @model_validator(mode="before")
    @classmethod
    def _geodetic_placed(cls, data: object) -> object:
        return _unplaced_geodetic(data)


class Transit(Strict):
    """Go to a point (or home) at a depth or an altitude; with neither, keep the current depth."""

    to: Literal["home"] | Point
    depth: Depth | None = None
    altitude: Altitude | None = None
    speed: Speed | None = None
    navigation: Literal["usbl", "dead-reckoning"] = "usbl"
    capture_radius: Distance = 3.0

    @model_validator(mode="after")
    def _depth_or_altitude(self) -> Transit:
        if self.depth is not None and self.altitude is not None:
            raise ValueError("give either depth or altitude, not both")
        return self


class Survey(Strict):
    area: Polygon
    exclude: Annotated[list[Polygon], Field(max_length=L.MAX_EXCLUSION_ZONES)] = []
    sensor: Literal["mbes"] = "mbes"
    altitude: Annotated[float, between(0.1, L.MAX_ALTITUDE)]
    overlap: Annotated[Percent, Field(le=90)] = 20.0
    pattern: Literal["meander"] = "meander"
    heading: Angle | Literal["auto"] = "auto"
    speed: Speed | None = None
    resolution: Annotated[float, between(L.MIN_RESOLUTION, 5.0)] = 0.5  # voxel size of the occupancy map (m)


class Weights(Strict):
    distance: Annotated[float, between(0.0, 1000.0)] = 0.3
    frontier: Annotated[float, between(0.0, 1000.0)] = 0.5
    contour: Annotated[float, between(0.0, 1000.0)] = 0.2


class Explore(Strict):
    object: Identifier = "detected"
    sensor: Literal["scanner", "stereo", "mbes"] = "scanner"
    planner: Literal["next-best-view", "rrt-photo"] = "next-best-view"
    goal: Literal["map", "reconstruct"] = "map"  # reconstruct: views for the stereo camera too (agents.explore_stereo)
    weights: Weights = Weights()
    safe_distance: Distance = 5.0
    budget: Time = 900.0


class Search(Strict):
    pattern: Literal["expanding-square", "lawnmower"] = "expanding-square"
    budget: Time = 300.0


class Inspect(Strict):
    object: Identifier
    targets: Literal["all"] | list[Identifier] = "all"
    order: Literal["auto", "as-listed"] = "auto"
    search: Search = Search()


class Reference(Strict):
    """Reference the vehicle to a known object by stereo (seed 002 §3.1–3.3): search above the object's point
    sets at `search_altitude` over their tops until a set is identified in the triangulated cloud, then hover
    centred over it at `altitude`, aligned with the object, and reference precisely; when a set is not
    recognised, try the next position (database pose + `offsets`)."""

    object: Identifier
    point_sets: Literal["all"] | list[Identifier] = "all"
    altitude: Annotated[float, Field(gt=0.5, le=20)] = 3.6  # of the final, precise referencing
    search_altitude: Annotated[float, Field(gt=0.5, le=30)] = 6.0  # while searching: a wider view
    offsets: Annotated[list[Vec2], Field(max_length=L.MAX_OFFSETS)] = [  # north, east (m) around each set
        (0.0, 0.0), (1.5, 0.0), (-1.5, 0.0), (0.0, 1.5), (0.0, -1.5),
        (1.5, 1.5), (1.5, -1.5), (-1.5, 1.5), (-1.5, -1.5)]
    tolerance: Annotated[float, Field(gt=0, le=1)] = 0.05
    settle: Time = 3.0


Action = Literal["map", "detect_objects", "photograph", "model", "record"]
ELEMENT_KINDS = ("transit", "survey", "explore", "inspect", "reference")


class RouteElement(Strict):
    """One element of the route: exactly one motion kind, what to do, and how long it may take."""

    id: Identifier
    transit: Transit | None = None
    survey: Survey | None = None
    explore: Explore | None = None
    inspect: Inspect | None = None
    reference: Reference | None = None
    actions: Annotated[list[Action], Field(max_length=20)] = []
    timeout: Annotated[Time, Field(gt=0)] | None = None
    on_failure: Literal["continue", "abort"] = "continue"
    priority: Annotated[int, Field(ge=-100, le=100)] = 0  # when the budget falls short, the lowest is dropped first

    @model_validator(mode="after")
    def _exactly_one_kind(self) -> RouteElement:
        given = [k for k in ELEMENT_KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            found = ", ".join(given) if given else "none"
            raise ValueError(f"a route element needs exactly one of {', '.join(ELEMENT_KINDS)} (found: {found})")
        return self

    @property
    def kind(self) -> str:
        return next(k for k in ELEMENT_KINDS if getattr(self, k) is not None)

    @property
    def params(self) -> Transit | Survey | Explore | Inspect | Reference:
        return getattr(self, self.kind)  # type: ignore[no-any-return]


class Strategy(Strict):
    """The strategic level (seed 002 §1, `mission.strategy`): the order of the work bound to known objects, and
    the share of the time and energy budgets kept in hand when it decides what fits."""

    order: Literal["auto", "as-listed"] = "auto"
    budget_margin: Percent = 10.0


class Mission(Strict):
    """A whole mission. The loader resolves `world` to an absolute path and records the source file."""

    name: Identifier
    description: str = ""
    origin: Origin | None = None  # required by exports and by `{lat, lon}` points; never assumed
    world: str | None = None
    seed: Seed = 0
    home: Home = Home()
    vehicle: VehicleSettings = VehicleSettings()
    sensors: Sensors = Sensors()
    plugins: Plugins = Plugins()
    safety: Safety = Safety()
    strategy: Strategy = Strategy()
    objects: Annotated[list[KnownObject], Field(max_length=L.MAX_OBJECTS)] = []
    route: Annotated[list[RouteElement], Field(min_length=1, max_length=L.MAX_ROUTE_ELEMENTS)]
    faults: Annotated[list[Fault], Field(max_length=L.MAX_ROUTE_ELEMENTS)] = []  # simulation only (fault_models)
    _source: str | None = PrivateAttr(default=None)

    @model_validator(mode="before")
    @classmethod
    def _geodetic_to_local(cls, data: object) -> object:
        return geodesy.localize(data)

    @property
    def source(self) -> str | None:
        """The file the mission was loaded from, if any."""
        return self._source

    def object(self, object_id: str) -> KnownObject:
        return next(o for o in self.objects if o.id == object_id)
