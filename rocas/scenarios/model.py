"""The scenario model: a frozen, picklable description of one world and one mission.

Everything is SI inside (metres, seconds, radians, m/s) except the user-facing angles that the
scenario format names in degrees (weather sun angles, ``*_deg`` fields). Every class is a frozen
dataclass, so a search mutates a scenario with :func:`dataclasses.replace`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

#: Actor and ego body models: name -> (length, width, height) [m].
VEHICLE_DIMENSIONS: dict[str, tuple[float, float, float]] = {
    "sedan": (4.7, 1.85, 1.5),
    "suv": (4.9, 2.0, 1.8),
    "truck": (8.5, 2.5, 3.3),
    "bus": (12.0, 2.55, 3.2),
}
CYCLIST_DIMENSIONS: tuple[float, float, float] = (1.8, 0.6, 1.7)
PEDESTRIAN_DIMENSIONS: tuple[float, float, float] = (0.5, 0.5, 1.75)
#: Map entity models: kind -> (length, width, height) [m].
OBJECT_DIMENSIONS: dict[str, tuple[float, float, float]] = {
    "cone": (0.4, 0.4, 0.7),
    "box": (1.0, 1.0, 0.8),
}
#: Named colours and their RGB in [0, 1] (what the camera sees).
COLORS: dict[str, tuple[float, float, float]] = {
    "white": (0.92, 0.92, 0.92),
    "black": (0.08, 0.08, 0.08),
    "silver": (0.7, 0.7, 0.72),
    "gray": (0.45, 0.45, 0.45),
    "red": (0.85, 0.1, 0.08),
    "blue": (0.1, 0.2, 0.8),
    "green": (0.1, 0.6, 0.2),
    "yellow": (0.95, 0.85, 0.1),
    "orange": (0.95, 0.5, 0.05),
    "brown": (0.45, 0.3, 0.15),
}
ACTOR_KINDS = ("vehicle", "cyclist", "pedestrian")
VEHICLE_MODELS = tuple(VEHICLE_DIMENSIONS)
OBJECT_KINDS = tuple(OBJECT_DIMENSIONS)
AREA_KINDS = ("building", "vegetation")
LIGHT_COLORS = ("red", "yellow", "green", "off")
LIGHT_MODES = ("fixed", "cycle")
#: Ego body: a sedan-sized test vehicle.
EGO_LENGTH_M = 4.9
EGO_WIDTH_M = 2.0
EGO_WHEELBASE_M = 2.85

Point = tuple[float, float]


@dataclass(frozen=True)
class Lane:
    """A lane: a centre polyline driven from its first to its last point.

    Attributes:
        id: unique lane id.
        centerline: points ``(x, y)`` [m], at least two.
        width_m: lane width [m].
        speed_limit_mps: legal speed [m/s].
        successors: lanes one may continue onto (junction branches, merges, roundabout ring).
        is_junction: True for lanes inside an intersection or roundabout.
    """

    id: str
    centerline: tuple[Point, ...]
    width_m: float = 3.5
    speed_limit_mps: float = 13.9
    successors: tuple[str, ...] = ()
    is_junction: bool = False


@dataclass(frozen=True)
class LightPolicy:
    """What a traffic light shows over time.

    ``fixed`` shows ``color`` for ever; ``cycle`` runs green -> yellow -> red with the given
    durations [s], shifted by ``offset_s`` (the cycle position at t = 0).
    """

    mode: str = "fixed"
    color: str = "green"
    green_s: float = 10.0
    yellow_s: float = 3.0
    red_s: float = 10.0
    offset_s: float = 0.0


@dataclass(frozen=True)
class TrafficLight:
    """A traffic light head and the stop line it governs.

    Attributes:
        id: unique id.
        position: light head position (x, y) [m].
        facing_rad: direction the light's face points to (towards the traffic it governs) [rad].
        stop_lane: lane whose traffic stops for it.
        stop_s_m: arc length of the stop line on ``stop_lane`` [m].
        policy: colour policy.
        enabled: a disabled light is dark (perceived as off, never red).
    """

    id: str
    position: Point
    facing_rad: float
    stop_lane: str
    stop_s_m: float
    policy: LightPolicy = field(default_factory=LightPolicy)
    enabled: bool = True


@dataclass(frozen=True)
class StaticObject:
    """A traffic cone or box on the road (collidable, perceivable)."""

    id: str
    kind: str
    position: Point
    yaw_rad: float = 0.0

    @property
    def dimensions(self) -> tuple[float, float, float]:
        return OBJECT_DIMENSIONS[self.kind]


@dataclass(frozen=True)
class Area:
    """A building or vegetation footprint: occludes perception, collidable when enabled."""

    id: str
    kind: str
    polygon: tuple[Point, ...]
    enabled: bool = True
    height_m: float = 8.0


@dataclass(frozen=True)
class Weather:
    """Weather: percentages in [0, 100], sun angles in degrees."""

    cloudiness: float = 0.0
    precipitation: float = 0.0
    fog_density: float = 0.0
    sun_azimuth_deg: float = 0.0
    sun_altitude_deg: float = 45.0


@dataclass(frozen=True)
class Actor:
    """A traffic participant that follows a route with a speed profile.

    Attributes:
        id: unique id.
        kind: vehicle, cyclist or pedestrian.
        model: vehicle model (sedan, suv, truck, bus); ignored for cyclists and pedestrians.
        color: colour name (see :data:`COLORS`).
        route: lane ids followed in order (empty when ``waypoints`` is given).
        waypoints: explicit path points (x, y) [m] (pedestrians crossing, off-map paths).
        start_s_m: start arc length along the route [m].
        lateral_offset_m: offset from the route centre, positive left [m].
        speed_profile: ``(time_s, speed_mps)`` knots, linear in between, held after the last.
        reactive: keeps a distance to whatever is ahead on its path.
        reactive_gap_m: standstill gap kept when reactive [m].
    """

    id: str
    kind: str = "vehicle"
    model: str = "sedan"
    color: str = "white"
    route: tuple[str, ...] = ()
    waypoints: tuple[Point, ...] = ()
    start_s_m: float = 0.0
    lateral_offset_m: float = 0.0
    speed_profile: tuple[tuple[float, float], ...] = ((0.0, 10.0),)
    reactive: bool = False
    reactive_gap_m: float = 4.0

    @property
    def dimensions(self) -> tuple[float, float, float]:
        """(length, width, height) [m]."""
        if self.kind == "vehicle":
            return VEHICLE_DIMENSIONS[self.model]
        if self.kind == "cyclist":
            return CYCLIST_DIMENSIONS
        return PEDESTRIAN_DIMENSIONS


#: the stack a scenario file that names none is driven by (the built-in ADS)
DEFAULT_STACK = "ads"


@dataclass(frozen=True)
class Ego:
    """The vehicle under test and its mission.

    Attributes:
        route: lane ids of the mission, in order (the reference line of planning).
        start_s_m: start arc length along the route [m].
        start_lateral_m: start offset from the route centre, positive left [m].
        start_speed_mps: initial speed [m/s].
        destination_s_m: mission end along the route [m]; None means the route's end.
        params: parameter overrides of the stack ``(("module.name", value), ...)`` sorted by
            name.
        stack: the registered stack that drives the ego (:mod:`rocas.stacks.registry`);
            :data:`DEFAULT_STACK` when a scenario file names none.
    """

    route: tuple[str, ...]
    start_s_m: float = 0.0
    start_lateral_m: float = 0.0
    start_speed_mps: float = 0.0
    destination_s_m: float | None = None
    params: tuple[tuple[str, float], ...] = ()
    stack: str = DEFAULT_STACK

    @property
    def overrides(self) -> dict[str, float]:
        return dict(self.params)


@dataclass(frozen=True)
class Scenario:
    """One world (map, entities, weather), its actors and the ego mission."""

    name: str
    lanes: tuple[Lane, ...]
    ego: Ego
    traffic_lights: tuple[TrafficLight, ...] = ()
    objects: tuple[StaticObject, ...] = ()
    areas: tuple[Area, ...] = ()
    weather: Weather = field(default_factory=Weather)
    actors: tuple[Actor, ...] = ()
    duration_s: float = 30.0
    dt_s: float = 0.05
    seed: int = 0
    description: str = ""

    @property
    def lane_by_id(self) -> Mapping[str, Lane]:
        return {lane.id: lane for lane in self.lanes}

    @property
    def num_ticks(self) -> int:
        return int(round(self.duration_s / self.dt_s))
