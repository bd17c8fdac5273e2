"""An autopilot played by the simulator: a flight's samples as the MAVLink messages ArduPlane
or PX4 streams, each at its stream's rate on the autopilot's boot clock (the flight's time).

The inverse of autopilot_messages, in the units and integer fields the link carries
(docs/onboard.md, MAVLink fields and units): ATTITUDE [rad], GLOBAL_POSITION_INT [degE7,
mm, cm/s, cdeg], VFR_HUD (airspeed [m/s], throttle [%]), SERVO_OUTPUT_RAW (PWM [us] through
the airframe's servo mapping, rounded to whole microseconds), NAV_CONTROLLER_OUTPUT [deg],
and the stack's own:
ArduPlane's WIND (where the wind comes from [deg], |w|, w_D) and RPM; PX4's WIND_COV and
LOCAL_POSITION_NED. A HEARTBEAT once a second says which stack it is.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_aircraft.airframe import CONTROLS, Airframe, outputs_of_controls
from uav_aircraft.frames import north_east_m
from uav_common.channels import AIRSPEED_INDEX, CONTROL_CHANNELS, STATE_CHANNELS

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
MILLI_G_MPS2 = 9.80665e-3  # RAW_IMU's unit of acceleration, as MAVROS converts it [m/s^2]
# POSITION_TARGET_*'s type_mask: ignore the position (1, 2, 4), the acceleration (64, 128,
# 256), yaw (1024) and yaw rate (2048): a velocity alone
_VELOCITY_ONLY = 1 | 2 | 4 | 64 | 128 | 256 | 1024 | 2048
_MESSAGES = {ARDUPILOT: frozenset(ARDUPLANE_DEFAULT_HZ), PX4: frozenset(PX4_ONBOARD_HZ)}
_STATE = {name: index for index, name in enumerate(STATE_CHANNELS)}
_EULER, _RATES = ("roll", "pitch", "yaw"), ("roll_rate", "pitch_rate", "yaw_rate")
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


def flight_sample(time_s: float, state: np.ndarray, controls: np.ndarray,
                  air_data: np.ndarray | None, wind_ned_mps: np.ndarray,
                  setpoints: np.ndarray) -> FlightSample:
    """A FlightSample from the simulator's streams at time_s [s] (state, controls,
    air data or None, the wind NED [m/s], setpoints: uav_common.channels orders). Without
    a usable airspeed (no air data, or NaN) the autopilot's is the synthetic one an
    autopilot without a pitot flies on: the ground velocity less the wind [m/s]."""
    airspeed_mps = math.nan if air_data is None else float(air_data[AIRSPEED_INDEX])
    if not math.isfinite(airspeed_mps):
        velocity = state[[_STATE[f"velocity_{axis}"] for axis in ("north", "east", "down")]]
        airspeed_mps = float(np.linalg.norm(velocity - wind_ned_mps))
    return FlightSample(time_s, state, controls, airspeed_mps, wind_ned_mps, setpoints)


class AutopilotEmulator:
    """The messages a stack (ARDUPILOT or PX4) would stream for a flight's samples, each
    type at its rate [Hz] (rates_hz; a type of the stack not named is not sent). A message
    whose integer fields a sample cannot fill (a NaN or infinite value: a lost sensor) is
    not sent, and counted by type in `unsent`."""

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
        self.unsent: Counter[str] = Counter()

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
                try:
                    message = getattr(self, "_" + kind.lower())(sample)
                except (ValueError, OverflowError):  # round() of a NaN or infinity
                    self.unsent[kind] += 1
                    continue
                if message is not None:
                    due.append(message)
        return due

    def _heartbeat(self, _sample: FlightSample) -> Any:
        return heartbeat_message(self.stack)

    def _attitude(self, sample: FlightSample) -> Any:
        s = sample.state
        return attitude_message(sample.time_s, [s[_STATE[name]] for name in _EULER],
                                [s[_STATE[name]] for name in _RATES])

    def _global_position_int(self, sample: FlightSample) -> Any:
        s = sample.state
        north, east, down = (s[_STATE[f"velocity_{axis}"]] for axis in ("north", "east", "down"))
        return mavlink.MAVLink_global_position_int_message(
            _boot_ms(sample.time_s), round(math.degrees(s[_STATE["latitude"]]) * 1e7),
            round(math.degrees(s[_STATE["longitude"]]) * 1e7),
            round(s[_STATE["altitude"]] * 1e3),
            round((s[_STATE["altitude"]] - self.origin[2]) * 1e3),
            round(north * 100), round(east * 100), round(down * 100),
            round(math.degrees(s[_STATE["yaw"]]) % 360.0 * 100) % 36000)

    def _local_position_ned(self, sample: FlightSample) -> Any:
        s = sample.state
        north_m, east_m = north_east_m(s[_STATE["latitude"]], s[_STATE["longitude"]],
                                       self.origin[:2])
        return local_position_ned_message(
            sample.time_s, (north_m, east_m, self.origin[2] - s[_STATE["altitude"]]),
            [s[_STATE[f"velocity_{axis}"]] for axis in ("north", "east", "down")])

    def _vfr_hud(self, sample: FlightSample) -> Any:
        s = sample.state
        north, east = s[_STATE["velocity_north"]], s[_STATE["velocity_east"]]
        return vfr_hud_message(sample.airspeed_mps, math.hypot(north, east),
                               math.degrees(s[_STATE["yaw"]]),
                               sample.controls[CONTROL_CHANNELS.index("throttle")],
                               s[_STATE["altitude"]], -s[_STATE["velocity_down"]])

    def _servo_output_raw(self, sample: FlightSample) -> Any:
        controls = {name: sample.controls[CONTROL_CHANNELS.index(name)] for name in CONTROLS}
        outputs = outputs_of_controls(self.airframe, controls)
        return servo_output_raw_message(
            sample.time_s, [outputs.get(n, math.nan) for n in range(1, SERVO_OUTPUTS + 1)])

    def _nav_controller_output(self, sample: FlightSample) -> Any | None:
        roll_rad, pitch_rad, _ = sample.setpoints
        if not (math.isfinite(roll_rad) and math.isfinite(pitch_rad)):
            return None  # no command yet
        return nav_controller_output_message(roll_rad, pitch_rad)

    def _wind(self, sample: FlightSample) -> Any:
        return wind_message(sample.wind_ned_mps)

    def _wind_cov(self, sample: FlightSample) -> Any:
        return wind_cov_message(sample.time_s, sample.wind_ned_mps,
                                sample.state[_STATE["altitude"]])

    def _rpm(self, sample: FlightSample) -> Any:
        return mavlink.MAVLink_rpm_message(sample.state[_STATE["engine_speed"]], 0.0)


# The messages' packing from values in the project's units, shared by the emulator and by
# log_messages (a flight log's rows as the messages they were made from).

def heartbeat_message(stack: str) -> Any:
    """The autopilot's HEARTBEAT: a fixed wing of the stack (ARDUPILOT, PX4), armed, in
    its AUTO mode, active."""
    return mavlink.MAVLink_heartbeat_message(
        mavlink.MAV_TYPE_FIXED_WING, _AUTOPILOT[stack],
        mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
        _AUTO_MODE[stack], mavlink.MAV_STATE_ACTIVE, 3)


def attitude_message(time_s: float, euler_rad: Sequence[float],
                     rates_radps: Sequence[float]) -> Any:
    """ATTITUDE at boot time time_s [s]: roll, pitch, yaw [rad] (yaw into -pi..pi, as both
    stacks send it) and the body rates p, q, r [rad/s]."""
    roll, pitch, yaw = euler_rad
    return mavlink.MAVLink_attitude_message(_boot_ms(time_s), roll, pitch,
                                            math.remainder(yaw, 2.0 * math.pi), *rates_radps)


def local_position_ned_message(time_s: float, position_ned_m: Sequence[float],
                               velocity_ned_mps: Sequence[float]) -> Any:
    """LOCAL_POSITION_NED at boot time time_s [s]: position from the origin and velocity,
    north, east, down [m, m/s] (NaN: not known)."""
    return mavlink.MAVLink_local_position_ned_message(_boot_ms(time_s), *position_ned_m,
                                                      *velocity_ned_mps)


def vfr_hud_message(airspeed_mps: float, groundspeed_mps: float, heading_deg: float,
                    throttle: float, altitude_m: float, climb_mps: float) -> Any:
    """VFR_HUD: airspeed (0 when not known, as the stacks send it) and ground speed [m/s],
    heading [deg] (rounded into 0..359), throttle 0..1 (sent in whole %), altitude [m] and
    climb rate [m/s]."""
    return mavlink.MAVLink_vfr_hud_message(
        airspeed_mps if math.isfinite(airspeed_mps) else 0.0, groundspeed_mps,
        round(heading_deg) % 360, round(100 * throttle), altitude_m, climb_mps)


def servo_output_raw_message(time_s: float, pwm_us: Sequence[float]) -> Any:
    """SERVO_OUTPUT_RAW of port 0 at boot time time_s [s] (its uint32 of microseconds,
    wrapping): outputs 1..16 [us], rounded to whole microseconds (NaN or missing: 0, no
    output)."""
    whole_us = [round(value) if math.isfinite(value) else 0 for value in pwm_us]
    whole_us += [0] * (SERVO_OUTPUTS - len(whole_us))
    return mavlink.MAVLink_servo_output_raw_message(round(time_s * 1e6) % 2**32, 0, *whole_us)


def nav_controller_output_message(roll_rad: float, pitch_rad: float) -> Any:
    """NAV_CONTROLLER_OUTPUT of the commanded roll and pitch [rad] (sent in degrees); the
    bearings, distance and errors 0 (not known)."""
    return mavlink.MAVLink_nav_controller_output_message(
        math.degrees(roll_rad), math.degrees(pitch_rad), 0, 0, 0, 0.0, 0.0, 0.0)


def position_target_velocity_message(time_s: float, velocity_ned_mps: Sequence[float]) -> Any:
    """POSITION_TARGET_GLOBAL_INT at boot time time_s [s] carrying only a commanded velocity
    north, east, down [m/s]: its type_mask says to ignore the position, acceleration, yaw
    and yaw rate (left 0)."""
    return mavlink.MAVLink_position_target_global_int_message(
        _boot_ms(time_s), mavlink.MAV_FRAME_GLOBAL_INT, _VELOCITY_ONLY, 0, 0, 0.0,
        *velocity_ned_mps, 0.0, 0.0, 0.0, 0.0, 0.0)


def raw_imu_message(time_s: float, rates_radps: Sequence[float],
                    specific_force_mps2: Sequence[float]) -> Any:
    """ArduPilot's RAW_IMU (its IMU1 scaled, not raw) at boot time time_s [s]: the body
    rates [rad/s] in whole mrad/s and the specific force [m/s^2] in whole mG, FRD; the
    magnetometer 0 (not known)."""
    gyro = [round(rate * 1e3) for rate in rates_radps]
    accel = [round(force / MILLI_G_MPS2) for force in specific_force_mps2]
    return mavlink.MAVLink_raw_imu_message(round(time_s * 1e6), *accel, *gyro, 0, 0, 0)


def wind_message(wind_ned_mps: Sequence[float]) -> Any:
    """ArduPilot's WIND of the wind north, east, down [m/s] (the way it blows): where it comes
    from [deg], its 3-D speed and its down component, as ArduPilot sends them."""
    north, east, down = wind_ned_mps
    return mavlink.MAVLink_wind_message(math.degrees(math.atan2(-east, -north)),
                                        math.sqrt(north**2 + east**2 + down**2), down)


def wind_cov_message(time_s: float, wind_ned_mps: Sequence[float], altitude_m: float) -> Any:
    """PX4's WIND_COV at boot time time_s [s]: the wind north, east, down [m/s] at altitude
    altitude_m [m]; the variances and accuracies 0 (not known)."""
    return mavlink.MAVLink_wind_cov_message(round(time_s * 1e6), *wind_ned_mps, 0.0, 0.0,
                                            altitude_m, 0.0, 0.0)


def _boot_ms(time_s: float) -> int:
    """A boot time [s] as MAVLink's time_boot_ms [ms]."""
    return round(time_s * 1e3)
