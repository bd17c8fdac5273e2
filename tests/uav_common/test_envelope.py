"""The input gates: a glitch inside the envelope is told by its rate, and the shipped
flights never are; each vehicle's measured state stays inside the envelope."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from uav_aircraft.vehicles import vehicle_names
from uav_common.channels import STATE_CHANNELS
from uav_common.envelope import STATE_LIMITS, STATE_RATE_BOUNDS, gate, state_rate_gate
from uav_sim.scenario import load_scenario, vehicle_scenario_path
from uav_sim.simulation import Simulation

NORTH = STATE_CHANNELS.index("velocity_north")
ROLL_RATE = STATE_CHANNELS.index("roll_rate")


@pytest.mark.timeout(120)
def test_the_default_flight_passes_the_rate_gate_whole(default_flight):
    gate = state_rate_gate()
    glitches = sum(gate(sample.time_s, sample.state)[1] for sample in default_flight)
    states = np.array([sample.state for sample in default_flight])
    times = np.array([sample.time_s for sample in default_flight])
    index = [STATE_CHANNELS.index(name) for name in STATE_RATE_BOUNDS]
    fastest = np.max(np.abs(np.diff(states[:, index], axis=0)) / np.diff(times)[:, None], axis=0)
    print("fastest change per second:", dict(zip(STATE_RATE_BOUNDS, fastest.round(1),
                                                 strict=True)))
    assert glitches == 0 and np.all(fastest < 0.5 * np.array(list(STATE_RATE_BOUNDS.values())))


@pytest.mark.timeout(30)
def test_a_one_sample_glitch_is_one_missing_value_and_a_real_step_passes_soon():
    gate = state_rate_gate()
    state = np.zeros(len(STATE_CHANNELS))
    state[NORTH] = 25.0
    times = 0.05 * np.arange(40)
    out = []
    for k, time_s in enumerate(times):
        sample = state.copy()
        if k == 10:
            sample[NORTH] += 30.0            # one sample of +30 m/s: 600 m/s²
        if k >= 20:
            sample[ROLL_RATE] = 8.0          # a sensor re-initialised: a lasting step
        out.append(gate(time_s, sample))
    missing = [k for k, (values, _) in enumerate(out) if np.isnan(values).any()]
    print("samples with a value taken as missing:", missing)
    assert missing == [10, 20]  # the glitch; the step until 100 rad/s² · dt allows 8 rad/s
    assert sum(count for _, count in out) == 2
    assert out[11][0][NORTH] == 25.0 and out[21][0][ROLL_RATE] == 8.0
    gate.reset()
    assert gate(0.0, state)[1] == 0  # after a restart, time going back is no glitch


@pytest.mark.timeout(60)
@pytest.mark.parametrize("vehicle", vehicle_names())
def test_each_vehicles_measured_state_stays_inside_the_envelope(vehicle):
    """20 s of its default flight with sensor noise: no value taken as implausible (the
    Carbon-Z carries no fuel: its gauge reads 0, not noise about it)."""
    scenario = load_scenario(vehicle_scenario_path(vehicle, "default"))
    simulation = Simulation(dataclasses.replace(scenario, duration_s=20.0))
    outside, sample = 0, simulation.sample()
    while not simulation.finished:
        outside += gate(sample.state, STATE_LIMITS)[1]
        sample = simulation.step()
    assert outside == 0
