"""The simulator as ArduPlane and as PX4: a flight's samples sent as the stack's messages,
packed and parsed as the link carries them, read back (autopilot_messages, sample_assembly,
the airframe's servo mapping) give the flight again, to the link's resolution; and each
message type goes at its stream's rate."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from uav_aircraft.airframe import CONTROLS, MAX_OUTPUTS, control_values, load_airframe
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_mavlink.autopilot_emulator import (
    ARDUPLANE_DEFAULT_HZ,
    PX4_ONBOARD_HZ,
    AutopilotEmulator,
    FlightSample,
)
from uav_mavlink.autopilot_messages import (
    ENGINE,
    SETPOINTS,
    STREAMS,
    VELOCITY,
    VELOCITY_SETPOINT,
    read_message,
)
from uav_mavlink.sample_assembly import HELD_STREAMS, SampleAssembly
from uav_mavlink.stream_rates import ARDUPILOT, PX4
from uav_sim.scenario import default_scenario_path, load_scenario
from uav_sim.simulation import Simulation

PERIOD_S = 0.05  # the simulator's sensor period and the grid
DURATION_S = 10.0
# How finely the link carries each state channel: float32 angles and rates, degE7, mm, cm/s.
RESOLUTION = {"latitude": 2e-9, "longitude": 2e-9, "altitude": 6e-4, "roll": 1e-6,
              "pitch": 1e-6, "yaw": 1e-6, "velocity_north": 6e-3, "velocity_east": 6e-3,
              "velocity_down": 6e-3, "roll_rate": 1e-6, "pitch_rate": 1e-6, "yaw_rate": 1e-6}
PWM_STEP_US = 1.0  # SERVO_OUTPUT_RAW carries whole microseconds
# The streams each stack sends nothing of: missing at every grid point. (ArduPlane sends no
# LOCAL_POSITION_NED, neither stack a POSITION_TARGET_GLOBAL_INT, PX4 no RPM.)
NOT_SENT = {ARDUPILOT: {VELOCITY, VELOCITY_SETPOINT}, PX4: {VELOCITY_SETPOINT, ENGINE}}


def flight_sample(sample) -> FlightSample:
    return FlightSample(sample.time_s, sample.state, sample.controls, sample.air_data[0],
                        sample.wind_ned_mps, sample.setpoints)


def through_the_link(stack: str, rates_hz: dict[str, float]):
    """A 10 s default flight sent by the emulated stack and read back: the simulator's
    samples by time, the grid samples read back, and the messages sent by type."""
    scenario = dataclasses.replace(load_scenario(default_scenario_path()), duration_s=DURATION_S)
    simulation = Simulation(scenario)
    airframe = load_airframe(next(iter(load_vehicle("aerosonde").airframe_files.values())))
    emulator = AutopilotEmulator(stack, airframe, rates_hz)
    # a waited stream's gap below its period: each grid point is read off the reading on it;
    # a held stream's hold over one period: the reading before the point (see the test)
    max_age_s = {stream: (1.5 if stream in HELD_STREAMS else 0.5) * PERIOD_S
                 for stream in STREAMS}
    assembly = SampleAssembly(PERIOD_S, max_age_s, 0.0)
    sender, receiver = mavlink.MAVLink(None, srcSystem=1, srcComponent=1), mavlink.MAVLink(None)
    flown, read_back, sent = {}, [], {}
    sample = simulation.sample()
    while True:
        flown[round(sample.time_s / PERIOD_S)] = sample
        for message in emulator.messages(flight_sample(sample)):
            sent.setdefault(message.get_type(), []).append(sample.time_s)
            parsed = receiver.decode(bytearray(message.pack(sender)))
            reading = read_message(parsed)
            if reading is not None:
                read_back += assembly.add(reading).samples
        if simulation.finished:
            return airframe, flown, read_back, sent
        sample = simulation.step()


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("stack", "messages"), [(ARDUPILOT, ARDUPLANE_DEFAULT_HZ),
                                                 (PX4, PX4_ONBOARD_HZ)])
def test_a_flight_sent_at_the_sample_rate_reads_back_to_the_links_resolution(stack, messages):
    airframe, flown, read_back, _ = through_the_link(stack, dict.fromkeys(messages, 20.0))
    assert len(read_back) == round(DURATION_S / PERIOD_S) + 1  # every grid point, 0 to the end
    # the first goes out with the first ATTITUDE, before the first of the other streams
    for grid in read_back[1:]:
        point = round(grid.boot_time_s / PERIOD_S)
        truth = flown[point]
        # the wind and setpoint messages of an instant go after the waited streams' (the
        # emulator's order), and they are not waited for: the point holds the instant
        # before's
        held = flown[point - 1]
        commanded = np.isfinite(held.setpoints[:2]).all()  # no setpoints before a command
        expected = NOT_SENT[stack] if commanded else NOT_SENT[stack] | {SETPOINTS}
        assert set(grid.missing) == expected, (stack, grid.boot_time_s, grid.missing)
        for name, resolution in RESOLUTION.items():
            index = STATE_CHANNELS.index(name)
            error = grid.state[index] - truth.state[index]
            if name == "yaw":
                error = math.remainder(error, 2 * math.pi)
            assert abs(error) <= resolution, (stack, grid.boot_time_s, name, error)
        read_controls = control_values(airframe, lambda n, g=grid: g.outputs_us[None, n - 1],
                                       range(1, MAX_OUTPUTS + 1), 1)[0]
        for name, value in zip(CONTROLS, read_controls, strict=True):
            control = airframe.controls[name]
            step = abs(control.scale / control.span) * PWM_STEP_US / 2  # half a microsecond
            assert value == pytest.approx(truth.controls[CONTROL_CHANNELS.index(name)],
                                          abs=step * 1.001), (name, grid.boot_time_s)
        assert grid.airspeed_mps == pytest.approx(truth.air_data[0], rel=1e-6)
        np.testing.assert_allclose(grid.wind_ned_mps, held.wind_ned_mps, atol=1e-5)
        if commanded:
            np.testing.assert_allclose(grid.setpoints[:2], held.setpoints[:2], atol=1e-6)
    if stack == ARDUPILOT:  # the engine speed comes with RPM, ArduPilot's alone
        engine = STATE_CHANNELS.index("engine_speed")
        assert all(g.state[engine] == pytest.approx(flown[round(g.boot_time_s / PERIOD_S)]
                                                    .state[engine], rel=1e-6)
                   for g in read_back[1:])


@pytest.mark.timeout(60)
def test_each_message_goes_at_its_streams_rate():
    """ArduPlane at its 1 Hz defaults and PX4's onboard rates, capped by the 20 Hz samples."""
    for stack, rates_hz in ((ARDUPILOT, ARDUPLANE_DEFAULT_HZ), (PX4, PX4_ONBOARD_HZ)):
        _, _, _, sent = through_the_link(stack, rates_hz)
        for kind, hz in {**rates_hz, "HEARTBEAT": 1.0}.items():
            expected = math.floor(DURATION_S * min(hz, 1.0 / PERIOD_S) + 1e-9) + 1
            if kind == "NAV_CONTROLLER_OUTPUT":  # none before the autopilot's first command
                assert 0 < len(sent[kind]) <= expected, (stack, kind)
            else:
                assert len(sent[kind]) == expected, (stack, kind, len(sent[kind]))
