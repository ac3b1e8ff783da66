"""Compile scenarios into arrays: the static road geometry and a batch of N variants.

A batch holds N variants of one scenario *structure*: the same map, ego route and numbers of
actors, objects, areas and lights; everything else (actor models, colours, paths, speeds, object
poses, areas enabled, light policies, weather, ADS parameters, seeds) may differ per variant.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rocas.errors import ScenarioError
from rocas.geometry import point_at
from rocas.scenarios.model import (
    COLORS,
    EGO_LENGTH_M,
    EGO_WIDTH_M,
    OBJECT_KINDS,
    Lane,
    Scenario,
)
from rocas.sim.geometry import NearestGrid, clip, polyline_curvature, polyline_headings, resample_polyline

#: Actor kind codes used in arrays.
KIND_VEHICLE, KIND_CYCLIST, KIND_PEDESTRIAN, KIND_CONE, KIND_BOX = 0, 1, 2, 3, 4
MODEL_CODES = {"sedan": 0, "suv": 1, "truck": 2, "bus": 3}
COLOR_NAMES = tuple(COLORS)
LIGHT_CODES = {"off": 0, "red": 1, "yellow": 2, "green": 3}
REF_SPACING_M = 0.5
ACTOR_PATH_SPACING_M = 0.5
CHAIN_EXTRA_M = 100.0
GRID_CELL_M = 5.0
GRID_CANDIDATES = 24


def _polyline(points: Sequence[tuple[float, float]]) -> np.ndarray:
    return np.asarray(points, dtype=np.float64).reshape(-1, 2)


def _extend(points: np.ndarray, extra_m: float) -> np.ndarray:
    d = points[-1] - points[-2]
    d = d / max(float(np.hypot(*d)), 1e-9)
    return np.vstack([points, points[-1] + d * extra_m])


def _length(points: np.ndarray) -> float:
    return float(np.hypot(*np.diff(points, axis=0).T).sum())


def _concat(lanes: dict[str, Lane], route: Sequence[str]) -> np.ndarray:
    parts = []
    for i, lane_id in enumerate(route):
        pts = _polyline(lanes[lane_id].centerline)
        parts.append(pts if i == 0 else pts[1:] if np.allclose(pts[0], parts[-1][-1]) else pts)
    return np.vstack(parts)


def _offset(points: np.ndarray, lateral_m: float) -> np.ndarray:
    if lateral_m == 0.0:
        return points
    h = polyline_headings(points)
    return points + lateral_m * np.stack([-np.sin(h), np.cos(h)], -1)


@dataclass(frozen=True, eq=False)
class RoadGeometry:
    """The map and the ego route as arrays, shared by every variant of a batch.

    Attributes:
        lane_ids: lane ids, index = lane code.
        lane_points: (Q, 2) lane centre samples (1 m apart) [m]; row Q-1 is a far sentinel.
        lane_point_heading: (Q,) [rad].
        lane_point_lane: (Q,) lane code.
        lane_point_s: (Q,) arc length on its lane [m].
        chain_points: (NL, C, 2) each lane followed by its first successors, 1 m apart [m].
        chain_heading: (NL, C) [rad].
        lane_grid: candidate lane points near any location (nearest-point queries).
        ref_grid: candidate reference points near any location.
        ref_lane_s: (R,) arc length of each reference point on its own lane [m].
        ref_points: (R, 2) ego reference line, 0.5 m apart, extended beyond the route end [m].
        ref_heading, ref_kappa: (R,) [rad], [1/m].
        ref_speed_limit: (R,) [m/s]; ref_junction: (R,) bool; ref_lane: (R,) lane code.
        route_length_m: length of the ego route [m].
        start_s_m, destination_s_m: ego start and mission end along the reference [m].
    """

    lane_ids: tuple[str, ...]
    lane_points: np.ndarray
    lane_point_heading: np.ndarray
    lane_point_lane: np.ndarray
    lane_point_s: np.ndarray
    chain_points: np.ndarray
    chain_heading: np.ndarray
    lane_grid: NearestGrid
    ref_grid: NearestGrid
    ref_lane_s: np.ndarray
    ref_points: np.ndarray
    ref_heading: np.ndarray
    ref_kappa: np.ndarray
    ref_speed_limit: np.ndarray
    ref_junction: np.ndarray
    ref_lane: np.ndarray
    ref_half_width: np.ndarray
    route_length_m: float
    start_s_m: float
    destination_s_m: float

    def ref_index(self, s: np.ndarray) -> np.ndarray:
        return clip((s / REF_SPACING_M).astype(np.int64), 0, self.ref_points.shape[0] - 1)

    @functools.cached_property
    def ref_table(self) -> np.ndarray:
        """(R, 8) per reference point: x, y, heading, curvature, the next point's x and y (the
        last point's own), cos and sin of the heading; one gather reads all of them."""
        nxt = np.vstack([self.ref_points[1:], self.ref_points[-1:]])
        return np.column_stack([self.ref_points, self.ref_heading, self.ref_kappa, nxt,
                                np.cos(self.ref_heading), np.sin(self.ref_heading)])


@functools.lru_cache(maxsize=16)
def road_geometry(lanes: tuple[Lane, ...], route: tuple[str, ...], start_s_m: float,
                  destination_s_m: float | None) -> RoadGeometry:
    """Compile the map and the ego route (cached: a batch shares one map)."""
    by_id = {ln.id: ln for ln in lanes}
    code = {ln.id: i for i, ln in enumerate(lanes)}
    pts, head, lane_of, s_of = [], [], [], []
    chains = []
    for i, ln in enumerate(lanes):
        poly = _polyline(ln.centerline)
        length = _length(poly)
        n = max(2, int(math.ceil(length)) + 1)
        rp, ds = resample_polyline(poly, n)
        pts.append(rp)
        head.append(polyline_headings(rp))
        lane_of.append(np.full(n, i))
        s_of.append(np.arange(n) * ds)
        route_ids = [ln.id]
        total = length
        cur = ln
        while total < length + CHAIN_EXTRA_M and cur.successors and len(route_ids) < 20:
            cur = by_id[cur.successors[0]]
            route_ids.append(cur.id)
            total += _length(_polyline(cur.centerline))
        chains.append(_concat(by_id, route_ids))
    lane_points = np.vstack([*pts, [[1e7, 1e7]]])
    lane_heading = np.concatenate([*head, [0.0]])
    lane_lane = np.concatenate([*lane_of, [0]])
    lane_s = np.concatenate([*s_of, [0.0]])
    cmax = int(max(math.ceil(_length(c)) for c in chains) + CHAIN_EXTRA_M) + 1
    chain_pts = np.zeros((len(lanes), cmax, 2))
    for i, c in enumerate(chains):
        ext = _extend(c, CHAIN_EXTRA_M + 1.0)
        length = _length(ext)
        rp, _ = resample_polyline(ext, int(math.ceil(length)) + 1)
        # resample at exactly 1 m
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rp, axis=0).T))])
        t = np.arange(cmax, dtype=np.float64)
        chain_pts[i, :, 0] = np.interp(t, s, rp[:, 0])
        chain_pts[i, :, 1] = np.interp(t, s, rp[:, 1])
    chain_heading = polyline_headings(chain_pts)
    lane_grid = NearestGrid.build(lane_points[:-1], GRID_CELL_M, GRID_CANDIDATES, 10.0)
    # ego reference line
    route_poly = _concat(by_id, route)
    route_len = _length(route_poly)
    ext = _extend(route_poly, 60.0)
    count = int(math.ceil(_length(ext) / REF_SPACING_M)) + 1
    s_knots = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ext, axis=0).T))])
    rs = np.arange(count) * REF_SPACING_M
    ref = np.stack([np.interp(rs, s_knots, ext[:, 0]), np.interp(rs, s_knots, ext[:, 1])], -1)
    ref_heading = polyline_headings(ref)
    ref_kappa = polyline_curvature(ref, REF_SPACING_M)
    bounds = np.cumsum([0.0] + [_length(_polyline(by_id[r].centerline)) for r in route])
    lane_idx = clip(np.searchsorted(bounds, rs, side="right") - 1, 0, len(route) - 1)
    ref_limit = np.array([by_id[route[i]].speed_limit_mps for i in lane_idx])
    ref_junction = np.array([by_id[route[i]].is_junction for i in lane_idx])
    ref_lane = np.array([code[route[i]] for i in lane_idx])
    ref_lane_s = rs - bounds[lane_idx]
    ref_half_width = np.array([by_id[route[i]].width_m / 2 for i in lane_idx])
    return RoadGeometry(
        lane_ids=tuple(ln.id for ln in lanes),
        lane_points=lane_points, lane_point_heading=lane_heading, lane_point_lane=lane_lane,
        lane_point_s=lane_s, chain_points=chain_pts, chain_heading=chain_heading,
        lane_grid=lane_grid, ref_grid=NearestGrid.build(ref, 1.0, 4, 12.0),
        ref_lane_s=ref_lane_s,
        ref_points=ref, ref_heading=ref_heading, ref_kappa=ref_kappa, ref_speed_limit=ref_limit,
        ref_junction=ref_junction, ref_lane=ref_lane, ref_half_width=ref_half_width,
        route_length_m=route_len, start_s_m=start_s_m,
        destination_s_m=route_len if destination_s_m is None else destination_s_m,
    )


def route_s_of_lane(road_route: Sequence[str], lanes: Sequence[Lane], lane_id: str, s: float
                    ) -> float:
    """Arc length along the ego route of a point ``s`` on ``lane_id`` (nan if off-route)."""
    by_id = {ln.id: ln for ln in lanes}
    acc = 0.0
    for r in road_route:
        if r == lane_id:
            return acc + s
        acc += _length(_polyline(by_id[r].centerline))
    return float("nan")


@dataclass(frozen=True, eq=False)
class BatchWorld:
    """N variants of one scenario structure as arrays (N = batch, A = actors, E = objects,
    G = areas, L = traffic lights, P = actor path samples).

    Attributes:
        road: shared :class:`RoadGeometry`.
        dt_s: step [s]; num_ticks: steps per run.
        seeds: (N,) uint64.
        actor_ids, object_ids, area_ids, light_ids: ids in array order.
        actor_kind: (N, A) int (KIND_*); actor_model: (N, A) int (MODEL_CODES, -1 none).
        actor_dims: (N, A, 3) length, width, height [m]; actor_rgb: (N, A, 3);
        actor_color: (N, A) colour code (index into COLOR_NAMES).
        actor_path: (N, A, P, 2) [m]; actor_path_ds: (N, A) spacing [m];
        actor_path_heading: (N, A, P) [rad]; actor_start_s: (N, A) [m].
        actor_path_count: (N, A) int, the samples of each path: each variant samples its
            paths as it would alone, and the samples past its count repeat its last one (P is
            the batch's largest count), so a variant's result does not depend on the batch it
            is in.
        actor_profile_t, actor_profile_v: (N, A, K) speed-profile knots [s], [m/s].
        actor_reactive: (N, A) bool; actor_reactive_gap: (N, A) [m].
        object_kind: (N, E); object_pos: (N, E, 2); object_yaw: (N, E); object_dims: (N, E, 3).
        area_edges: (GE, 4) polygon edges; area_edge_owner: (GE,); area_kind: (G,)
            0 building, 1 vegetation; area_enabled: (N, G) bool; area_height: (G,).
        light_pos: (L, 2); light_facing: (L,); light_stop_xy: (L, 2);
        light_stop_route_s: (L,) stop line along the ego route (nan off-route) [m];
        light_mode: (N, L) 0 fixed 1 cycle; light_color: (N, L) LIGHT_CODES;
        light_green/yellow/red/offset: (N, L) [s]; light_enabled: (N, L) bool.
        weather: (N, 5) cloudiness, precipitation, fog, sun azimuth [deg], sun altitude [deg].
        ego_dims: (3,) [m].
    """

    road: RoadGeometry
    dt_s: float
    num_ticks: int
    seeds: np.ndarray
    actor_ids: tuple[str, ...]
    actor_kind: np.ndarray
    actor_model: np.ndarray
    actor_dims: np.ndarray
    actor_rgb: np.ndarray
    actor_color: np.ndarray
    actor_path: np.ndarray
    actor_path_ds: np.ndarray
    actor_path_heading: np.ndarray
    actor_path_count: np.ndarray
    actor_start_s: np.ndarray
    actor_profile_t: np.ndarray
    actor_profile_v: np.ndarray
    actor_reactive: np.ndarray
    actor_reactive_gap: np.ndarray
    object_ids: tuple[str, ...]
    object_kind: np.ndarray
    object_pos: np.ndarray
    object_yaw: np.ndarray
    object_dims: np.ndarray
    area_ids: tuple[str, ...]
    area_edges: np.ndarray
    area_edge_owner: np.ndarray
    area_kind: np.ndarray
    area_enabled: np.ndarray
    area_height: np.ndarray
    light_ids: tuple[str, ...]
    light_pos: np.ndarray
    light_facing: np.ndarray
    light_stop_xy: np.ndarray
    light_stop_route_s: np.ndarray
    light_mode: np.ndarray
    light_color: np.ndarray
    light_green: np.ndarray
    light_yellow: np.ndarray
    light_red: np.ndarray
    light_offset: np.ndarray
    light_enabled: np.ndarray
    weather: np.ndarray
    ego_dims: np.ndarray

    @property
    def batch_size(self) -> int:
        return int(self.seeds.shape[0])


def _structure(s: Scenario) -> tuple[object, ...]:
    return (s.lanes, s.ego.route, s.ego.start_s_m, s.ego.destination_s_m, s.dt_s, s.duration_s,
            tuple(a.id for a in s.actors), tuple(o.id for o in s.objects),
            tuple((a.id, a.polygon) for a in s.areas),
            tuple((t.id, t.position, t.facing_rad, t.stop_lane, t.stop_s_m)
                  for t in s.traffic_lights))


def _actor_path(s: Scenario, i: int) -> np.ndarray:
    a = s.actors[i]
    by_id = {ln.id: ln for ln in s.lanes}
    base = _concat(by_id, a.route) if a.route else _polyline(a.waypoints)
    return _extend(_offset(base, a.lateral_offset_m), 40.0)


def _check_structure(scenarios: Sequence[Scenario]) -> None:
    """Refuse a batch whose variants differ in more than their properties."""
    if not scenarios:
        raise ScenarioError("a batch needs at least one scenario")
    key = _structure(scenarios[0])
    for k, s in enumerate(scenarios[1:], 1):
        if _structure(s) != key:
            raise ScenarioError(
                f"variant {k} ({s.name}): differs from variant 0 in its structure",
                "a batch varies properties (models, colours, poses, speeds, weather, policies, "
                "parameters) of one map, ego route and set of entities")


def _actor_paths(scenarios: Sequence[Scenario]) -> dict[str, np.ndarray]:
    """The actors' resampled paths (N, A, P, 2), their headings (N, A, P), spacing (N, A) [m]
    and point counts (N, A).

    Variants of a batch mostly share their actors' paths: each distinct path (a function of
    the route, waypoints and offset on the batch's one map), its resampling and a variant's
    headings are computed once and copied (the same values). Each variant samples its paths
    with its own count (as alone in a batch): a batch-wide count made a variant's result
    depend on the other variants' path lengths.
    """
    n, na = len(scenarios), len(scenarios[0].actors)
    path_keys = [[(a.route, a.waypoints, a.lateral_offset_m) for a in s.actors]
                 for s in scenarios]
    known: dict[tuple[object, ...], np.ndarray] = {}
    lengths: dict[tuple[object, ...], float] = {}
    for s, row in zip(scenarios, path_keys, strict=True):
        for i, key in enumerate(row):
            if key not in known:
                known[key] = _actor_path(s, i)
                lengths[key] = _length(known[key])
    counts = [max([int(math.ceil(lengths[k] / ACTOR_PATH_SPACING_M)) + 1 for k in row] + [2])
              for row in path_keys]
    npts = max(counts)
    actor_path = np.zeros((n, na, npts, 2))
    actor_heading = np.zeros((n, na, npts))
    actor_ds = np.zeros((n, na))
    sampled: dict[tuple[object, ...], tuple[np.ndarray, float]] = {}
    headings: dict[tuple[object, ...], np.ndarray] = {}
    for v, c in enumerate(counts):
        for i, key in enumerate(path_keys[v]):
            got = sampled.get((key, c))
            if got is None:
                got = sampled[key, c] = resample_polyline(known[key], c)
            actor_path[v, i, :c], actor_ds[v, i] = got
        if na:
            actor_path[v, :, c:] = actor_path[v, :, c - 1:c]
            hkey = (tuple(path_keys[v]), c)
            if hkey not in headings:
                headings[hkey] = polyline_headings(actor_path[v, :, :c])
            actor_heading[v, :, :c] = headings[hkey]
            actor_heading[v, :, c:] = actor_heading[v, :, c - 1:c]
    return {"actor_path": actor_path, "actor_path_ds": actor_ds,
            "actor_path_heading": actor_heading,
            "actor_path_count": np.broadcast_to(np.asarray(counts, dtype=np.int64)[:, None],
                                                (n, na))}


def _speed_profiles(scenarios: Sequence[Scenario]) -> dict[str, np.ndarray]:
    """The actors' speed-profile knots, padded to one count: times (N, A, K) [s] (padding
    far in the future) and speeds (N, A, K) [m/s]."""
    n, na = len(scenarios), len(scenarios[0].actors)
    kmax = max([len(a.speed_profile) for s in scenarios for a in s.actors] + [1])
    prof_t = np.zeros((n, na, kmax))
    prof_v = np.zeros((n, na, kmax))
    for v, s in enumerate(scenarios):
        for i, a in enumerate(s.actors):
            knots = list(a.speed_profile) + [a.speed_profile[-1]] * (kmax - len(a.speed_profile))
            last_t = a.speed_profile[-1][0]
            for k, (t, sp) in enumerate(knots):
                prof_t[v, i, k] = t if k < len(a.speed_profile) else last_t + 1e3 * (k + 1)
                prof_v[v, i, k] = sp
    return {"actor_profile_t": prof_t, "actor_profile_v": prof_v}


def _area_fields(first: Scenario) -> dict[str, np.ndarray]:
    """The areas' polygon edges (E, 4) [x0, y0, x1, y1], each edge's area, kinds, heights."""
    edges, owner = [], []
    for g, area in enumerate(first.areas):
        poly = _polyline(area.polygon)
        for j in range(len(poly)):
            edges.append([*poly[j], *poly[(j + 1) % len(poly)]])
            owner.append(g)
    return {"area_edges": np.array(edges, dtype=np.float64).reshape(-1, 4),
            "area_edge_owner": np.array(owner, dtype=np.int64),
            "area_kind": np.array([0 if a.kind == "building" else 1 for a in first.areas],
                                  np.int64),
            "area_height": np.array([a.height_m for a in first.areas], dtype=np.float64)}


def _light_geometry(first: Scenario) -> dict[str, np.ndarray]:
    """The lights' positions and facings, stop points (L, 2) [m] and their arc length along
    the ego's route [m]."""
    lanes_by_id = {ln.id: ln for ln in first.lanes}
    stop_xy = [list(point_at(lanes_by_id[tl.stop_lane].centerline, tl.stop_s_m)[:2])
               for tl in first.traffic_lights]
    lights = first.traffic_lights
    return {"light_pos": np.array([t.position for t in lights], np.float64).reshape(-1, 2),
            "light_facing": np.array([t.facing_rad for t in lights], np.float64),
            "light_stop_xy": np.array(stop_xy, np.float64).reshape(-1, 2),
            "light_stop_route_s": np.array([route_s_of_lane(first.ego.route, first.lanes,
                                                            t.stop_lane, t.stop_s_m)
                                            for t in lights])}


def _per_variant(scenarios: Sequence[Scenario]) -> dict[str, np.ndarray]:
    """The properties a batch's variants may differ in, one row per variant."""
    first = scenarios[0]
    n, na, ne = len(scenarios), len(first.actors), len(first.objects)
    nl = len(first.traffic_lights)
    kind_code = {"vehicle": KIND_VEHICLE, "cyclist": KIND_CYCLIST, "pedestrian": KIND_PEDESTRIAN}

    def arr(f, shape, dtype=np.float64):  # noqa: ANN001, ANN202
        return np.array([f(s) for s in scenarios], dtype=dtype).reshape((n, *shape))

    return {
        "actor_kind": arr(lambda s: [kind_code[a.kind] for a in s.actors], (na,), np.int64),
        "actor_model": arr(lambda s: [MODEL_CODES[a.model] if a.kind == "vehicle" else -1
                                      for a in s.actors], (na,), np.int64),
        "actor_dims": arr(lambda s: [a.dimensions for a in s.actors], (na, 3)),
        "actor_rgb": arr(lambda s: [COLORS[a.color] for a in s.actors], (na, 3)),
        "actor_color": arr(lambda s: [COLOR_NAMES.index(a.color) for a in s.actors], (na,),
                           np.int64),
        "actor_start_s": arr(lambda s: [a.start_s_m for a in s.actors], (na,)),
        "actor_reactive": arr(lambda s: [a.reactive for a in s.actors], (na,), bool),
        "actor_reactive_gap": arr(lambda s: [a.reactive_gap_m for a in s.actors], (na,)),
        "object_kind": arr(lambda s: [KIND_CONE + OBJECT_KINDS.index(o.kind) for o in s.objects],
                           (ne,), np.int64),
        "object_pos": arr(lambda s: [o.position for o in s.objects], (ne, 2)),
        "object_yaw": arr(lambda s: [o.yaw_rad for o in s.objects], (ne,)),
        "object_dims": arr(lambda s: [o.dimensions for o in s.objects], (ne, 3)),
        "area_enabled": arr(lambda s: [a.enabled for a in s.areas], (len(first.areas),), bool),
        "light_mode": arr(lambda s: [t.policy.mode == "cycle" for t in s.traffic_lights], (nl,),
                          np.int64),
        "light_color": arr(lambda s: [LIGHT_CODES[t.policy.color] for t in s.traffic_lights],
                           (nl,), np.int64),
        "light_green": arr(lambda s: [t.policy.green_s for t in s.traffic_lights], (nl,)),
        "light_yellow": arr(lambda s: [t.policy.yellow_s for t in s.traffic_lights], (nl,)),
        "light_red": arr(lambda s: [t.policy.red_s for t in s.traffic_lights], (nl,)),
        "light_offset": arr(lambda s: [t.policy.offset_s for t in s.traffic_lights], (nl,)),
        "light_enabled": arr(lambda s: [t.enabled for t in s.traffic_lights], (nl,), bool),
        "weather": arr(lambda s: [s.weather.cloudiness, s.weather.precipitation,
                                  s.weather.fog_density, s.weather.sun_azimuth_deg,
                                  s.weather.sun_altitude_deg], (5,)),
    }


def compile_batch(scenarios: Sequence[Scenario], seeds: Sequence[int]) -> BatchWorld:
    """Stack N scenario variants (same structure) into a :class:`BatchWorld`."""
    _check_structure(scenarios)
    first = scenarios[0]
    road = road_geometry(first.lanes, first.ego.route, first.ego.start_s_m,
                         first.ego.destination_s_m)
    return BatchWorld(
        road=road, dt_s=first.dt_s, num_ticks=first.num_ticks,
        seeds=np.array([int(x) & 0xFFFFFFFFFFFF for x in seeds], dtype=np.uint64),
        actor_ids=tuple(a.id for a in first.actors),
        object_ids=tuple(o.id for o in first.objects),
        area_ids=tuple(a.id for a in first.areas),
        light_ids=tuple(t.id for t in first.traffic_lights),
        ego_dims=np.array([EGO_LENGTH_M, EGO_WIDTH_M, 1.6]),
        **_actor_paths(scenarios), **_speed_profiles(scenarios), **_area_fields(first),
        **_light_geometry(first), **_per_variant(scenarios),
    )


def light_state(world: BatchWorld, t: float) -> np.ndarray:
    """Colour code of every light at time ``t`` [s], shape (N, L) (0 off/disabled)."""
    cycle = world.light_green + world.light_yellow + world.light_red
    phase = np.mod(t + world.light_offset, cycle)
    cyc = np.where(phase < world.light_green, LIGHT_CODES["green"],
                   np.where(phase < world.light_green + world.light_yellow,
                            LIGHT_CODES["yellow"], LIGHT_CODES["red"]))
    color = np.where(world.light_mode == 1, cyc, world.light_color)
    return np.where(world.light_enabled, color, LIGHT_CODES["off"])


def road_friction(precipitation: np.ndarray) -> np.ndarray:
    """Tyre-road friction coefficient from precipitation in [0, 100]: 0.9 dry, 0.4 soaked."""
    return 0.9 - 0.5 * clip(precipitation, 0.0, 100.0) / 100.0


#: lateral offset [m] reported for points too far from the reference line to project on it
FAR_LATERAL_M = 1000.0


def project_on_reference(road: RoadGeometry, x: np.ndarray, y: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Project points (any shape) on the ego reference line.

    Points farther from the line than its grid reaches (about 12 m) have no nearest point; they
    are projected on the tangent at the line's last point, and their lateral offset is
    FAR_LATERAL_M (with the projection's sign), so that no caller takes them for something
    beside the path: measured on that tangent, on a curved route a vehicle on a road the ego
    never comes near could land a few metres beside the path just ahead.

    Returns:
        (index of the nearest reference point, arc length s [m], signed lateral offset [m],
        positive left).
    """
    from rocas.sim.geometry import nearest_on

    idx, _ = nearest_on(road.ref_grid, x, y)
    last = road.ref_points.shape[0] - 1
    far = idx > last
    idx = np.minimum(idx, last)
    row = np.take(road.ref_table, idx, axis=0)
    rx, ry, c, s = row[..., 0], row[..., 1], row[..., 6], row[..., 7]
    dx, dy = x - rx, y - ry
    lateral = -dx * s + dy * c
    lateral = np.where(far, np.where(lateral < 0.0, -FAR_LATERAL_M, FAR_LATERAL_M), lateral)
    return idx, idx * REF_SPACING_M + dx * c + dy * s, lateral


def reference_at(road: RoadGeometry, s: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Interpolate the reference line at arc lengths s (any shape): x, y, heading, curvature."""
    r = road.ref_points.shape[0]
    f = clip(s / REF_SPACING_M, 0.0, r - 1.000001)
    i = f.astype(np.int64)
    u = f - i
    row = np.take(road.ref_table, i, axis=0)
    x0, y0 = row[..., 0], row[..., 1]
    return (x0 + u * (row[..., 4] - x0), y0 + u * (row[..., 5] - y0), row[..., 2], row[..., 3])
