"""The self-tuning detector's calibration (Blanke & Hansen): what fault-free flights taught
of each residual generator, and the parameters' airspeed schedule. The detector that uses it
is detector.py; its fitting calibration_fit.py; its file calibration_file.py. No ROS here.

Airspeed schedule (the paper's a_pa(U), a_qe(U), a_ra(U), b_ra(U), "air speed U being the
dominating parameter"): a calibration made from flights at several speeds may make the
parameters' fault-free means affine in airspeed, mean_i(U) = mean_i + slope_i (U - U_ref),
U the airspeed filtered with the RLS's own forgetting factor (the parameters' memory), so
that a slow aircraft is not taken for a broken one. The RLS and the GLRT are unchanged: the
RLS tracks the parameters, the GLRT's statistic is scale-free (docs/detector.md says why
this form and not gains normalised by U or U^2).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from uav_aircraft.vehicles import DEFAULT_VEHICLE

from uav_fault_estimator.detection.change_detection import Weibull

# What a calibration is made with unless told otherwise; each calibration carries its own
# (Calibration), and the detector runs with the calibration's.
DEFAULT_SAMPLE_PERIOD_S = 0.2  # the paper's 5 Hz: the grid of every calibration made here
DEFAULT_SETTLE_S = 30.0  # no test until the RLS has had this long after a start [s]
# lambda_f of the RLS: a memory of about 200 samples (40 s); below 0.5 the RLS would
# remember about two samples, nothing left to identify
DEFAULT_FORGETTING_FACTOR = 0.995
DEFAULT_WINDOW = 25  # M, the GLRT's window [samples]
# W, the fast test's window [samples]: 3 s at 5 Hz. Chosen on the dev flights of
# studies/failure_kinds.py (seeds from 501; docs/detector.md): of 2, 3, 4 and 5 s, 3 s found
# the most single-aileron failures of the Carbon-Z within 5 s with no fault-free alarm.
DEFAULT_FAST_WINDOW = 15
# R, the fast test's reference before its window [samples]: 30 s at 5 Hz, long beside W
# (its mean's noise adds W/R to the statistic's variance) and short beside a day's drift.
DEFAULT_FAST_REFERENCE = 150


def simulated_airframe(vehicle: str = DEFAULT_VEHICLE) -> str:
    """The airframe of a vehicle as the simulator flies it, which its shipped calibration
    names; a calibration holds for its airframe only."""
    return f"{vehicle}_sim"


SIMULATED_AIRFRAME = simulated_airframe()
# Least spread of the calibration flights' airspeeds (5th to 95th percentile) for an airspeed
# schedule: over less, the slopes are not told from the noise.
MIN_SCHEDULE_SPAN_MPS = 2.0

@dataclass(frozen=True)
class FastTestCalibration:
    """What fault-free flights taught of one generator's residual with its parameters fixed
    at theta0 (the fast test's): its standard deviation, and the Weibull distribution of the
    window statistic (change_detection.SlidingMeanChange) on them."""

    residual_std: float
    statistic: Weibull


@dataclass(frozen=True)
class ChannelCalibration:
    """What fault-free flights taught of one generator: initial parameters theta0 and
    covariance P0 of the RLS, the parameters' mean (at the reference airspeed when
    scheduled) and standard deviation in flight, the Weibull distribution of its GLRT
    statistic, the fast test's calibration, and with an airspeed schedule the means'
    slopes [per m/s]."""

    theta0: np.ndarray
    p0: np.ndarray
    parameter_mean: np.ndarray
    parameter_std: np.ndarray
    glrt: Weibull
    fast: FastTestCalibration
    parameter_slope: np.ndarray | None = None

    def expected_parameters(self, airspeed_offset_mps: float) -> np.ndarray:
        """The fault-free mean of the parameters at U_ref + airspeed_offset_mps."""
        if self.parameter_slope is None:
            return self.parameter_mean
        return self.parameter_mean + self.parameter_slope * airspeed_offset_mps



@dataclass(frozen=True)
class Calibration:
    """The detector's calibration; valid for its sample period, forgetting factor, GLRT
    window and fast-test windows only (the statistics' distributions depend on them)."""

    sample_period_s: float
    forgetting_factor: float
    window: int
    settle_s: float  # after a (re)start, no test until the RLS has had this long
    channels: Mapping[str, ChannelCalibration]  # by generator name (generators.GENERATORS)
    parameter: Weibull  # of the largest normalised parameter deviation over the channels
    airframe: str = SIMULATED_AIRFRAME
    reference_airspeed_mps: float | None = None  # U_ref of the airspeed schedule; None: none
    fast_window: int = DEFAULT_FAST_WINDOW  # W of the fast test [samples]
    fast_reference: int = DEFAULT_FAST_REFERENCE  # R of the fast test [samples]

    @property
    def scheduled(self) -> bool:
        return self.reference_airspeed_mps is not None

    @property
    def channel_names(self) -> tuple[str, ...]:
        """The generators (generators.GENERATORS) the calibration holds, in its order."""
        return tuple(self.channels)



def parameter_deviations(theta: np.ndarray, channel: ChannelCalibration,
                         airspeed_offset_mps: float | np.ndarray = 0.0) -> np.ndarray:
    """(theta_i - mean_i(U)) / std_i for each of a channel's parameters; theta (n,) or
    (K, n) for K samples, airspeed_offset_mps U - U_ref [m/s] (scalar or (K,); unused
    without a schedule)."""
    offset = np.asarray(airspeed_offset_mps, dtype=float)[..., None]
    return (theta - channel.expected_parameters(offset)) / channel.parameter_std


def parameter_deviation(theta: np.ndarray, channel: ChannelCalibration,
                        airspeed_offset_mps: float | np.ndarray = 0.0) -> np.ndarray:
    """The largest |theta_i - mean_i(U)| / std_i over a channel's parameters (section
    III.C); theta (n,) or (K, n), airspeed_offset_mps as parameter_deviations takes them."""
    return np.max(np.abs(parameter_deviations(theta, channel, airspeed_offset_mps)), axis=-1)


