"""The parameters a simulated ArduPlane answers, from an airframe file: its servo set-up
(SERVOn_FUNCTION, _MIN, _MAX, _TRIM, _REVERSED for the outputs n = 1..16) and its pitch trim
(PTCH_TRIM_DEG), each with the MAVLink type ArduPilot declares it with. No ROS here.

What ArduPilot's parameters mean (docs/onboard.md, MAVLink fields and units; SRV_Channel.h):
- FUNCTION: 4 aileron, 19 elevator, 21 rudder, 70 throttle, 0 disabled (an output the
  airframe does not map). A copy of a surface (the airframe's `mixed`: a second aileron
  servo) drives the same function.
- MIN, MAX, TRIM [us]: a surface's output is TRIM + v (MAX - TRIM) / 4500 for a command v > 0
  and TRIM - |v| (TRIM - MIN) / 4500 for v < 0; the throttle's goes from MIN (none) to MAX
  (full). An unmapped output has ArduPilot's defaults, 1100, 1900 and 1500.
- REVERSED (0 or 1) negates the command. ArduPlane's commands are positive for a roll to the
  right, a pitch up and a yaw to the right (its roll, pitch and yaw controllers' outputs),
  the project's surfaces the other way round (uav_aircraft.airframe: a positive aileron
  rolls left): a surface whose PWM rises with the project's positive deflection is reversed.
- PTCH_TRIM_DEG [deg]: 0, as the simulated autopilot sends the pitch as flown.

Only PWM airframes are expressed (ArduPilot drives PWM); the surfaces' deflection at full
throw (max_deflection_rad) has no ArduPilot parameter. A MIN/MAX/TRIM is the airframe's
PWM rounded to the whole microsecond ArduPilot stores.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_aircraft.airframe import THROTTLE, Airframe, OutputMap

from uav_mavlink.autopilot_messages import SERVO_OUTPUTS

FUNCTIONS = {"aileron": 4, "elevator": 19, "rudder": 21, THROTTLE: 70}  # SERVOn_FUNCTION
DISABLED = 0
DEFAULT_MIN_MAX_TRIM_US = (1100, 1900, 1500)  # an unmapped output's
# The suffixes of an output's parameters and their types: AP_Int16 MIN/MAX/TRIM, AP_Int8
# REVERSED, AP_Enum16 FUNCTION (SRV_Channel.h).
SERVO_FIELDS = {"FUNCTION": mavlink.MAV_PARAM_TYPE_INT16, "MIN": mavlink.MAV_PARAM_TYPE_INT16,
                "MAX": mavlink.MAV_PARAM_TYPE_INT16, "TRIM": mavlink.MAV_PARAM_TYPE_INT16,
                "REVERSED": mavlink.MAV_PARAM_TYPE_INT8}
PITCH_TRIM = "PTCH_TRIM_DEG"  # AP_Float


@dataclass(frozen=True)
class ParameterValue:
    """One parameter as PARAM_VALUE carries it: its name, value (ArduPilot sends integer
    parameters' values as floats), MAV_PARAM_TYPE and index in the table."""

    name: str
    value: float
    mav_type: int
    index: int


class ParameterTable:
    """An ArduPlane's parameters for an airframe (module docstring), in a fixed order:
    PTCH_TRIM_DEG, then SERVO1_FUNCTION .. SERVO16_REVERSED. ValueError for an airframe
    whose outputs are not PWM."""

    def __init__(self, airframe: Airframe) -> None:
        if airframe.output_unit != "pwm_us":
            raise ValueError(f"airframe {airframe.path}: outputs are {airframe.output_unit}, "
                             "but ArduPilot's servo parameters are PWM")
        named = [(PITCH_TRIM, 0.0, mavlink.MAV_PARAM_TYPE_REAL32)]
        for output in range(1, SERVO_OUTPUTS + 1):
            settings = servo_settings(airframe, output)
            named += [(f"SERVO{output}_{field}", float(settings[field]), mav_type)
                      for field, mav_type in SERVO_FIELDS.items()]
        self.values = [ParameterValue(name, value, mav_type, index)
                       for index, (name, value, mav_type) in enumerate(named)]
        self._by_name = {value.name: value for value in self.values}

    @property
    def count(self) -> int:
        """PARAM_VALUE's param_count."""
        return len(self.values)

    def read(self, name: str, index: int) -> ParameterValue | None:
        """The parameter PARAM_REQUEST_READ asks for: by index when index >= 0, else by name
        (param_id, NUL padding ignored); None for one the table does not have."""
        if index >= 0:
            return self.values[index] if index < len(self.values) else None
        return self._by_name.get(name.rstrip("\0"))

    def message(self, value: ParameterValue) -> Any:
        """The PARAM_VALUE that answers for value."""
        return mavlink.MAVLink_param_value_message(value.name.encode(), value.value,
                                                   value.mav_type, self.count, value.index)


def servo_settings(airframe: Airframe, output: int) -> dict[str, int]:
    """SERVO<output>_* by field (SERVO_FIELDS) for a 1-based output: the surface or throttle
    the airframe maps to it, or a copy of one (mixed), else disabled at the defaults."""
    copy = next((m for m in airframe.mixed if m.output == output), None)
    driven = copy.of_output if copy else output
    factor = copy.factor if copy else 1.0
    name = next((n for n, c in airframe.controls.items() if c.output == driven), None)
    if name is None:
        low, high, trim = DEFAULT_MIN_MAX_TRIM_US
        return {"FUNCTION": DISABLED, "MIN": low, "MAX": high, "TRIM": trim, "REVERSED": 0}
    control = airframe.controls[name]
    return {"FUNCTION": FUNCTIONS[name], **(_throttle_range(control, factor) if name == THROTTLE
                                            else _surface_range(control, factor))}


def _surface_range(control: OutputMap, factor: float) -> dict[str, int]:
    """A surface's output at factor times its own throw: symmetric about its trim, reversed
    when its PWM rises with the project's positive deflection (ArduPlane's negative)."""
    throw_us = abs(factor * control.span)
    return {"MIN": round(control.zero - throw_us), "MAX": round(control.zero + throw_us),
            "TRIM": round(control.zero), "REVERSED": int(factor * control.span > 0)}


def _throttle_range(control: OutputMap, factor: float) -> dict[str, int]:
    """The throttle's output from none to full (a copy: factor times its travel), reversed
    when full throttle is the lower PWM; its trim at no throttle."""
    none_us, full_us = control.zero, control.zero + factor * control.span
    return {"MIN": round(min(none_us, full_us)), "MAX": round(max(none_us, full_us)),
            "TRIM": round(none_us), "REVERSED": int(full_us < none_us)}
