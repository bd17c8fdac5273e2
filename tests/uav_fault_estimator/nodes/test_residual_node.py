"""residual_node and sim_node as processes: residuals every 0.5 s of sim time, a dropout
marks the rows that need the missing channel, and a restarted simulator resets the filters."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from uav_common.channels import PAPER_FAULT_NAMES
from uav_common.message_fields import stamp_seconds
from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
from uav_common.ros_processes import fast_flight_ros_args, ros2_run_argv
from uav_fault_estimator.estimation.residuals import WIND_ERROR_NAMES
from uav_fault_msgs.msg import Residuals

pytestmark = pytest.mark.integration

PERIOD_S = 0.5
RECOVERY_S = 1.0
FIRST_S, SECOND_S = 8.0, 4.0
PITCH_RATE_DROPOUT = {"channel": "pitch_rate", "start_s": 2.0, "end_s": 3.0}
AIRSPEED_DROPOUT = {"channel": "airspeed", "start_s": 5.0, "end_s": 6.0}
ANGULAR_Y = 4  # the residual row that needs the pitch rate
SENSOR_PERIOD_S = 0.05  # the simulator's samples (uav_sim config)


def fly(start_process, scenario, name: str) -> None:
    sim = start_process(
        ros2_run_argv("uav_sim", "sim_node",
                      ros_args=fast_flight_ros_args(scenario, subscribers=1)),
        name,
    )
    assert sim.wait(timeout_s=60) == 0, sim.output()


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_residuals_every_half_second_with_dropout_and_restart(
    short_scenario, graph, start_process
):
    received = graph.subscribe({"/residuals": Residuals}, STREAM_QOS)["/residuals"]
    diagnostics = graph.subscribe({"/diagnostics": DiagnosticArray},
                                  DIAGNOSTICS_QOS)["/diagnostics"]
    residual_node = start_process(
        ros2_run_argv("uav_fault_estimator", "residual_node",  # inputs once we listen
                      ros_args=["-p", f"recovery_s:={RECOVERY_S}", "-p",
                                "wait_for_subscribers:=1"]),
        "residual_node",
    )
    assert graph.wait_for_publishers("/residuals", 1, timeout_s=30)
    fly(start_process, short_scenario(FIRST_S, sensor_dropouts=[PITCH_RATE_DROPOUT,
                                                                    AIRSPEED_DROPOUT]), "first")
    first = round(FIRST_S / PERIOD_S)
    graph.spin(30.0, until=lambda: len(received) >= first)
    # the fallback is counted on /diagnostics: every sensor sample of the airspeed dropout
    fallback = round((AIRSPEED_DROPOUT["end_s"] - AIRSPEED_DROPOUT["start_s"])
                     / SENSOR_PERIOD_S)
    graph.spin(5.0, until=lambda: filtered_wind_samples(diagnostics) == fallback)
    assert filtered_wind_samples(diagnostics) == fallback
    fly(start_process, short_scenario(SECOND_S), "restarted")
    expected = first + round(SECOND_S / PERIOD_S)
    graph.spin(30.0, until=lambda: len(received) >= expected)
    graph.spin(1.0)  # nothing more may come

    stamps = [stamp_seconds(message.header.stamp) for message in received]
    print(f"{len(received)} residuals, stamps {stamps}")
    assert stamps == pytest.approx(
        [PERIOD_S * k for k in range(1, first + 1)]
        + [PERIOD_S * k for k in range(1, expected - first + 1)], abs=1e-9)
    columns = list(PAPER_FAULT_NAMES + WIND_ERROR_NAMES)  # the defaults
    for message in received:
        assert list(message.fault_names) == columns
        sensitivity = np.array(message.sensitivity).reshape(6, -1)
        assert sensitivity.shape == (6, len(columns))
        assert np.all(np.isfinite(sensitivity)) and np.all(np.isfinite(message.residual))
    # where the vanes measure the flow (every sample's since the start) the wind errors are 0
    wind_columns = [np.array(message.sensitivity).reshape(6, -1)[:, len(PAPER_FAULT_NAMES):]
                    for message in received if message.wind_source == Residuals.WIND_AIR_DATA
                    and stamp_seconds(message.header.stamp) < 5.0]
    assert wind_columns and not np.any(wind_columns)
    valid = {stamp: list(message.valid)
             for stamp, message in zip(stamps[:first], received[:first], strict=True)}
    row_only = [row != ANGULAR_Y for row in range(6)]
    assert valid[1.5] == [True] * 6                   # settled before the dropout
    assert valid[2.5] == valid[3.5] == row_only        # missing, then settling for 1 s
    assert valid[4.5] == [True] * 6
    # the models fly the air data, and the filtered wind while the airspeed is missing
    sources = {stamp: message.wind_source
               for stamp, message in zip(stamps[:first], received[:first], strict=True)}
    filtered = [stamp for stamp, source in sources.items() if source == Residuals.WIND_FILTERED]
    assert filtered == [5.0, 5.5], sources
    assert all(source == Residuals.WIND_AIR_DATA for source in sources.values()
               if source != Residuals.WIND_FILTERED)
    log = residual_node.output()
    assert log.count("the source restarted, filters reset") == 1, log
    assert residual_node.running()


def filtered_wind_samples(diagnostics: list[DiagnosticArray]) -> int | None:
    """residual_node's latest count of samples flown on the filtered wind (/diagnostics)."""
    for array in reversed(diagnostics):
        for status in array.status:
            values = {value.key: value.value for value in status.values}
            if status.name.endswith("residual_node") and "filtered_wind_samples" in values:
                return int(values["filtered_wind_samples"])
    return None


@pytest.mark.timeout(60)
def test_an_unknown_fault_name_ends_residual_node_with_one_message():
    result = subprocess.run(
        ros2_run_argv("uav_fault_estimator", "residual_node",
                      ros_args=["-p", "fault_names:=[right_wing_lift_loss, wing_fell_off]"]),
        capture_output=True, text=True, timeout=50,
    )
    assert result.returncode == 2  # bad input
    assert "Traceback" not in result.stderr
    assert "residual_node: unknown fault names ['wing_fell_off']" in result.stderr


@pytest.mark.timeout(60)
def test_a_calibration_of_another_model_ends_residual_node_with_one_message(tmp_path):
    calibration = tmp_path / "model.yaml"
    calibration.write_text(yaml.safe_dump({"vehicle": "aerosonde", "model_file": "aerosonde.xml",
                                           "model_sha256": "0" * 64,
                                           "aircraft": {}}))
    result = subprocess.run(
        ros2_run_argv("uav_fault_estimator", "residual_node",
                      ros_args=["-p", f"model_calibration_file:={calibration}"]),
        capture_output=True, text=True, timeout=50,
    )
    assert result.returncode == 2  # bad input
    assert "Traceback" not in result.stderr
    assert f"model calibration {calibration}: made for another model file" in result.stderr
