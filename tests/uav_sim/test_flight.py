"""The simulated Aerosonde flies: trim in calm air, the default loop in wind, repeatably."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.flights import calm, column, fly
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_sim.scenario import SensorDropout, SetpointChange
from uav_sim.simulation import Simulation

ALTITUDE = STATE_CHANNELS.index("altitude")


def test_trim_holds_level_flight_for_60_s_in_calm_air(default_scenario):
    samples = fly(calm(default_scenario, 60.0))
    altitude_error_m = (column(samples, "true_state", ALTITUDE)
                        - default_scenario.initial.altitude_m)
    airspeed_error_mps = (column(samples, "true_air_data", 0)
                          - default_scenario.initial.airspeed_mps)
    print(
        f"calm 60 s: altitude error {np.abs(altitude_error_m).max():.3f} m, "
        f"airspeed error {np.abs(airspeed_error_mps).max():.3f} m/s"
    )
    assert samples[-1].time_s == pytest.approx(60.0)
    assert np.abs(altitude_error_m).max() <= 5.0
    assert np.abs(airspeed_error_mps).max() <= 1.0


def loop_errors(scenario, samples) -> tuple[np.ndarray, float]:
    """Closest pass [m] of each waypoint, and the largest altitude error [m] after 30 s."""
    position = column(samples, "position_ne_m")
    closest_m = np.array(
        [np.hypot(*(position - waypoint).T).min() for waypoint in scenario.waypoints_ne_m]
    )
    altitude_error_m = column(samples, "true_state", ALTITUDE) - scenario.initial.altitude_m
    after_30_s = column(samples, "time_s") >= 30.0
    return closest_m, float(np.abs(altitude_error_m[after_30_s]).max())


@pytest.mark.slow
def test_default_loop_is_flown_in_its_wind(default_scenario, default_flight):
    closest_m, worst_m = loop_errors(default_scenario, default_flight)
    print(f"default: waypoints passed at {closest_m.round(1)} m, altitude error {worst_m:.1f} m")
    assert closest_m.max() <= 100.0 and worst_m <= 30.0
    assert all(np.isfinite(sample.state).all() for sample in default_flight)


@pytest.mark.slow
def test_loop_is_flown_in_wind_of_25_percent_of_airspeed(default_scenario):
    """The upper end of the required wind range, with another turbulence seed."""
    airspeed_mps = default_scenario.initial.airspeed_mps
    wind = dataclasses.replace(
        default_scenario.wind,
        north_mps=0.8 * 0.25 * airspeed_mps,
        east_mps=0.6 * 0.25 * airspeed_mps,
    )
    samples = fly(dataclasses.replace(default_scenario, wind=wind, seed=11))
    closest_m, worst_m = loop_errors(default_scenario, samples)
    print(f"wind 25 %: waypoints passed at {closest_m.round(1)} m, altitude error {worst_m:.1f} m")
    assert closest_m.max() <= 100.0 and worst_m <= 30.0


def test_wind_is_20_to_25_percent_of_airspeed_with_turbulence(default_scenario, default_flight):
    """The default scenario's turbulence is from_wind (its statistics: test_turbulence.py)."""
    wind = column(default_flight, "wind_ned_mps")
    background = np.hypot(default_scenario.wind.north_mps, default_scenario.wind.east_mps)
    turbulence_std = (wind - wind.mean(axis=0)).std(axis=0)
    print(f"background {background:.1f} m/s, turbulence std NED {turbulence_std.round(2)} m/s")
    assert 0.2 <= background / default_scenario.initial.airspeed_mps <= 0.25
    assert default_scenario.wind.turbulence == "from_wind"
    assert np.all(turbulence_std > 0.25)


def test_same_seed_same_flight_other_seed_other_flight(default_scenario):
    short = dataclasses.replace(default_scenario, duration_s=10.0)
    first, again = fly(short), fly(short)
    other = fly(dataclasses.replace(short, seed=short.seed + 1))
    assert np.array_equal(column(first, "state"), column(again, "state"))
    assert not np.allclose(column(first, "wind_ned_mps"), column(other, "wind_ned_mps"))


def test_filtered_wind_is_the_exact_discretisation_of_eq_4(default_scenario, default_flight):
    wind = column(default_flight, "wind_ned_mps")
    filtered = column(default_flight, "wind_filtered_ned_mps")
    period_s = default_flight[1].time_s - default_flight[0].time_s
    decay = np.exp(-period_s / default_scenario.wind.filter_time_constant_s)
    expected = np.empty_like(wind)
    expected[0] = wind[0]
    for k in range(1, len(wind)):
        expected[k] = decay * expected[k - 1] + (1.0 - decay) * wind[k]
    np.testing.assert_allclose(filtered, expected, rtol=0, atol=1e-12)


def test_seeded_faults_follow_the_scenario(default_scenario, default_flight):
    seeded = column(default_flight, "seeded_faults_pct")
    time_s = column(default_flight, "time_s")
    assert seeded[time_s < 50.0, 0].max() == 0.0
    # one sample at each of these times (measured); an empty selection would pass approx
    halfway, before_step, at_step = (np.isclose(time_s, t) for t in (70.0, 109.95, 110.0))
    assert halfway.sum() == before_step.sum() == at_step.sum() == 1
    assert seeded[halfway, 0] == pytest.approx(5.0)  # halfway up its ramp
    assert seeded[-1, 0] == pytest.approx(10.0)
    assert seeded[before_step, 3] == 0.0
    assert seeded[at_step, 3] == pytest.approx(25.0)  # a step


def test_sensor_dropout_is_nan_for_its_duration(default_scenario):
    dropout = SensorDropout("pitch_rate", start_s=1.0, end_s=2.0)
    scenario = dataclasses.replace(default_scenario, duration_s=3.0, sensor_dropouts=(dropout,))
    samples = fly(scenario)
    pitch_rate = column(samples, "state", STATE_CHANNELS.index("pitch_rate"))
    time_s = column(samples, "time_s")
    inside = (time_s >= 1.0 - 1e-9) & (time_s < 2.0 - 1e-9)
    assert np.isnan(pitch_rate[inside]).all() and inside.sum() == 20
    assert np.isfinite(pitch_rate[~inside]).all()
    assert np.isfinite(
        np.delete(column(samples, "state"), STATE_CHANNELS.index("pitch_rate"), 1)
    ).all()


@pytest.mark.timeout(300)
def test_the_autopilot_flies_the_setpoint_changes(default_scenario):
    """A speed step and a climb: 30 s after each the aircraft is within 1 m/s and 5 m of it
    (measured: 0.3 m/s and 2 m), and the throttle has swung well off its trim."""
    changes = (SetpointChange(10.0, airspeed_mps=28.0), SetpointChange(50.0, altitude_m=280.0))
    scenario = dataclasses.replace(default_scenario, duration_s=80.0, faults=(),
                                   setpoints=changes)
    samples = fly(scenario)
    time_s = column(samples, "time_s")
    airspeed = column(samples, "true_air_data", 0)
    altitude = column(samples, "true_state", STATE_CHANNELS.index("altitude"))
    throttle = column(samples, "true_controls", CONTROL_CHANNELS.index("throttle"))
    assert abs(airspeed[np.isclose(time_s, 40.0)][0] - 28.0) < 1.0
    assert abs(altitude[np.isclose(time_s, 80.0)][0] - 280.0) < 5.0
    assert abs(airspeed[np.isclose(time_s, 9.0)][0] - 25.0) < 1.0
    assert throttle.max() - throttle.min() > 0.4


def test_sensor_rate_must_divide_the_simulation_rate(default_scenario):
    with pytest.raises(ValueError, match="must divide the simulation rate"):
        Simulation(default_scenario, sensor_rate_hz=7.0)
