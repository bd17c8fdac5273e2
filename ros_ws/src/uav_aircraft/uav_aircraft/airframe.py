"""The airframe file: how a log's raw actuator outputs become the detector's surface
deflections, and what else a log does not say about the aircraft.

A YAML file, read strictly like a scenario (uav_common.strict_yaml): an unknown or missing
key, a wrong type or an out-of-range value stops with one AirframeError line naming the
file and the key. the Aerosonde's aircraft/aerosonde/airframes/aerosonde_sim.yaml is a commented
example; a vehicle's files are its Vehicle.airframe_files.

    name: aerosonde_sim          # the airframe's name (a calibration will name it)
    output_unit: pwm_us          # of the log's outputs: pwm_us or normalised
    axes: FLU                    # optional: FRD or FLU; absent: the log format's default
    airspeed_source: true        # optional: true, calibrated or indicated
    surfaces:
      aileron:  {output: 1, trim_us: 1500, throw_us: 500, max_deflection_rad: 0.52, sign: 1}
      elevator: {output: 2, trim_us: 1500, throw_us: 500, max_deflection_rad: 0.52, sign: -1}
      rudder:   {output: 4, trim_us: 1500, throw_us: 500, max_deflection_rad: 0.52, sign: 1}
      throttle: {output: 3, idle_us: 1000, full_us: 2000}
    mixed:                       # optional: outputs that copy another (a second aileron servo)
      - {output: 5, of_output: 1, factor: -1.0}

Surfaces (aileron and elevator required: the detector's generators use them; rudder and
throttle optional, NaN when absent). `output` is the 1-based output channel, as the log
names it (output_3). One form for every surface:

    deflection_rad = sign * max_deflection_rad * (pwm_us - trim_us) / throw_us

trim_us the PWM at zero deflection, throw_us (> 0) the PWM distance from trim to the full
deflection max_deflection_rad (> 0): the numbers a servo set-up gives (PX4's PWM_*_TRIM, its
MAX minus TRIM, and the surface's measured throw); sign +1 when a PWM above trim deflects the
surface the project's positive way (ControlInputs: a positive elevator pitches nose down, a
positive aileron rolls left, a positive rudder yaws left), -1 otherwise. The map is linear
and not clipped: a deflection beyond max_deflection_rad shows a wrong throw rather than hide
it. With normalised outputs (-1..1 at full throw) trim_us and throw_us are not given:
deflection_rad = sign * max_deflection_rad * value. Throttle: idle_us the PWM of no
throttle, full_us of full throttle, throttle = (pwm_us - idle_us) / (full_us - idle_us)
clipped to 0..1 (an ESC stops below idle and saturates above full); normalised: the value
clipped to 0..1.

Mixed outputs: an output that carries a scaled copy of another's command (a second aileron
servo, often reversed), (pwm_us - trim_us) = factor * (of_pwm_us - trim_us) with the trim of
the surface that of_output drives (0 for normalised outputs). A copy commands nothing new;
it is checked against the log (mixed_output_mismatches), which tells a right airframe file
from a wrong channel assignment, and it takes part in the vote for the surface's command: a
surface with two copies or more is commanded by the median of what its outputs imply
(intended_raw), so that one output pinned by a failure (ALFA injects a jammed surface so, a
servo fault would too) is outvoted by the others and the generators see what the autopilot
intended, not the injection. With one copy the surface's own output is read (two sources
cannot tell which is wrong). Elevons and other true mixes of two surfaces are not expressed.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from uav_common.strict_yaml import FileKind, Reader, load_yaml

# The values a file's keys take, one home: the log readers name theirs by these.
OUTPUT_UNITS = ("pwm_us", "normalised")  # of a log's raw actuator outputs
# What a log's airspeed is: true (TAS), calibrated (CAS) or indicated (IAS).
AIRSPEED_SOURCES = ("true", "calibrated", "indicated")
AXES = ("FRD", "FLU")  # a log's body axes
CONTROLS = ("aileron", "elevator", "rudder", "throttle")  # [rad, ControlInputs.msg's signs], 0..1

# An airframe file is a page of hand-written YAML: 16 KiB is ten times the example.
MAX_AIRFRAME_BYTES = 16 * 1024
# PX4's actuator_outputs and MAVLink's SERVO_OUTPUT_RAW (MAVROS RCOut) carry 16 outputs.
MAX_OUTPUTS = 16
# PWM that servos and ESCs take (nominally 1000-2000 us; some use 500-2500 us).
PWM_RANGE_US = (500.0, 2500.0)
# The most a surface may deflect: beyond a quarter turn a "surface" is no longer one.
MAX_DEFLECTION_RAD = np.pi / 2
REQUIRED_CONTROLS = ("aileron", "elevator")  # the detector's generators (self_tuning)
THROTTLE = "throttle"
# Sources a vote needs: the surface's own output and two copies (a median of two is their
# mean, which a pinned output would halve).
VOTING_SOURCES = 3


class AirframeError(ValueError):
    """An airframe file that cannot be used; the message names the file and the key."""


AIRFRAME_FILE = FileKind("airframe", AirframeError, MAX_AIRFRAME_BYTES,
                         "the example is under 2 kB")


@dataclass(frozen=True)
class OutputMap:
    """One output channel to one control: value = scale * (raw - zero) / span, with raw in
    the log's output unit; zero the raw value of no deflection (no throttle), span the raw
    change to full deflection (full throttle), its sign the surface's; scale the value at
    full: max_deflection_rad for a surface [rad], 1 for the throttle."""

    output: int
    zero: float
    span: float
    scale: float

    def value(self, raw: np.ndarray) -> np.ndarray:
        return self.scale * (raw - self.zero) / self.span

    def raw(self, value: np.ndarray) -> np.ndarray:
        """The raw output that gives value (value's inverse)."""
        return self.zero + self.span * value / self.scale


@dataclass(frozen=True)
class MixedOutput:
    """output carries factor times of_output's command, about of_output's trim."""

    output: int
    of_output: int
    factor: float


@dataclass(frozen=True)
class Airframe:
    """An airframe file: name, output_unit (OUTPUT_UNITS), the controls present by
    name (aileron, elevator, and rudder, throttle if given), the mixed outputs, the log's axes
    (AXES, None: the format's default) and airspeed source (AIRSPEED_SOURCES,
    None: whichever the log has), and the file read."""

    name: str
    output_unit: str
    controls: dict[str, OutputMap]
    mixed: tuple[MixedOutput, ...]
    axes: str | None
    airspeed_source: str | None
    path: Path


def _surface(reader: Reader, output_unit: str) -> OutputMap:
    common = {"output", "max_deflection_rad", "sign"}
    pwm = output_unit == "pwm_us"
    reader.check_keys(common | {"trim_us", "throw_us"} if pwm else common)
    sign = reader.choice("sign", (1, -1))
    zero = reader.number("trim_us", minimum=PWM_RANGE_US[0], maximum=PWM_RANGE_US[1]) if pwm \
        else 0.0
    throw = reader.number("throw_us", positive=True, maximum=np.diff(PWM_RANGE_US)[0]) if pwm \
        else 1.0
    return OutputMap(
        output=reader.integer("output", 1, MAX_OUTPUTS),
        zero=zero, span=sign * throw,
        scale=reader.number("max_deflection_rad", positive=True, maximum=MAX_DEFLECTION_RAD),
    )


def _throttle(reader: Reader, output_unit: str) -> OutputMap:
    if output_unit != "pwm_us":
        reader.check_keys({"output"})
        return OutputMap(reader.integer("output", 1, MAX_OUTPUTS), zero=0.0, span=1.0, scale=1.0)
    reader.check_keys({"output", "idle_us", "full_us"})
    idle_us, full_us = (reader.number(name, minimum=PWM_RANGE_US[0], maximum=PWM_RANGE_US[1])
                        for name in ("idle_us", "full_us"))
    if full_us == idle_us:
        reader.fail(f"'{reader.key('full_us')}' must differ from idle_us")
    return OutputMap(reader.integer("output", 1, MAX_OUTPUTS), zero=idle_us,
                     span=full_us - idle_us, scale=1.0)


def _controls(reader: Reader, output_unit: str) -> dict[str, OutputMap]:
    reader.check_keys(set(REQUIRED_CONTROLS), set(CONTROLS) - set(REQUIRED_CONTROLS))
    controls = {name: (_throttle if name == THROTTLE else _surface)(reader.child(name),
                                                                     output_unit)
                for name in CONTROLS if name in reader.data}
    drives: dict[int, str] = {}
    for name, control in controls.items():
        if control.output in drives:
            reader.fail(f"'{reader.key(name)}.output' is output {control.output}, already "
                        f"{drives[control.output]}'s (a copy belongs under mixed)")
        drives[control.output] = name
    return controls


def _mixed(reader: Reader, controls: dict[str, OutputMap]) -> tuple[MixedOutput, ...]:
    drives = {control.output: name for name, control in controls.items()}
    mixed: list[MixedOutput] = []
    for index in range(len(reader.items("mixed"))):
        entry = reader.element("mixed", index)
        entry.check_keys({"output", "of_output", "factor"})
        output = entry.integer("output", 1, MAX_OUTPUTS)
        of_output = entry.integer("of_output", 1, MAX_OUTPUTS)
        factor = entry.number("factor")
        if output in drives or output in {m.output for m in mixed}:
            entry.fail(f"'{entry.key('output')}' is output {output}, already mapped above")
        if of_output not in drives:
            entry.fail(f"'{entry.key('of_output')}' is output {of_output}, which no surface "
                       "uses")
        if factor == 0:
            entry.fail(f"'{entry.key('factor')}' must not be 0 (an output that is not a copy "
                       "needs no entry)")
        mixed.append(MixedOutput(output, of_output, factor))
    return tuple(mixed)


def load_airframe(path: str | Path) -> Airframe:
    """Read and check an airframe file; AirframeError with one line naming the file and key."""
    path = Path(path)
    reader = load_yaml(AIRFRAME_FILE, path)
    reader.check_keys({"name", "output_unit", "surfaces"}, {"mixed", "axes", "airspeed_source"})
    output_unit = reader.choice("output_unit", OUTPUT_UNITS)
    controls = _controls(reader.child("surfaces"), output_unit)
    return Airframe(
        name=reader.text("name"),
        output_unit=output_unit,
        controls=controls,
        mixed=_mixed(reader, controls),
        axes=reader.choice("axes", AXES) if "axes" in reader.data else None,
        airspeed_source=(reader.choice("airspeed_source", AIRSPEED_SOURCES)
                         if "airspeed_source" in reader.data else None),
        path=path,
    )


def intended_raw(airframe: Airframe, control: OutputMap, raw_of: Callable[[int], np.ndarray],
                 present: Collection[int]) -> np.ndarray:
    """The control's command (n,) in raw output units: its own output, or with at least
    VOTING_SOURCES - 1 copies among the present outputs (mixed) the median of its output and
    each copy's implied original, zero + (copy - zero) / factor (NaN-aware, per sample).
    raw_of(output) gives an output's raw values (n,); present: the outputs the source
    carries (1-based)."""
    own = raw_of(control.output)
    copies = [mixed for mixed in airframe.mixed
              if mixed.of_output == control.output and mixed.output in present]
    if 1 + len(copies) < VOTING_SOURCES:
        return own
    implied = [control.zero + (raw_of(mixed.output) - control.zero) / mixed.factor
               for mixed in copies]
    sources = np.column_stack([own, *implied])
    voted = np.full(own.shape, np.nan)
    known = np.isfinite(sources).any(axis=1)
    voted[known] = np.nanmedian(sources[known], axis=1)
    return voted


def control_values(airframe: Airframe, raw_of: Callable[[int], np.ndarray],
                   present: Collection[int], count: int) -> np.ndarray:
    """(count, len(CONTROLS)): aileron, elevator, rudder [rad] and throttle [0..1] through
    the airframe's maps (each control's intended_raw, raw_of and present as there); NaN for
    a control the airframe does not give; the throttle clipped to 0..1 (NaN stays NaN)."""
    values = np.full((count, len(CONTROLS)), np.nan)
    for index, name in enumerate(CONTROLS):
        if name in airframe.controls:
            control = airframe.controls[name]
            values[:, index] = control.value(intended_raw(airframe, control, raw_of, present))
    throttle = CONTROLS.index(THROTTLE)
    values[:, throttle] = np.clip(values[:, throttle], 0.0, 1.0)
    return values


def outputs_of_controls(airframe: Airframe, controls: dict[str, float]) -> dict[int, float]:
    """The raw outputs (by 1-based output) an autopilot would drive for the controls (by
    CONTROLS name: aileron, elevator, rudder [rad], throttle [0..1]) through the airframe's
    maps, a mixed output as its factor times its original's command: control_values'
    inverse, for a simulated autopilot's servo outputs. A control the airframe does not map,
    or a NaN one, drives nothing."""
    outputs = {}
    for name, control in airframe.controls.items():
        value = controls.get(name, np.nan)
        if np.isfinite(value):
            outputs[control.output] = float(control.raw(value))
    for mixed in airframe.mixed:
        if mixed.of_output in outputs:
            original = next(c for c in airframe.controls.values()
                            if c.output == mixed.of_output)
            outputs[mixed.output] = original.zero + mixed.factor * (
                outputs[mixed.of_output] - original.zero)
    return outputs
