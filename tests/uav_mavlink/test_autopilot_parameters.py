"""The parameters the simulated ArduPlane answers from an airframe file, in ArduPilot's
meanings and types; and what the simulated autopilot does with a sample it cannot fully send
(a lost value) or one without air data."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_aircraft.airframe import load_airframe
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import CONTROL_CHANNELS, SETPOINT_FIELDS, STATE_CHANNELS
from uav_mavlink.autopilot_emulator import (
    ARDUPLANE_ADVISED_HZ,
    AutopilotEmulator,
    flight_sample,
)
from uav_mavlink.autopilot_parameters import ParameterTable
from uav_mavlink.stream_rates import ARDUPILOT

INT16, INT8, REAL32 = (mavlink.MAV_PARAM_TYPE_INT16, mavlink.MAV_PARAM_TYPE_INT8,
                       mavlink.MAV_PARAM_TYPE_REAL32)


def table_of(vehicle: str, airframe: str) -> ParameterTable:
    return ParameterTable(load_airframe(load_vehicle(vehicle).airframe_files[airframe]))


def servo(table: ParameterTable, output: int) -> dict[str, float]:
    return {field: table.read(f"SERVO{output}_{field}", -1).value
            for field in ("FUNCTION", "MIN", "MAX", "TRIM", "REVERSED")}


@pytest.mark.timeout(10)
def test_the_aerosondes_outputs_are_arduplanes_functions_reversed_for_the_projects_signs():
    """aerosonde_sim.yaml: aileron 1, elevator 2, throttle 3, rudder 4, each surface 500 us
    of throw about 1500 with its PWM rising for the project's positive deflection (ArduPlane's
    negative command): reversed; the throttle 1000 (none) to 2000 (full)."""
    table = table_of("aerosonde", "aerosonde_sim")
    assert servo(table, 1) == {"FUNCTION": 4, "MIN": 1000, "MAX": 2000, "TRIM": 1500,
                               "REVERSED": 1}
    assert servo(table, 2)["FUNCTION"] == 19 and servo(table, 4)["FUNCTION"] == 21
    assert servo(table, 3) == {"FUNCTION": 70, "MIN": 1000, "MAX": 2000, "TRIM": 1000,
                               "REVERSED": 0}
    assert servo(table, 5) == {"FUNCTION": 0, "MIN": 1100, "MAX": 1900, "TRIM": 1500,
                               "REVERSED": 0}  # not mapped: ArduPilot's defaults
    assert table.count == 1 + 16 * 5


@pytest.mark.timeout(10)
def test_a_copy_of_a_surface_drives_its_function_at_its_factor_of_the_throw():
    """carbon_z_alfa.yaml: aileron on 5 (sign -1, 400 us), copies on 6 (factor 1) and 4
    (factor 0.4975)."""
    table = table_of("carbon_z", "carbon_z_alfa")
    assert servo(table, 5) == {"FUNCTION": 4, "MIN": 1100, "MAX": 1900, "TRIM": 1500,
                               "REVERSED": 0}
    assert servo(table, 6) == servo(table, 5)
    assert servo(table, 4) == {"FUNCTION": 4, "MIN": 1301, "MAX": 1699, "TRIM": 1500,
                               "REVERSED": 0}  # 0.4975 * 400 us = 199 us
    assert servo(table, 3) == {"FUNCTION": 70, "MIN": 1100, "MAX": 1900, "TRIM": 1100,
                               "REVERSED": 0}


@pytest.mark.timeout(10)
def test_a_parameter_is_read_by_name_or_index_with_arduplanes_type():
    table = table_of("aerosonde", "aerosonde_sim")
    by_name = table.read("SERVO2_REVERSED\0", -1)  # param_id NUL-padded to 16
    assert (by_name.value, by_name.mav_type) == (1.0, INT8)
    assert table.read("", by_name.index) == by_name
    assert table.read("SERVO2_TRIM", -1).mav_type == INT16
    trim = table.read("PTCH_TRIM_DEG", -1)
    assert (trim.value, trim.mav_type, trim.index) == (0.0, REAL32, 0)
    assert table.read("SERVO17_MIN", -1) is None and table.read("", table.count) is None
    packed = table.message(by_name).pack(mavlink.MAVLink(None, srcSystem=1, srcComponent=1))
    parsed = mavlink.MAVLink(None).decode(bytearray(packed))
    assert (parsed.param_id, parsed.param_value, parsed.param_type, parsed.param_count,
            parsed.param_index) == ("SERVO2_REVERSED", 1.0, INT8, table.count, by_name.index)


@pytest.mark.timeout(10)
def test_an_airframe_of_normalised_outputs_has_no_arduplane_servo_parameters(tmp_path):
    path = tmp_path / "normalised.yaml"
    path.write_text("name: n\noutput_unit: normalised\nsurfaces:\n"
                    "  aileron: {output: 1, max_deflection_rad: 0.3, sign: 1}\n"
                    "  elevator: {output: 2, max_deflection_rad: 0.3, sign: 1}\n")
    with pytest.raises(ValueError, match="ArduPilot's servo parameters are PWM"):
        ParameterTable(load_airframe(path))


def a_sample(time_s: float, air_data: np.ndarray | None, **state_values: float):
    state = np.zeros(len(STATE_CHANNELS))
    for name, value in {"velocity_north": 20.0, "velocity_east": 5.0, "altitude": 100.0,
                        **state_values}.items():
        state[STATE_CHANNELS.index(name)] = value
    return flight_sample(time_s, state, np.zeros(len(CONTROL_CHANNELS)), air_data,
                         np.array([3.0, -4.0, 0.0]), np.zeros(len(SETPOINT_FIELDS)))


@pytest.mark.timeout(10)
def test_without_air_data_the_airspeed_is_the_ground_velocity_less_the_wind():
    assert a_sample(0.0, None).airspeed_mps == pytest.approx(math.hypot(17.0, 9.0))
    assert a_sample(0.0, np.array([np.nan, 0.0, 0.0])).airspeed_mps == pytest.approx(
        math.hypot(17.0, 9.0))
    assert a_sample(0.0, np.array([23.0, 0.0, 0.0])).airspeed_mps == 23.0


@pytest.mark.timeout(10)
def test_a_message_a_lost_value_cannot_fill_is_not_sent_and_counted():
    """GLOBAL_POSITION_INT carries the altitude in whole mm: with the altitude lost it is
    kept back; ATTITUDE (floats) goes on."""
    airframe = load_airframe(load_vehicle("aerosonde").simulated_airframe_file)
    emulator = AutopilotEmulator(ARDUPILOT, airframe, ARDUPLANE_ADVISED_HZ)
    sent = [message.get_type() for message in emulator.messages(a_sample(0.0, None))]
    assert "GLOBAL_POSITION_INT" in sent and not emulator.unsent
    lost = [message.get_type()
            for message in emulator.messages(a_sample(0.1, None, altitude=math.nan))]
    assert "GLOBAL_POSITION_INT" not in lost and "ATTITUDE" in lost
    assert emulator.unsent == {"GLOBAL_POSITION_INT": 1}
