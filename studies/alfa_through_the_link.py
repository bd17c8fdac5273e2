#!/usr/bin/env python3
"""ALFA's flights through the MAVLink link against screen_logs.py, sample for sample.

    python studies/alfa_through_the_link.py FLIGHT_OR_FOLDER... --calibration CAL.yaml \\
        [--airframe AIRFRAME.yaml] [--false-alarm-probability 0.01]

Each flight is read two ways and run through the same detector core: as screen_logs.py reads
it (flight_logs.replay.load_replay, then detection.detector.run_detector), and as its
autopilot sent it (uav_mavlink.log_messages), each message packed and parsed as the link
carries it, read (autopilot_messages), put on the grid (sample_assembly, with the maximum
ages below) and turned into the streams (project_streams) that mavlink_node publishes. Per
flight it prints the combined alarms of each, whether the alarm samples are the same, the
grid samples the detector ran on in each, the link's release latency (how far behind the
autopilot's clock each sample went out) and how far the inputs of the samples both ran on
lie apart (the largest difference per channel). No ROS here.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np
from uav_aircraft.airframe import load_airframe
from uav_common.channels import CONTROL_CHANNELS, SETPOINT_FIELDS, STATE_CHANNELS
from uav_fault_estimator.detection.calibration_file import read_calibration
from uav_fault_estimator.detection.detector import SelfTuningDetector, run_detector
from uav_fault_estimator.flight_logs.readers import log_paths
from uav_fault_estimator.flight_logs.replay import load_replay

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_mavlink.autopilot_messages import (
    AIRSPEED,
    ATTITUDE,
    ENGINE,
    OUTPUTS,
    POSITION,
    SETPOINTS,
    VELOCITY,
    VELOCITY_SETPOINT,
    WIND,
    read_message,
)
from uav_mavlink.log_messages import BOOT_AT_START_S, log_messages
from uav_mavlink.project_streams import StreamConversion
from uav_mavlink.sample_assembly import SampleAssembly

AIRFRAME = Path("ros_ws/src/uav_aircraft/aircraft/carbon_z/airframes/carbon_z_alfa.yaml")
GRID_S = 0.05  # mavlink_node's sample_period_s
# mavlink_node's maximum ages raised for ALFA's rates (ATTITUDE 2.5 Hz, SERVO_OUTPUT_RAW
# 2.9 Hz, LOCAL_POSITION_NED 4 Hz, the rest faster): the longest gap a stream is interpolated
# over is 2.5 median periods, as flight_logs.resample's, at most these [s]
MAX_AGE_S = {ATTITUDE: 1.0, POSITION: 0.6, VELOCITY: 0.6, AIRSPEED: 1.0, OUTPUTS: 0.9,
             SETPOINTS: 3.0, VELOCITY_SETPOINT: 3.0, WIND: 3.0, ENGINE: 3.0}
WIND_TAU_S = 10.0
ANGLES = ("roll", "pitch", "yaw", "roll_rad", "pitch_rad")


def link_flight(path: Path, airframe_path: Path) -> tuple[np.ndarray, ...]:
    """The flight as mavlink_node publishes it: times [s from the log's start], state,
    controls, airspeed [m/s], setpoints, and each sample's release latency (the boot time of
    the message that released it less the sample's [s]), one row per grid sample."""
    assembly = SampleAssembly(GRID_S, MAX_AGE_S, 0.0)
    conversion = StreamConversion(load_airframe(airframe_path), WIND_TAU_S)
    sender, receiver = mavlink.MAVLink(None, srcSystem=1, srcComponent=1), mavlink.MAVLink(None)
    rows = []
    for timed in log_messages(path):
        reading = read_message(receiver.decode(bytearray(timed.message.pack(sender))))
        if reading is None:
            continue
        for sample in assembly.add(reading).samples:
            streams = conversion.streams(sample)
            rows.append((sample.boot_time_s - BOOT_AT_START_S, streams.state, streams.controls,
                         streams.air_data[0], streams.setpoints,
                         timed.boot_time_s - sample.boot_time_s))
    return tuple(np.array(column) for column in zip(*rows, strict=True))


def link_alarms(calibration, flight, probability: float) -> dict:
    """The detector over the link's samples, as detector_node runs it: sample time -> the
    detector's sample."""
    detector = SelfTuningDetector(calibration, probability)
    out = {}
    for time_s, state, controls, airspeed, setpoints, _ in zip(*flight, strict=True):
        sample = detector.update(time_s, state, controls, airspeed, setpoints)
        if sample is not None:
            out[round(time_s / calibration.sample_period_s)] = sample
    return out


def compared(path: Path, calibration, airframe_path: Path, probability: float) -> str:
    """One line: the flight's combined alarm samples by screen_logs and through the link."""
    period_s = calibration.sample_period_s
    replay = load_replay(path, airframe_path, None, period_s)
    inputs = replay.inputs
    logged = {round(s.time_s / period_s): s
              for s in run_detector(calibration, inputs.flight, probability)}
    flight = link_flight(path, airframe_path)
    linked = link_alarms(calibration, flight, probability)
    log_alarms = sorted(k for k, s in logged.items() if s.combined_alarm)
    link_alarm_keys = sorted(k for k, s in linked.items() if s.combined_alarm)
    both = sorted(set(logged) & set(linked))
    by_time = {round(t / period_s): k for k, t in enumerate(flight[0])
               if abs(t / period_s - round(t / period_s)) < 1e-6}
    log_index = {round(t / period_s): k for k, t in enumerate(inputs.times_s)}
    differences = []
    for channels, log_values, link_values in (
            (STATE_CHANNELS, inputs.state, flight[1]),
            (CONTROL_CHANNELS, inputs.controls, flight[2]),
            (SETPOINT_FIELDS, inputs.setpoints, flight[4])):
        rows = [(log_index[k], by_time[k]) for k in both if k in by_time and k in log_index]
        if not rows:
            continue
        a = log_values[[r[0] for r in rows]]
        b = link_values[[r[1] for r in rows]]
        gap = np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi)  # angles' short way
        linear = [k for k, channel in enumerate(channels) if channel not in ANGLES]
        gap[:, linear] = np.abs(a - b)[:, linear]
        for index, channel in enumerate(channels):
            finite = np.isfinite(gap[:, index])
            if finite.any() and gap[finite, index].max() > 0:
                differences.append(f"{channel} {np.nanmax(gap[:, index]):.2g}")
    equal = log_alarms == link_alarm_keys
    return (f"{path.name}: screen_logs {len(log_alarms)} alarm samples (first "
            f"{_first_s(log_alarms, period_s)} s), link {len(link_alarm_keys)} (first "
            f"{_first_s(link_alarm_keys, period_s)} s), "
            f"{'EQUAL' if equal else 'DIFFERENT'}; detector samples {len(logged)} / "
            f"{len(linked)}, in both {len(both)}; release latency mean "
            f"{flight[5].mean():.2f} s, largest {flight[5].max():.2f} s; largest input "
            f"differences: {', '.join(differences) or 'none'}")


def _first_s(keys: list[int], period_s: float) -> str:
    """The first alarm's time [s from the log's start], or "-"."""
    return f"{keys[0] * period_s:.1f}" if keys else "-"


def main(argv: list[str] | None = None) -> int:
    top = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    top.add_argument("logs", nargs="+", type=Path)
    top.add_argument("--calibration", type=Path, required=True)
    top.add_argument("--airframe", type=Path, default=AIRFRAME)
    top.add_argument("--false-alarm-probability", type=float, default=0.01)
    arguments = top.parse_args(argv)
    airframe = load_airframe(arguments.airframe)
    calibration = read_calibration(str(arguments.calibration), airframe.name)
    for path in log_paths(arguments.logs):
        print(compared(path, calibration, arguments.airframe,
                       arguments.false_alarm_probability), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
