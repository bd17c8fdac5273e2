"""A flight log as the streams the project's nodes take, on the detector's grid:
what log_replay_node publishes, so that detector_node runs unchanged on a real flight. No
ROS here.

Every grid point of the log is kept, also those whose rates or surfaces are missing (NaN):
the detector skips such a sample itself, exactly as it does offline (run_detector), while
leaving a row out would make a hole in the stamps, which the nodes' stamp guard reads as a
restart of the source once it is longer than its 2 s (and resets the detector).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uav_common.channels import AIR_DATA_CHANNELS

from uav_fault_estimator.flight_logs.airframe import load_airframe
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.resample import DetectorInputs, detector_samples
from uav_fault_estimator.flight_logs.streams import AIRSPEED


@dataclass(frozen=True)
class LogReplay:
    """A log on the grid: source (the path read), inputs (times_s (K,) [s], state (K, 14),
    controls (K, 7), setpoints, warnings: resample.DetectorInputs) and air_data (K, 3) in
    AIR_DATA_CHANNELS order (the log's airspeed [m/s], angle of attack and sideslip NaN:
    no log carries them), None for a log without airspeed."""

    source: str
    inputs: DetectorInputs
    air_data: np.ndarray | None

    @property
    def setpoints(self) -> np.ndarray | None:
        """(K, 3) the autopilot's setpoints (SETPOINT_FIELDS order), None for a log without
        any."""
        setpoints = self.inputs.setpoints
        return None if setpoints is None or np.isnan(setpoints).all() else setpoints


def air_data_rows(airspeed_mps: np.ndarray) -> np.ndarray:
    """(K, 3) rows in AIR_DATA_CHANNELS order from airspeed_mps (K,) [m/s]: the airspeed,
    the vanes' angles NaN (missing)."""
    rows = np.full((airspeed_mps.size, len(AIR_DATA_CHANNELS)), np.nan)
    rows[:, AIR_DATA_CHANNELS.index("airspeed")] = airspeed_mps
    return rows


def load_replay(log_path: str | Path, airframe_path: str | Path | None, axes: str | None,
                period_s: float) -> LogReplay:
    """The log at log_path on the grid of period_s [s]. airframe_path maps its actuator
    outputs to surfaces (None for a log that carries surfaces itself); axes ("FRD", "FLU")
    overrides the log's convention, else the airframe's `axes` if it names one, else the
    format's own. ValueError (one line naming the file) for a bad log or airframe."""
    airframe = load_airframe(airframe_path) if airframe_path else None
    log = read_log(Path(log_path), axes or (airframe.axes if airframe else None))
    inputs = detector_samples(log, airframe, period_s)
    air_data = air_data_rows(inputs.airspeed_mps) if AIRSPEED in log.streams else None
    return LogReplay(log.source, inputs, air_data)
