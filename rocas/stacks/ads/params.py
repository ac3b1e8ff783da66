"""The parameter inventory of the built-in ADS: every named parameter, its default, range and unit.

Parameters are named ``module.name`` (``planning.yield_distance_m``). A :class:`ParamSet` is an
immutable mapping name -> value with every parameter present; a batch of N parameter sets is
:func:`stack_params` -> ``{name: array (N,)}``, which is what the modules read.
"""

from __future__ import annotations

from rocas.stacks.base import ParamSpec

MODULES = ("localization", "canbus", "perception", "prediction", "planning", "control")


#: one ADS parameter: the stacks' parameter declaration (module, name, default, range, unit)
Param = ParamSpec


_P = Param
_INVENTORY: tuple[Param, ...] = (
    # --- localization -----------------------------------------------------------------------
    _P("localization", "position_noise_std_m", 0.02, 0.0, 0.5, "m",
       "standard deviation of the published position error"),
    _P("localization", "heading_noise_std_rad", 0.002, 0.0, 0.05, "rad",
       "standard deviation of the published heading error"),
    _P("localization", "speed_noise_std_mps", 0.02, 0.0, 0.5, "m/s",
       "standard deviation of the published speed error"),
    _P("localization", "lane_match_max_distance_m", 3.0, 0.5, 10.0, "m",
       "largest distance to the route centre at which the ego is matched to a route lane"),
    # --- canbus (actuators and chassis feedback) -----------------------------------------------
    _P("canbus", "throttle_max_accel_mps2", 3.0, 1.0, 6.0, "m/s^2",
       "acceleration the vehicle produces at 100 % throttle"),
    _P("canbus", "brake_max_decel_mps2", 8.0, 4.0, 12.0, "m/s^2",
       "deceleration the vehicle produces at 100 % brake (before friction limits)"),
    _P("canbus", "max_steer_angle_rad", 0.55, 0.3, 0.8, "rad",
       "road-wheel angle at 100 % steering"),
    _P("canbus", "actuator_time_constant_s", 0.15, 0.01, 1.0, "s",
       "first-order lag of acceleration and steering actuators"),
    _P("canbus", "steer_rate_limit_radps", 0.6, 0.1, 2.0, "rad/s",
       "largest road-wheel angle rate the steering motor achieves"),
    _P("canbus", "speed_sensor_noise_std_mps", 0.02, 0.0, 0.5, "m/s",
       "standard deviation of the chassis speed feedback error"),
    # --- perception ---------------------------------------------------------------------------
    _P("perception", "max_range_m", 80.0, 20.0, 200.0, "m",
       "detection range of vehicles in clear weather"),
    _P("perception", "fov_deg", 120.0, 30.0, 360.0, "deg",
       "horizontal field of view of the forward sensors"),
    _P("perception", "rear_range_m", 25.0, 0.0, 80.0, "m",
       "range of the all-round short-range lidar (outside the forward field of view)"),
    _P("perception", "pedestrian_range_m", 45.0, 10.0, 120.0, "m",
       "detection range of pedestrians and cyclists in clear weather"),
    _P("perception", "static_object_range_m", 40.0, 10.0, 120.0, "m",
       "detection range of cones and boxes in clear weather"),
    _P("perception", "min_obstacle_height_m", 0.3, 0.0, 1.5, "m",
       "obstacles lower than this are filtered out as ground returns"),
    _P("perception", "occlusion_min_visible_fraction", 0.34, 0.0, 1.0, "",
       "fraction of an obstacle's sample points that must be visible to detect it"),
    _P("perception", "vegetation_opacity", 0.7, 0.0, 1.0, "",
       "how much a line of sight through vegetation counts as blocked (buildings count 1)"),
    _P("perception", "fog_range_factor", 0.7, 0.0, 0.95, "",
       "relative range lost at fog density 100"),
    _P("perception", "precipitation_range_factor", 0.4, 0.0, 0.95, "",
       "relative range lost at precipitation 100"),
    _P("perception", "glare_sun_altitude_deg", 15.0, 0.0, 60.0, "deg",
       "sun altitude under which the sun ahead blinds the camera"),
    _P("perception", "glare_azimuth_window_deg", 35.0, 5.0, 90.0, "deg",
       "angle between heading and sun azimuth within which glare occurs"),
    _P("perception", "glare_range_factor", 0.5, 0.0, 0.95, "",
       "relative range lost under glare"),
    _P("perception", "position_noise_std_m", 0.05, 0.0, 1.0, "m",
       "standard deviation of detected positions at zero range in clear weather"),
    _P("perception", "noise_range_gain", 1.0, 0.0, 5.0, "",
       "growth of position noise with range (relative to the effective range)"),
    _P("perception", "weather_noise_gain", 2.0, 0.0, 10.0, "",
       "growth of position noise with fog and precipitation (blur)"),
    _P("perception", "heading_noise_std_rad", 0.02, 0.0, 0.3, "rad",
       "standard deviation of detected headings"),
    _P("perception", "size_noise_std_m", 0.05, 0.0, 0.5, "m",
       "standard deviation of detected length and width"),
    _P("perception", "confidence_range_decay", 0.5, 0.0, 1.0, "",
       "confidence lost between zero range and the effective range"),
    _P("perception", "min_confidence", 0.3, 0.0, 0.95, "",
       "detections below this confidence are dropped"),
    _P("perception", "classify_min_confidence", 0.45, 0.0, 1.0, "",
       "below this confidence a movable obstacle is published as UNKNOWN_MOVABLE"),
    _P("perception", "color_max_distance_m", 50.0, 5.0, 150.0, "m",
       "farthest distance at which an obstacle's colour is recognised"),
    _P("perception", "track_gate_m", 3.0, 0.3, 10.0, "m",
       "largest jump between a track's prediction and a detection that keeps the track id"),
    _P("perception", "track_max_missed_frames", 3, 0, 20, "frames",
       "frames a track coasts without detections before it is dropped"),
    _P("perception", "track_min_hits", 2, 1, 10, "frames",
       "detections a new track needs before it is published"),
    _P("perception", "velocity_filter_alpha", 0.1, 0.02, 1.0, "",
       "velocity gain of the alpha-beta tracker (share of the innovation per frame)"),
    _P("perception", "heading_from_velocity_speed_mps", 2.0, 0.0, 20.0, "m/s",
       "above this speed a track's heading follows its velocity, below it the detector"),
    _P("perception", "brake_threshold", 0.8, 0.05, 0.99, "",
       "brake classifier probability above which perception asks to brake"),
    _P("perception", "brake_min_frames", 3, 1, 10, "frames",
       "consecutive frames above threshold before the brake decision is raised"),
    _P("perception", "camera_range_m", 40.0, 10.0, 100.0, "m",
       "farthest distance rasterised into the front-camera view"),
    _P("perception", "camera_glare_gain", 0.3, 0.0, 1.0, "",
       "brightness added to the camera view by glare"),
    _P("perception", "tl_max_range_m", 70.0, 10.0, 200.0, "m",
       "farthest traffic light that is detected"),
    _P("perception", "tl_facing_tolerance_deg", 40.0, 5.0, 90.0, "deg",
       "a light is a candidate when it faces the ego within this angle"),
    _P("perception", "tl_fov_deg", 60.0, 10.0, 180.0, "deg",
       "field of view of the traffic-light camera"),
    _P("perception", "tl_lateral_weight", 1.0, 0.0, 10.0, "",
       "weight of lateral offset against distance when selecting the governing light"),
    _P("perception", "tl_min_visibility", 0.3, 0.0, 1.0, "",
       "below this weather visibility a light's colour is UNKNOWN"),
    # --- prediction ---------------------------------------------------------------------------
    _P("prediction", "horizon_s", 5.0, 1.0, 8.0, "s", "length of predicted trajectories"),
    _P("prediction", "time_step_s", 0.5, 0.5, 1.0, "s", "time between predicted points"),
    _P("prediction", "still_obstacle_speed_mps", 0.5, 0.0, 5.0, "m/s",
       "obstacles slower than this are static and get no forecast"),
    _P("prediction", "pedestrian_still_speed_mps", 0.2, 0.0, 2.0, "m/s",
       "pedestrians slower than this are static"),
    _P("prediction", "lane_follow_max_distance_m", 1.8, 0.0, 5.0, "m",
       "largest distance to a lane centre for a lane-following forecast"),
    _P("prediction", "lane_follow_max_heading_deg", 35.0, 5.0, 90.0, "deg",
       "largest heading difference to a lane for a lane-following forecast"),
    _P("prediction", "lane_follow_convergence_s", 1.5, 0.1, 5.0, "s",
       "time for a lane follower's lateral offset to decay to the centre"),
    _P("prediction", "accel_decay_s", 1.5, 0.1, 10.0, "s",
       "time constant with which an observed acceleration fades in forecasts"),
    _P("prediction", "max_accel_mps2", 2.0, 0.0, 6.0, "m/s^2",
       "largest acceleration magnitude used in forecasts"),
    _P("prediction", "max_speed_mps", 25.0, 5.0, 50.0, "m/s", "forecast speeds are capped here"),
    _P("prediction", "pedestrian_max_speed_mps", 2.5, 0.5, 6.0, "m/s",
       "forecast pedestrian speeds are capped here"),
    _P("prediction", "cyclist_cut_in_lateral_m", 2.5, 0.0, 6.0, "m",
       "a cyclist this close beside the ego is predicted to cut across its path"),
    _P("prediction", "cyclist_cut_in_longitudinal_m", 6.0, 0.0, 20.0, "m",
       "longitudinal window beside the ego for the cyclist cut-in rule"),
    _P("prediction", "cyclist_cut_in_lateral_speed_mps", 1.2, 0.1, 4.0, "m/s",
       "lateral speed of a predicted cyclist cut-in"),
    _P("prediction", "max_distance_m", 70.0, 10.0, 200.0, "m",
       "obstacles farther than this are not forecast (static)"),
    _P("prediction", "behind_ignore_m", 15.0, 0.0, 100.0, "m",
       "obstacles more than this behind the ego are not forecast (static)"),
    _P("prediction", "min_tracking_time_s", 0.15, 0.0, 2.0, "s",
       "younger tracks get a constant-velocity forecast only"),
    _P("prediction", "trajectory_probability", 0.9, 0.1, 1.0, "",
       "probability published with the main forecast"),
    # --- planning -----------------------------------------------------------------------------
    _P("planning", "cruise_speed_mps", 11.0, 2.0, 30.0, "m/s", "desired speed on free road"),
    _P("planning", "speed_limit_factor", 1.0, 0.5, 1.3, "",
       "fraction of the lane speed limit the ego may drive"),
    _P("planning", "junction_speed_mps", 7.0, 2.0, 20.0, "m/s", "speed cap on junction lanes"),
    _P("planning", "max_lateral_accel_mps2", 2.0, 0.5, 6.0, "m/s^2",
       "lateral acceleration that limits speed in curves"),
    _P("planning", "curve_preview_m", 30.0, 5.0, 80.0, "m",
       "distance ahead over which curvature limits the speed"),
    _P("planning", "max_accel_mps2", 1.5, 0.3, 4.0, "m/s^2", "acceleration on free road"),
    _P("planning", "comfort_decel_mps2", 2.5, 0.5, 6.0, "m/s^2",
       "comfortable deceleration (IDM b)"),
    _P("planning", "max_decel_mps2", 6.0, 2.0, 10.0, "m/s^2",
       "hardest deceleration the planner commands outside an estop"),
    _P("planning", "emergency_decel_mps2", 8.0, 4.0, 12.0, "m/s^2",
       "deceleration planned on an estop"),
    _P("planning", "trajectory_horizon_s", 6.0, 2.0, 8.0, "s", "length of the planned trajectory"),
    _P("planning", "trajectory_time_step_s", 0.25, 0.1, 0.5, "s",
       "time between planned trajectory points"),
    _P("planning", "follow_distance_m", 6.0, 1.0, 30.0, "m",
       "standstill gap kept to a followed obstacle"),
    _P("planning", "follow_time_headway_s", 1.5, 0.3, 4.0, "s",
       "time headway kept to a followed obstacle"),
    _P("planning", "stop_distance_obstacle_m", 4.0, 0.5, 15.0, "m",
       "gap kept when stopping for a blocking obstacle"),
    _P("planning", "obstacle_consider_lateral_m", 8.0, 2.0, 20.0, "m",
       "obstacles farther from the path than this are ignored"),
    _P("planning", "obstacle_ignore_behind_m", 3.0, 0.0, 30.0, "m",
       "obstacles this far behind the ego's rear are ignored"),
    _P("planning", "static_obstacle_lateral_buffer_m", 0.6, 0.0, 3.0, "m",
       "lateral clearance required to nudge past a static obstacle"),
    _P("planning", "nudge_max_offset_m", 1.6, 0.0, 4.0, "m",
       "largest lateral offset from the reference line when nudging"),
    _P("planning", "nudge_lookahead_m", 40.0, 5.0, 100.0, "m",
       "static obstacles within this distance ahead shape the path"),
    _P("planning", "nudge_transition_m", 10.0, 2.0, 30.0, "m",
       "distance over which the path shifts to and from a nudge offset"),
    _P("planning", "lateral_safety_buffer_m", 0.3, 0.0, 3.0, "m",
       "lateral buffer to moving obstacles: ST-overlap check, follow, and not drawing level "
       "with a vehicle beside the path"),
    _P("planning", "use_path_tangent_heading", 1, 0, 1, "bool",
       "take an obstacle's heading from its predicted path tangent instead of its perceived heading"),
    _P("planning", "st_longitudinal_buffer_m", 1.0, 0.0, 10.0, "m",
       "longitudinal buffer added around ST-overlap regions"),
    _P("planning", "yield_distance_m", 6.0, 0.0, 20.0, "m",
       "gap kept before the region a yielded obstacle crosses"),
    _P("planning", "yield_time_headway_s", 0.5, 0.0, 4.0, "s",
       "time headway of the stop before a yielded region (the follow headway's counterpart)"),
    _P("planning", "min_overtake_distance_m", 3.0, 0.0, 40.0, "m",
       "margin beyond an overlap region the ego must reach to overtake"),
    _P("planning", "overtake_time_buffer_s", 1.0, 0.0, 5.0, "s",
       "time margin required before an obstacle arrives to overtake it"),
    _P("planning", "decision_hysteresis_s", 0.5, 0.0, 3.0, "s",
       "extra time margin needed to switch from yield back to overtake"),
    _P("planning", "overlap_check_horizon_s", 5.0, 1.0, 8.0, "s",
       "predicted points later than this are ignored in ST-overlap checks"),
    _P("planning", "stop_line_buffer_m", 1.0, 0.0, 5.0, "m", "gap kept before a stop line"),
    _P("planning", "tl_consider_distance_m", 60.0, 10.0, 150.0, "m",
       "traffic lights farther than this are ignored"),
    _P("planning", "yellow_stop_max_decel_mps2", 3.0, 0.5, 8.0, "m/s^2",
       "on yellow the ego stops when this deceleration suffices"),
    _P("planning", "unknown_light_as_red", 0, 0, 1, "bool",
       "treat a light of unknown colour as red"),
    _P("planning", "perception_brake_enabled", 1, 0, 1, "bool",
       "obey perception's brake decision"),
    _P("planning", "perception_brake_decel_mps2", 6.0, 2.0, 12.0, "m/s^2",
       "deceleration planned when perception says brake"),
    _P("planning", "collision_check_moving_m", 0.5, 0.0, 3.0, "m",
       "clearance to a moving obstacle's forecast below which the trajectory collides"),
    _P("planning", "collision_check_static_m", 0.2, 0.0, 2.0, "m",
       "clearance to a static obstacle below which the trajectory collides"),
    _P("planning", "collision_check_horizon_s", 3.0, 0.5, 8.0, "s",
       "collisions later than this along the trajectory are ignored"),
    _P("planning", "estop_ttc_s", 1.0, 0.0, 4.0, "s",
       "a predicted collision sooner than this triggers an estop"),
    _P("planning", "pedestrian_stop_buffer_m", 5.0, 1.0, 15.0, "m",
       "gap kept when stopping for a pedestrian or cyclist in the path"),
    _P("planning", "vru_lateral_buffer_m", 0.3, 0.0, 4.0, "m",
       "extra lateral buffer around pedestrians and cyclists"),
    _P("planning", "destination_buffer_m", 2.0, 0.0, 10.0, "m",
       "gap kept before the mission end"),
    _P("planning", "standstill_speed_mps", 0.3, 0.05, 2.0, "m/s",
       "below this speed the ego counts as standing and holds still at a close stop point"),
    _P("planning", "idm_exponent", 4.0, 1.0, 8.0, "",
       "free-road exponent of the intelligent driver model"),
    _P("planning", "path_lateral_convergence_m", 15.0, 3.0, 50.0, "m",
       "distance over which the path returns from the ego's current offset"),
    _P("planning", "stop_decision_min_distance_m", 0.5, 0.0, 5.0, "m",
       "a stop point closer than this is reported as reached (main decision STOP, distance 0)"),
    # --- control ------------------------------------------------------------------------------
    _P("control", "lateral_controller", 0, 0, 1, "enum",
       "lateral tracking law: 0 pure pursuit, 1 Stanley"),
    _P("control", "pure_pursuit_min_lookahead_m", 4.0, 1.0, 15.0, "m",
       "shortest pure-pursuit look-ahead distance"),
    _P("control", "pure_pursuit_lookahead_gain_s", 0.6, 0.1, 2.0, "s",
       "pure-pursuit look-ahead distance per unit of speed"),
    _P("control", "stanley_gain", 1.2, 0.1, 5.0, "1/s", "Stanley cross-track gain"),
    _P("control", "stanley_softening_mps", 1.0, 0.1, 5.0, "m/s",
       "Stanley speed softening term"),
    _P("control", "curvature_feedforward_gain", 1.0, 0.0, 2.0, "",
       "weight of the path curvature feedforward in the Stanley law"),
    _P("control", "wheelbase_m", 2.85, 2.0, 4.0, "m", "wheelbase the controller assumes"),
    _P("control", "max_steer_angle_rad", 0.55, 0.3, 0.8, "rad",
       "road-wheel angle the controller maps to 100 % steering"),
    _P("control", "steering_rate_limit_pct_s", 250.0, 20.0, 1000.0, "%/s",
       "largest change of the steering command per second"),
    _P("control", "preview_time_s", 0.3, 0.0, 1.5, "s",
       "how far ahead on the trajectory the longitudinal target is taken"),
    _P("control", "speed_kp", 0.8, 0.0, 5.0, "1/s", "speed PID proportional gain"),
    _P("control", "speed_ki", 0.1, 0.0, 2.0, "1/s^2", "speed PID integral gain"),
    _P("control", "speed_kd", 0.02, 0.0, 1.0, "", "speed PID derivative gain"),
    _P("control", "integral_limit_mps", 2.0, 0.0, 10.0, "m/s",
       "anti-windup bound of the speed integral"),
    _P("control", "station_kp", 0.2, 0.0, 2.0, "1/s^2",
       "acceleration per metre of station error"),
    _P("control", "low_speed_threshold_mps", 2.0, 0.0, 6.0, "m/s",
       "below this speed the low-speed proportional gain applies"),
    _P("control", "low_speed_kp", 1.2, 0.0, 5.0, "1/s", "speed proportional gain at low speed"),
    _P("control", "max_accel_cmd_mps2", 2.5, 0.5, 6.0, "m/s^2", "largest commanded acceleration"),
    _P("control", "max_decel_cmd_mps2", 8.0, 2.0, 12.0, "m/s^2", "largest commanded deceleration"),
    _P("control", "calibration_max_accel_mps2", 3.0, 1.0, 6.0, "m/s^2",
       "acceleration the controller believes 100 % throttle gives"),
    _P("control", "calibration_max_decel_mps2", 8.0, 4.0, 12.0, "m/s^2",
       "deceleration the controller believes 100 % brake gives"),
    _P("control", "throttle_deadzone_pct", 1.0, 0.0, 15.0, "%",
       "throttle commands below this are sent as 0"),
    _P("control", "brake_deadzone_pct", 1.0, 0.0, 15.0, "%",
       "brake commands below this are sent as 0"),
    _P("control", "estop_brake_pct", 100.0, 30.0, 100.0, "%", "brake command on an estop"),
    _P("control", "standstill_brake_pct", 30.0, 0.0, 100.0, "%",
       "brake held when the target speed is zero and the ego stands"),
    _P("control", "lateral_error_estop_m", 3.5, 0.05, 10.0, "m",
       "lateral error beyond which control raises an estop"),
)

PARAMETERS: dict[str, Param] = {}
for _p in _INVENTORY:
    if _p.full_name in PARAMETERS:
        raise RuntimeError(f"duplicate ADS parameter {_p.full_name}")
    if not _p.low <= _p.default <= _p.high:
        raise RuntimeError(f"default of {_p.full_name} is out of its range")
    PARAMETERS[_p.full_name] = _p


#: Parameters that cap how hard the ego may brake or switch a braking safeguard off. Lowering
#: them hides an emergency-braking accident from the oracle (the ego brakes at 3.9 m/s^2 and
#: runs the light instead) rather than removing its cause, so the cyber search leaves them alone.
BRAKING_LIMITS = frozenset({
    "canbus.brake_max_decel_mps2", "control.max_decel_cmd_mps2", "control.estop_brake_pct",
    "planning.max_decel_mps2", "planning.emergency_decel_mps2",
    "planning.perception_brake_decel_mps2", "planning.perception_brake_enabled",
})

#: Parameters that bound what perception can sense: detection ranges and fields of view. Shrinking
#: one avoids an accident by no longer seeing what the ADS misjudged (the red truck beyond 31 m,
#: the side road's light outside a narrow view), which hides the cause as a braking cap would, so
#: the cyber search may widen them but never narrow them.
SENSING_LIMITS = frozenset({
    "perception.max_range_m", "perception.fov_deg", "perception.rear_range_m",
    "perception.pedestrian_range_m", "perception.static_object_range_m",
    "perception.camera_range_m", "perception.color_max_distance_m",
    "perception.tl_max_range_m", "perception.tl_fov_deg",
})


#: Parameters that set how fast the ego drives: desired speeds, speed caps and accelerations.
#: Raising one avoids an accident by getting the ego through before the other party arrives, a
#: race won rather than a cause removed (generated A4 and A5 variants: the cruise speed 11 ->
#: 12.5 m/s, the junction speed 7 -> 7.6 m/s, each the smallest fix found while the documented
#: yield and overtake margins were about as small), so the cyber search may lower them but
#: never raise them.
PACE_LIMITS = frozenset({
    "planning.cruise_speed_mps", "planning.speed_limit_factor", "planning.junction_speed_mps",
    "planning.max_accel_mps2", "planning.max_lateral_accel_mps2", "control.max_accel_cmd_mps2",
    "canbus.throttle_max_accel_mps2",
})


def parameters(module: str | None = None) -> list[Param]:
    """Parameters of one module (or all), in inventory order."""
    return [p for p in _INVENTORY if module is None or p.module == module]


__all__ = ["BRAKING_LIMITS", "MODULES", "PACE_LIMITS", "PARAMETERS", "SENSING_LIMITS", "Param",
           "parameters"]
