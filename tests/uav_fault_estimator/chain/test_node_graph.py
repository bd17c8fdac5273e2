"""The node graph both launchers start: its order, keys and wiring."""

from __future__ import annotations

import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from uav_fault_estimator.chain.node_graph import (
    ModelCalibrationFiles,
    live_plan,
    node_ros_args,
    vehicle_namespaces,
)
from uav_fault_estimator.estimation.estimator_settings import VANELESS_HORIZON, EstimatorSettings
from uav_sim.paths import scenarios_dir

SIM_TIME = ["-p", "use_sim_time:=true"]
NO_LOG_FILE = ["--disable-external-lib-logs"]  # the launchers write each node's output
VEHICLE = ["-p", "vehicle:=aerosonde"]  # the shipped scenarios' vehicle
A, B = scenarios_dir() / "default.yaml", scenarios_dir() / "fault_free.yaml"


@pytest.mark.timeout(10)
def test_several_aircraft_start_last_first_each_simulator_last():
    plan = live_plan([A, B], foxglove=True)
    assert [node.key for node in plan] == [
        *(f"uav2/{n}" for n in ("residual_node", "mhe_node", "detector_node",
                                "standard_topics_node", "sim_node")),
        *(f"uav1/{n}" for n in ("residual_node", "mhe_node", "detector_node",
                                "standard_topics_node", "sim_node")),
        "foxglove_node"]
    sims = {node.key: node.ros_args for node in plan if node.executable == "sim_node"}
    # the first aircraft's simulator publishes /clock; every other node follows it
    assert sims["uav1/sim_node"] == [*NO_LOG_FILE, "-r", "__ns:=/uav1", *VEHICLE, "-p",
                                     f"scenario:={A}"]
    assert sims["uav2/sim_node"] == [*NO_LOG_FILE, "-r", "__ns:=/uav2", *VEHICLE, *SIM_TIME,
                                     "-p", f"scenario:={B}"]
    assert all(node.ros_args[-2:] == SIM_TIME for node in plan
               if node.executable != "sim_node")
    modelling = {"sim_node", "residual_node", "mhe_node", "detector_node"}
    assert all((node.ros_args[3:5] == VEHICLE) == (node.executable in modelling)
               for node in plan[:-1])
    assert plan[-1].ros_args == [*NO_LOG_FILE, *SIM_TIME]  # the whole graph's: no namespace


@pytest.mark.timeout(10)
def test_a_model_calibration_wires_residual_and_mhe_nodes_after_the_parameter_file():
    calibration = ModelCalibrationFiles(Path("/m.yaml"), Path("/n.yaml"))
    plan = {node.key: node.ros_args for node in live_plan(
        [], "/uav3", Path("/p.yaml"), calibration)}
    assert plan["residual_node"] == ["--params-file", "/p.yaml", *NO_LOG_FILE, "-r",
                                     "__ns:=/uav3", *VEHICLE, "-p",
                                     "model_calibration_file:=/m.yaml", *SIM_TIME]
    assert plan["mhe_node"][:9] == ["--params-file", "/p.yaml", *NO_LOG_FILE, "-r",
                                    "__ns:=/uav3", *VEHICLE, "-p",
                                    "noise_calibration_file:=/n.yaml"]
    assert "model_calibration_file:=/m.yaml" not in plan["mhe_node"]
    assert node_ros_args("detector_node", "", False, calibration) == [*NO_LOG_FILE, *VEHICLE,
                                                                      *SIM_TIME]


@pytest.mark.timeout(30)
def test_the_plan_reads_back_in_a_shell_word_for_word(tmp_path):
    spaced = tmp_path / "my flights" / "a b.yaml"
    spaced.parent.mkdir()
    spaced.write_text(A.read_text())
    result = subprocess.run([sys.executable, "-m", "uav_fault_estimator.chain.node_graph",
                             "--scenario", str(spaced)], capture_output=True, text=True,
                            check=True)
    lines = result.stdout.splitlines()
    assert [shlex.split(line) for line in lines] == [
        [node.key, node.package, node.executable, *node.ros_args]
        for node in live_plan([spaced])]
    assert shlex.split(lines[-1])[-1] == f"scenario:={spaced}"


@pytest.mark.timeout(30)
def test_one_namespace_for_several_aircraft_is_refused():
    assert vehicle_namespaces(1, "/uav7") == ["/uav7"]
    assert vehicle_namespaces(3) == ["/uav1", "/uav2", "/uav3"]
    with pytest.raises(ValueError, match="one aircraft"):
        vehicle_namespaces(2, "/uav7")
    result = subprocess.run([sys.executable, "-m", "uav_fault_estimator.chain.node_graph", "--ns",
                             "/x", "--scenario", str(A), "--scenario", str(B)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 2 and result.stderr.count("\n") == 1


@pytest.mark.timeout(30)
def test_a_scenario_that_cannot_be_read_is_one_line(tmp_path):
    missing = tmp_path / "missing.yaml"
    result = subprocess.run([sys.executable, "-m", "uav_fault_estimator.chain.node_graph",
                             "--scenario", str(missing)], capture_output=True, text=True,
                            check=False)
    assert result.returncode == 2
    assert result.stderr == f"node_graph: scenario {missing}: cannot read the file (No such " \
                            "file or directory)\n"


@pytest.mark.timeout(30)
def test_a_model_calibration_of_another_vehicle_is_one_line_named_as_the_caller(tmp_path):
    calibration = tmp_path / "model.yaml"
    calibration.write_text("vehicle: carbon_z\nmodel_file: carbon_z.xml\nmodel_sha256: '0'\n"
                           "aircraft: {}\n")
    result = subprocess.run([sys.executable, "-m", "uav_fault_estimator.chain.node_graph",
                             "--caller", "bringup.sh", "--scenario", str(A),
                             "--model-calibration", str(calibration)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr == (f"bringup.sh: model calibration {calibration}: made for the "
                             "vehicle 'carbon_z', not 'aerosonde'\n")


@pytest.mark.timeout(30)
@pytest.mark.parametrize("vehicle", ["aerosonde", "carbon_z"])
def test_the_link_listener_takes_its_vehicle_and_the_parameter_file(vehicle):
    plan = {node.key: node.ros_args for node in live_plan(
        [], params=Path("/p.yaml"), mavlink="udpin:127.0.0.1:14550", vehicle=vehicle)}
    args = plan["mavlink_node"]
    # the fuel is the node's own default (its vehicle model's), so the file's value wins
    assert args[:2] == ["--params-file", "/p.yaml"] and f"vehicle:={vehicle}" in args
    assert not any(arg.startswith("fuel_mass_kg") for node_args in plan.values()
                   for arg in node_args)


@pytest.mark.timeout(30)
def test_behind_a_link_or_without_vanes_the_estimator_takes_the_wind_errors(tmp_path):
    """A link carries a pitot and no vanes, and so does a scenario saying so: mhe_node then
    estimates the wind errors over the longer window; with vanes it keeps its defaults."""
    wind_errors = ["-p", "estimate_wind_errors:=true"]
    longer_window = ["-p", f"horizon:={VANELESS_HORIZON}"]
    assert EstimatorSettings().horizon < VANELESS_HORIZON

    def mhe_args(plan) -> list[str]:
        return next(node.ros_args for node in plan if node.executable == "mhe_node")

    def has(args: list[str], wanted: list[str]) -> bool:
        return any(args[i:i + 2] == wanted for i in range(len(args) - 1))

    vaneless = tmp_path / "vaneless.yaml"
    vaneless.write_text(A.read_text().replace("sensors: {air_data: true, noise: true}",
                                              "sensors: {air_data: true, noise: true, "
                                              "vanes: false}"))
    assert "vanes: false" in vaneless.read_text()
    for plan in (live_plan([], mavlink="udpin:127.0.0.1:14550"), live_plan([vaneless])):
        assert has(mhe_args(plan), wind_errors) and has(mhe_args(plan), longer_window)
    with_vanes = mhe_args(live_plan([A]))
    assert not has(with_vanes, wind_errors) and not any("horizon" in a for a in with_vanes)
