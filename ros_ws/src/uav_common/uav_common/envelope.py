"""The physical envelope of the small aircraft this project flies: which measured values are
possible at all (no ROS here).

A value outside it (a stuck bit, a corrupted message, a unit mix-up) is not a fault of the
aircraft but of the data, and is treated like a missing value: replaced by NaN, so that the
consumers' handling of a lost channel (held last good value, rows invalid, recovery) takes
over, and nothing downstream, least of all a JSBSim model copy, ever sees it. The bounds are
generous, several times what the aircraft flies (the shipped scenarios, moderate turbulence
included, stay within a third of each), so that no real flight is cut.
"""

from __future__ import annotations

import math

import numpy as np

from uav_common.channels import (
    AIR_DATA_CHANNELS,
    CONTROL_CHANNELS,
    SETPOINT_FIELDS,
    STATE_CHANNELS,
)

# (low, high) per channel, in uav_common.channels order and units.
STATE_BOUNDS: dict[str, tuple[float, float]] = {
    # Angles [rad]: the range of either wrapping convention (-pi..pi or 0..2 pi), with room
    # for sensor noise (a heading of 0 reads 6.285 rad as often as 0.001).
    "latitude": (-2.0, 2.0),
    "longitude": (-7.0, 7.0),
    "altitude": (-500.0, 10_000.0),              # m: Dead Sea shore to beyond the ceiling
    "roll": (-4.0, 4.0),
    "pitch": (-2.0, 2.0),
    "yaw": (-7.0, 7.0),
    "velocity_north": (-100.0, 100.0),           # m/s: twice the top speed plus a gale
    "velocity_east": (-100.0, 100.0),
    "velocity_down": (-100.0, 100.0),
    "roll_rate": (-10.0, 10.0),                  # rad/s: about 570 deg/s
    "pitch_rate": (-10.0, 10.0),
    "yaw_rate": (-10.0, 10.0),
    "fuel_mass": (0.0, 20.0),                    # kg: four times the tank
    "engine_speed": (0.0, 20_000.0),             # rpm: over twice the engine's red line
}
CONTROL_BOUNDS: dict[str, tuple[float, float]] = {
    "flap": (-1.0, 1.0),                         # rad: the surfaces move ±0.5 at most
    "elevator": (-1.0, 1.0),
    "aileron": (-1.0, 1.0),
    "rudder": (-1.0, 1.0),
    "throttle": (-0.1, 1.1),                     # commands 0..1
    "mixture": (-0.1, 1.1),
    "ignition": (-0.1, 1.1),
}
AIR_DATA_BOUNDS: dict[str, tuple[float, float]] = {
    "airspeed": (0.0, 100.0),                    # m/s
    "angle_of_attack": (-math.pi / 2, math.pi / 2),  # rad
    "sideslip": (-math.pi / 2, math.pi / 2),
}
WIND_BOUND_MPS = 50.0  # per NED axis: a hurricane
# The fastest plausible change of the channels whose derivatives the residuals take, per
# second: 10 g of acceleration, 100 rad/s² of angular acceleration. The shipped flights
# (moderate turbulence, fault onsets and the sensor model included) reach 12 m/s² and
# 22 rad/s² from one 20 Hz sample to the next. A sample further from the channel's last
# accepted value than this allows since is a glitch, not a motion: one sample of +30 m/s in
# velocity (inside STATE_BOUNDS) would otherwise reach the residuals as a 600 m/s² impulse
# and pin every estimate.
STATE_RATE_BOUNDS: dict[str, float] = {
    "velocity_north": 100.0,                     # m/s²
    "velocity_east": 100.0,
    "velocity_down": 100.0,
    "roll_rate": 100.0,                          # rad/s²
    "pitch_rate": 100.0,
    "yaw_rate": 100.0,
}


def _limits(bounds: dict[str, tuple[float, float]],
            channels: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    return (np.array([bounds[name][0] for name in channels]),
            np.array([bounds[name][1] for name in channels]))


STATE_LIMITS = _limits(STATE_BOUNDS, STATE_CHANNELS)
# The autopilot's setpoints (SETPOINT_FIELDS) within the state's own bounds
SETPOINT_LIMITS = _limits({"roll_rad": STATE_BOUNDS["roll"], "pitch_rad": STATE_BOUNDS["pitch"],
                           "velocity_down_mps": STATE_BOUNDS["velocity_down"]},
                          SETPOINT_FIELDS)
CONTROL_LIMITS = _limits(CONTROL_BOUNDS, CONTROL_CHANNELS)
AIR_DATA_LIMITS = _limits(AIR_DATA_BOUNDS, AIR_DATA_CHANNELS)
WIND_LIMITS = (np.full(3, -WIND_BOUND_MPS), np.full(3, WIND_BOUND_MPS))


def gate(values: np.ndarray, limits: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, int]:
    """values with every entry outside limits (low, high) replaced by NaN, and how many were
    (NaN already there does not count: it is a missing value, not an implausible one)."""
    values = np.asarray(values, dtype=float)
    low, high = limits
    outside = (values < low) | (values > high)
    if not outside.any():
        return values, 0
    return np.where(outside, np.nan, values), int(outside.sum())


class RateGate:
    """A stream's glitches: each bounded channel (channels' names, bounds per second as
    STATE_RATE_BOUNDS) against its last accepted value. A value further from it than the
    bound times the time since is replaced by NaN (missing, as gate() does) and counted;
    the next samples are held against the same last good value, so a glitch of one sample
    is one missing sample, and a real step (a sensor re-initialised) passes once the time
    since allows it. NaN in, and the first sample, pass. reset() after a restart."""

    def __init__(self, channels: tuple[str, ...], bounds: dict[str, float]) -> None:
        self.index = np.array([channels.index(name) for name in bounds])
        self.bound = np.array(list(bounds.values()))
        self.reset()

    def reset(self) -> None:
        self.last = np.full(self.index.size, np.nan)
        self.last_time_s = np.full(self.index.size, np.nan)

    def __call__(self, time_s: float, values: np.ndarray) -> tuple[np.ndarray, int]:
        """values (in the stream's channel order) at time_s [s], the glitches NaN; and how
        many there were."""
        picked = values[self.index]
        jump = np.abs(picked - self.last) > self.bound * (time_s - self.last_time_s)  # NaN: no
        accepted = np.isfinite(picked) & ~jump
        self.last[accepted], self.last_time_s[accepted] = picked[accepted], time_s
        if not jump.any():
            return values, 0
        values = np.array(values, dtype=float)
        values[self.index[jump]] = np.nan
        return values, int(jump.sum())


def state_rate_gate() -> RateGate:
    """A RateGate for an AircraftState stream: STATE_RATE_BOUNDS on STATE_CHANNELS."""
    return RateGate(STATE_CHANNELS, STATE_RATE_BOUNDS)
