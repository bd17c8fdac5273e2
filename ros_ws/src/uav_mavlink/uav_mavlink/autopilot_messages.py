"""What each MAVLink message an autopilot streams carries, in the project's channels and units.

One function per message (pymavlink's decoded message in, a `Reading` out): fields, units and
conventions as docs/onboard.md (MAVLink fields and units) gives them from the MAVLink XML
and the ArduPlane and PX4 sources. The project's conventions are uav_common.channels': NED,
radians, SI, a positive elevator pitching nose down (that mapping is the airframe's, from the
raw outputs).

- ATTITUDE: roll, pitch, yaw [rad] and the body rates p, q, r [rad/s]. (ArduPlane subtracts
  its pitch trim from the pitch it sends unless told not to: sample_assembly adds it back.)
- RAW_IMU (ArduPilot's IMU1, scaled: whole mrad/s) and HIGHRES_IMU (PX4, rad/s), each of
  its first IMU (id 0), and SCALED_IMU2 (ArduPilot's IMU2, mrad/s): the body rates p, q, r
  [rad/s], FRD (ArduPilot rotates every IMU by the board's orientation before it sends it).
  RAW_IMU's and HIGHRES_IMU's time_usec is boot time, or UNIX time where it is as large
  (the XML: tell by its magnitude): such a reading is untimed.
- GLOBAL_POSITION_INT: latitude, longitude [degE7], altitude above mean sea level [mm],
  velocities north, east, down [cm/s].
- LOCAL_POSITION_NED: velocities north, east, down [m/s] (PX4 streams it at 30 Hz).
- VFR_HUD: the airspeed [m/s] (the autopilot's airspeed estimate; no time field).
- SERVO_OUTPUT_RAW: the outputs' PWM [us] (servo1_raw .. servo16_raw on port 0; time_usec a
  uint32 of boot time in us, wrapping every 71.6 min).
- NAV_CONTROLLER_OUTPUT: the commanded roll and pitch [deg] (no time field; ArduPlane sends
  no ATTITUDE_TARGET on a fixed wing, and none of this in MANUAL).
- POSITION_TARGET_GLOBAL_INT: the commanded velocity north, east, down [m/s], when its
  type_mask does not say to ignore it (ArduPlane's EXT_STAT group).
- WIND (ArduPilot): the direction the wind comes from [deg], its speed (3-D) and vertical
  component [m/s]: ArduPilot sends atan2(-w_E, -w_N), |w| and w_D of its NED wind estimate w.
- WIND_COV (PX4): the wind north, east, down [m/s] (NaN: unknown); its time_usec is left
  unread (boot or UNIX time, the XML does not say which; the wind is slow).
- RPM (ArduPilot): the first sensor's speed [rpm].
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

# The streams a reading belongs to (sample_assembly samples each on the grid).
ATTITUDE, POSITION, VELOCITY, AIRSPEED, OUTPUTS, SETPOINTS, WIND, ENGINE = (
    "attitude", "position", "velocity", "airspeed", "outputs", "setpoints", "wind", "engine")
VELOCITY_SETPOINT = "velocity_setpoint"
RATES, RATES_2 = "rates", "rates_2"  # the body rates of the first IMU, of the second
STREAMS = (ATTITUDE, RATES, RATES_2, POSITION, VELOCITY, AIRSPEED, OUTPUTS, SETPOINTS,
           VELOCITY_SETPOINT, WIND, ENGINE)
# A time_usec of RAW_IMU or HIGHRES_IMU this large is UNIX time, not boot time [us] (2001)
_UNIX_TIME_US = 1e15
# POSITION_TARGET_*'s type_mask bits that say to ignore vx, vy, vz
_IGNORE_VELOCITY = 8 | 16 | 32
SERVO_OUTPUTS = 16  # SERVO_OUTPUT_RAW's servo1_raw .. servo16_raw
UINT32_US_S = 2**32 * 1e-6  # SERVO_OUTPUT_RAW.time_usec wraps after this [s]

_DEG_E7_TO_RAD = math.radians(1e-7)


@dataclass(frozen=True)
class Reading:
    """One message's values: its stream, the autopilot's boot time it carries [s] (None:
    a message without a time field, or a wrapping one: SERVO_OUTPUT_RAW's is
    wrapped_boot_time_s), and the values by channel name in the project's units."""

    stream: str
    boot_time_s: float | None
    values: dict[str, float]
    wrapped_boot_time_s: float | None = None


def attitude(message: Any) -> Reading:
    return Reading(ATTITUDE, message.time_boot_ms * 1e-3, {
        "roll": message.roll, "pitch": message.pitch, "yaw": message.yaw,
        "roll_rate": message.rollspeed, "pitch_rate": message.pitchspeed,
        "yaw_rate": message.yawspeed})


def _imu_rates(stream: str, boot_time_s: float | None, message: Any,
               scale: float) -> Reading:
    """The body rates of an IMU message whose gyro fields are in 1/scale rad/s."""
    return Reading(stream, boot_time_s, {"roll_rate": message.xgyro * scale,
                                         "pitch_rate": message.ygyro * scale,
                                         "yaw_rate": message.zgyro * scale})


def _boot_time_us(time_usec: int) -> float | None:
    """A time_usec that may be boot or UNIX time [us] as boot time [s]; None for UNIX."""
    return None if time_usec >= _UNIX_TIME_US else time_usec * 1e-6


def raw_imu(message: Any) -> Reading | None:
    """ArduPilot's IMU1 [mrad/s]; None for another IMU's (id, where sent, not 0)."""
    if getattr(message, "id", 0):
        return None
    return _imu_rates(RATES, _boot_time_us(message.time_usec), message, 1e-3)


def scaled_imu2(message: Any) -> Reading:
    """ArduPilot's IMU2 [mrad/s]."""
    return _imu_rates(RATES_2, message.time_boot_ms * 1e-3, message, 1e-3)


def highres_imu(message: Any) -> Reading | None:
    """PX4's first IMU [rad/s]; None for another's."""
    if getattr(message, "id", 0):
        return None
    return _imu_rates(RATES, _boot_time_us(message.time_usec), message, 1.0)


def global_position(message: Any) -> Reading:
    return Reading(POSITION, message.time_boot_ms * 1e-3, {
        "latitude": message.lat * _DEG_E7_TO_RAD, "longitude": message.lon * _DEG_E7_TO_RAD,
        "altitude": message.alt * 1e-3, "velocity_north": message.vx * 1e-2,
        "velocity_east": message.vy * 1e-2, "velocity_down": message.vz * 1e-2})


def local_position(message: Any) -> Reading:
    return Reading(VELOCITY, message.time_boot_ms * 1e-3, {
        "velocity_north": message.vx, "velocity_east": message.vy,
        "velocity_down": message.vz})


def vfr_hud(message: Any) -> Reading:
    return Reading(AIRSPEED, None, {"airspeed": message.airspeed})


def servo_outputs(message: Any) -> Reading:
    """Port 0's outputs 1..16 as output_N [us]; an output of 0 (ArduPilot's 'none') NaN."""
    values = {}
    for output in range(1, SERVO_OUTPUTS + 1):
        pwm_us = getattr(message, f"servo{output}_raw", 0)
        values[f"output_{output}"] = float(pwm_us) if pwm_us else math.nan
    return Reading(OUTPUTS, None, values, wrapped_boot_time_s=message.time_usec * 1e-6)


def nav_controller(message: Any) -> Reading:
    return Reading(SETPOINTS, None, {"roll_rad": math.radians(message.nav_roll),
                                     "pitch_rad": math.radians(message.nav_pitch)})


def position_target(message: Any) -> Reading | None:
    """The commanded velocity (vx, vy, vz: north, east, down [m/s]); None when its type_mask
    says to ignore it."""
    if message.type_mask & _IGNORE_VELOCITY:
        return None
    return Reading(VELOCITY_SETPOINT, message.time_boot_ms * 1e-3, {
        "velocity_north_mps": message.vx, "velocity_east_mps": message.vy,
        "velocity_down_mps": message.vz})


def ardupilot_wind(message: Any) -> Reading:
    """The wind the air moves with (towards), NED [m/s], from where it comes from."""
    down_mps = message.speed_z
    horizontal_mps = math.sqrt(max(message.speed**2 - down_mps**2, 0.0))
    from_rad = math.radians(message.direction)
    return Reading(WIND, None, {"north": -horizontal_mps * math.cos(from_rad),
                                "east": -horizontal_mps * math.sin(from_rad),
                                "down": down_mps})


def px4_wind(message: Any) -> Reading:
    return Reading(WIND, None, {"north": message.wind_x, "east": message.wind_y,
                                "down": message.wind_z})


def engine_rpm(message: Any) -> Reading:
    return Reading(ENGINE, None, {"engine_speed": message.rpm1})


DECODERS: dict[str, Callable[[Any], Reading | None]] = {
    "ATTITUDE": attitude,
    "RAW_IMU": raw_imu,
    "SCALED_IMU2": scaled_imu2,
    "HIGHRES_IMU": highres_imu,
    "GLOBAL_POSITION_INT": global_position,
    "LOCAL_POSITION_NED": local_position,
    "VFR_HUD": vfr_hud,
    "SERVO_OUTPUT_RAW": servo_outputs,
    "NAV_CONTROLLER_OUTPUT": nav_controller,
    "POSITION_TARGET_GLOBAL_INT": position_target,
    "WIND": ardupilot_wind,
    "WIND_COV": px4_wind,
    "RPM": engine_rpm,
}


def read_message(message: Any) -> Reading | None:
    """The message's Reading, or None for a message the chain does not use (a
    SERVO_OUTPUT_RAW of another port than 0, a position target without a velocity, another
    IMU's than the first)."""
    kind = message.get_type()
    if kind == "SERVO_OUTPUT_RAW" and message.port != 0:
        return None
    decoder = DECODERS.get(kind)
    return decoder(message) if decoder else None
