"""The aircraft's sensors: what a small UAV measures of the true state, controls and air data.

Each published channel is the true value plus, where a real sensor of its kind has them,
white noise, a constant bias drawn once per flight, and a first-order Gauss-Markov error
(slowly wandering, as GNSS position errors do). Values are datasheet-typical for a small UAV
with a GNSS/INS (the paper's states), a pitot-static probe and alpha/beta vanes; the source
is beside each number. What is not modelled: sensor lag and latency, quantisation, GNSS
outages, vane upwash and boom-rotation terms, pitot position error, scale-factor errors.

Every draw comes from the scenario seed, one random stream for the state and controls and one
for the air data, so flying without air data leaves the other channels' noise unchanged.
With noise off the measurements are the true values themselves (bit for bit). No ROS here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from uav_aircraft.flown_aircraft import SensorBias, biased_air_data
from uav_aircraft.frames import EARTH_RADIUS_M
from uav_common.channels import AIR_DATA_CHANNELS, CONTROL_CHANNELS, STATE_CHANNELS


@dataclass(frozen=True)
class ChannelNoise:
    """Error model of one channel, in the channel's unit (GNSS position: metres)."""

    white: float = 0.0  # standard deviation of white noise per sample
    bias: float = 0.0  # standard deviation of a constant bias drawn per flight
    markov: float = 0.0  # stationary standard deviation of a Gauss-Markov error
    markov_tau_s: float = 1.0  # its correlation time [s]


DEG = math.radians(1.0)
RPM_SENSOR = ChannelNoise(white=10.0)  # Hall tachometer, period timing: 0.2 % of 5000 rpm
SURFACE_SENSOR = ChannelNoise(white=0.1 * DEG)  # servo feedback potentiometer, 0.1 deg
GNSS_HORIZONTAL = ChannelNoise(markov=1.0, markov_tau_s=60.0)
GNSS_VERTICAL = ChannelNoise(markov=1.5, markov_tau_s=60.0)
INS_VELOCITY = ChannelNoise(white=0.05)
# Gyro: 0.0035 deg/s/sqrt(Hz) noise density over the 10 Hz band of 20 Hz samples; in-run
# bias stability 10 deg/h as the constant bias.
GYRO = ChannelNoise(white=0.0035 * math.sqrt(10.0) * DEG, bias=10.0 / 3600.0 * DEG)

# Sources: VectorNav VN-200 GNSS/INS datasheet (position 1.0 m horizontal, 1.5 m vertical,
# velocity 0.05 m/s, pitch/roll 0.03 deg, heading 0.2 deg, all RMS; gyro as above); the
# 60 s correlation of GNSS position errors is this model's choice, not a datasheet's. Fuel:
# a capacitive probe's 2 % of a 5 kg tank.
STATE_NOISE: dict[str, ChannelNoise] = {
    "latitude": GNSS_HORIZONTAL,
    "longitude": GNSS_HORIZONTAL,
    "altitude": GNSS_VERTICAL,
    "roll": ChannelNoise(white=0.03 * DEG),
    "pitch": ChannelNoise(white=0.03 * DEG),
    "yaw": ChannelNoise(white=0.2 * DEG),
    "velocity_north": INS_VELOCITY,
    "velocity_east": INS_VELOCITY,
    "velocity_down": INS_VELOCITY,
    "roll_rate": GYRO,
    "pitch_rate": GYRO,
    "yaw_rate": GYRO,
    "fuel_mass": ChannelNoise(white=0.1),
    "engine_speed": RPM_SENSOR,
}
# Surface positions are measured; throttle, mixture and ignition are the commands themselves.
CONTROL_NOISE: dict[str, ChannelNoise] = {
    "flap": SURFACE_SENSOR,
    "elevator": SURFACE_SENSOR,
    "aileron": SURFACE_SENSOR,
    "rudder": SURFACE_SENSOR,
}
# Pitot-static airspeed, MS4525DO-class differential pressure sensor: 0.3 m/s at 25 m/s;
# alpha/beta vanes of a mini air-data boom (SpaceAge Control class): 0.3 deg.
AIR_DATA_NOISE: dict[str, ChannelNoise] = {
    "airspeed": ChannelNoise(white=0.3),
    "angle_of_attack": ChannelNoise(white=0.3 * DEG),
    "sideslip": ChannelNoise(white=0.3 * DEG),
}


class ChannelErrors:
    """The errors of a group of channels, sample by sample: white + bias + Gauss-Markov,
    each scaled per channel (a channel absent from the model has no error)."""

    def __init__(self, channels: tuple[str, ...], model: dict[str, ChannelNoise],
                 scale: np.ndarray, period_s: float, rng: np.random.Generator) -> None:
        noise = [model.get(channel, ChannelNoise()) for channel in channels]
        self.white = scale * np.array([n.white for n in noise])
        self.markov = scale * np.array([n.markov for n in noise])
        self.decay = np.array([math.exp(-period_s / n.markov_tau_s) for n in noise])
        self.markov_drive = self.markov * np.sqrt(1.0 - self.decay**2)
        self.bias = scale * np.array([n.bias for n in noise]) * rng.standard_normal(len(noise))
        self.markov_error = self.markov * rng.standard_normal(len(noise))  # stationary start
        self.rng = rng

    def next(self) -> np.ndarray:
        """The error of the next sample, in the channels' units."""
        white, drive = self.rng.standard_normal((2, self.white.size))
        self.markov_error = self.decay * self.markov_error + self.markov_drive * drive
        return self.bias + self.markov_error + self.white * white


_FUEL_MASS = STATE_CHANNELS.index("fuel_mass")


def state_scale(latitude_rad: float) -> np.ndarray:
    """Unit conversion of STATE_NOISE to the state's units: GNSS metres to radians of
    latitude and longitude; 1 for every other channel."""
    scale = np.ones(len(STATE_CHANNELS))
    scale[STATE_CHANNELS.index("latitude")] = 1.0 / EARTH_RADIUS_M
    scale[STATE_CHANNELS.index("longitude")] = 1.0 / (EARTH_RADIUS_M * math.cos(latitude_rad))
    return scale


class SensorModel:
    """Measured state, controls and air data from the true ones, one sample at a time."""

    def __init__(self, noise: bool, period_s: float, latitude_rad: float,
                 state_rng: np.random.Generator, air_data_rng: np.random.Generator,
                 air_data_bias: SensorBias | None = None) -> None:
        self.noise = noise
        self.air_data_bias = None if air_data_bias in (None, SensorBias()) else air_data_bias
        self.state_errors = ChannelErrors(STATE_CHANNELS, STATE_NOISE, state_scale(latitude_rad),
                                          period_s, state_rng)
        self.control_errors = ChannelErrors(CONTROL_CHANNELS, CONTROL_NOISE,
                                            np.ones(len(CONTROL_CHANNELS)), period_s, state_rng)
        self.air_data_errors = ChannelErrors(AIR_DATA_CHANNELS, AIR_DATA_NOISE,
                                             np.ones(len(AIR_DATA_CHANNELS)), period_s,
                                             air_data_rng)

    def measure(self, state: np.ndarray, controls: np.ndarray,
                air_data: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Measured (state, controls, air data) of the true ones (arrays in uav_common.channels
        order); without noise, the true arrays themselves. The air data's bias (the flown
        aircraft's sensors) applies with or without noise."""
        if self.air_data_bias is not None:
            air_data = biased_air_data(air_data, self.air_data_bias)
        if not self.noise:
            return state, controls, air_data
        measured = state + self.state_errors.next()
        # a gauge reads no less than empty: an aircraft without fuel (electric) reads 0,
        # not noise around it (half of it negative: outside the envelope, a lost value)
        measured[_FUEL_MASS] = max(measured[_FUEL_MASS], 0.0)
        return (measured, controls + self.control_errors.next(),
                air_data + self.air_data_errors.next())

