"""Perception: detection with range, field of view, occlusion and weather; tracking; the
front-camera brake classifier; traffic-light recognition.

Obstacle slots: slot m < A is actor m, slot A + e is map object e (cones, boxes). A slot's
track id changes when the association gate is violated (an id switch), as real trackers do.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.sim import rng
from rocas.sim.geometry import clip, segments_blocked_by_edge, wrap_angle
from rocas.sim.world import (
    KIND_BOX,
    KIND_CONE,
    KIND_CYCLIST,
    KIND_PEDESTRIAN,
    LIGHT_CODES,
    BatchWorld,
)
from rocas.stacks.ads import classifier
from rocas.stacks.ads.localization import LocalizationOutput

# PerceptionObstacle.Type / SubType codes (see perception.proto)
T_UNKNOWN_MOVABLE, T_UNKNOWN_UNMOVABLE, T_PEDESTRIAN, T_BICYCLE, T_VEHICLE = 1, 2, 3, 4, 5
ST_UNKNOWN, ST_CAR, ST_SUV, ST_TRUCK, ST_BUS, ST_CYCLIST, ST_PEDESTRIAN, ST_CONE, ST_BOX = range(9)
# TrafficLight.Color codes
TL_UNKNOWN, TL_RED, TL_YELLOW, TL_GREEN, TL_BLACK = 0, 1, 2, 3, 4
_SIM_TO_TL = np.array([TL_BLACK, TL_RED, TL_YELLOW, TL_GREEN])  # index = LIGHT_CODES value
_STREAM_DET = 100
POSITION_GAIN = 0.6  # share of the innovation applied to a track's position


@dataclass(frozen=True, eq=False)
class ObstacleFrame:
    """Ground truth the sensors see at one instant (world frame), each (N, M) unless noted.

    Attributes:
        x, y [m]; yaw [rad]; length, width, height [m]; kind (KIND_*); model (-1 none);
        rgb (N, M, 3); color (colour code).
    """

    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    length: np.ndarray
    width: np.ndarray
    height: np.ndarray
    kind: np.ndarray
    model: np.ndarray
    rgb: np.ndarray
    color: np.ndarray


@dataclass(frozen=True, eq=False)
class PerceptionOutput:
    """Published perception results; obstacle fields (N, M) in the ego frame (x forward,
    y left), velocities absolute but expressed in ego axes.

    Attributes:
        published: (N, M) bool, slot carries a published track.
        track_id: (N, M) int.
        type, sub_type: proto enum codes; color: colour code or -1 (unknown).
        x, y [m], theta [rad], vx, vy [m/s], ax, ay [m/s^2]; length, width, height [m];
        confidence [0, 1]; tracking_time [s].
        ego_x, ego_y, ego_heading: (N,) pose the ego frame refers to (localization estimate).
        brake_probability, brake_threshold: (N,); brake: (N,) bool.
        tl_detected: (N, L) bool; tl_color: (N, L) proto colour; tl_confidence: (N, L);
        tl_distance: (N, L) distance to the light's stop line [m]; tl_selected: (N,) light
        index or -1.
    """

    published: np.ndarray
    track_id: np.ndarray
    type: np.ndarray
    sub_type: np.ndarray
    color: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    length: np.ndarray
    width: np.ndarray
    height: np.ndarray
    confidence: np.ndarray
    tracking_time: np.ndarray
    ego_x: np.ndarray
    ego_y: np.ndarray
    ego_heading: np.ndarray
    brake_probability: np.ndarray
    brake_threshold: np.ndarray
    brake: np.ndarray
    tl_detected: np.ndarray
    tl_color: np.ndarray
    tl_confidence: np.ndarray
    tl_distance: np.ndarray
    tl_selected: np.ndarray


@dataclass(frozen=True, eq=False)
class SensorView:
    """Where each obstacle is seen from the true ego pose, each (N, M): rx (forward), ry
    (left) [m] in the ego frame, dist [m], bearing [rad]."""

    rx: np.ndarray
    ry: np.ndarray
    dist: np.ndarray
    bearing: np.ndarray


@dataclass(frozen=True, eq=False)
class Detection:
    """What the detector reports this cycle, each (N, M): detected (bool), confidence
    [0, 1], visible (fraction not occluded), eff_range (the detection range after the
    weather and the glare) [m]."""

    detected: np.ndarray
    confidence: np.ndarray
    visible: np.ndarray
    eff_range: np.ndarray


@dataclass(frozen=True, eq=False)
class Measurement:
    """The detector's noisy boxes in the world frame, each (N, M): x, y [m], yaw [rad] in
    [-pi/2, pi/2) (orientation modulo pi), length, width [m]."""

    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    length: np.ndarray
    width: np.ndarray


def no_lights(n: int) -> dict[str, np.ndarray]:
    """The traffic-light fields of a perception output for N variants in a world without lights."""
    z = np.zeros((n, 0))
    return {"tl_detected": z.astype(bool), "tl_color": z.astype(np.int64),
            "tl_confidence": z, "tl_distance": z, "tl_selected": np.full(n, -1)}


class Perception:
    """Sensors + detector + tracker + camera classifier + traffic-light recogniser."""

    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray], period_s: float
                 ) -> None:
        self.world = world
        self.p = {k.split(".", 1)[1]: v for k, v in params.items() if k.startswith("perception.")}
        self.period = period_s
        self._opacity: np.ndarray | None = None
        n = world.batch_size
        m = len(world.actor_ids) + len(world.object_ids)
        self.track_id = np.full((n, m), -1, dtype=np.int64)
        self.next_id = np.ones(n, dtype=np.int64)
        self.tx = np.zeros((n, m))
        self.ty = np.zeros((n, m))
        self.tvx = np.zeros((n, m))
        self.tvy = np.zeros((n, m))
        self.tax = np.zeros((n, m))
        self.tay = np.zeros((n, m))
        self.theading = np.zeros((n, m))
        self.hits = np.zeros((n, m), dtype=np.int64)
        self.missed = np.zeros((n, m), dtype=np.int64)
        self.age = np.zeros((n, m))
        self.brake_frames = np.zeros(n, dtype=np.int64)
        self.weights = classifier.load_weights()
        self._weather_consts: dict[str, np.ndarray] | None = None
        self._slot_consts: dict[str, np.ndarray] | None = None
        edges = world.area_edges
        self.edge_weight_kind = world.area_kind[world.area_edge_owner] if len(edges) else None

    # -- helpers -----------------------------------------------------------------------------
    def _weather(self) -> dict[str, np.ndarray]:
        """What the weather and the parameters fix for a run (computed once)."""
        if self._weather_consts is None:
            p = self.p
            w = self.world.weather
            fog = w[:, 2] / 100.0
            rain = w[:, 1] / 100.0
            sun_alt = w[:, 4]
            self._weather_consts = {
                "sun_az": np.deg2rad(w[:, 3]),
                "sun_low": (sun_alt < p["glare_sun_altitude_deg"]) & (sun_alt > -2.0),
                "glare_window": np.deg2rad(p["glare_azimuth_window_deg"]),
                "factor": (1.0 - p["fog_range_factor"] * fog)
                * (1.0 - p["precipitation_range_factor"] * rain),
                "glare_keep": 1.0 - p["glare_range_factor"],
                "blur": 1.0 + p["weather_noise_gain"][:, None] * (
                    0.6 * w[:, 2:3] / 100.0 + 0.4 * w[:, 1:2] / 100.0),
                "fov_half": np.deg2rad(p["fov_deg"])[:, None] / 2,
                "tl_facing_tol": np.deg2rad(p["tl_facing_tolerance_deg"])[:, None],
                "tl_fov_half": np.deg2rad(p["tl_fov_deg"])[:, None] / 2,
            }
        return self._weather_consts

    def _range_factor(self, ego_yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c = self._weather()
        glare = c["sun_low"] & (np.abs(wrap_angle(ego_yaw - c["sun_az"])) < c["glare_window"])
        factor = c["factor"]
        return factor * np.where(glare, c["glare_keep"], 1.0), glare, factor

    def _slots(self, gt: ObstacleFrame) -> dict[str, np.ndarray]:
        """What the obstacle slots' kinds, models and heights fix (the world's fixed slots:
        computed once, again only if given other arrays)."""
        got = self._slot_consts
        if got is None or got["_kind"] is not gt.kind or got["_model"] is not gt.model \
                or got["_height"] is not gt.height:
            p = self.p
            kind = gt.kind
            vru = (kind == KIND_CYCLIST) | (kind == KIND_PEDESTRIAN)
            static_obj = (kind == KIND_CONE) | (kind == KIND_BOX)
            is_ped = kind == KIND_PEDESTRIAN
            is_bike = kind == KIND_CYCLIST
            got = self._slot_consts = {
                "_kind": kind, "_model": gt.model, "_height": gt.height,
                "static_obj": static_obj, "movable": ~static_obj,
                "base_range": np.where(vru, p["pedestrian_range_m"][:, None],
                                       np.where(static_obj, p["static_object_range_m"][:, None],
                                                p["max_range_m"][:, None])),
                "tall": gt.height >= p["min_obstacle_height_m"][:, None],
                "type_known": np.where(is_ped, T_PEDESTRIAN, np.where(is_bike, T_BICYCLE,
                                                                      T_VEHICLE)),
                "is_cone": kind == KIND_CONE, "is_box": kind == KIND_BOX,
                "sub_known": np.where(is_ped, ST_PEDESTRIAN, np.where(
                    is_bike, ST_CYCLIST, clip(gt.model, 0, 3) + ST_CAR)),
            }
        return got

    def _edge_opacity(self) -> np.ndarray:
        """(E, N, 1, 1) how much each area edge hides what is behind it (0 for an area a variant
        disabled); fixed for a run, computed once."""
        if self._opacity is None:
            w = self.world
            enabled = w.area_enabled[:, w.area_edge_owner]  # (N, E)
            opacity = np.where(self.edge_weight_kind == 0, 1.0,
                               self.p["vegetation_opacity"][:, None])  # (N, E)
            self._opacity = np.ascontiguousarray(np.where(enabled, opacity, 0.0).T)[..., None, None]
        return self._opacity

    def _visibility(self, ex: np.ndarray, ey: np.ndarray, gt: ObstacleFrame) -> np.ndarray:
        """Visible fraction of each obstacle (N, M) from three sample points."""
        w = self.world
        if w.area_edges.shape[0] == 0 or gt.x.shape[1] == 0:
            return np.ones_like(gt.x)
        c, s = np.cos(gt.yaw), np.sin(gt.yaw)
        hl = gt.length / 2
        px = np.stack([gt.x, gt.x + hl * c, gt.x - hl * c], -1)  # (N, M, 3)
        py = np.stack([gt.y, gt.y + hl * s, gt.y - hl * s], -1)
        # (E, N, M, 3): the edges first, so that the largest opacity is a fast outer reduction
        crosses = segments_blocked_by_edge(ex[:, None, None], ey[:, None, None], px, py,
                                           w.area_edges)
        block = np.maximum.reduce(np.where(crosses, self._edge_opacity(), 0.0), axis=0)
        return (1.0 - block).mean(axis=-1)

    # -- the step -----------------------------------------------------------------------------
    def step(self, tick: int, ego_x: np.ndarray, ego_y: np.ndarray, ego_yaw: np.ndarray,
             gt: ObstacleFrame, light_colors: np.ndarray, loc: LocalizationOutput
             ) -> PerceptionOutput:
        """One perception cycle: what the sensors detect, measured and tracked, classified,
        the camera's brake decision and the traffic lights, published in the ego frame of the
        localization estimate."""
        p = self.p
        view = _sensor_view(ego_x, ego_y, ego_yaw, gt)
        factor, glare, _ = self._range_factor(ego_yaw)
        slots = self._slots(gt)
        det = self._detect(ego_x, ego_y, gt, view, slots, factor)
        lc, ls = np.cos(loc.heading)[:, None], np.sin(loc.heading)[:, None]
        meas = self._measure(tick, view, det, gt, ego_yaw, loc, lc, ls)
        new = self._track(det.detected, meas)
        self._resolve_heading(det.detected, new, meas.yaw)
        published = (self.track_id >= 0) & (self.hits >= p["track_min_hits"][:, None])
        typ, sub, color = self._classify(det.confidence, view.dist, slots, gt)
        # publish in the ego frame of the localization estimate
        ddx, ddy = self.tx - loc.x[:, None], self.ty - loc.y[:, None]
        out_x = ddx * lc + ddy * ls
        out_y = -ddx * ls + ddy * lc
        brake_prob, brake = self._brake(view.bearing, view.dist, gt, det.visible * det.detected,
                                        glare)
        tl = self._lights(ego_x, ego_y, ego_yaw, light_colors, factor)
        return PerceptionOutput(
            published=published, track_id=self.track_id.copy(), type=typ, sub_type=sub,
            color=color, x=out_x, y=out_y, theta=wrap_angle(self.theading - loc.heading[:, None]),
            vx=self.tvx * lc + self.tvy * ls, vy=-self.tvx * ls + self.tvy * lc,
            ax=self.tax * lc + self.tay * ls, ay=-self.tax * ls + self.tay * lc,
            length=meas.length, width=meas.width, height=gt.height, confidence=det.confidence,
            tracking_time=self.age, ego_x=loc.x, ego_y=loc.y, ego_heading=loc.heading,
            brake_probability=brake_prob, brake_threshold=p["brake_threshold"], brake=brake,
            **tl,
        )

    def _detect(self, ego_x: np.ndarray, ego_y: np.ndarray, gt: ObstacleFrame,
                view: SensorView, slots: dict[str, np.ndarray], factor: np.ndarray
                ) -> Detection:
        """Which obstacles the detector reports: within the weather's range and the field of
        view (or close behind), tall enough, visible enough and confident enough."""
        p = self.p
        dist = view.dist
        eff_range = slots["base_range"] * factor[:, None]
        in_fov = (np.abs(view.bearing) <= self._weather()["fov_half"]) | (
            dist <= p["rear_range_m"][:, None])
        visible = self._visibility(ego_x, ego_y, gt)
        conf = visible * clip(1.0 - p["confidence_range_decay"][:, None] * dist / eff_range,
                                 0.0, 1.0)
        detected = ((dist <= eff_range) & in_fov & slots["tall"]
                    & (visible >= p["occlusion_min_visible_fraction"][:, None])
                    & (conf >= p["min_confidence"][:, None]))
        return Detection(detected=detected, confidence=conf, visible=visible,
                         eff_range=eff_range)

    def _measure(self, tick: int, view: SensorView, det: Detection, gt: ObstacleFrame,
                 ego_yaw: np.ndarray, loc: LocalizationOutput, lc: np.ndarray, ls: np.ndarray
                 ) -> Measurement:
        """The detector's noisy boxes, placed in the world through the localization estimate
        (``lc``, ``ls``: (N, 1) cosine and sine of its heading); orientation modulo pi."""
        p = self.p
        w = self.world
        n, m = gt.x.shape
        noise = rng.normal(w.seeds, tick, _STREAM_DET, (m, 5)) if m else np.zeros((n, 0, 5))
        std = p["position_noise_std_m"][:, None] * (
            1.0 + p["noise_range_gain"][:, None] * view.dist / det.eff_range) \
            * self._weather()["blur"]
        mrx = view.rx + std * noise[..., 0]
        mry = view.ry + std * noise[..., 1]
        mx = loc.x[:, None] + mrx * lc - mry * ls
        my = loc.y[:, None] + mrx * ls + mry * lc
        # the detector sees box orientation modulo pi, in the world via localization
        box_yaw = gt.yaw - ego_yaw[:, None] + loc.heading[:, None] \
            + p["heading_noise_std_rad"][:, None] * noise[..., 2]
        box_yaw = wrap_angle(2.0 * box_yaw) / 2.0  # in [-pi/2, pi/2)
        mlen = np.maximum(gt.length + p["size_noise_std_m"][:, None] * noise[..., 3], 0.1)
        mwid = np.maximum(gt.width + p["size_noise_std_m"][:, None] * noise[..., 4], 0.1)
        return Measurement(x=mx, y=my, yaw=box_yaw, length=mlen, width=mwid)

    def _track(self, detected: np.ndarray, meas: Measurement) -> np.ndarray:
        """Update the tracks with the detections (associated within the gate, else a new
        track; undetected tracks coast until they have missed too many frames); returns
        (N, M) bool, the slots that started a new track."""
        p = self.p
        mx, my = meas.x, meas.y
        dt = self.period
        alive = self.track_id >= 0
        pred_x = self.tx + self.tvx * dt
        pred_y = self.ty + self.tvy * dt
        gate_ok = np.hypot(mx - pred_x, my - pred_y) <= p["track_gate_m"][:, None]
        update = detected & alive & gate_ok
        new = detected & ~update
        # alpha-beta tracker: positions corrected by a fixed gain, velocity by the
        # velocity gain (the parameter), acceleration by a fraction of it
        gain = p["velocity_filter_alpha"][:, None]
        rx_, ry_ = mx - pred_x, my - pred_y
        fx = np.where(update, pred_x + POSITION_GAIN * rx_, mx)
        fy = np.where(update, pred_y + POSITION_GAIN * ry_, my)
        nvx = np.where(update, self.tvx + gain * rx_ / dt, np.where(new, 0.0, self.tvx))
        nvy = np.where(update, self.tvy + gain * ry_ / dt, np.where(new, 0.0, self.tvy))
        nax = np.where(update, (1 - gain) * self.tax + gain * (nvx - self.tvx) / dt, 0.0)
        nay = np.where(update, (1 - gain) * self.tay + gain * (nvy - self.tvy) / dt, 0.0)
        new_ids = self.next_id[:, None] + np.cumsum(new, axis=1) - 1
        self.next_id = self.next_id + new.sum(axis=1)
        coast = ~detected & alive
        self.track_id = np.where(new, new_ids, self.track_id)
        self.tx = np.where(detected, fx, np.where(coast, pred_x, self.tx))
        self.ty = np.where(detected, fy, np.where(coast, pred_y, self.ty))
        self.tvx, self.tvy, self.tax, self.tay = nvx, nvy, nax, nay
        self.hits = np.where(new, 1, np.where(update, self.hits + 1, self.hits))
        self.missed = np.where(detected, 0, np.where(alive, self.missed + 1, 0))
        self.age = np.where(new, 0.0, np.where(alive | new, self.age + dt, 0.0))
        dead = self.missed > p["track_max_missed_frames"][:, None]
        self.track_id = np.where(dead, -1, self.track_id)
        return new

    def _resolve_heading(self, detected: np.ndarray, new: np.ndarray, box_yaw: np.ndarray
                         ) -> None:
        """Set the detected tracks' headings: the box's orientation with its pi ambiguity
        resolved by the velocity when fast, else by the track's heading so far."""
        speed = np.hypot(self.tvx, self.tvy)
        ref_dir = np.where(speed > self.p["heading_from_velocity_speed_mps"][:, None],
                           numerics.arctan2(self.tvy, self.tvx), self.theading)
        flip = np.abs(wrap_angle(box_yaw - ref_dir)) > np.pi / 2
        resolved = wrap_angle(box_yaw + np.where(flip, np.pi, 0.0))
        first = new & (self.hits == 1)
        self.theading = np.where(detected, np.where(first, box_yaw, resolved), self.theading)

    def _classify(self, conf: np.ndarray, dist: np.ndarray, slots: dict[str, np.ndarray],
                  gt: ObstacleFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, M) type, sub-type and colour code (-1: too far to tell) of each slot; movable
        obstacles seen with too little confidence are of unknown type."""
        p = self.p
        unsure = conf < p["classify_min_confidence"][:, None]
        unknown = slots["movable"] & unsure
        typ = np.where(slots["static_obj"], T_UNKNOWN_UNMOVABLE, np.where(
            unknown, T_UNKNOWN_MOVABLE, slots["type_known"]))
        sub = np.where(slots["is_cone"], ST_CONE, np.where(
            slots["is_box"], ST_BOX, np.where(unknown, ST_UNKNOWN, slots["sub_known"])))
        color = np.where(dist <= p["color_max_distance_m"][:, None], gt.color, -1)
        return typ, sub, color

    def _brake(self, bearing: np.ndarray, dist: np.ndarray, gt: ObstacleFrame,
               visible: np.ndarray, glare: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = self.p
        rel = gt.yaw - (bearing + 0.0)
        lat_extent = 0.5 * (gt.width * np.abs(np.cos(rel)) + gt.length * np.abs(np.sin(rel)))
        in_cam = (dist <= p["camera_range_m"][:, None]) & (
            np.abs(bearing) < classifier.CAMERA_HFOV_RAD / 2 + 0.3)
        feats = classifier.camera_view(
            bearing, dist, lat_extent, gt.height, gt.rgb, np.where(in_cam, visible, 0.0),
            self.world.weather[:, 2], glare * p["camera_glare_gain"])
        prob = classifier.mlp_forward(self.weights, feats)
        above = prob > p["brake_threshold"]
        self.brake_frames = np.where(above, self.brake_frames + 1, 0)
        return prob, self.brake_frames >= p["brake_min_frames"]

    def _lights(self, ex: np.ndarray, ey: np.ndarray, eyaw: np.ndarray, colors: np.ndarray,
                vis: np.ndarray) -> dict[str, np.ndarray]:
        """``vis``: (N,) the weather's and the glare's range factor (:meth:`_range_factor`)."""
        p = self.p
        w = self.world
        k = self._weather()
        n, nl = colors.shape
        if nl == 0:
            return no_lights(n)
        c, s = np.cos(eyaw)[:, None], np.sin(eyaw)[:, None]
        dx, dy = w.light_pos[:, 0] - ex[:, None], w.light_pos[:, 1] - ey[:, None]
        rx, ry = dx * c + dy * s, -dx * s + dy * c
        dist = np.hypot(rx, ry)
        facing = np.abs(wrap_angle(w.light_facing - (eyaw[:, None] + np.pi))) \
            <= k["tl_facing_tol"]
        in_view = (rx > 0) & (np.abs(numerics.arctan2(ry, rx)) <= k["tl_fov_half"])
        detected = (dist <= p["tl_max_range_m"][:, None]) & facing & in_view
        readable = vis >= p["tl_min_visibility"]
        color = np.where(readable[:, None], _SIM_TO_TL[colors], TL_UNKNOWN)
        color = np.where(colors == LIGHT_CODES["off"], TL_BLACK, color)
        score = np.where(detected, p["tl_lateral_weight"][:, None] * np.abs(ry) + 0.1 * dist,
                         np.inf)
        best = np.argmin(score, axis=1)
        selected = np.where(np.isfinite(score.min(axis=1)), best, -1)
        sx = w.light_stop_xy[:, 0] - ex[:, None]
        sy = w.light_stop_xy[:, 1] - ey[:, None]
        return {"tl_detected": detected, "tl_color": np.where(detected, color, TL_UNKNOWN),
                "tl_confidence": np.where(detected, np.broadcast_to(vis[:, None], dist.shape),
                                          0.0),
                "tl_distance": np.hypot(sx, sy), "tl_selected": selected}


def _sensor_view(ego_x: np.ndarray, ego_y: np.ndarray, ego_yaw: np.ndarray, gt: ObstacleFrame
                 ) -> SensorView:
    """The obstacles' ground truth (N, M) seen from the true ego pose (N,)."""
    ce, se = np.cos(ego_yaw)[:, None], np.sin(ego_yaw)[:, None]
    dxw, dyw = gt.x - ego_x[:, None], gt.y - ego_y[:, None]
    rx = dxw * ce + dyw * se
    ry = -dxw * se + dyw * ce
    return SensorView(rx=rx, ry=ry, dist=np.hypot(rx, ry), bearing=numerics.arctan2(ry, rx))


def sim_light_to_tl(colors: np.ndarray) -> np.ndarray:
    """TrafficLight.Color codes of simulator light codes (LIGHT_CODES values, any shape)."""
    return _SIM_TO_TL[colors]


def ground_truth(world: BatchWorld, ax: np.ndarray, ay: np.ndarray, ayaw: np.ndarray
                 ) -> ObstacleFrame:
    """Stack actor states (N, A) and the map objects into obstacle slots (N, A + E)."""
    cat = np.concatenate
    fixed = _fixed_slots(world)
    return ObstacleFrame(
        x=cat([ax, world.object_pos[..., 0]], 1), y=cat([ay, world.object_pos[..., 1]], 1),
        yaw=cat([ayaw, world.object_yaw], 1), **fixed,
    )


_FIXED_SLOTS: weakref.WeakKeyDictionary[BatchWorld, dict[str, np.ndarray]] = (
    weakref.WeakKeyDictionary())


def _fixed_slots(world: BatchWorld) -> dict[str, np.ndarray]:
    """The obstacle slots' fields no step changes (sizes, kinds, colours), stacked once."""
    got = _FIXED_SLOTS.get(world)
    if got is None:
        cat = np.concatenate
        got = _FIXED_SLOTS[world] = dict(
            length=cat([world.actor_dims[..., 0], world.object_dims[..., 0]], 1),
            width=cat([world.actor_dims[..., 1], world.object_dims[..., 1]], 1),
            height=cat([world.actor_dims[..., 2], world.object_dims[..., 2]], 1),
            kind=cat([world.actor_kind, world.object_kind], 1),
            model=cat([world.actor_model, np.full(world.object_kind.shape, -1)], 1),
            rgb=cat([world.actor_rgb, np.broadcast_to(np.array([0.95, 0.45, 0.05]),
                                                      (*world.object_kind.shape, 3))], 1),
            color=cat([world.actor_color, np.full(world.object_kind.shape, 8)], 1),  # orange
        )
    return got


