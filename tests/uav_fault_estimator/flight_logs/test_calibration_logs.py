"""A model calibration from an autopilot's own log: a simulated flight written as an ArduPilot
DataFlash log and as a PX4 ULog (flight_logs/log_writers.py), read back by pymavlink and
pyulog and by the calibration's reader (flight_logs/calibration_logs.py), and calibrated."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest
from helpers.flights import calm, fly
from helpers.repo import SCRIPTS
from pymavlink import mavutil
from pyulog import ULog
from uav_aircraft.airframe import PWM_RANGE_US, load_airframe, outputs_of_controls
from uav_aircraft.flown_aircraft import FlownAircraft
from uav_aircraft.vehicles import load_vehicle
from uav_common.channels import CONTROL_CHANNELS, STATE_CHANNELS
from uav_common.interpolation import wrap_rad
from uav_fault_estimator.chain.offline import sensor_flight
from uav_fault_estimator.estimation.model_calibration import calibrate
from uav_fault_estimator.estimation.model_file import load_model_calibration
from uav_fault_estimator.estimation.noise_model import load_noise_calibration
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.flight_logs.calibration_logs import (
    CalibrationLogError,
    sensor_flight_from_log,
)
from uav_fault_estimator.flight_logs.log_writers import (
    DATAFLASH_NAMES,
    ULOG_NAMES,
    write_dataflash,
    write_ulog,
)
from uav_sim.scenario import SensorSuite, default_scenario_path, load_scenario

FLIGHT_S = 50.0  # the first leg of the default route
WIND_NE_MPS = (3.0, -2.0)  # a steady wind, no turbulence: the wind columns carry something
# The flown aircraft differs from the model by a few percent (the calibration's truth)
FLOWN = FlownAircraft(coefficients=(("CDmin", 1.05), ("Cmalpha", 1.04)))
PARAMETERS = ("CDmin", "Cmalpha")
WRITERS = {".bin": write_dataflash, ".ulg": write_ulog}
AIRFRAME = load_airframe(load_vehicle("aerosonde").only_airframe_file())

# What each format resolves (the tolerances of the round trip). A float field (float32)
# keeps 24 bits: one unit in its last place is 2^-23 of its value. DataFlash stores the
# attitude in whole centidegrees (ATT's 'c'/'C'), latitude and longitude in whole 1e-7 deg
# ('L'), the wind in whole cm/s (XKF2's 'c'; the filter averages, so its output is no further
# off) and the PWM outputs in whole microseconds (RCOU's uint16): half of each at most. A
# ULog's attitude is a float32 quaternion (its angles within 1e-6 rad), its latitude and
# longitude doubles, its outputs float32.
FLOAT32 = 2.0**-23
HALF_CENTIDEGREE_RAD = math.radians(0.005)
HALF_1E7_DEG_RAD = math.radians(0.5e-7)
HALF_CM_PER_S = 0.005
QUATERNION_ANGLE_RAD = 1e-6
PWM_RESOLUTION_US = {".bin": 0.5, ".ulg": FLOAT32 * PWM_RANGE_US[1]}
ANGLE_TOLERANCE_RAD = {".bin": HALF_CENTIDEGREE_RAD, ".ulg": QUATERNION_ANGLE_RAD}
POSITION_TOLERANCE = {".bin": {"atol": HALF_1E7_DEG_RAD, "rtol": 1e-15},
                      ".ulg": {"atol": 0.0, "rtol": 1e-15}}
WIND_TOLERANCE_MPS = {".bin": HALF_CM_PER_S, ".ulg": FLOAT32 * max(map(abs, WIND_NE_MPS))}
# Calibrated from a log, a parameter lands within this many posterior deviations of its value
# from the flight itself: DataFlash's whole-microsecond PWM moves the elevator by up to
# 0.03 deg, which moves Cmalpha by 0.22 deviations on this flight.
SAME_CALIBRATION_SIGMAS = 0.3


@pytest.fixture(scope="module")
def scenario():
    """The default route's first leg in a steady wind, ideal sensors with air data, of
    FLOWN."""
    scenario = calm(load_scenario(default_scenario_path()), FLIGHT_S)
    wind = dataclasses.replace(scenario.wind, north_mps=WIND_NE_MPS[0],
                               east_mps=WIND_NE_MPS[1])
    return dataclasses.replace(scenario, wind=wind, aircraft=FLOWN,
                               sensors=SensorSuite(air_data=True, noise=False))


@pytest.fixture(scope="module")
def samples(scenario):
    """Every sample of the flight: what the writers write."""
    return fly(scenario)


@pytest.fixture(scope="module")
def flight(scenario):
    """The flight as a recording of it gives it (what a calibration reads)."""
    return sensor_flight(scenario)


@pytest.fixture(scope="module")
def logs(samples, tmp_path_factory):
    """The flight written as a DataFlash log and as a ULog, by suffix."""
    folder = tmp_path_factory.mktemp("logs")
    for suffix, write in WRITERS.items():
        write(folder / f"flight{suffix}", samples, AIRFRAME)
    return {suffix: folder / f"flight{suffix}" for suffix in WRITERS}


def _read(path, flight):
    """The log read as a calibration reads it, with the flight's fuel at take-off."""
    return sensor_flight_from_log(path, AIRFRAME,
                                  fuel_mass_kg=flight.states[0, STATE_CHANNELS.index("fuel_mass")])


@pytest.mark.timeout(60)
@pytest.mark.parametrize("suffix", list(WRITERS))
def test_a_log_gives_the_flight_back_within_its_resolution(logs, flight, suffix):
    read = _read(logs[suffix], flight)
    assert np.allclose(read.times_s, flight.times_s, rtol=0.0, atol=1e-9)  # TimeUS: us
    state = dict(zip(STATE_CHANNELS, read.states.T, strict=True))
    truth = dict(zip(STATE_CHANNELS, flight.states.T, strict=True))
    for channel in ("latitude", "longitude"):
        np.testing.assert_allclose(state[channel], truth[channel], err_msg=channel,
                                   **POSITION_TOLERANCE[suffix])
    for channel in ("roll", "pitch", "yaw"):  # yaw: 0..360 deg in ATT, (-pi, pi] read
        assert np.abs(wrap_rad(state[channel] - truth[channel])).max() <= (
            ANGLE_TOLERANCE_RAD[suffix]), channel
    for channel in ("altitude", "velocity_north", "velocity_east", "velocity_down",
                    "roll_rate", "pitch_rate", "yaw_rate", "engine_speed"):
        np.testing.assert_allclose(state[channel], truth[channel], rtol=FLOAT32, atol=0.0,
                                   err_msg=channel)
    # no log holds the fuel: the given constant, the flight's burning 8 g from it
    assert np.all(state["fuel_mass"] == truth["fuel_mass"][0])
    assert np.abs(state["fuel_mass"] - truth["fuel_mass"]).max() < 0.01
    controls = dict(zip(CONTROL_CHANNELS, read.controls.T, strict=True))
    expected = dict(zip(CONTROL_CHANNELS, flight.controls.T, strict=True))
    for name, control in AIRFRAME.controls.items():
        per_us = control.scale / abs(control.span)  # [rad or throttle per us]
        np.testing.assert_allclose(controls[name], expected[name], rtol=0.0,
                                   atol=PWM_RESOLUTION_US[suffix] * per_us * (1 + FLOAT32),
                                   err_msg=name)
    for name in ("flap", "mixture", "ignition"):
        assert np.array_equal(controls[name], expected[name]), name
    np.testing.assert_allclose(read.winds_ned_mps, flight.winds_ned_mps, rtol=0.0,
                               atol=WIND_TOLERANCE_MPS[suffix])
    np.testing.assert_allclose(read.air_data[:, 0], flight.air_data[:, 0], rtol=FLOAT32,
                               atol=0.0)
    assert np.isnan(read.air_data[:, 1:]).all()  # no vanes in an autopilot's log


@pytest.mark.timeout(60)
def test_pymavlink_reads_the_dataflash_log_written(logs, samples):
    reader = mavutil.mavlink_connection(str(logs[".bin"]))
    counts = {name: reader.counts[reader.name_to_id[name]] for name in DATAFLASH_NAMES}
    assert counts == dict.fromkeys(DATAFLASH_NAMES, len(samples))
    rcou = reader.recv_match(type="RCOU")
    pwm_us = outputs_of_controls(AIRFRAME, dict(zip(
        CONTROL_CHANNELS, samples[0].controls.tolist(), strict=True)))
    assert {output: getattr(rcou, f"C{output}") for output in pwm_us} == {
        output: round(value) for output, value in pwm_us.items()}
    assert rcou.TimeUS == 0


@pytest.mark.timeout(60)
def test_pyulog_reads_the_ulog_written(logs, samples):
    log = ULog(str(logs[".ulg"]))
    assert sorted(data.name for data in log.data_list) == sorted(ULOG_NAMES)
    assert all(data.data["timestamp"].size == len(samples) for data in log.data_list)
    outputs = next(data.data for data in log.data_list if data.name == "actuator_outputs")
    pwm_us = outputs_of_controls(AIRFRAME, dict(zip(
        CONTROL_CHANNELS, samples[-1].controls.tolist(), strict=True)))
    assert {output: outputs[f"output[{output - 1}]"][-1] for output in pwm_us} == (
        pytest.approx(pwm_us, rel=FLOAT32))


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("suffix", "left_out", "words"), [
    (".bin", "RPM", "no engine speed, which a model calibration needs (looked for RPM)"),
    (".bin", "XKF2", "no wind, which a model calibration needs (looked for XKF2, NKF2)"),
    (".ulg", "wind", "no wind, which a model calibration needs (looked for wind, "
                     "wind_estimate)"),
    (".ulg", "vehicle_global_position", "no position, which a model calibration needs "
                                        "(looked for vehicle_global_position)"),
])
def test_a_log_without_a_needed_message_is_refused_in_one_line(samples, tmp_path, suffix,
                                                                left_out, words):
    path = tmp_path / f"flight{suffix}"
    names = DATAFLASH_NAMES if suffix == ".bin" else ULOG_NAMES
    WRITERS[suffix](path, samples, AIRFRAME, [name for name in names if name != left_out])
    with pytest.raises(CalibrationLogError) as refused:
        sensor_flight_from_log(path, AIRFRAME)
    assert str(refused.value) == f"log {path}: {words}"


@pytest.mark.timeout(60)
def test_a_log_without_airspeed_has_no_air_data(samples, tmp_path):
    """The airspeed is optional: without vanes the calibration flies the wind estimate."""
    path = tmp_path / "flight.bin"
    write_dataflash(path, samples, AIRFRAME, [name for name in DATAFLASH_NAMES
                                              if name != "ARSP"])
    assert np.isnan(sensor_flight_from_log(path, AIRFRAME).air_data).all()


@pytest.mark.timeout(60)
def test_an_airframe_without_a_rudder_is_refused(logs):
    """A control the airframe file does not map is one the models need and lack."""
    alfa = load_vehicle("carbon_z").airframe_files["carbon_z_alfa"]
    with pytest.raises(CalibrationLogError, match=r"^airframe .*carbon_z_alfa.yaml maps no "
                       r"rudder, which a model calibration needs \(log .*flight.bin\)$"):
        sensor_flight_from_log(logs[".bin"], load_airframe(alfa))


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_calibration_from_the_log_finds_what_the_flight_itself_gives(logs, flight):
    """The flight with the air data a log has (the airspeed, no vanes: both fly the wind
    estimate), against the same flight read from each log."""
    as_logged = dataclasses.replace(
        flight, air_data=np.column_stack([flight.air_data[:, :1],
                                          np.full((flight.times_s.size, 2), np.nan)]))

    def calibrated(source):
        return calibrate([source], PARAMETERS, ResidualSettings(), load_noise_calibration(),
                         log=lambda line: None)

    reference = calibrated(as_logged)
    assert reference.values == pytest.approx([5.0, 4.0], abs=2 * reference.posterior_std.max())
    for suffix, path in logs.items():
        moved = (calibrated(_read(path, flight)).values - reference.values) \
            / reference.posterior_std
        assert np.abs(moved).max() < SAME_CALIBRATION_SIGMAS, (suffix, moved)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_calibrate_model_takes_logs(logs, flight, tmp_path):
    """Both logs calibrate, through the vehicle's only airframe file; the files written are
    ones the nodes take. A vehicle with two airframe files needs one named."""
    fuel_kg = flight.states[0, STATE_CHANNELS.index("fuel_mass")]
    result = subprocess.run(
        [sys.executable, str(SCRIPTS / "calibrate_model.py"), str(logs[".bin"]),
         str(logs[".ulg"]), "--out", "model.yaml", "--parameters", ",".join(PARAMETERS),
         "--fuel-mass-kg", str(fuel_kg)],
        capture_output=True, text=True, timeout=100, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert f"flight 1: {logs['.bin']}" in result.stdout
    calibrated = load_model_calibration(tmp_path / "model.yaml", "aerosonde")
    assert dict(calibrated.aircraft.coefficients) == pytest.approx(dict(FLOWN.coefficients),
                                                                   abs=0.01)
    load_noise_calibration(tmp_path / "model.noise.yaml")
    refused = subprocess.run(
        [sys.executable, str(SCRIPTS / "calibrate_model.py"), str(logs[".bin"]), "--out",
         "other.yaml", "--vehicle", "carbon_z"],
        capture_output=True, text=True, timeout=100, cwd=tmp_path)
    assert refused.returncode == 2
    assert "vehicle carbon_z has 2 airframe files" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
