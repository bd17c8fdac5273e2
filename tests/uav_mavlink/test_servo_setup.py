"""An ArduPlane's servo parameters read back as an airframe: the simulated ArduPlane's
answers (autopilot_parameters, from an airframe file) give that file's maps again; what the
parameters cannot express is said; lost answers are asked for again, then given up."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_aircraft.airframe import CONTROLS, control_values, load_airframe
from uav_aircraft.vehicles import load_vehicle
from uav_mavlink.autopilot_parameters import ParameterTable
from uav_mavlink.servo_setup import (
    READ_ATTEMPTS,
    RETRY_S,
    SERVO_PARAMETERS,
    ServoParameterReads,
    airframe_from_servo_parameters,
)

AIRFRAMES = [("aerosonde", "aerosonde_sim"), ("carbon_z", "carbon_z_sim"),
             ("carbon_z", "carbon_z_alfa")]


def answered(airframe) -> dict[str, float]:
    """What the simulated ArduPlane answers for each servo parameter."""
    table = ParameterTable(airframe)
    return {name: table.read(name, -1).value for name in SERVO_PARAMETERS}


@pytest.mark.timeout(10)
@pytest.mark.parametrize(("vehicle", "name"), AIRFRAMES)
def test_the_parameters_of_an_airframe_read_back_as_its_maps(vehicle, name):
    airframe = load_airframe(load_vehicle(vehicle).airframe_files[name])
    read, notes = airframe_from_servo_parameters(answered(airframe), airframe, "system 1")
    assert notes == []
    assert read.controls.keys() == airframe.controls.keys()
    for control, own in airframe.controls.items():
        got = read.controls[control]
        assert (got.output, got.scale) == (own.output, own.scale), control
        # whole microseconds on the link: each trim and throw to within 0.5 us
        assert got.zero == pytest.approx(own.zero, abs=0.5), control
        assert got.span == pytest.approx(own.span, abs=0.5), control
    assert {(m.output, m.of_output) for m in read.mixed} == \
        {(m.output, m.of_output) for m in airframe.mixed}
    for mixed in airframe.mixed:
        factor = next(m.factor for m in read.mixed if m.output == mixed.output)
        assert factor == pytest.approx(mixed.factor, abs=1e-3), mixed
    # the same PWM outputs give the same controls through either (1 us of PWM is 0.2 % of a
    # 500 us throw: within 1e-3 of full deflection)
    rng = np.random.default_rng(3)
    pwm_us = rng.uniform(1000.0, 2000.0, size=(50, 16))
    through = [control_values(a, lambda output: pwm_us[:, output - 1], range(1, 17), 50)
               for a in (airframe, read)]
    scale = np.array([airframe.controls[c].scale if c in airframe.controls else 1.0
                      for c in CONTROLS])
    np.testing.assert_allclose(through[1] / scale, through[0] / scale, atol=2e-3)


@pytest.mark.timeout(10)
def test_what_the_parameters_cannot_express_is_said_and_a_missing_surface_refused():
    airframe = load_airframe(load_vehicle("aerosonde").airframe_files["aerosonde_sim"])
    values = answered(airframe)
    values["SERVO1_MAX"] += 40  # the aileron throws 40 us further up than down
    values["SERVO7_FUNCTION"] = 19  # a second elevator servo, trimmed 20 us apart
    values.update({"SERVO7_MIN": 1020, "SERVO7_MAX": 2020, "SERVO7_TRIM": 1520,
                   "SERVO7_REVERSED": 0})
    read, notes = airframe_from_servo_parameters(values, airframe, "system 1")
    assert len(notes) == 2
    assert "SERVO1 (aileron) throws 540 us up and 500 us down" in notes[0]
    assert "SERVO7_TRIM 1520 differs from SERVO2_TRIM 1500" in notes[1]
    assert read.controls["aileron"].span == pytest.approx(
        math.copysign(520.0, airframe.controls["aileron"].span))
    # SERVO2 reversed (its PWM rises with the project's positive elevator), SERVO7 not
    assert [(m.output, m.of_output, m.factor) for m in read.mixed] == [(7, 2, -1.0)]

    values["SERVO2_FUNCTION"] = values["SERVO7_FUNCTION"] = 0
    with pytest.raises(ValueError, match="no output drives the elevator"):
        airframe_from_servo_parameters(values, airframe, "system 1")


@pytest.mark.timeout(10)
def test_lost_answers_are_asked_for_again_then_given_up():
    reads = ServoParameterReads()
    assert reads.due(0.0) == SERVO_PARAMETERS
    assert reads.due(RETRY_S / 2) == ()  # the answers are on their way
    for name in SERVO_PARAMETERS[1:]:
        reads.take(name + "\0\0", 1.0)  # NUL-padded, as param_id may come
    reads.take("PTCH_TRIM_DEG", 0.0)  # not a servo parameter: ignored
    assert reads.due(RETRY_S) == SERVO_PARAMETERS[:1]
    for attempt in range(2, READ_ATTEMPTS):
        assert reads.due(attempt * RETRY_S) == SERVO_PARAMETERS[:1]
    assert not reads.done
    assert reads.due(READ_ATTEMPTS * RETRY_S) == ()
    assert reads.given_up and reads.done and reads.attempts == READ_ATTEMPTS

    answered_late = ServoParameterReads()
    answered_late.due(0.0)
    for name in SERVO_PARAMETERS:
        answered_late.take(name, 0.0)
    assert answered_late.complete and answered_late.due(RETRY_S) == ()
