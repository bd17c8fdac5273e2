"""One sample of every project message, with literal field values the tests check."""

from __future__ import annotations

import re
from typing import Any

STAMP_SEC, STAMP_NANOSEC = 12, 500_000_000
FRAME_ID = "ned"

SAMPLE_FIELDS: dict[str, dict[str, Any]] = {
    "AircraftState": {
        "latitude_rad": 0.9704,
        "longitude_rad": 0.2182,
        "altitude_m": 1000.5,
        "roll_rad": 0.1,
        "pitch_rad": 0.05,
        "yaw_rad": -1.5,
        "velocity_north_mps": 24.0,
        "velocity_east_mps": 3.5,
        "velocity_down_mps": -0.25,
        "roll_rate_radps": 0.01,
        "pitch_rate_radps": -0.02,
        "yaw_rate_radps": 0.125,
        "fuel_mass_kg": 4.75,
        "engine_speed_rpm": 5500.0,
    },
    "ControlInputs": {
        "flap_rad": 0.0,
        "elevator_rad": -0.0625,
        "aileron_rad": 0.015625,
        "rudder_rad": -0.001,
        "throttle": 0.6,
        "mixture": 1.0,
        "ignition": True,
    },
    "WindEstimate": {
        "north_mps": 4.0,
        "east_mps": 3.0,
        "down_mps": -0.5,
        "filter_time_constant_s": 10.0,
    },
    "FaultVector": {
        "names": ["right_wing_lift_loss", "left_wing_drag_increase"],
        "values_pct": [10.0, 25.0],
    },
    "Residuals": {
        "residual": [0.5, -0.25, 1.0, 0.01, -0.02, 0.03],
        "observed": [1.0, 0.0, -9.5, 0.0, 0.0, 0.0],
        "predicted": [0.5, 0.25, -10.5, -0.01, 0.02, -0.03],
        "valid": [True, True, True, True, False, True],
        "fault_names": ["right_wing_lift_loss", "right_wing_drag_increase"],
        "sensitivity": [0.0, -0.01, 0.0, 0.0, 0.09, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.05],
    },
    "FaultEstimate": {
        "names": ["right_wing_lift_loss"],
        "values_pct": [9.5],
        "solver_status": 0,
        "updated": True,
        "horizon": 3,
        "horizon_s": 1.0,
        "window_values_pct": [9.0, 9.25, 9.5],
        "iterations": 7,
        "solve_time_ms": 0.375,
    },
    "FaultAlarm": {
        "channel_names": ["roll", "pitch", "yaw"],
        "statistic": [1.5, 30.0, 2.0],
        "threshold": [20.0, 20.0, 20.0],
        "alarm": [False, True, False],
        "parameter_deviation": [0.5, 4.0, 0.25],
        "parameter_threshold": 3.0,
        "parameter_alarm": True,
        "fast_statistic": [0.5, 6.25, 1.0],
        "fast_threshold": [4.5, 4.5, 4.75],
        "fast_alarm": [False, True, False],
        "template_kinds": ["engine_cut", "elevator_stuck"],
        "template_statistic": [2.5, 5.0],
        "template_threshold": [4.0, 4.25],
        "template_alarm": [False, True],
        "combined_alarm": True,
        "false_alarm_probability": 0.001,
        "fast_false_alarms_per_hour": 1.0,
        "template_false_alarms_per_hour": 0.1,
        "cause": "elevator",
    },
}


def topic_of(type_name: str) -> str:
    """Topic a sample is published on: `sample/<snake_case type>`."""
    return "sample/" + re.sub(r"(?<!^)(?=[A-Z])", "_", type_name).lower()


def build_sample(type_name: str) -> Any:
    """The sample message of a type, with its header stamped and framed."""
    import uav_fault_msgs.msg

    message = getattr(uav_fault_msgs.msg, type_name)(**SAMPLE_FIELDS[type_name])
    message.header.stamp.sec = STAMP_SEC
    message.header.stamp.nanosec = STAMP_NANOSEC
    message.header.frame_id = FRAME_ID
    return message
