"""The residual noise model of the estimator: Q per sensor suite, calibrated on a vehicle's
fault-free flights (scripts/calibrate_estimator.py writes its folder's residual_noise.yaml).

What the residuals carry without a fault is turbulence the models do not see plus sensor
noise, both through F_a, so it depends on where the models' wind came from: the air data
(Residuals.WIND_AIR_DATA), a pitot without vanes (WIND_PITOT) or the filtered wind
(WIND_FILTERED). A pitot's samples are those of an estimator that takes the wind errors
out as unknowns of its window: their calibration is of what the residuals carry beyond the
wind errors' fit (without_wind_errors). The calibration holds, per
suite, each residual channel's variance and one-step (0.5 s) correlation over the flights;
the estimator's Q is the variance times `variance_factor`, one factor for both suites. The
correlation after F_a (about exp(-0.5 / 4) = 0.88) means fewer independent samples than the
window holds; the factor stands for that (the AR(1) white-equivalent (1 + rho)/(1 - rho) =
16 would be the factor for a constant fault; the shipped 4 was tuned on the default
scenario, docs/estimator.md). No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from uav_aircraft.vehicles import DEFAULT_VEHICLE, load_vehicle
from uav_common.strict_yaml import kind_mismatch

from uav_fault_estimator.estimation.residuals import (
    RESIDUAL_CHANNELS,
    WIND_AIR_DATA,
    WIND_FILTERED,
    WIND_PITOT,
)

SUITES = {WIND_AIR_DATA: "air_data", WIND_PITOT: "pitot", WIND_FILTERED: "filtered_wind"}
# What a noise calibration file is, for the line that refuses a file of another kind
NOISE_CALIBRATION = ("a noise calibration (scripts/calibrate_estimator.py's file, a vehicle's "
                     "residual_noise.yaml)")
# suite name -> what the aircraft has on board: (a pitot, vanes) (scenario sensors.air_data,
# sensors.vanes)
SUITE_SENSORS = {"air_data": (True, True), "pitot": (True, False), "filtered_wind": (False, False)}


@dataclass(frozen=True)
class NoiseCalibration:
    """Per suite name (SUITES): variances (6,) [residual unit²] and one-step correlations
    (6,) of the fault-free residuals."""

    variances: dict[str, np.ndarray]
    correlations: dict[str, np.ndarray]

    def q_diag(self, wind_source: int, variance_factor: float) -> np.ndarray:
        """Q (6,) for residuals whose models flew wind_source."""
        return variance_factor * self.variances[SUITES[wind_source]]

    def to_dict(self, vehicle: str) -> dict:
        """The file's mapping: the vehicle it was made for, then each suite's."""
        return {"vehicle": vehicle} | {suite: {"channels": list(RESIDUAL_CHANNELS),
                        "variances": [float(v) for v in self.variances[suite]],
                        "one_step_correlations": [float(c) for c in self.correlations[suite]]}
                for suite in SUITES.values()}


class SuiteNoise:
    """Q per residual sample from its suite, or a hold.

    An aircraft without air data flies the filtered wind throughout: its samples get the
    filtered-wind suite's Q; one without vanes flies its pitot throughout, with the pitot
    suite's. Where the air data has been flown and is lost (the vanes or all of it), the
    wind's gust error is no white noise: its one-step correlation is about 0.99, so over a
    30 s loss it reads as a slowly changing fault whatever its Q (measured: 10 times Q, or
    the AR(1) white equivalent, still gave fault-free estimates of 3 %). Such samples are
    not used: the estimator holds its estimate (MovingHorizonEstimator.hold) through the
    loss and for HOLD_AFTER_TAU_A F_a time constants after it, while F_a still carries
    that wind's error (it fades as exp(-t / tau_a), tau_a the residuals' own, per sample).
    Inputs: the calibration and the variance factor (Q = factor times the variances).
    """

    # exp(-3) = 5 %: what F_a keeps of the filtered wind's error when the hold ends
    HOLD_AFTER_TAU_A = 3.0

    def __init__(self, calibration: NoiseCalibration, variance_factor: float) -> None:
        self.calibration, self.variance_factor = calibration, variance_factor
        self.reset()

    def reset(self) -> None:
        """A new flight: no sample before."""
        self.last_filtered_s = -math.inf
        self.air_data_flown = False

    def weigh(self, time_s: float, wind_source: int, tau_a_s: float) -> np.ndarray | None:
        """Q (6,) of the residual sample at time_s [s] whose newest model flew wind_source,
        filtered with F_a of time constant tau_a_s [s]; None when the estimator is to hold
        instead: the air data lost, or back for less than HOLD_AFTER_TAU_A times tau_a_s."""
        if wind_source != WIND_AIR_DATA:
            self.last_filtered_s = time_s
            if self.air_data_flown:
                return None
        elif (time_s - self.last_filtered_s < self.HOLD_AFTER_TAU_A * tau_a_s
              and self.air_data_flown):
            return None
        else:
            self.air_data_flown = True
        return self.calibration.q_diag(wind_source, self.variance_factor)


def without_wind_errors(residuals: np.ndarray, wind_sensitivity: np.ndarray) -> np.ndarray:
    """What fault-free residuals carry beyond the wind errors (K, 6): each sample (K, 6)
    less its least-squares fit by the wind-error columns of S (K, 6, w), rows weighted by
    the inverse of their mean squares, and scaled by sqrt(6 / (6 - r)), r the fit's rank,
    so that its mean square estimates the variance without the bias of the r degrees of
    freedom the fit takes."""
    weight = 1.0 / np.sqrt(np.mean(residuals**2, axis=0))
    left = np.empty_like(residuals)
    for k, (y, s) in enumerate(zip(residuals, wind_sensitivity, strict=True)):
        whitened_s = weight[:, None] * s
        fit, _, rank, _ = np.linalg.lstsq(whitened_s, weight * y, rcond=1e-6)
        left[k] = (y - s @ fit) * np.sqrt(y.size / (y.size - rank))
    return left


def white_share(correlations: np.ndarray) -> np.ndarray:
    """Per channel, the AR(1) white equivalent (1 - rho) / (1 + rho) of a one-step
    correlation rho (clipped to 0..0.99): the share of a sample that counts as independent."""
    rho = np.clip(correlations, 0.0, 0.99)
    return (1.0 - rho) / (1.0 + rho)


def fit_noise(residuals: dict[str, list[np.ndarray]]) -> NoiseCalibration:
    """The calibration from, per suite name, a list of flights' residual sequences (K, 6):
    variances about zero and one-step correlations pooled over the flights."""
    variances, correlations = {}, {}
    for suite, flights in residuals.items():
        squares = np.concatenate([flight**2 for flight in flights])
        lagged = np.concatenate([flight[1:] * flight[:-1] for flight in flights])
        variances[suite] = squares.mean(axis=0)
        correlations[suite] = lagged.mean(axis=0) / variances[suite]
    return NoiseCalibration(variances, correlations)


def shipped_noise_path(vehicle: str = DEFAULT_VEHICLE) -> Path:
    """The vehicle's residual_noise.yaml (its aircraft folder)."""
    return load_vehicle(vehicle).noise_file


def load_noise_calibration(path: str | Path = "",
                           vehicle: str = DEFAULT_VEHICLE) -> NoiseCalibration:
    """Read the vehicle's calibration file ("" for the shipped one); ValueError naming the
    file and what is wrong, a file made for another vehicle included."""
    path = Path(path) if path else shipped_noise_path(vehicle)
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        raise ValueError(f"noise calibration {path}: cannot be read ({error})") from None
    mismatch = kind_mismatch(data, ("vehicle", *SUITES.values()), NOISE_CALIBRATION)
    if mismatch:
        raise ValueError(f"noise calibration {path}: {mismatch}")
    try:
        made_for = data["vehicle"]
        variances = {suite: np.array(data[suite]["variances"], dtype=float)
                     for suite in SUITES.values()}
        correlations = {suite: np.array(data[suite]["one_step_correlations"], dtype=float)
                        for suite in SUITES.values()}
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"noise calibration {path}: cannot be read ({error})") from None
    if made_for != vehicle:
        raise ValueError(f"noise calibration {path}: made for the vehicle {made_for!r}, not "
                         f"{vehicle!r}")
    for suite, values in variances.items():
        if values.shape != (len(RESIDUAL_CHANNELS),) or not np.all(values > 0):
            raise ValueError(f"noise calibration {path}: {suite} needs "
                             f"{len(RESIDUAL_CHANNELS)} positive variances")
    return NoiseCalibration(variances, correlations)
