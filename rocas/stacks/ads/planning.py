"""Planning: reference line, path (nudge) and speed (IDM over follow/stop/yield constraints)
decisions, ST-overlap yield/overtake, traffic lights, perception brake, collision check.

All quantities are along the ego reference line (route s, lateral offset positive left).
:meth:`Planning.step` takes one decision per helper; the values passed between them are the
frozen records of :mod:`rocas.stacks.ads.planning_values`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocas import numerics
from rocas.sim.geometry import box_gap, clip, wrap_angle
from rocas.sim.world import REF_SPACING_M, BatchWorld, project_on_reference, reference_at
from rocas.stacks.ads.localization import ChassisOutput, LocalizationOutput
from rocas.stacks.ads.perception import (
    T_BICYCLE,
    T_PEDESTRIAN,
    TL_RED,
    TL_UNKNOWN,
    TL_YELLOW,
    PerceptionOutput,
)
from rocas.stacks.ads.planning_values import (
    EgoOnReference,
    EmergencyStop,
    ForecastGrid,
    Interactions,
    NudgePath,
    RefObstacles,
    SpeedCommand,
    StopPoints,
    StOverlap,
)
from rocas.stacks.ads.prediction import PredictionOutput

MAX_POINTS = 41
# ObjectDecision.Type
D_IGNORE, D_FOLLOW, D_YIELD, D_OVERTAKE, D_STOP, D_NUDGE = range(6)
# MainDecision.Type
M_CRUISE, M_STOP, M_ESTOP = range(3)
# ADCTrajectory.EStopReason
E_NONE, E_COLLISION, E_PERCEPTION_BRAKE, E_NO_PATH = range(4)
#: Stop/slow-down reasons (main_decision.reason).
REASONS = ("cruise", "destination", "traffic_light", "follow", "yield", "blocked_by_static",
           "vulnerable_road_user", "perception_brake", "collision_imminent", "collision_fallback")
R_CRUISE, R_DEST, R_LIGHT, R_FOLLOW, R_YIELD, R_BLOCKED, R_VRU, R_PBRAKE, R_COLL, R_FALLBACK = (
    range(10))
#: Reasons under which standing still is not justified by traffic (the oracles' unexpected
#: stop: cruising, a static blockage, a brake-classifier brake, a collision reflex).
UNJUSTIFIED_STOP_REASONS = (R_CRUISE, R_BLOCKED, R_PBRAKE, R_COLL, R_FALLBACK)
#: (len(REASONS),) bool: per reason code, whether it justifies a stop (``np.isin`` costs
#: ~150 us a call, a lookup nothing)
STOP_JUSTIFIED = ~np.isin(np.arange(len(REASONS)), UNJUSTIFIED_STOP_REASONS)
ACCEL_DECAY_S = 1.0  # [s] planned accelerations fade with this time constant
HOLD_TAU_S = 0.5  # [s] a hold behind a vehicle beside the path closes its speed error this fast
HOLD_RECOVER_S = 2.0  # [s] ... and drops back to its hold gap over this time when too close


@dataclass(frozen=True, eq=False)
class PlanningOutput:
    """The planned trajectory and decisions.

    Attributes:
        x, y [m], theta [rad], kappa [1/m], s [m along the route], v [m/s], a [m/s^2],
            t [s]: (N, K) trajectory points; valid: (N, K) bool.
        decision: (N, M) ObjectDecision type per obstacle slot; decision_s: (N, M) [m];
        nudge_offset: (N,) lateral offset of the nudge [m].
        main: (N,) MainDecision type; stop_distance: (N,) [m]; reason: (N,) index into REASONS.
        estop: (N,) bool; estop_reason: (N,) code; cruise_speed: (N,) [m/s];
        lane: (N,) lane code of the reference at the ego; total_length: (N,) [m].
        track_id: (N, M) ids the decisions refer to.
    """

    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    kappa: np.ndarray
    s: np.ndarray
    v: np.ndarray
    a: np.ndarray
    t: np.ndarray
    valid: np.ndarray
    decision: np.ndarray
    decision_s: np.ndarray
    nudge_offset: np.ndarray
    main: np.ndarray
    stop_distance: np.ndarray
    reason: np.ndarray
    estop: np.ndarray
    estop_reason: np.ndarray
    cruise_speed: np.ndarray
    lane: np.ndarray
    total_length: np.ndarray
    track_id: np.ndarray


class Planning:
    def __init__(self, world: BatchWorld, params: dict[str, np.ndarray]) -> None:
        self.world = world
        self.p = {k.split(".", 1)[1]: v for k, v in params.items() if k.startswith("planning.")}
        n = world.batch_size
        m = len(world.actor_ids) + len(world.object_ids)
        self.prev_decision = np.zeros((n, m), dtype=np.int64)
        self.prev_track = np.full((n, m), -1, dtype=np.int64)
        self.ego_hl = float(world.ego_dims[0]) / 2
        self.ego_hw = float(world.ego_dims[1]) / 2
        # what no step changes: parameter columns (N, 1), the trajectory's time grid, and the
        # IDM constraints' layout (obstacle follow gaps, then the stop points)
        self.cols = {k: v[:, None] for k, v in self.p.items()}
        p, c = self.p, self.cols
        self.preview = np.arange(0.0, 80.0, 2.0)[None, :]
        self.t = np.arange(MAX_POINTS)[None, :] * p["trajectory_time_step_s"][:, None]
        self.valid = self.t <= p["trajectory_horizon_s"][:, None] + 1e-9
        self.accel_fade = 1.0 - numerics.exp(-self.t / ACCEL_DECAY_S)  # (N, K)
        stop_reason = np.concatenate([np.full((n, m), R_YIELD), np.full((n, m), R_VRU),
                                      np.full((n, 1), R_BLOCKED), np.full((n, 1), R_LIGHT),
                                      np.full((n, 1), R_DEST)], axis=1)
        self.reasons = np.concatenate([np.full((n, m), R_FOLLOW), stop_reason], axis=1)
        self.smin = np.concatenate([
            np.broadcast_to(c["follow_distance_m"], (n, m)),
            np.broadcast_to(c["stop_decision_min_distance_m"], stop_reason.shape)], axis=1)
        self.headway = np.where(self.reasons == R_YIELD, c["yield_time_headway_s"],
                                c["follow_time_headway_s"])
        self.idm_root = (2.0 * np.sqrt(p["max_accel_mps2"] * p["comfort_decel_mps2"]))[:, None]
        self.rows = np.arange(n)
        # the cruise-speed preview's fixed terms, flags and the trajectory's steps
        self.curve_on = self.preview <= c["curve_preview_m"]
        self.cruise_cap = np.broadcast_to(c["cruise_speed_mps"], (n, self.preview.shape[1]))
        self.brake_room = 2.0 * (0.5 * c["comfort_decel_mps2"]) * self.preview
        self.tangent = p["use_path_tangent_heading"][:, None, None] >= 0.5
        self.stop_dest = np.full(n, world.road.destination_s_m - p["destination_buffer_m"]
                                 - self.ego_hl)
        self.pbrake_on = p["perception_brake_enabled"] >= 0.5
        self.unknown_red = p["unknown_light_as_red"] >= 0.5
        self.traj_dt = np.diff(self.t, axis=1)
        self.zero_col = np.zeros((n, 1))
        self._grid: tuple[np.ndarray, np.ndarray, ForecastGrid] | None = None

    def _forecast_grid(self, pred: PredictionOutput) -> ForecastGrid:
        """What the forecast's time grid decides (fixed while prediction publishes the same
        grid arrays): the forecast points some variant checks for overlap (their count), the
        collision check's times (now, then the forecast's) up to the last one some variant
        checks and which it checks, and where those times fall on the trajectory's grid."""
        got = self._grid
        if got is not None and got[0] is pred.traj_t and got[1] is pred.traj_valid:
            return got[2]
        p, c = self.p, self.cols
        n = pred.traj_t.shape[0]
        # forecast points no variant checks (past its forecast's or its overlap horizon)
        # cannot overlap: only the leading points up to the last one some variant checks are
        # projected, the others would be masked out
        checks_k = pred.traj_valid & (pred.traj_t <= p["overlap_check_horizon_s"][:, None])
        live_k = np.flatnonzero(checks_k.any(axis=0))
        kk = int(live_k[-1]) + 1 if live_k.size else 0
        # collision check at the forecast times (and now), only the leading times up to the
        # last one some variant checks (now is always checked): the others' gaps would be
        # masked out
        tp = np.concatenate([np.zeros((n, 1)), pred.traj_t], axis=1)  # (N, Kp + 1)
        tcheck = np.concatenate([np.ones((n, 1), bool), pred.traj_valid], axis=1) & (
            tp <= c["collision_check_horizon_s"]) & (tp <= p["trajectory_horizon_s"][:, None])
        kc = int(np.flatnonzero(tcheck.any(axis=0))[-1]) + 1
        tp, tcheck = tp[:, :kc], tcheck[:, :kc]
        # the trajectory's samples at those times (uniform time grid per row)
        t = self.t
        f = clip(tp / t[:, 1:2], 0.0, t.shape[1] - 1.000001)
        i = f.astype(np.int64)
        flat = np.arange(n)[:, None] * t.shape[1] + i
        grid = ForecastGrid(kk=kk, tp=tp, tcheck=tcheck, kc=kc, flat=flat, frac=f - i)
        self._grid = (pred.traj_t, pred.traj_valid, grid)
        return grid

    def step(self, pred: PredictionOutput, per: PerceptionOutput, loc: LocalizationOutput,
             chassis: ChassisOutput) -> PlanningOutput:
        """One planning cycle: the cruise speed, where the obstacles are along the reference,
        the path around static ones, each obstacle's decision, the stop points, the speed
        command with its emergency overrides, the trajectory checked for collision, and the
        decisions published with it."""
        road = self.world.road
        _, s0, d0 = project_on_reference(road, loc.x, loc.y)
        ego = EgoOnReference(s=s0, d=d0, v=chassis.speed)
        v_cruise = self._cruise_speed(ego)
        obs = self._obstacles(pred, ego)
        path = self._nudge_path(pred, obs, ego)
        grid = self._forecast_grid(pred)
        acts = self._interactions(pred, obs, path, grid, ego, v_cruise)
        stops = self._stop_points(pred, per, obs, path, acts, ego)
        cmd = self._speed_command(stops, acts.beside, ego, v_cruise)
        cmd, halt = self._emergency_stops(cmd, stops, per, ego)
        traj, cmd, halt = self._checked_trajectory(pred, obs, path, acts, grid, ego, v_cruise,
                                                   cmd, halt)
        decision, decision_s = self._decide(pred, obs, path, acts, stops, ego)
        main, stop_distance = self._main_decision(cmd, halt, ego)
        x, y, th, kp, s, v, a = traj
        return PlanningOutput(
            x=x, y=y, theta=th, kappa=kp, s=s, v=v, a=a, t=self.t, valid=self.valid,
            decision=decision, decision_s=np.where(np.isfinite(decision_s), decision_s, 0.0),
            nudge_offset=path.target, main=main, stop_distance=stop_distance,
            reason=cmd.reason, estop=halt.estop, estop_reason=halt.code, cruise_speed=v_cruise,
            lane=road.ref_lane[road.ref_index(s0)],
            total_length=s[:, -1] - s[:, 0], track_id=pred.track_id,
        )

    # -- reference and route ---------------------------------------------------------------
    def _cruise_speed(self, ego: EgoOnReference) -> np.ndarray:
        """(N,) cruise speed [m/s]: every cap ahead (lane limit, junction, curvature) previewed
        with a braking profile at half the comfortable deceleration, so a lower cap is
        approached gently instead of being met by a hard brake where it starts."""
        p, c = self.p, self.cols.__getitem__
        road = self.world.road
        dist = self.preview
        ahead = ego.s[:, None] + dist
        _, _, _, kap = reference_at(road, ahead)
        ii = road.ref_index(ahead)
        v_curve = np.sqrt(p["max_lateral_accel_mps2"][:, None] / np.maximum(np.abs(kap), 1e-4))
        v_curve = np.where(self.curve_on, v_curve, np.inf)
        cap = np.minimum.reduce([
            self.cruise_cap,
            road.ref_speed_limit[ii] * c("speed_limit_factor"), v_curve,
            np.where(road.ref_junction[ii], c("junction_speed_mps"), np.inf)])
        return np.min(np.sqrt(cap * cap + self.brake_room), axis=1)

    def _obstacles(self, pred: PredictionOutput, ego: EgoOnReference) -> RefObstacles:
        """The predicted obstacles placed on the reference line, and which of them count."""
        c = self.cols.__getitem__
        road = self.world.road
        s0, hl_e = ego.s, self.ego_hl
        hl_o, hw_o = pred.length / 2, pred.width / 2
        vru = (pred.type == T_PEDESTRIAN) | (pred.type == T_BICYCLE)
        oi, so, lo = project_on_reference(road, pred.x, pred.y)
        ref_h = road.ref_heading[oi]
        head_now = np.where(self.tangent[..., 0], pred.traj_heading[..., 0], pred.heading)
        rel = head_now - ref_h
        lat_ext = hw_o * np.abs(np.cos(rel)) + hl_o * np.abs(np.sin(rel))
        lon_ext = hl_o * np.abs(np.cos(rel)) + hw_o * np.abs(np.sin(rel))
        buf_vru = np.where(vru, c("vru_lateral_buffer_m"), 0.0)
        not_behind = pred.published & (
            so + lon_ext > (s0 - hl_e)[:, None] - c("obstacle_ignore_behind_m"))
        # near the reference now: shapes the path and the follow decision; moving obstacles
        # farther out still enter the ST-overlap and collision checks through their forecasts
        consider = not_behind & (np.abs(lo) < c("obstacle_consider_lateral_m"))
        return RefObstacles(
            half_length=hl_o, half_width=hw_o, vru=vru, s=so, l=lo, ref_heading=ref_h,
            heading=head_now, lat_ext=lat_ext, lon_ext=lon_ext, vru_buffer=buf_vru,
            not_behind=not_behind, consider=consider)

    # -- path --------------------------------------------------------------------------------
    def _nudge_path(self, pred: PredictionOutput, obs: RefObstacles, ego: EgoOnReference
                    ) -> NudgePath:
        """The path: the smallest lateral offset that clears the static obstacles ahead (people
        standing in the way are waited for, not nudged around), ramped in and out around them."""
        p, c = self.p, self.cols.__getitem__
        s0, hl_e, hw_e = ego.s, self.ego_hl, self.ego_hw
        so, lo, lon_ext = obs.s, obs.l, obs.lon_ext
        static = obs.consider & pred.is_static & ~obs.vru & (
            so - lon_ext - s0[:, None] < c("nudge_lookahead_m"))
        static &= so + lon_ext > (s0 - hl_e)[:, None]
        half = obs.lat_ext + c("static_obstacle_lateral_buffer_m") + hw_e + obs.vru_buffer
        lo_b, hi_b = lo - half, lo + half
        cands = np.concatenate([self.zero_col, lo_b - 0.01, hi_b + 0.01], axis=1)
        inside = static[:, None, :] & (cands[:, :, None] > lo_b[:, None, :]) & (
            cands[:, :, None] < hi_b[:, None, :])
        feasible = ~inside.any(-1) & (np.abs(cands) <= c("nudge_max_offset_m"))
        cost = np.where(feasible, np.abs(cands), np.inf)
        best = np.argmin(cost, axis=1)
        no_path = ~np.isfinite(cost.min(axis=1))
        target = np.where(no_path, 0.0, cands[self.rows, best])
        blocking = static & (lo_b < 0.0) & (hi_b > 0.0)
        any_block = blocking.any(axis=1)
        first_s = np.min(np.where(blocking, so - lon_ext, np.inf), axis=1, initial=np.inf)
        last_s = np.max(np.where(blocking, so + lon_ext, -np.inf), axis=1, initial=-np.inf)
        target = np.where(any_block, target, 0.0)
        tr = p["nudge_transition_m"]
        a0 = np.where(any_block, first_s - hl_e - tr, 0.0)
        a1 = np.where(any_block, last_s + hl_e + tr, 0.0)
        return NudgePath(
            target=target, start=a0, end=a1, transition=tr,
            convergence=p["path_lateral_convergence_m"], s0=s0, d0=ego.d, blocking=blocking,
            any_block=any_block, first_s=first_s, no_path=no_path)

    # -- obstacles: follow, VRU stop, ST overlap -> yield / overtake -------------------------
    def _interactions(self, pred: PredictionOutput, obs: RefObstacles, path: NudgePath,
                      grid: ForecastGrid, ego: EgoOnReference, v_cruise: np.ndarray
                      ) -> Interactions:
        """Each obstacle's relation to the ego: followed, held beside, stopped for, yielded to,
        or overtaken, from where it is now and where its forecast crosses the path."""
        c = self.cols.__getitem__
        s0, hl_e, hw_e = ego.s, self.ego_hl, self.ego_hw
        so, vru = obs.s, obs.vru
        d_obs = path.offset_at(so)
        # lateral clearance between the obstacle's body and the ego's swept width (< 0: overlap)
        lat_gap = np.abs(obs.l - d_obs) - (hw_e + obs.lat_ext + obs.vru_buffer)
        ahead_now = so - obs.lon_ext > s0[:, None]
        in_path_now = obs.consider & (lat_gap < c("lateral_safety_buffer_m")) & ahead_now
        dir_rel = np.abs(wrap_angle(numerics.arctan2(pred.vy, pred.vx) - obs.ref_heading))
        aligned = dir_rel < np.pi / 4
        moving_vru = vru & ~pred.is_static
        follow = in_path_now & ~pred.is_static & (aligned | moving_vru)
        vru_stop = in_path_now & vru & pred.is_static
        # forecasts against the path (only slots that move in some variant are projected)
        mov = obs.not_behind & ~pred.is_static
        st = self._st_overlap(pred, obs, path, mov, grid.kk, ego)
        t_in = pred.traj_t[self.rows[:, None], st.k_in]
        # a vehicle going the ego's way whose body is clear of the swept width, now and along its
        # forecast, but inside the lateral buffer is not followed: the ego only declines to draw
        # level with it (the hold below)
        beside = follow & ~vru & (lat_gap >= 0.0) & ~st.body_over
        follow = follow & ~beside
        s_lo = st.s_lo - c("st_longitudinal_buffer_m")
        s_hi = st.s_hi + c("st_longitudinal_buffer_m")
        behind_same_way = aligned & (so < s0[:, None])
        cross = st.any_over & ~follow & ~beside & ~vru_stop & ~behind_same_way
        t_pass = self._time_to_pass(s_hi, ego, v_cruise)
        same = self.prev_track == pred.track_id
        was_yield = same & (self.prev_decision == D_YIELD)
        need = c("overtake_time_buffer_s") + np.where(was_yield, c("decision_hysteresis_s"), 0.0)
        overtake = cross & (t_in - t_pass > need)
        yield_ = cross & ~overtake & (s_lo > (s0 + hl_e)[:, None])
        return Interactions(follow=follow, beside=beside, vru_stop=vru_stop, yield_=yield_,
                            overtake=overtake, moving=mov, s_lo=s_lo, s_hi=s_hi,
                            dir_rel=dir_rel)

    def _st_overlap(self, pred: PredictionOutput, obs: RefObstacles, path: NudgePath,
                    mov: np.ndarray, kk: int, ego: EgoOnReference) -> StOverlap:
        """Where each moving obstacle's forecast (its leading ``kk`` points) comes within the
        lateral buffer of the path, and whether its body does."""
        p, c = self.p, self.cols.__getitem__
        road = self.world.road
        n, m = pred.x.shape
        s0, hl_e, hw_e = ego.s, self.ego_hl, self.ego_hw
        cols = np.flatnonzero(mov.any(axis=0)) if kk else np.zeros(0, dtype=np.int64)
        any_over = np.zeros((n, m), dtype=bool)
        body_over = np.zeros((n, m), dtype=bool)
        k_in = np.zeros((n, m), dtype=np.int64)
        s_lo = np.full((n, m), np.inf)
        s_hi = np.full((n, m), -np.inf)
        if cols.size:
            sub = (slice(None), cols)
            subk = (slice(None), cols, slice(0, kk))
            _, sk, lk = project_on_reference(road, pred.traj_x[subk], pred.traj_y[subk])
            ref_hk = road.ref_heading[road.ref_index(sk)]
            head_k = np.where(self.tangent, pred.traj_heading[subk], pred.heading[sub][..., None])
            rel_k = head_k - ref_hk
            ca, sa = np.abs(np.cos(rel_k)), np.abs(np.sin(rel_k))
            hw_s, hl_s = obs.half_width[sub][..., None], obs.half_length[sub][..., None]
            lat_k = hw_s * ca + hl_s * sa
            lon_k = hl_s * ca + hw_s * sa
            tk = pred.traj_t[:, None, :kk]
            buf_vru = obs.vru_buffer
            # distance of each forecast point from the ego's path and the bodies' half widths,
            # shared by the buffered overlap and the body overlap below
            dist_k = np.abs(lk - path.offset_at(sk))
            half_k = hw_e + lat_k
            over = (mov[sub][..., None] & pred.traj_valid[:, None, :kk]
                    & (tk <= p["overlap_check_horizon_s"][:, None, None])
                    & (dist_k < half_k + c("lateral_safety_buffer_m")[..., None] + buf_vru[sub][..., None])
                    & (sk + lon_k > (s0 - hl_e)[:, None, None]))
            any_over[sub] = over.any(-1)
            body_k = over & (dist_k < half_k + buf_vru[sub][..., None])
            body_over[sub] = body_k.any(-1)
            k_in[sub] = np.argmax(over, axis=-1)
            s_lo[sub] = np.min(np.where(over, sk - lon_k, np.inf), -1)
            s_hi[sub] = np.max(np.where(over, sk + lon_k, -np.inf), -1)
        return StOverlap(any_over=any_over, body_over=body_over, k_in=k_in, s_lo=s_lo,
                         s_hi=s_hi)

    def _time_to_pass(self, s_hi: np.ndarray, ego: EgoOnReference, v_cruise: np.ndarray
                      ) -> np.ndarray:
        """(N, M) time [s] for the ego's rear to clear each overlap region plus the margin,
        accelerating at max_accel up to the cruise speed."""
        p, c = self.p, self.cols.__getitem__
        s0, v0 = ego.s, ego.v
        dist_pass = np.maximum(s_hi + c("min_overtake_distance_m") - (s0 - self.ego_hl)[:, None],
                               0.0)
        a_pass = p["max_accel_mps2"][:, None]
        vc = np.maximum(v_cruise, v0)[:, None]
        v0c = v0[:, None]
        t1 = (vc - v0c) / a_pass
        d1 = (vc * vc - v0c * v0c) / (2.0 * a_pass)
        return np.where(dist_pass <= d1,
                        (np.sqrt(v0c * v0c + 2.0 * a_pass * dist_pass) - v0c) / a_pass,
                        t1 + (dist_pass - d1) / np.maximum(vc, 0.1))

    # -- stop points, lights and the speed command -------------------------------------------
    def _stop_points(self, pred: PredictionOutput, per: PerceptionOutput, obs: RefObstacles,
                     path: NudgePath, acts: Interactions, ego: EgoOnReference) -> StopPoints:
        """The gaps to what the ego follows and the points along the route it stops at."""
        p, c = self.p, self.cols.__getitem__
        s0, hl_e = ego.s, self.ego_hl
        inf = np.inf
        so, lon_ext = obs.s, obs.lon_ext
        # bumper-to-rear gap to each obstacle ahead; followed and beside vehicles use it
        gap_rear = so - lon_ext - (s0 + hl_e)[:, None]
        return StopPoints(
            gap_follow=np.where(acts.follow, gap_rear, inf),
            gap_beside=np.where(acts.beside, gap_rear, inf),
            v_lead=np.maximum(pred.speed * np.cos(np.minimum(acts.dir_rel, np.pi / 2)), 0.0),
            stop_yield=np.where(acts.yield_, acts.s_lo - c("yield_distance_m") - hl_e, inf),
            stop_vru=np.where(acts.vru_stop, so - lon_ext - c("pedestrian_stop_buffer_m") - hl_e,
                              inf),
            stop_block=np.where(path.no_path & path.any_block,
                                path.first_s - hl_e - p["stop_distance_obstacle_m"], inf),
            stop_light=self._light_stop(per, ego))

    def _light_stop(self, per: PerceptionOutput, ego: EgoOnReference) -> np.ndarray:
        """(N,) where the ego stops for the selected traffic light [m along the route], inf
        where it goes: red, a yellow it can stop for comfortably, unknown if read as red."""
        p = self.p
        n, s0, v0, hl_e = ego.s.shape[0], ego.s, ego.v, self.ego_hl
        inf = np.inf
        sel = per.tl_selected
        has = sel >= 0
        selc = clip(sel, 0, max(per.tl_color.shape[1] - 1, 0))
        if per.tl_color.shape[1]:
            col = per.tl_color[self.rows, selc]
            dist = per.tl_distance[self.rows, selc]
        else:
            col = np.zeros(n, dtype=np.int64)
            dist = np.full(n, inf)
        room = dist - p["stop_line_buffer_m"] - hl_e
        req = v0 * v0 / (2.0 * np.maximum(room, 0.1))
        stop_for_light = has & (dist <= p["tl_consider_distance_m"]) & (room > -0.5) & (
            (col == TL_RED) | ((col == TL_YELLOW) & (req <= p["yellow_stop_max_decel_mps2"]))
            | ((col == TL_UNKNOWN) & self.unknown_red))
        return np.where(stop_for_light, s0 + room, inf)

    def _speed_command(self, stops: StopPoints, beside: np.ndarray, ego: EgoOnReference,
                       v_cruise: np.ndarray) -> SpeedCommand:
        """The IDM acceleration over every constraint, capped by the hold beside vehicles,
        clipped to the limits, and never creeping at a stop point reached."""
        p = self.p
        v0 = ego.v
        cmd = self._idm(stops, ego, v_cruise)
        if beside.any():
            cmd = self._hold_beside(cmd, stops, beside, v0)
        a_cmd = clip(cmd.accel, -p["max_decel_mps2"], p["max_accel_mps2"])
        # hold still at a stop point reached (no creeping)
        at_stop = (v0 < p["standstill_speed_mps"]) & cmd.bound & (cmd.reason != R_FOLLOW) & (
            cmd.bind_gap < 2.0)
        a_cmd = np.where(at_stop, np.minimum(a_cmd, 0.0), a_cmd)
        return SpeedCommand(accel=a_cmd, reason=cmd.reason, bind_gap=cmd.bind_gap,
                            bound=cmd.bound)

    def _idm(self, stops: StopPoints, ego: EgoOnReference, v_cruise: np.ndarray
             ) -> SpeedCommand:
        """IDM over the follow gaps and the stop points (a stop point is a standing leader):
        the lowest acceleration wins and names the reason."""
        p = self.p
        s0, v0 = ego.s, ego.v
        inf = np.inf
        st = np.concatenate([stops.stop_yield, stops.stop_vru, stops.stop_block[:, None],
                             stops.stop_light[:, None], self.stop_dest[:, None]], axis=1)
        gaps = np.concatenate([stops.gap_follow, st - s0[:, None]], axis=1)
        leads = np.concatenate([stops.v_lead, np.zeros_like(st)], axis=1)
        smin, reasons = self.smin, self.reasons
        amax = p["max_accel_mps2"]
        a_free = amax * (1.0 - numerics.power(v0 / np.maximum(v_cruise, 0.1), p["idm_exponent"]))
        headway = self.headway
        sstar = smin + np.maximum(0.0, v0[:, None] * headway + v0[:, None]
                                  * (v0[:, None] - leads) / self.idm_root)
        active = np.isfinite(gaps)
        a_c = np.where(active, a_free[:, None] - amax[:, None] * (
            sstar / np.maximum(np.where(active, gaps, 1.0), 0.1)) ** 2, inf)
        binding = np.argmin(a_c, axis=1)
        a_cmd = np.minimum(a_free, a_c.min(axis=1))
        bound = np.isfinite(a_c.min(axis=1)) & (a_c.min(axis=1) < a_free)
        reason = np.where(bound, reasons[self.rows, binding], R_CRUISE)
        bind_gap = np.where(bound, gaps[self.rows, binding], inf)
        return SpeedCommand(accel=a_cmd, reason=reason, bind_gap=bind_gap, bound=bound)

    def _hold_beside(self, cmd: SpeedCommand, stops: StopPoints, beside: np.ndarray,
                     v0: np.ndarray) -> SpeedCommand:
        """Hold behind a vehicle beside the path: the closing speed is capped so that the ego,
        braking at the comfortable deceleration, ends at the vehicle's speed a standstill gap
        plus a yield headway behind its rear (late, unlike IDM's following); never harder."""
        c = self.cols.__getitem__
        gap_beside, v_lead = stops.gap_beside, stops.v_lead
        gap_h = gap_beside - c("follow_distance_m") - v_lead * c("yield_time_headway_s")
        v_hold = v_lead + np.where(gap_h > 0.0, np.sqrt(
            2.0 * c("comfort_decel_mps2") * np.maximum(gap_h, 0.0)), gap_h / HOLD_RECOVER_S)
        a_hold = np.maximum((v_hold - v0[:, None]) / HOLD_TAU_S, -c("comfort_decel_mps2"))
        a_hold = np.where(beside, a_hold, np.inf).min(axis=1)
        held = a_hold < cmd.accel
        return SpeedCommand(
            accel=np.minimum(cmd.accel, a_hold), reason=np.where(held, R_FOLLOW, cmd.reason),
            bind_gap=np.where(held, gap_beside.min(axis=1), cmd.bind_gap),
            bound=cmd.bound | held)

    # -- emergency stops ---------------------------------------------------------------------
    def _emergency_stops(self, cmd: SpeedCommand, stops: StopPoints, per: PerceptionOutput,
                         ego: EgoOnReference) -> tuple[SpeedCommand, EmergencyStop]:
        """The emergency overrides before the collision check: blocked with no feasible path
        and too close to stop comfortably, and the perception brake."""
        p = self.p
        s0, v0 = ego.s, ego.v
        a_cmd = cmd.accel
        estop = np.zeros(s0.shape[0], dtype=bool)
        estop_reason = np.zeros(s0.shape[0], dtype=np.int64)
        gap_block = stops.stop_block - s0
        urgent = np.isfinite(gap_block) & (
            v0 * v0 / (2.0 * np.maximum(gap_block, 0.1)) > p["max_decel_mps2"])
        a_cmd = np.where(urgent, -p["emergency_decel_mps2"], a_cmd)
        estop |= urgent
        estop_reason = np.where(urgent, E_NO_PATH, estop_reason)
        pbrake = per.brake & self.pbrake_on
        a_cmd = np.where(pbrake, np.minimum(a_cmd, -p["perception_brake_decel_mps2"]), a_cmd)
        estop |= pbrake
        estop_reason = np.where(pbrake, E_PERCEPTION_BRAKE, estop_reason)
        return (SpeedCommand(accel=a_cmd, reason=np.where(pbrake, R_PBRAKE, cmd.reason),
                             bind_gap=cmd.bind_gap, bound=cmd.bound),
                EmergencyStop(estop=estop, code=estop_reason, perception_brake=pbrake))

    # -- trajectory and collision check ------------------------------------------------------
    def _checked_trajectory(self, pred: PredictionOutput, obs: RefObstacles, path: NudgePath,
                            acts: Interactions, grid: ForecastGrid, ego: EgoOnReference,
                            v_cruise: np.ndarray, cmd: SpeedCommand, halt: EmergencyStop
                            ) -> tuple[tuple[np.ndarray, ...], SpeedCommand, EmergencyStop]:
        """The trajectory of the speed command, checked against the obstacles' forecasts: a
        collision soon is an emergency stop, a later one brakes to stop short of it (the
        fallback); either replans the trajectory."""
        p = self.p
        s0, v0 = ego.s, ego.v
        a_cmd, reason, pbrake = cmd.accel, cmd.reason, halt.perception_brake
        vcap = np.maximum(v_cruise, v0)
        traj = self._trajectory(s0, v0, a_cmd, vcap, self.t, path.offset_at)
        hit_k, es = self._hits(pred, obs, acts.moving, traj, grid)
        collide = hit_k.any(axis=1)
        k_hit = np.argmax(hit_k, axis=1)
        t_hit = grid.tp[self.rows, k_hit]
        s_hit = es[self.rows, k_hit]
        imminent = collide & (t_hit < p["estop_ttc_s"])
        fallback = collide & ~imminent
        a_fb = -v0 * v0 / (2.0 * np.maximum(s_hit - s0 - 1.0, 0.3))
        a_new = np.where(imminent, -p["emergency_decel_mps2"],
                         np.where(fallback, np.maximum(np.minimum(a_cmd, a_fb),
                                                       -p["max_decel_mps2"]), a_cmd))
        halt = EmergencyStop(
            estop=halt.estop | imminent,
            code=np.where(imminent & ~pbrake, E_COLLISION, halt.code), perception_brake=pbrake)
        reason = np.where(imminent & ~pbrake, R_COLL, np.where(fallback & ~pbrake & (
            a_fb < a_cmd), R_FALLBACK, reason))
        if collide.any():
            a_cmd = a_new
            traj = self._trajectory(s0, v0, a_cmd, vcap, self.t, path.offset_at)
        return (traj, SpeedCommand(accel=a_cmd, reason=reason, bind_gap=cmd.bind_gap,
                                   bound=cmd.bound), halt)

    def _hits(self, pred: PredictionOutput, obs: RefObstacles, mov: np.ndarray,
              traj: tuple[np.ndarray, ...], grid: ForecastGrid
              ) -> tuple[np.ndarray, np.ndarray]:
        """(N, Q) whether the ego's trajectory comes within the collision threshold of some
        obstacle at each check time (now, then the forecast's), and (N, Q) the ego's route
        position at those times [m]."""
        c = self.cols.__getitem__
        hl_e, hw_e, tangent, tcheck = self.ego_hl, self.ego_hw, self.tangent, grid.tcheck
        ex, ey, eh, es = self._sample(traj, grid.flat, grid.frac)
        # only slots some variant considers are checked (the others' gaps would be discarded)
        checked = obs.consider | mov
        cols = np.flatnonzero(checked.any(axis=0))
        if cols.size:
            sub = (slice(None), cols)
            subk = (slice(None), cols, slice(0, grid.kc - 1))
            ox = np.concatenate([pred.x[sub][..., None], pred.traj_x[subk]], axis=-1)
            oy = np.concatenate([pred.y[sub][..., None], pred.traj_y[subk]], axis=-1)
            oh = np.where(tangent, np.concatenate([obs.heading[sub][..., None],
                                                   pred.traj_heading[subk]], -1),
                          pred.heading[sub][..., None])
            gap = box_gap(ex[:, None, :], ey[:, None, :], eh[:, None, :], hl_e, hw_e,
                          ox, oy, oh, obs.half_length[sub][..., None],
                          obs.half_width[sub][..., None])
            thr = np.where(pred.is_static[sub], c("collision_check_static_m"),
                           c("collision_check_moving_m"))
            hit = checked[sub][..., None] & tcheck[:, None, :] & (gap < thr[..., None])
            hit_k = hit.any(axis=1)
        else:
            hit_k = np.zeros(tcheck.shape, dtype=bool)
        return hit_k, es

    # -- decisions ---------------------------------------------------------------------------
    def _decide(self, pred: PredictionOutput, obs: RefObstacles, path: NudgePath,
                acts: Interactions, stops: StopPoints, ego: EgoOnReference
                ) -> tuple[np.ndarray, np.ndarray]:
        """(N, M) each obstacle's published decision and (N, M) its distance from the ego
        [m] (inf where none), remembered for the next cycle's hysteresis."""
        s0, so, lon_ext = ego.s, obs.s, obs.lon_ext
        w = np.where
        decision = w(~(obs.consider | acts.moving), D_IGNORE, w(
            acts.follow | acts.beside, D_FOLLOW, w(acts.yield_, D_YIELD, w(
                acts.overtake, D_OVERTAKE, w(acts.vru_stop, D_STOP, w(path.blocking, w(
                    path.no_path[:, None], D_STOP, D_NUDGE), D_IGNORE))))))
        decision_s = w(decision == D_FOLLOW, np.minimum(stops.gap_follow, stops.gap_beside), w(
            decision == D_YIELD, stops.stop_yield - s0[:, None], w(
                decision == D_OVERTAKE, acts.s_hi - s0[:, None], w(
                    decision == D_STOP, np.minimum(stops.stop_vru, so - lon_ext) - s0[:, None],
                    0.0))))
        self.prev_decision = decision
        self.prev_track = pred.track_id
        return decision, decision_s

    def _main_decision(self, cmd: SpeedCommand, halt: EmergencyStop, ego: EgoOnReference
                       ) -> tuple[np.ndarray, np.ndarray]:
        """(N,) the main decision (cruise, stop, emergency stop) and (N,) the distance to the
        stop point when stopping [m]."""
        p = self.p
        v0, a_cmd, reason, bind_gap = ego.v, cmd.accel, cmd.reason, cmd.bind_gap
        standing = v0 < p["standstill_speed_mps"]
        stop_reason_now = ((reason == R_DEST) | (reason == R_LIGHT) | (reason == R_YIELD)
                           | (reason == R_BLOCKED) | (reason == R_VRU) | (reason == R_FALLBACK))
        stopping = stop_reason_now & ((a_cmd < 0) | standing)
        main = np.where(halt.estop, M_ESTOP, np.where(
            stopping | (standing & (a_cmd <= 0)), M_STOP, M_CRUISE))
        stop_distance = np.where(main == M_STOP, np.where(
            bind_gap < p["stop_decision_min_distance_m"], 0.0, np.minimum(bind_gap, 1e3)), 0.0)
        return main, stop_distance


    @staticmethod
    def _sample(traj: tuple[np.ndarray, ...], flat: np.ndarray, u: np.ndarray
                ) -> tuple[np.ndarray, ...]:
        """Trajectory x, y, theta, s (N, Q) at the times whose grid samples are ``flat``
        (N, Q) (index into a flattened (N, K) trajectory array) plus the fraction ``u`` of the
        next step (:meth:`_forecast_grid`)."""
        x, y, th, _, s = traj[:5]
        out = []
        for a in (x, y, s):
            a = a.reshape(-1)
            a0 = a.take(flat)
            out.append(a0 + u * (a.take(flat + 1) - a0))
        return out[0], out[1], th.reshape(-1).take(flat), out[2]

    def _trajectory(self, s0: np.ndarray, v0: np.ndarray, a_cmd: np.ndarray, vcap: np.ndarray,
                    t: np.ndarray, offset_at) -> tuple[np.ndarray, ...]:  # noqa: ANN001
        road = self.world.road
        a = a_cmd[:, None]
        v_acc = v0[:, None] + a * ACCEL_DECAY_S * self.accel_fade
        v_dec = v0[:, None] + a * t
        v = clip(np.where(a > 0, v_acc, v_dec), 0.0, vcap[:, None])
        dt = self.traj_dt
        s = s0[:, None] + np.concatenate(
            [self.zero_col, np.cumsum(0.5 * (v[:, 1:] + v[:, :-1]) * dt, axis=1)], 1)
        acc = np.concatenate([np.diff(v, axis=1) / dt, self.zero_col], axis=1)
        rx, ry, rh, rk = reference_at(road, s)
        d = offset_at(s)
        x = rx - d * np.sin(rh)
        y = ry + d * np.cos(rh)
        dd = _row_gradient(d) / np.maximum(_row_gradient(s), 1e-3)
        # most of a path runs along the reference (no offset, dd == +-0.0, about 60 % of the
        # points): arctan(+-0.0) is +-0.0, so only the other points go through arctan
        turn = dd != 0.0
        if turn.all():
            atan = numerics.arctan(dd)
        else:
            atan = dd.copy()
            atan[turn] = numerics.arctan(dd[turn])
        th = wrap_angle(rh + atan)
        return x, y, th, rk, s, v, acc


def _row_gradient(a: np.ndarray) -> np.ndarray:
    """``np.gradient(a, axis=1)`` for (N, K >= 2) rows of unit spacing, with the same
    arithmetic (central differences halved, one-sided ones at the ends) and none of its
    Python overhead."""
    out = np.empty_like(a)
    out[:, 1:-1] = (a[:, 2:] - a[:, :-2]) / 2.0
    out[:, 0] = a[:, 1] - a[:, 0]
    out[:, -1] = a[:, -1] - a[:, -2]
    return out


__all__ = ["MAX_POINTS", "REASONS", "STOP_JUSTIFIED", "UNJUSTIFIED_STOP_REASONS", "Planning",
           "PlanningOutput", "REF_SPACING_M"]
