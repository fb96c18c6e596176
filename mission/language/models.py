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
from mission.language.units import Duration, Percent

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]


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
Polygon = Annotated[list[PlanePoint], Field(min_length=3, description="[[north, east], ...] in metres, or "
                                                                      "{lat, lon} points (degrees, WGS84)")]
Identifier = Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_.\-]+$")]
Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Origin(Strict):
    """Geodetic origin (WGS84 degrees) of the local NED frame: exports and `{lat, lon}` points need it."""

    lat: Annotated[float, Field(ge=-90, le=90)]
    lon: Annotated[float, Field(ge=-180, le=180)]


class Home(Strict):
    """The launch point, in the local frame. `transit: {to: home}` returns here."""

    north: float = 0.0
    east: float = 0.0
    depth: NonNegative = 0.0
    heading: float = 0.0


class VehicleSettings(Strict):
    """The mission's `vehicle:` section: the limits and energy of the vehicle (the vehicle itself, simulated or
    real, is `mission.vehicle.VehicleInterface`)."""

    max_speed: Positive = 2.0
    cruise_speed: Positive = 1.5
    max_acceleration: Positive = 0.2
    max_yaw_rate: Positive = 15.0
    max_vertical_speed: Positive = 0.5
    turn_radius: NonNegative = 6.0
    energy_wh: Positive = 4000.0
    hotel_power_w: NonNegative = 60.0
    propulsion_power_w: NonNegative = 180.0

    @field_validator("cruise_speed")
    @classmethod
    def _cruise_within_max(cls, value: float, info: ValidationInfo) -> float:
        top = info.data.get("max_speed")
        if top is not None and value > top:
            raise ValueError(f"cruise_speed {value:g} exceeds max_speed {top:g}")
        return value


Vehicle = VehicleSettings  # the same model under its short name (`Mission.vehicle`)


class Mbes(Strict):
    beams: Annotated[int, Field(ge=2)] = 256
    swath_deg: Annotated[float, Field(gt=0, lt=180)] = 120.0
    max_range: Positive = 80.0
    rate_hz: Positive = 10.0
    range_sigma: NonNegative = 0.05


class Stereo(Strict):
    width: Annotated[int, Field(ge=16)] = 1200
    height: Annotated[int, Field(ge=16)] = 900
    fx: Positive = 1000.0
    baseline: Positive = 0.25
    rate_hz: Positive = 10.0
    max_range: Positive = 8.0


class Scanner(Strict):
    fov_deg: tuple[Annotated[float, Field(gt=0, lt=180)], Annotated[float, Field(gt=0, lt=180)]] = (60.0, 45.0)
    max_range: Positive = 12.0
    rate_hz: Positive = 2.0


class Usbl(Strict):
    sigma: NonNegative = 1.5
    rate_hz: Positive = 0.5


class Dvl(Strict):
    drift_percent: NonNegative = 0.5
    velocity_sigma: NonNegative = 0.01
    max_altitude: Positive = 100.0


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
    north: float
    east: float
    depth: NonNegative = 0.0


class OnViolation(Strict):
    """What the executive does when a safety monitor trips: go to a point (or home) and surface there."""

    abort_to: Literal["home"] | AbortTo = "home"
    surface: bool = True


class Safety(Strict):
    geofence: Polygon | None = None
    max_depth: Positive = 300.0
    min_altitude: NonNegative = 1.0
    max_duration: Duration = 6 * 3600.0
    energy_reserve: Percent = 20.0
    on_violation: OnViolation = OnViolation()
    link_timeout: Duration = 3.0  # onboard: no heartbeat from the vehicle for this long is a lost link


class Pose(Strict):
    """Pose of an object frame in the world: position of its origin and heading of its x-axis."""

    north: float
    east: float
    depth: float
    heading: float = 0.0


class PointSet(Strict):
    id: Identifier
    points: list[Vec3]


class Target(Strict):
    id: Identifier
    at: Vec3
    reference: Identifier
    standoff: Positive = 2.0
    photos: Annotated[int, Field(ge=1)] = 1


class KnownObject(Strict):
    id: Identifier
    description: str = ""
    pose: Pose
    size: tuple[Positive, Positive, Positive]
    characteristic_points: list[PointSet] = []
    targets: list[Target] = []
    model: str | None = Field(None, description="multi-view model file (`auv model build`), relative to the "
                                                "mission file; the loader resolves it to an absolute path")


class Point(Strict):
    """A point in the local frame; `{lat, lon}` is accepted too and converted with the mission's `origin`."""

    model_config = ConfigDict(json_schema_extra=lambda schema: _or_geodetic(schema))

    north: float
    east: float

    @model_validator(mode="before")
    @classmethod
    def _geodetic_placed(cls, data: object) -> object:
        return _unplaced_geodetic(data)


class Transit(Strict):
    """Go to a point (or home) at a depth or an altitude; with neither, keep the current depth."""

    to: Literal["home"] | Point
    depth: NonNegative | None = None
    altitude: NonNegative | None = None
    speed: Positive | None = None
    navigation: Literal["usbl", "dead-reckoning"] = "usbl"
    capture_radius: Positive = 3.0

    @model_validator(mode="after")
    def _depth_or_altitude(self) -> Transit:
        if self.depth is not None and self.altitude is not None:
            raise ValueError("give either depth or altitude, not both")
        return self


class Survey(Strict):
    area: Polygon
    exclude: list[Polygon] = []
    sensor: Literal["mbes"] = "mbes"
    altitude: Positive
    overlap: Percent = 20.0
    pattern: Literal["meander"] = "meander"
    heading: float | Literal["auto"] = "auto"
    speed: Positive | None = None
    resolution: Annotated[float, Field(gt=0, le=5)] = 0.5  # voxel size of the occupancy map (m)


class Weights(Strict):
    distance: NonNegative = 0.3
    frontier: NonNegative = 0.5
    contour: NonNegative = 0.2


class Explore(Strict):
    object: Identifier = "detected"
    sensor: Literal["scanner", "stereo", "mbes"] = "scanner"
    planner: Literal["next-best-view", "rrt-photo"] = "next-best-view"
    weights: Weights = Weights()
    safe_distance: Positive = 5.0
    budget: Duration = 900.0


class Search(Strict):
    pattern: Literal["expanding-square", "lawnmower"] = "expanding-square"
    budget: Duration = 300.0


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
    offsets: list[Vec2] = [(0.0, 0.0), (1.5, 0.0), (-1.5, 0.0), (0.0, 1.5), (0.0, -1.5),
                           (1.5, 1.5), (1.5, -1.5), (-1.5, 1.5), (-1.5, -1.5)]  # north, east (m) around each set
    tolerance: Annotated[float, Field(gt=0, le=1)] = 0.05
    settle: Duration = 3.0


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
    actions: list[Action] = []
    timeout: Duration | None = None
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
    seed: int = 0
    home: Home = Home()
    vehicle: VehicleSettings = VehicleSettings()
    sensors: Sensors = Sensors()
    plugins: Plugins = Plugins()
    safety: Safety = Safety()
    strategy: Strategy = Strategy()
    objects: list[KnownObject] = []
    route: Annotated[list[RouteElement], Field(min_length=1)]
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
