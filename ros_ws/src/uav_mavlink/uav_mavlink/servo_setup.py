"""An ArduPlane's servo set-up read from its parameters (SERVOn_FUNCTION, _MIN, _MAX, _TRIM,
_REVERSED for the outputs n = 1..16) as the airframe that maps its SERVO_OUTPUT_RAW to the
project's surfaces: autopilot_parameters' inverse. No ROS here.

ServoParameterReads keeps track of the PARAM_REQUEST_READs a listener sends and the
PARAM_VALUEs that answer them (a lost one asked again, up to READ_ATTEMPTS times);
airframe_from_servo_parameters turns the answers into an Airframe. What the parameters mean
is autopilot_parameters' docstring: of the outputs of a function (4 aileron, 19 elevator,
21 rudder, 70 throttle) the one with the widest throw (the lowest-numbered of equals) is the
control's, a further one a copy of it (the airframe's `mixed`). A surface's full
deflection has no ArduPilot parameter: it is the airframe file's. ArduPilot scales a
command above trim by MAX - TRIM and below by TRIM - MIN; the airframe's map is one line
through the trim, so an output set up asymmetrically takes the mean of the two (said in the
notes).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

from uav_aircraft.airframe import REQUIRED_CONTROLS, THROTTLE, Airframe, MixedOutput, OutputMap

from uav_mavlink.autopilot_messages import SERVO_OUTPUTS
from uav_mavlink.autopilot_parameters import FUNCTIONS, SERVO_FIELDS

SERVO_PARAMETERS = tuple(f"SERVO{output}_{field}" for output in range(1, SERVO_OUTPUTS + 1)
                         for field in SERVO_FIELDS)
READ_ATTEMPTS = 5  # times each parameter is asked for before the file's map is kept
RETRY_S = 2.0  # wait for answers before asking again [s]
_ASYMMETRY_US = 1.0  # MAX - TRIM and TRIM - MIN further apart: said in the notes [us]


class ServoParameterReads:
    """The servo parameters asked for and answered (module docstring). due(now_s) gives the
    names to ask for now; take() an answer; done once all are answered or given up."""

    def __init__(self) -> None:
        self.values: dict[str, float] = {}
        self.attempts = 0
        self.asked_s: float | None = None
        self.given_up = False  # asked READ_ATTEMPTS times, RETRY_S past the last, unanswered

    def due(self, now_s: float) -> tuple[str, ...]:
        """The unanswered names when a read is due at now_s [s]: first, then RETRY_S after
        the last, READ_ATTEMPTS times in all; () otherwise (and given up RETRY_S after the
        last attempt with some unanswered)."""
        if self.done or (self.asked_s is not None and now_s - self.asked_s < RETRY_S):
            return ()
        if self.attempts >= READ_ATTEMPTS:
            self.given_up = True
            return ()
        self.attempts += 1
        self.asked_s = now_s
        return self.unanswered

    def take(self, name: str, value: float) -> None:
        """A PARAM_VALUE (its param_id, NUL padding ignored); other parameters are ignored."""
        name = name.rstrip("\0")
        if name in SERVO_PARAMETERS:
            self.values[name] = value

    @property
    def unanswered(self) -> tuple[str, ...]:
        return tuple(name for name in SERVO_PARAMETERS if name not in self.values)

    @property
    def complete(self) -> bool:
        return not self.unanswered

    @property
    def done(self) -> bool:
        return self.complete or self.given_up


def airframe_from_servo_parameters(values: Mapping[str, float], file_airframe: Airframe,
                                   source: str) -> tuple[Airframe, list[str]]:
    """The airframe the servo parameters (SERVO_PARAMETERS by name, all present) describe,
    with each surface's full deflection [rad] from file_airframe (a PWM airframe), named
    source; and notes, one line each, on what the parameters could not express (a surface
    the file gives no deflection for, an asymmetric throw, a copy trimmed apart from its
    original). ValueError when the aileron or the elevator is on no output."""
    outputs: dict[int, list[int]] = {}
    for output in range(1, SERVO_OUTPUTS + 1):
        outputs.setdefault(round(values[f"SERVO{output}_FUNCTION"]), []).append(output)
    notes: list[str] = []
    controls: dict[str, OutputMap] = {}
    mixed: list[MixedOutput] = []
    for name, function in FUNCTIONS.items():
        driving = outputs.get(function, [])
        if not driving:
            continue
        if name != THROTTLE and name not in file_airframe.controls:
            notes.append(f"{name} (output {driving[0]}): {file_airframe.path} gives no full "
                         "deflection for it, so it is left out")
            continue
        scale = 1.0 if name == THROTTLE else file_airframe.controls[name].scale
        maps = [_output_map(values, output, name, scale, notes) for output in driving]
        own = max(maps, key=lambda m: abs(m.span))  # the first of the widest throws
        controls[name] = own
        for copied in maps:
            if copied is own:
                continue
            mixed.append(MixedOutput(copied.output, own.output, copied.span / own.span))
            if abs(copied.zero - own.zero) > _ASYMMETRY_US:
                notes.append(f"SERVO{copied.output}_TRIM {copied.zero:.0f} differs from "
                             f"SERVO{own.output}_TRIM {own.zero:.0f}: its copy of the "
                             f"{name} is read about the latter")
    missing = [name for name in REQUIRED_CONTROLS if name not in controls]
    if missing:
        raise ValueError(f"no output drives the {' or the '.join(missing)} (SERVOn_FUNCTION "
                         f"{' or '.join(str(FUNCTIONS[n]) for n in missing)})")
    return dataclasses.replace(file_airframe, name=f"{file_airframe.name} ({source})",
                               controls=controls, mixed=tuple(mixed),
                               path=Path(source)), notes


def _output_map(values: Mapping[str, float], output: int, name: str, scale: float,
                notes: list[str]) -> OutputMap:
    """One output's map: a surface's about its trim, positive deflection the way a reversed
    output's PWM rises (ArduPlane's commands are the project's negated); the throttle's from
    MIN (none) to MAX, the other way when reversed."""
    low, high, trim = (values[f"SERVO{output}_{field}"] for field in ("MIN", "MAX", "TRIM"))
    reversed_ = round(values[f"SERVO{output}_REVERSED"]) == 1
    if name == THROTTLE:
        none_us, full_us = (high, low) if reversed_ else (low, high)
        return OutputMap(output, zero=none_us, span=full_us - none_us, scale=scale)
    if abs((high - trim) - (trim - low)) > _ASYMMETRY_US:
        notes.append(f"SERVO{output} ({name}) throws {high - trim:.0f} us up and "
                     f"{trim - low:.0f} us down from its trim: read with their mean")
    throw_us = (high - low) / 2.0
    return OutputMap(output, zero=trim, span=throw_us if reversed_ else -throw_us,
                     scale=scale)
