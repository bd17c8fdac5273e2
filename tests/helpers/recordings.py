"""A simulated flight written as recorder_node records sim_node's streams (rosbag2): what
calibrate_model.py and calibrate_detector.py --bags read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from uav_common.channels import AIR_DATA_FIELDS, CONTROL_CHANNELS
from uav_common.health import VEHICLE_KEY, hardware_id
from uav_common.message_fields import CONTROL_FIELDS, STATE_FIELDS
from uav_fault_estimator.estimation.model_calibration import SensorFlight
from uav_fault_estimator.recording.project_bag import Recording, project_typestore


def write_recording(path: Path, flight: SensorFlight, seeded_pct: float = 0.0,
                    vehicle: str | None = None) -> Path:
    """The flight as recorder_node records sim_node's streams, a right-wing lift loss of
    seeded_pct [%] seeded from 10 s on /faults/seeded; with a vehicle, sim_node's
    /diagnostics saying it flies it, once a second."""
    typestore = project_typestore()
    types = typestore.types
    recording = Recording(path, typestore)
    topics = {"/state": "AircraftState", "/controls": "ControlInputs",
              "/wind/filtered": "WindEstimate", "/air_data": "AirData",
              "/faults/seeded": "FaultVector"}
    try:
        for topic, name in topics.items():
            recording.add_topic(topic, f"uav_fault_msgs/msg/{name}")
        if vehicle is not None:
            _write_vehicle_diagnostics(recording, flight.times_s, vehicle)
        for k, time_s in enumerate(flight.times_s):
            stamp_ns = round(time_s * 1e9)
            header = types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](
                sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000), frame_id="")
            fields = {
                "/state": dict(zip(STATE_FIELDS, map(float, flight.states[k]), strict=True)),
                "/controls": {f: bool(v) if c == "ignition" else float(v) for f, c, v in zip(
                    CONTROL_FIELDS, CONTROL_CHANNELS, flight.controls[k], strict=True)},
                "/wind/filtered": {"north_mps": float(flight.winds_ned_mps[k, 0]),
                                   "east_mps": float(flight.winds_ned_mps[k, 1]),
                                   "down_mps": float(flight.winds_ned_mps[k, 2]),
                                   "filter_time_constant_s": 10.0},
                "/air_data": dict(zip(AIR_DATA_FIELDS, map(float, flight.air_data[k]),
                                      strict=True)),
                "/faults/seeded": {"names": ["right_wing_lift_loss"],
                                   "values_pct": np.array([seeded_pct if time_s > 10.0 else 0.0])},
            }
            for topic, name in topics.items():
                message = types[f"uav_fault_msgs/msg/{name}"](header=header, **fields[topic])
                recording.write(topic, stamp_ns, typestore.serialize_cdr(
                    message, f"uav_fault_msgs/msg/{name}"))
    finally:
        recording.close()
    return path


def _write_vehicle_diagnostics(recording: Recording, times_s, vehicle: str) -> None:
    """sim_node's /diagnostics status saying the vehicle, at each whole second of times_s."""
    types, kind = recording.typestore.types, "diagnostic_msgs/msg/DiagnosticArray"
    recording.add_topic("/diagnostics", kind)
    for second in range(int(times_s[0]), int(times_s[-1]) + 1):
        status = types["diagnostic_msgs/msg/DiagnosticStatus"](
            level=0, name="/sim_node", message="flying", hardware_id=hardware_id(""),
            values=[types["diagnostic_msgs/msg/KeyValue"](key=VEHICLE_KEY, value=vehicle)])
        header = types["std_msgs/msg/Header"](
            stamp=types["builtin_interfaces/msg/Time"](sec=second, nanosec=0), frame_id="")
        recording.write("/diagnostics", second * 1_000_000_000, recording.typestore.serialize_cdr(
            types[kind](header=header, status=[status]), kind))
