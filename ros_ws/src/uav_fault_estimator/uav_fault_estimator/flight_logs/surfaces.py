"""A flight log's surface deflections through its airframe file (uav_aircraft.airframe): the
outputs' map to deflections, the vote of a surface's copies, and the copies' check."""

from __future__ import annotations

import numpy as np
from uav_aircraft.airframe import CONTROLS, MAX_OUTPUTS, Airframe, control_values

from uav_fault_estimator.flight_logs.streams import (
    OUTPUTS,
    FlightLog,
    TimedSeries,
)

# A copy (mixed) may differ from factor times its original by this much of the throw
# (PWM rounding to 1 us on a 400-500 us throw is 0.25 %).
MIXED_TOLERANCE_OF_THROW = 0.02


def output_column(output: int) -> str:
    """The OUTPUTS stream's column of a 1-based output channel: output_3."""
    return f"output_{output}"


def _outputs(log: FlightLog, airframe: Airframe) -> TimedSeries:
    """The log's OUTPUTS stream, checked against the airframe's unit; ValueError otherwise."""
    if OUTPUTS not in log.streams:
        raise ValueError(f"log {log.source}: no actuator outputs to map with airframe "
                         f"{airframe.path}")
    if log.output_unit != airframe.output_unit:
        raise ValueError(f"log {log.source} has {log.output_unit} outputs, airframe "
                         f"{airframe.path} maps {airframe.output_unit} ones")
    return log.streams[OUTPUTS]


def _raw(outputs: TimedSeries, output: int, log: FlightLog, airframe: Airframe) -> np.ndarray:
    """The raw values (n,) of one output channel; ValueError when the log lacks it."""
    column = output_column(output)
    if column not in outputs.columns:
        raise ValueError(f"log {log.source} has no {column}, which airframe {airframe.path} "
                         f"maps (the log has {', '.join(outputs.columns) or 'none'})")
    return outputs.values[:, outputs.columns.index(column)]


def surface_deflections(log: FlightLog, airframe: Airframe) -> TimedSeries:
    """The SURFACES stream (aileron, elevator, rudder [rad], throttle [0..1]) at the OUTPUTS
    stream's instants, through the airframe's maps and votes (airframe.control_values); NaN
    for a control the airframe does not give. ValueError (one line) for a log without
    outputs, with outputs of another unit, or without an output the airframe maps."""
    outputs = _outputs(log, airframe)
    present = {output for output in range(1, MAX_OUTPUTS + 1)
               if output_column(output) in outputs.columns}
    values = control_values(airframe, lambda output: _raw(outputs, output, log, airframe),
                            present, outputs.times_s.size)
    return TimedSeries(outputs.times_s, values, CONTROLS)


def mixed_output_mismatches(log: FlightLog, airframe: Airframe) -> list[str]:
    """One line per mixed output that the log contradicts: absent, or somewhere further from
    factor times its original than MIXED_TOLERANCE_OF_THROW of the original's throw (samples
    where either is NaN are not compared). Empty when the log bears the file out."""
    outputs = _outputs(log, airframe)
    by_output = {control.output: control for control in airframe.controls.values()}
    lines = []
    for mixed in airframe.mixed:
        column = output_column(mixed.output)
        if column not in outputs.columns:
            lines.append(f"airframe {airframe.path}: log {log.source} has no {column} "
                         f"(mixed: a copy of output_{mixed.of_output})")
            continue
        original = by_output[mixed.of_output]
        copy = _raw(outputs, mixed.output, log, airframe) - original.zero
        expected = mixed.factor * (_raw(outputs, mixed.of_output, log, airframe) - original.zero)
        error_of_throw = np.abs(copy - expected) / abs(original.span)
        compared = np.isfinite(error_of_throw)
        if compared.any() and error_of_throw[compared].max() > MIXED_TOLERANCE_OF_THROW:
            worst = np.flatnonzero(compared)[np.argmax(error_of_throw[compared])]
            lines.append(
                f"airframe {airframe.path}: in log {log.source} {column} is not "
                f"{mixed.factor:g} x output_{mixed.of_output} (off by "
                f"{100 * error_of_throw[worst]:.0f} % of the throw at "
                f"t = {outputs.times_s[worst]:.2f} s)")
    return lines
