"""flight_logs.replay, what log_replay_node publishes: the log on the detector's grid as
detector_samples gives it, air data from the log's airspeed (only when it has one), the
log's axes from the parameter, else the airframe's, else the format's own."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import simulated_logs
from helpers.simulated_logs import FIXTURE_AIRFRAME, ROSTOPIC
from uav_aircraft.airframe import load_airframe
from uav_common.channels import STATE_CHANNELS
from uav_fault_estimator.flight_logs.readers import read_log
from uav_fault_estimator.flight_logs.replay import air_data_rows, load_replay
from uav_fault_estimator.flight_logs.resample import detector_samples
from uav_sim.paths import scenarios_dir
from uav_sim.scenario import load_scenario

PERIOD_S = 0.2
DURATION_S = 10.0
SEED = 17


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 10 s simulated flight as a PX4 ULog (flight.ulg) and as the CSV export of its MAVROS
    bag without the VFR_HUD topic (csv/: no airspeed)."""
    scenario = dataclasses.replace(load_scenario(scenarios_dir() / "aileron_loss.yaml"),
                                   duration_s=DURATION_S)
    truth = simulated_logs.simulate_truth(scenario, SEED)
    folder = tmp_path_factory.mktemp("replay")
    simulated_logs.write_ulog(folder / "flight.ulg", truth)
    simulated_logs.write_mavros_bag(folder / "flight.bag", truth, SEED)
    simulated_logs.export_csv(folder / "flight.bag", folder / "csv", ROSTOPIC)
    (folder / "csv" / "_mavros_vfr_hud.csv").unlink()
    return folder


@pytest.mark.timeout(30)
def test_the_log_on_the_grid_with_its_airspeed_as_air_data(folder: Path) -> None:
    replay = load_replay(folder / "flight.ulg", FIXTURE_AIRFRAME, None, PERIOD_S)
    expected = detector_samples(read_log(folder / "flight.ulg"),
                                load_airframe(FIXTURE_AIRFRAME), PERIOD_S)
    assert replay.source == str(folder / "flight.ulg")
    for got, want in zip(replay.inputs.flight, expected.flight, strict=True):
        np.testing.assert_array_equal(got, want)
    assert replay.inputs.warnings == expected.warnings
    assert replay.air_data.shape == (expected.times_s.size, 3)
    np.testing.assert_array_equal(replay.air_data[:, 0], expected.airspeed_mps)
    assert np.isnan(replay.air_data[:, 1:]).all()


@pytest.mark.timeout(30)
def test_a_log_without_airspeed_has_no_air_data(folder: Path) -> None:
    replay = load_replay(folder / "csv", FIXTURE_AIRFRAME, None, PERIOD_S)
    assert replay.air_data is None and replay.inputs.times_s.size > 0


@pytest.mark.timeout(30)
def test_axes_from_the_parameter_else_the_airframe_else_the_format(folder: Path,
                                                                    tmp_path: Path) -> None:
    flu = yaml.safe_load(FIXTURE_AIRFRAME.read_text()) | {"axes": "FLU"}
    flu_airframe = tmp_path / "flu.yaml"
    flu_airframe.write_text(yaml.safe_dump(flu))
    ulog = folder / "flight.ulg"
    own = load_replay(ulog, FIXTURE_AIRFRAME, None, PERIOD_S).inputs.state  # ULog: FRD
    by_airframe = load_replay(ulog, flu_airframe, None, PERIOD_S).inputs.state
    by_parameter = load_replay(ulog, flu_airframe, "FRD", PERIOD_S).inputs.state
    rates = [STATE_CHANNELS.index(name) for name in ("roll_rate", "pitch_rate", "yaw_rate")]
    # FLU to FRD: y and z turn round
    np.testing.assert_array_equal(by_airframe[:, rates], own[:, rates] * [1.0, -1.0, -1.0])
    np.testing.assert_array_equal(by_parameter, own)


def test_air_data_rows_carry_the_airspeed_alone() -> None:
    rows = air_data_rows(np.array([25.0, np.nan]))
    np.testing.assert_array_equal(rows, [[25.0, np.nan, np.nan], [np.nan, np.nan, np.nan]])


@pytest.mark.timeout(30)
def test_a_log_with_outputs_and_no_airframe_is_one_line(folder: Path) -> None:
    with pytest.raises(ValueError, match=r"actuator outputs need an airframe file"):
        load_replay(folder / "flight.ulg", None, None, PERIOD_S)
