"""The peer: Keipour, Mousaei and Scherer's model-free detector ("Automatic real-time anomaly
detection for autonomous aerial vehicles", ICRA 2019, arXiv 1907.00511), as a reference to
run beside the project's detector on the same flights (scripts/alfa_benchmark.py). Not
production code: no node runs it.

What the paper fixes: no model of the aircraft and no training on failures; pairs of
correlated signals, the autopilot's commanded quantity (input) against the measured one
(output); the relation of each pair identified online by recursive least squares; an
anomaly where the pair's prediction residual passes its threshold; thresholds set on
failure-free flight. Only the paper's abstract and its result table could be read here,
so what it leaves open to this reader is chosen as follows, once, before any score:

- pairs: the commanded against the measured roll and pitch (ALFA's nav_info setpoints,
  attitude from /mavctrl/rpy) and ground velocity north, east, down (nav_info/velocity's
  command, local_position/velocity): the commanded/measured pairs every ALFA log carries;
  the yaw and airspeed pairs are left out (airspeed is 0 in every log from 2018-09-11 on).
- the relation: y[k] = b_0 u[k] + ... + b_(L-1) u[k-L+1] + c over INPUT_LAGS lags of the
  command at RATE_HZ (nav_info's own rate), identified by RLS with FORGETTING; the residual
  is the prediction error before each update (rls.py's eq. 9). The output's own past is
  left out of the regressors: with it the one-step prediction follows any response, and a
  failure would hide in it.
- the test: an alarm where |residual| exceeds the pair's threshold, the largest |residual|
  the pair gave in the calibration flights' fault-free parts (after WARM_UP_S of each
  flight, while RLS converges, in which no alarm is raised either). The paper set its
  thresholds on the flights it reports; here they come from the same folds as the
  project's calibration (leave a flight or a day out): what a user who flew before gets.
No ROS here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uav_aircraft.airframe import load_airframe

from uav_fault_estimator.detection.rls import RecursiveLeastSquares
from uav_fault_estimator.flight_logs.benchmark import Fold, fault_free, in_folds
from uav_fault_estimator.flight_logs.evaluation import FlightOutcome, alarms_outcome
from uav_fault_estimator.flight_logs.ground_truth import FlightTruth
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.replay import files_signature
from uav_fault_estimator.flight_logs.resample import ANGULAR, LINEAR, grid_times_s, resample
from uav_fault_estimator.flight_logs.streams import (
    ATTITUDE,
    GROUND_VELOCITY,
    PITCH_SETPOINT,
    ROLL_SETPOINT,
    VELOCITY_SETPOINT,
    FlightLog,
)

NAME = "keipour2019_rls"
RATE_HZ = 20.0  # nav_info's rate: the commands' own
INPUT_LAGS = 10  # u[k] .. u[k-9]: half a second of the command
FORGETTING = 0.999  # memory about 1000 samples (50 s): a failure is not learnt away in seconds
WARM_UP_S = 10.0  # RLS from zero parameters; no alarm and no threshold sample before it
P0 = 1e3  # initial covariance (times the identity): parameters free to move at first


@dataclass(frozen=True)
class Pair:
    """A commanded/measured pair: its name (the channel), the commanded stream and column,
    the measured stream and column, and how both are resampled (angles the short way)."""

    name: str
    command: tuple[str, int]
    measured: tuple[str, int]
    method: str


PAIRS = (
    Pair("roll", (ROLL_SETPOINT, 0), (ATTITUDE, 0), ANGULAR),
    Pair("pitch", (PITCH_SETPOINT, 0), (ATTITUDE, 1), ANGULAR),
    Pair("velocity_north", (VELOCITY_SETPOINT, 0), (GROUND_VELOCITY, 0), LINEAR),
    Pair("velocity_east", (VELOCITY_SETPOINT, 1), (GROUND_VELOCITY, 1), LINEAR),
    Pair("velocity_down", (VELOCITY_SETPOINT, 2), (GROUND_VELOCITY, 2), LINEAR),
)
CHANNELS = tuple(pair.name for pair in PAIRS)
# The pairs that read what each failed part acts on (its first alarm's "right channel").
RIGHT_CHANNELS: Mapping[str, tuple[str, ...]] = {
    "aileron": ("roll",), "elevator": ("pitch", "velocity_down"),
    "rudder": ("roll", "velocity_north", "velocity_east"),
    "engine": ("pitch", "velocity_down")}


@dataclass(frozen=True)
class PeerFlight:
    """A flight's pairs on the RATE_HZ grid: name, truth, stamps_s (K,) [s, the log's
    clock], residuals (K, len(PAIRS)) (NaN where a pair cannot predict: a gap, the warm-up)."""

    name: str
    truth: FlightTruth
    stamps_s: np.ndarray
    residuals: np.ndarray


def pair_series(log: FlightLog) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times_s (K,) [s from the log's start], commands (K, P), measured (K, P)) on the
    RATE_HZ grid over the span the commands cover; ValueError for a log without them."""
    missing = [name for name in (ROLL_SETPOINT, PITCH_SETPOINT, VELOCITY_SETPOINT, ATTITUDE,
                                 GROUND_VELOCITY) if name not in log.streams]
    if missing:
        raise ValueError(log.missing(missing[0], f"{NAME} needs"))
    commands = log.streams[ROLL_SETPOINT]
    times_s = grid_times_s(commands.times_s[0], commands.times_s[-1], 1.0 / RATE_HZ)

    def column(stream: str, index: int, method: str) -> np.ndarray:
        return resample(log.streams[stream], times_s, method)[:, index]

    command = np.column_stack([column(*pair.command, pair.method) for pair in PAIRS])
    measured = np.column_stack([column(*pair.measured, pair.method) for pair in PAIRS])
    return times_s, command, measured


def prediction_residuals(times_s: np.ndarray, command: np.ndarray,
                         measured: np.ndarray) -> np.ndarray:
    """Each pair's RLS prediction error (K, P) (the module's docstring); NaN where a lag
    window or the output is not finite (the model is then neither used nor updated) and in
    the first WARM_UP_S."""
    residuals = np.full(command.shape, np.nan)
    models = [RecursiveLeastSquares(np.zeros(INPUT_LAGS + 1), P0 * np.eye(INPUT_LAGS + 1),
                                    FORGETTING) for _ in PAIRS]
    for k in range(INPUT_LAGS - 1, times_s.size):
        for j, model in enumerate(models):
            phi = np.append(command[k - INPUT_LAGS + 1:k + 1, j][::-1], 1.0)
            y = measured[k, j]
            if np.all(np.isfinite(phi)) and np.isfinite(y):
                residuals[k, j] = model.update(phi, y).prediction_error
    residuals[times_s < times_s[0] + WARM_UP_S] = np.nan
    return residuals


def peer_flight(name: str, path: Path, airframe_path: Path, truth: FlightTruth) -> PeerFlight:
    """One ALFA flight read and run through the pairs' RLS."""
    log = read_log(path, load_airframe(airframe_path).axes)
    times_s, command, measured = pair_series(log)
    return PeerFlight(name, truth, log.start_stamp_s + times_s,
                      prediction_residuals(times_s, command, measured))


def thresholds(flights: Sequence[PeerFlight]) -> np.ndarray:
    """(P,) the largest |residual| of each pair over the flights' fault-free parts (those
    the project's calibration learns from: benchmark.fault_free)."""
    parts = np.vstack([flight.residuals[fault_free(flight.stamps_s, flight.truth)]
                       for flight in flights])
    return np.nanmax(np.abs(parts), axis=0)


def outcome(flight: PeerFlight, threshold: np.ndarray) -> FlightOutcome:
    """The flight held against its truth with these thresholds, by the project's counting."""
    with np.errstate(invalid="ignore"):
        raised = np.abs(flight.residuals) > threshold  # NaN compares False
    right = tuple(channel for kind in (flight.truth.failure or "").split("+") if kind
                  for channel in RIGHT_CHANNELS[kind])
    end_stamp_s = float(flight.stamps_s[-1])
    return alarms_outcome(flight.name, flight.truth, flight.stamps_s, raised, CHANNELS, right,
                          end_stamp_s)


def screened_in_folds(flights: Sequence[PeerFlight], folds: Sequence[Fold],
                      calibration_flights: Sequence[PeerFlight] | None = None
                      ) -> list[FlightOutcome]:
    """Every flight held against its truth with the thresholds of its fold's calibration
    flights (indices into calibration_flights, flights themselves by default)."""
    calibration_flights = flights if calibration_flights is None else calibration_flights
    return in_folds(len(flights), folds,
                    lambda indices: thresholds([calibration_flights[j] for j in indices]),
                    lambda k, threshold: outcome(flights[k], threshold))


@dataclass(frozen=True)
class PeerTask:
    """peer_flight's arguments as a campaign task, with the signature of the files they name
    (a cached result is one of these very files)."""

    name: str
    path: Path
    airframe_path: Path
    truth: FlightTruth
    files: tuple

    @classmethod
    def of(cls, path: Path, airframe_path: Path, truth: FlightTruth) -> PeerTask:
        return cls(path.name, path, airframe_path, truth,
                   (files_signature(path), files_signature(airframe_path)))


def peer_flight_of(task: PeerTask) -> PeerFlight:
    """peer_flight of a PeerTask (a campaign's task function)."""
    return peer_flight(task.name, task.path, task.airframe_path, task.truth)
