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
from uav_aircraft.airframe import load_airframe
from uav_common.channels import AIR_DATA_CHANNELS, AIRSPEED_INDEX

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
    rows[:, AIRSPEED_INDEX] = airspeed_mps
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


@dataclass(frozen=True)
class ReplayTask:
    """load_replay's arguments as one campaign task, with the signature of the files they
    name (files_signature): a cached replay is one of these very files."""

    log_path: Path
    airframe_path: Path | None
    axes: str | None
    period_s: float
    files: tuple

    @classmethod
    def of(cls, log_path: Path, airframe_path: Path | None, axes: str | None,
           period_s: float) -> ReplayTask:
        named = [log_path, *([airframe_path] if airframe_path else [])]
        return cls(log_path, airframe_path, axes, period_s,
                   tuple(files_signature(path) for path in named))


def files_signature(path: Path) -> tuple[tuple[str, int, int], ...]:
    """A file's, or a folder's files', (relative name, size [bytes], modification time [ns]):
    put in a task that names a file, it makes the task's cache key change with the file."""
    path = Path(path)
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    return tuple((str(p.relative_to(path)) if path.is_dir() else p.name, p.stat().st_size,
                  p.stat().st_mtime_ns) for p in files if p.exists())


def replay_of(task: ReplayTask) -> LogReplay:
    """load_replay of a ReplayTask (a campaign's task function)."""
    return load_replay(task.log_path, task.airframe_path, task.axes, task.period_s)
