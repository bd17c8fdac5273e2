"""Whether a model calibration fits its flights: the check calibrate_model.py runs after it.

A fit can end looking good while it has pushed a difference the aircraft has in a parameter
it does not hold into those it does (drag into CDmin, a pitch damping into Cm0). Three
signs of that, each a warning naming what it suggests:

- the weighted residual per row (the fit's reduced chi-square, against the shipped noise
  model's variances) above MAX_WEIGHTED_RESIDUAL: the model still misses much of the flights;
- a parameter beyond MAX_PRIOR_DEVIATIONS of its prior: the flights pushed it where a real
  aircraft seldom is, likely standing in for one not fitted;
- a structured remainder: in one flight regime (straight, turning, climbing), a residual
  channel's mean beyond STRUCTURE_SIGMAS of the noise it should have,

      z = mean(y_c) / sqrt(variance_c / n_eff),   n_eff = n (1 - rho_c) / (1 + rho_c),

  as model_fit.py tests it in flight.

The noise the remainder is held against is the shipped noise model (config/
residual_noise.yaml: the model's own fault-free flights), never the one refitted on the
calibrated model's residuals: a refitted noise would widen to swallow the model error it is
to reveal. No ROS here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from uav_common.channels import state_indices

from uav_fault_estimator.estimation.model_calibration import ModelCalibration, SensorFlight
from uav_fault_estimator.estimation.noise_model import SUITES, NoiseCalibration, white_share
from uav_fault_estimator.estimation.residuals import RESIDUAL_CHANNELS, WIND_AIR_DATA

MAX_WEIGHTED_RESIDUAL = 3.0  # per row; about 1 (or less, in lighter air) when the model fits
MAX_PRIOR_DEVIATIONS = 2.0
STRUCTURE_SIGMAS = 6.0  # model_fit.py's in-flight threshold
TURNING_ROLL_RAD = np.radians(10.0)  # banked beyond this: turning
CLIMBING_MPS = 1.0  # climbing or sinking faster than this (not turning): climbing
REGIMES = ("straight", "turning", "climbing")
MIN_REGIME_SAMPLES = 20  # fewer samples of a regime: not judged
# What acts on each residual channel (model_parameters' names)
ACTING_ON = {
    "linear_x": ("CDmin", "CDinduced", "thrust_scale", "mass_scale", "airspeed_scale"),
    "linear_y": ("CYbeta", "CYdr", "sideslip_deg"),
    "linear_z": ("CL0", "CLalpha", "CLq", "mass_scale", "angle_of_attack_deg"),
    "angular_x": ("Clbeta", "Clp", "Clda", "Clr", "cg_y_cm", "cg_z_cm", "inertia_x_scale"),
    "angular_y": ("Cm0", "Cmalpha", "Cmq", "Cmde", "cg_x_cm", "cg_z_cm", "inertia_y_scale"),
    "angular_z": ("Cnbeta", "Cnr", "Cndr", "Cnp", "cg_y_cm", "inertia_z_scale"),
}
_ROLL, _VELOCITY_DOWN = state_indices("roll", "velocity_down")


@dataclass(frozen=True)
class CheckWarning:
    """One finding: what it is about (a parameter, a channel in a regime, or the fit) and
    one line saying it and what it suggests."""

    subject: str
    text: str


def regimes(flight: SensorFlight, times_s: np.ndarray) -> np.ndarray:
    """The flight regime (REGIMES) of the flight at each of times_s (K,) [s]: turning when
    banked beyond TURNING_ROLL_RAD, else climbing when |climb rate| exceeds CLIMBING_MPS,
    else straight."""
    index = np.clip(np.searchsorted(flight.times_s, times_s), 0, len(flight.times_s) - 1)
    states = flight.states[index]
    turning = np.abs(states[:, _ROLL]) > TURNING_ROLL_RAD
    climbing = np.abs(states[:, _VELOCITY_DOWN]) > CLIMBING_MPS
    return np.where(turning, "turning", np.where(climbing, "climbing", "straight"))


def remainder_sigmas(residuals: np.ndarray, noise: NoiseCalibration,
                     suite: str) -> np.ndarray:
    """z (6,) of the module docstring for residual rows (K, 6) of one suite."""
    variance, share = noise.variances[suite], white_share(noise.correlations[suite])
    effective = len(residuals) * share
    return residuals.mean(axis=0) / np.sqrt(variance / effective)


def check_calibration(calibration: ModelCalibration, flights: Sequence[SensorFlight],
                      noise: NoiseCalibration) -> list[CheckWarning]:
    """The module docstring's warnings for a calibration made from flights, its remainder
    held against noise (the shipped noise model)."""
    found = []
    if calibration.reduced_chi_square > MAX_WEIGHTED_RESIDUAL:
        found.append(CheckWarning("fit", (
            f"weighted residual {calibration.reduced_chi_square:.1f} per row (about 1 when "
            f"the model fits, above {MAX_WEIGHTED_RESIDUAL:g} here): the model misses much of "
            "the flights; see the channels below")))
    for name, value, mean, prior in zip(calibration.names, calibration.values,
                                        calibration.prior_mean, calibration.prior_std,
                                        strict=True):
        if abs(value - mean) > MAX_PRIOR_DEVIATIONS * prior:
            found.append(CheckWarning(name, (
                f"{name} at {value:+.1f} ({abs(value - mean) / prior:.1f} prior deviations): "
                "pushed there, it likely stands in for a difference not fitted; fit more "
                "parameters or check the aircraft")))
    found += _structured(calibration, flights, noise)
    return found


def _structured(calibration: ModelCalibration, flights: Sequence[SensorFlight],
                noise: NoiseCalibration) -> list[CheckWarning]:
    """A warning per channel and regime whose pooled remainder exceeds STRUCTURE_SIGMAS."""
    suite = SUITES[WIND_AIR_DATA]
    residuals = calibration.residuals[suite]
    labels = [regimes(flight, times) for flight, times in
              zip(flights, calibration.residual_times_s[suite], strict=True)]
    pooled, pooled_labels = np.concatenate(residuals), np.concatenate(labels)  # a flight or more
    found = []
    for regime in REGIMES:
        rows = pooled[pooled_labels == regime]
        if len(rows) < MIN_REGIME_SAMPLES:
            continue
        for channel, z in zip(RESIDUAL_CHANNELS, remainder_sigmas(rows, noise, suite),
                              strict=True):
            if abs(z) > STRUCTURE_SIGMAS:
                unfitted = [p for p in ACTING_ON[channel] if p not in calibration.names]
                found.append(CheckWarning(f"{channel} {regime}", (
                    f"{channel} keeps a mean of {z:+.1f} noise deviations when {regime} "
                    f"({len(rows)} samples): a structured remainder; what acts on it and "
                    f"was not fitted: {', '.join(unfitted) or 'none'}")))
    return found
