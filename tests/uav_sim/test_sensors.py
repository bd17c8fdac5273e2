"""The sensor model: every measured channel carries its configured noise, from the seed; ideal
sensors reproduce the simulator's states bit for bit; air data and the wind triangle."""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
import pytest
from helpers.flights import column, fly
from uav_aircraft.flown_aircraft import FlownAircraft, SensorBias
from uav_aircraft.frames import wind_triangle_ned_mps
from uav_common.channels import AIR_DATA_CHANNELS, CONTROL_CHANNELS, STATE_CHANNELS
from uav_sim.scenario import Guidance, SensorSuite
from uav_sim.sensors import (
    AIR_DATA_NOISE,
    CONTROL_NOISE,
    STATE_NOISE,
    ChannelErrors,
    ChannelNoise,
    state_scale,
)

# sha256 of the (401, 14) states and (401, 7) controls of the default scenario's first 20 s
# as the simulator flew them before it had a sensor model (commit ce4ba73), in JSBSim's
# moderate turbulence and in none, on the vector field (its only guidance then).
IDEAL_SENSOR_HASHES = {
    "moderate": ("3fb2129d3f6b1c633f9160f79d8d5682b0ed3568ac0d74ebbc3c5f886ef0b72c",
                 "14413861c9130c081df8cf5083e23cffdcf3aab78609573b23c5b770804e651a"),
    "none": ("51aa720505f43a2e9977fcfa132b80ed0a18ed11d3bf797b120741cff7a4efa4",
             "4c0d74a223d7ea212db60f2894688b95b8e46a1116dd82f6aede75ff65181dfa"),
}


def white_channels(model: dict[str, ChannelNoise]) -> list[str]:
    return [name for name, noise in model.items() if noise.white > 0 and noise.markov == 0]


def check_white_noise(errors: np.ndarray, channels: tuple[str, ...],
                      model: dict[str, ChannelNoise]) -> None:
    """std(measured - true) within 10 % of the configured white noise per channel."""
    for name in white_channels(model):
        error = errors[:, channels.index(name)]
        print(f"{name}: std {error.std():.4g}, configured {model[name].white:.4g}, "
              f"mean {error.mean():.3g}")
        assert error.std() == pytest.approx(model[name].white, rel=0.10), name


def test_state_control_and_air_data_noise_in_flight(default_flight):
    """The default flight (300 s at 20 Hz): the white-noise channels of the state, the
    surfaces and the air data; throttle, mixture and ignition are the commands themselves."""
    check_white_noise(column(default_flight, "state") - column(default_flight, "true_state"),
                      STATE_CHANNELS, STATE_NOISE)
    control_errors = column(default_flight, "controls") - column(default_flight, "true_controls")
    check_white_noise(control_errors, CONTROL_CHANNELS, CONTROL_NOISE)
    for name in set(CONTROL_CHANNELS) - set(CONTROL_NOISE):
        assert np.all(control_errors[:, CONTROL_CHANNELS.index(name)] == 0.0), name
    air_errors = column(default_flight, "air_data") - column(default_flight, "true_air_data")
    check_white_noise(air_errors, AIR_DATA_CHANNELS, AIR_DATA_NOISE)
    assert np.abs(air_errors.mean(axis=0)) == pytest.approx(
        [0.0] * 3, abs=4 * max(n.white for n in AIR_DATA_NOISE.values()) / np.sqrt(len(air_errors)))


@pytest.mark.timeout(60)
def test_gauss_markov_and_bias_errors_over_a_long_run():
    """GNSS position (Gauss-Markov, in metres) over 100 000 samples 1 s apart: std within
    10 % of the configured value and one-sample correlation exp(-1/tau); a gyro's constant bias
    is the mean of its errors."""
    errors = ChannelErrors(STATE_CHANNELS, STATE_NOISE, np.ones(len(STATE_CHANNELS)), 1.0,
                           np.random.default_rng(5))
    drawn = np.array([errors.next() for _ in range(100_000)])
    for name in ("latitude", "longitude", "altitude"):
        noise = STATE_NOISE[name]
        error = drawn[:, STATE_CHANNELS.index(name)]
        correlation = np.corrcoef(error[:-1], error[1:])[0, 1]
        print(f"{name}: std {error.std():.3f} m of {noise.markov} m, one-step correlation "
              f"{correlation:.4f} of {np.exp(-1.0 / noise.markov_tau_s):.4f}")
        assert error.std() == pytest.approx(noise.markov, rel=0.10)
        assert correlation == pytest.approx(np.exp(-1.0 / noise.markov_tau_s), abs=0.005)
    for name in ("roll_rate", "pitch_rate", "yaw_rate"):
        index = STATE_CHANNELS.index(name)
        assert drawn[:, index].mean() == pytest.approx(errors.bias[index],
                                                       abs=4 * STATE_NOISE[name].white / 300)
    assert np.all(errors.bias[[STATE_CHANNELS.index(n) for n in ("roll_rate", "yaw_rate")]] != 0)


def test_gnss_metres_become_radians_of_latitude_and_longitude():
    scale = state_scale(np.radians(55.6))
    assert scale[STATE_CHANNELS.index("latitude")] * 6378137.0 == pytest.approx(1.0)
    assert (scale[STATE_CHANNELS.index("longitude")] * 6378137.0 * np.cos(np.radians(55.6))
            == pytest.approx(1.0))


def short(scenario, seed: int, duration_s: float = 10.0, **sensors):
    return dataclasses.replace(scenario, seed=seed, duration_s=duration_s,
                               sensors=SensorSuite(**sensors))


def test_same_seed_same_noise(default_scenario):
    first, again = fly(short(default_scenario, 7)), fly(short(default_scenario, 7))
    other = fly(short(default_scenario, 8))
    for field in ("state", "controls", "air_data"):
        assert np.array_equal(column(first, field), column(again, field)), field
    assert not np.array_equal(column(first, "state"), column(other, "state"))


def test_without_air_data_the_other_channels_keep_their_noise(default_scenario):
    with_air_data = fly(short(default_scenario, 7))
    without = fly(short(default_scenario, 7, air_data=False))
    assert all(sample.air_data is None for sample in without)
    assert np.array_equal(column(with_air_data, "state"), column(without, "state"))


def test_a_pitot_without_vanes_measures_the_airspeed_alone(default_scenario):
    with_vanes = fly(short(default_scenario, 7, duration_s=3.0))
    pitot = fly(short(default_scenario, 7, duration_s=3.0, vanes=False))
    airspeed, angles = column(pitot, "air_data")[:, 0], column(pitot, "air_data")[:, 1:]
    assert np.array_equal(airspeed, column(with_vanes, "air_data")[:, 0])
    assert np.isnan(angles).all()
    assert np.array_equal(column(with_vanes, "state"), column(pitot, "state"))


@pytest.mark.parametrize("turbulence", sorted(IDEAL_SENSOR_HASHES))
def test_ideal_sensors_reproduce_the_simulator_bit_for_bit(default_scenario, turbulence):
    wind = dataclasses.replace(default_scenario.wind, turbulence=turbulence)
    samples = fly(dataclasses.replace(short(default_scenario, default_scenario.seed, 20.0,
                                            noise=False), wind=wind,
                                      guidance=Guidance("vector_field")))
    digests = tuple(hashlib.sha256(np.ascontiguousarray(column(samples, field)).tobytes())
                    .hexdigest() for field in ("state", "controls"))
    assert digests == IDEAL_SENSOR_HASHES[turbulence]
    assert np.array_equal(column(samples, "air_data"), column(samples, "true_air_data"))


def triangle(state: np.ndarray, air_data: np.ndarray) -> np.ndarray:
    return wind_triangle_ned_mps(state[6:9], *state[3:6], air_data)


def propagated_wind_variance(state: np.ndarray, air_data: np.ndarray) -> np.ndarray:
    """Per-axis variance [m^2/s^2] of the wind triangle's error that the configured white
    noise of velocity, attitude and air data implies (first order, numerical Jacobian)."""
    inputs = np.concatenate([state[3:9], air_data])
    sigma = np.array([STATE_NOISE[name].white for name in STATE_CHANNELS[3:9]]
                     + [AIR_DATA_NOISE[name].white for name in AIR_DATA_CHANNELS])

    def wind(values: np.ndarray) -> np.ndarray:
        full = state.copy()
        full[3:9] = values[:6]
        return triangle(full, values[6:])

    step = 1e-6
    jacobian = np.column_stack([(wind(inputs + step * e) - wind(inputs - step * e)) / (2 * step)
                                for e in np.eye(inputs.size)])
    return (jacobian**2) @ sigma**2


def test_wind_triangle_recovers_the_true_wind(default_flight):
    """From the true values the triangle is the true wind; from the measured ones its error
    is what the configured noise implies (per axis, std within 10 % of the propagated one)."""
    true_wind = column(default_flight, "wind_ned_mps")
    exact = np.array([triangle(s.true_state, s.true_air_data) for s in default_flight])
    assert np.abs(exact - true_wind).max() < 1e-6
    measured = np.array([triangle(s.state, s.air_data) for s in default_flight])
    error = measured - true_wind
    expected = np.sqrt(np.mean([propagated_wind_variance(s.true_state, s.true_air_data)
                                for s in default_flight], axis=0))
    print(f"wind triangle error NED: std {error.std(axis=0).round(3)} m/s, propagated "
          f"{expected.round(3)} m/s, mean {error.mean(axis=0).round(3)} m/s")
    assert error.std(axis=0) == pytest.approx(expected, rel=0.10)
    assert np.abs(error.mean(axis=0)).max() < 4 * expected.max() / np.sqrt(len(error))


@pytest.mark.timeout(120)
def test_a_flown_aircrafts_air_data_bias_is_in_every_sample(default_scenario):
    """Ideal sensors on a flown aircraft with a pitot reading 2 % high and vanes 0.5 and
    -0.3 deg off: the measured air data is the true one so biased, sample for sample."""
    bias = SensorBias(airspeed_scale=1.02, angle_of_attack_deg=0.5, sideslip_deg=-0.3)
    scenario = dataclasses.replace(short(default_scenario, default_scenario.seed, 5.0,
                                         noise=False), aircraft=FlownAircraft(sensor_bias=bias))
    samples = fly(scenario)
    measured, true = column(samples, "air_data"), column(samples, "true_air_data")
    np.testing.assert_allclose(measured[:, 0], 1.02 * true[:, 0], rtol=1e-12)
    np.testing.assert_allclose(measured[:, 1:] - true[:, 1:],
                               np.tile(np.radians([0.5, -0.3]), (len(samples), 1)), atol=1e-12)
