"""An autopilot played by the simulator: a flight's samples as the MAVLink messages ArduPlane
or PX4 streams, each at its stream's rate on the autopilot's boot clock (the flight's time).

The inverse of autopilot_messages, in the units and integer fields the link carries
(../shared/MAVLINK.md): ATTITUDE [rad], GLOBAL_POSITION_INT [degE7, mm, cm/s, cdeg], VFR_HUD
(airspeed [m/s], throttle [%]), SERVO_OUTPUT_RAW (PWM [us] through the airframe's servo
mapping, rounded to whole microseconds), NAV_CONTROLLER_OUTPUT [deg], and the stack's own:
ArduPlane's WIND (where the wind comes from [deg], |w|, w_D) and RPM; PX4's WIND_COV and
LOCAL_POSITION_NED. A HEARTBEAT once a second says which stack it is.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_aircraft.airframe import CONTROLS, Airframe, outputs_of_controls
from uav_aircraft.frames import north_east_m
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS

from uav_mavlink.autopilot_messages import SERVO_OUTPUTS
from uav_mavlink.stream_rates import ARDUPILOT, PX4

# ArduPlane at its defaults: every group at 1 Hz (SRn_* = 1).
ARDUPLANE_DEFAULT_HZ = dict.fromkeys(
    ("ATTITUDE", "RPM", "GLOBAL_POSITION_INT", "VFR_HUD", "SERVO_OUTPUT_RAW",
     "NAV_CONTROLLER_OUTPUT", "WIND"), 1.0)
# ArduPlane as docs/onboard.md advises (SRn_EXTRA1 25, POSITION, RC_CHAN and EXTRA2 10,
# EXT_STAT and EXTRA3 2).
ARDUPLANE_ADVISED_HZ = {"ATTITUDE": 25.0, "RPM": 25.0, "GLOBAL_POSITION_INT": 10.0,
                        "VFR_HUD": 10.0, "SERVO_OUTPUT_RAW": 10.0,
                        "NAV_CONTROLLER_OUTPUT": 2.0, "WIND": 2.0}
# PX4's onboard mode (MAV_n_MODE 2) defaults.
PX4_ONBOARD_HZ = {"ATTITUDE": 100.0, "GLOBAL_POSITION_INT": 50.0, "LOCAL_POSITION_NED": 30.0,
                  "VFR_HUD": 10.0, "SERVO_OUTPUT_RAW": 10.0, "NAV_CONTROLLER_OUTPUT": 10.0,
                  "WIND_COV": 10.0}
HEARTBEAT_HZ = 1.0
_MESSAGES = {ARDUPILOT: frozenset(ARDUPLANE_DEFAULT_HZ), PX4: frozenset(PX4_ONBOARD_HZ)}
_STATE = {name: index for index, name in enumerate(STATE_CHANNELS)}
_AUTO_MODE = {ARDUPILOT: 10, PX4: (4 << 16) | (4 << 24)}  # PLANE_MODE AUTO; PX4 AUTO.MISSION
_AUTOPILOT = {ARDUPILOT: mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, PX4: mavlink.MAV_AUTOPILOT_PX4}


@dataclass(frozen=True)
class FlightSample:
    """What the autopilot knows at one instant: time [s] (its boot time), state
    (STATE_CHANNELS), controls (CONTROL_CHANNELS), airspeed [m/s], the wind NED [m/s] and the
    setpoints (SETPOINT_FIELDS; NaN before its first command)."""

    time_s: float
    state: np.ndarray
    controls: np.ndarray
    airspeed_mps: float
    wind_ned_mps: np.ndarray
    setpoints: np.ndarray


class AutopilotEmulator:
    """The messages a stack (ARDUPILOT or PX4) would stream for a flight's samples, each
    type at its rate [Hz] (rates_hz; a type of the stack not named is not sent)."""

    def __init__(self, stack: str, airframe: Airframe, rates_hz: Mapping[str, float]) -> None:
        unknown = sorted(set(rates_hz) - _MESSAGES[stack])
        if unknown:
            raise ValueError(f"{stack} does not stream {unknown}")
        self.stack = stack
        self.airframe = airframe
        # the heartbeat first: a listener takes the autopilot from it
        self.periods_s = {"HEARTBEAT": 1.0 / HEARTBEAT_HZ,
                          **{kind: 1.0 / hz for kind, hz in rates_hz.items() if hz > 0}}
        self.due_s: dict[str, float] = {}
        self.origin: tuple[float, float, float] | None = None  # lat, lon [rad], alt [m]

    def messages(self, sample: FlightSample) -> list[Any]:
        """The messages due at the sample's time, in a stable order."""
        if self.origin is None:
            state = sample.state
            self.origin = (state[_STATE["latitude"]], state[_STATE["longitude"]],
                           state[_STATE["altitude"]])
        due = []
        for kind, period_s in self.periods_s.items():
            next_s = self.due_s.get(kind, sample.time_s)
            if sample.time_s + 1e-9 >= next_s:
                # the next due time on the rate's grid, never in the past (a slower caller)
                self.due_s[kind] = max(next_s + period_s, sample.time_s)
                message = getattr(self, "_" + kind.lower())(sample)
                if message is not None:
                    due.append(message)
        return due

    def _heartbeat(self, _sample: FlightSample) -> Any:
        return mavlink.MAVLink_heartbeat_message(
            mavlink.MAV_TYPE_FIXED_WING, _AUTOPILOT[self.stack],
            mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
            _AUTO_MODE[self.stack], mavlink.MAV_STATE_ACTIVE, 3)

    def _attitude(self, sample: FlightSample) -> Any:
        s = sample.state
        yaw = math.remainder(s[_STATE["yaw"]], 2.0 * math.pi)  # -pi..pi, as both stacks send
        return mavlink.MAVLink_attitude_message(
            _boot_ms(sample), s[_STATE["roll"]], s[_STATE["pitch"]], yaw,
            s[_STATE["roll_rate"]], s[_STATE["pitch_rate"]], s[_STATE["yaw_rate"]])

    def _global_position_int(self, sample: FlightSample) -> Any:
        s = sample.state
        north, east, down = (s[_STATE[f"velocity_{axis}"]] for axis in ("north", "east", "down"))
        return mavlink.MAVLink_global_position_int_message(
            _boot_ms(sample), round(math.degrees(s[_STATE["latitude"]]) * 1e7),
            round(math.degrees(s[_STATE["longitude"]]) * 1e7),
            round(s[_STATE["altitude"]] * 1e3),
            round((s[_STATE["altitude"]] - self.origin[2]) * 1e3),
            round(north * 100), round(east * 100), round(down * 100),
            round(math.degrees(s[_STATE["yaw"]]) % 360.0 * 100) % 36000)

    def _local_position_ned(self, sample: FlightSample) -> Any:
        s = sample.state
        north_m, east_m = north_east_m(s[_STATE["latitude"]], s[_STATE["longitude"]],
                                       self.origin[:2])
        return mavlink.MAVLink_local_position_ned_message(
            _boot_ms(sample), north_m, east_m, self.origin[2] - s[_STATE["altitude"]],
            *(s[_STATE[f"velocity_{axis}"]] for axis in ("north", "east", "down")))

    def _vfr_hud(self, sample: FlightSample) -> Any:
        s = sample.state
        north, east = s[_STATE["velocity_north"]], s[_STATE["velocity_east"]]
        throttle = sample.controls[CONTROL_CHANNELS.index("throttle")]
        return mavlink.MAVLink_vfr_hud_message(
            sample.airspeed_mps if math.isfinite(sample.airspeed_mps) else 0.0,
            math.hypot(north, east), round(math.degrees(s[_STATE["yaw"]])) % 360,
            round(100 * throttle), s[_STATE["altitude"]], -s[_STATE["velocity_down"]])

    def _servo_output_raw(self, sample: FlightSample) -> Any:
        controls = {name: sample.controls[CONTROL_CHANNELS.index(name)] for name in CONTROLS}
        outputs = outputs_of_controls(self.airframe, controls)
        pwm_us = [round(outputs[n]) if n in outputs else 0 for n in range(1, SERVO_OUTPUTS + 1)]
        return mavlink.MAVLink_servo_output_raw_message(
            round(sample.time_s * 1e6) % 2**32, 0, *pwm_us)

    def _nav_controller_output(self, sample: FlightSample) -> Any | None:
        roll_rad, pitch_rad, _ = sample.setpoints
        if not (math.isfinite(roll_rad) and math.isfinite(pitch_rad)):
            return None  # no command yet
        return mavlink.MAVLink_nav_controller_output_message(
            math.degrees(roll_rad), math.degrees(pitch_rad), 0, 0, 0, 0.0, 0.0, 0.0)

    def _wind(self, sample: FlightSample) -> Any:
        north, east, down = sample.wind_ned_mps
        return mavlink.MAVLink_wind_message(math.degrees(math.atan2(-east, -north)),
                                            math.sqrt(north**2 + east**2 + down**2), down)

    def _wind_cov(self, sample: FlightSample) -> Any:
        north, east, down = sample.wind_ned_mps
        return mavlink.MAVLink_wind_cov_message(
            round(sample.time_s * 1e6), north, east, down, 0.0, 0.0,
            sample.state[_STATE["altitude"]], 0.0, 0.0)

    def _rpm(self, sample: FlightSample) -> Any:
        return mavlink.MAVLink_rpm_message(sample.state[_STATE["engine_speed"]], 0.0)


def _boot_ms(sample: FlightSample) -> int:
    return round(sample.time_s * 1e3)
