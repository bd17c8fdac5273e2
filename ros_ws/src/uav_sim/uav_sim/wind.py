"""Wind and turbulence of a scenario on JSBSim, and the filtered wind estimate.

Turbulence `from_wind` (the paper's) is the project's own von Karman model,
uav_sim.turbulence, driving JSBSim's gust properties. The named levels are JSBSim's Tustin
model (`atmosphere/turb-type` 4): the MIL-F-8785C / MIL-HDBK-1797 Dryden spectra in bilinear
(Tustin) discrete form, with intensity from the wind speed at 20 ft and a
probability-of-exceedance severity; the presets are those of JSBSim's documentation."""

from __future__ import annotations

import math
from dataclasses import dataclass

import jsbsim
import numpy as np
from uav_aircraft.fdm import M_PER_FT, property_nodes
from uav_common.filters import LowPass

from uav_sim.scenario import Wind
from uav_sim.turbulence import VonKarmanTurbulence, milspec_scales

TUSTIN = 4
FROM_WIND = "from_wind"
GUST_VELOCITY_FPS = tuple(f"atmosphere/gust-{axis}-fps" for axis in ("north", "east", "down"))
GUST_RATE_RADPS = tuple(f"atmosphere/gust-{axis}-rad_sec" for axis in "pqr")  # each vehicle XML's
WINGSPAN_FT = "metrics/bw-ft"


@dataclass(frozen=True)
class TurbulencePreset:
    windspeed_at_20ft_mps: float
    severity: int  # MIL-HDBK-1797 probability-of-exceedance index 1..7


# JSBSim documentation presets: light 25 ft/s / 3, moderate 50 ft/s / 4, severe 75 ft/s / 6.
TURBULENCE_PRESETS = {
    "light": TurbulencePreset(25.0 * M_PER_FT, 3),
    "moderate": TurbulencePreset(50.0 * M_PER_FT, 4),
    "severe": TurbulencePreset(75.0 * M_PER_FT, 6),
}


def background_wind_ned_mps(wind: Wind) -> np.ndarray:
    return np.array([wind.north_mps, wind.east_mps, wind.down_mps])


def start_wind(fdm: jsbsim.FGFDMExec, wind: Wind, seed: int) -> None:
    """Background wind (all three axes) and turbulence from the seed, after run_ic.

    Turbulence starts only now: JSBSim's run_ic with Tustin turbulence on spreads NaN.
    `from_wind` leaves JSBSim's turbulence off: von_karman_turbulence drives the gusts.
    """
    fdm["atmosphere/wind-north-fps"] = wind.north_mps / M_PER_FT
    fdm["atmosphere/wind-east-fps"] = wind.east_mps / M_PER_FT
    fdm["atmosphere/wind-down-fps"] = wind.down_mps / M_PER_FT
    preset = TURBULENCE_PRESETS.get(wind.turbulence)
    fdm["simulation/randomseed"] = seed
    if preset is None:
        fdm["atmosphere/turb-type"] = 0
        return
    fdm["atmosphere/turb-type"] = TUSTIN
    fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = (
        preset.windspeed_at_20ft_mps / M_PER_FT
    )
    fdm["atmosphere/turbulence/milspec/severity"] = preset.severity


def von_karman_turbulence(fdm: jsbsim.FGFDMExec, wind: Wind, airspeed_mps: float,
                          altitude_m: float, period_s: float,
                          rng: np.random.Generator) -> VonKarmanTurbulence:
    """The paper's turbulence for this wind: MIL-F-8785C intensities with the horizontal
    background wind speed as the wind at 20 ft, axes along the background wind (north when
    there is none), at the airspeed and altitude the aircraft holds."""
    return VonKarmanTurbulence(
        milspec_scales(math.hypot(wind.north_mps, wind.east_mps), altitude_m),
        airspeed_mps, fdm[WINGSPAN_FT] * M_PER_FT, math.atan2(wind.east_mps, wind.north_mps),
        period_s, rng)


class GustProperties:
    """The aircraft's gust properties, written at the control rate (nodes found once)."""

    def __init__(self, fdm: jsbsim.FGFDMExec) -> None:
        self.velocity_nodes = property_nodes(fdm, GUST_VELOCITY_FPS)
        self.rate_nodes = property_nodes(fdm, GUST_RATE_RADPS)

    def set(self, velocity_ned_mps: np.ndarray, body_rates_radps: np.ndarray) -> None:
        """Gust velocities (NED) [m/s] and body-axis gust rates [rad/s] for the following
        JSBSim steps."""
        for node, value in zip(self.velocity_nodes, velocity_ned_mps / M_PER_FT, strict=True):
            node.set_double_value(float(value))
        for node, value in zip(self.rate_nodes, body_rates_radps, strict=True):
            node.set_double_value(float(value))


def total_wind_ned_mps(fdm: jsbsim.FGFDMExec) -> np.ndarray:
    """The wind the aircraft meets now, background plus turbulence, NED [m/s]."""
    return (
        np.array([fdm[f"atmosphere/total-wind-{axis}-fps"] for axis in ("north", "east", "down")])
        * M_PER_FT
    )


class FilteredWind:
    """w_hat = w / (tau s + 1) (embedded-estimation paper, eq. 3-4), exact at the sample rate."""

    def __init__(self, tau_s: float, period_s: float) -> None:
        self.filter = LowPass(tau_s)
        self.period_s = period_s

    def update(self, wind_ned_mps: np.ndarray) -> np.ndarray:
        return self.filter.update(wind_ned_mps, self.period_s).copy()
