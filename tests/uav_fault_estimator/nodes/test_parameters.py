"""Every bad parameter is one line naming it and exit status 2, before the node does
anything: a wrong type, a value out of its range, an unknown name, a params file that
does not parse. An integer given for a real is the real it names."""

from __future__ import annotations

import math
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from uav_common.ros.parameter_files import wildcard_only_names
from uav_common.ros.parameters import (
    ParameterError,
    ParameterSpec,
    checked_value,
    declare_parameters,
)
from uav_common.ros_processes import ros2_run_argv
from uav_common.settings import parameter_specs, settings_from
from uav_fault_estimator.detection.detector_settings import DetectorSettings
from uav_fault_estimator.estimation.estimator_settings import EstimatorSettings
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.nodes import (
    detector_node,
    foxglove_node,
    log_replay_node,
    mhe_node,
    recorder_node,
    residual_node,
)
from uav_sim.paths import scenarios_dir
from uav_sim.ros import sim_node

NODES = {"sim_node": sim_node.PARAMETERS, "residual_node": residual_node.PARAMETERS,
         "mhe_node": mhe_node.PARAMETERS, "detector_node": detector_node.PARAMETERS,
         "recorder_node": recorder_node.PARAMETERS, "foxglove_node": foxglove_node.PARAMETERS,
         "log_replay_node": log_replay_node.PARAMETERS}
SCENARIO = scenarios_dir() / "default.yaml"
NUMBERS = (Parameter.Type.INTEGER, Parameter.Type.DOUBLE, Parameter.Type.INTEGER_ARRAY,
           Parameter.Type.DOUBLE_ARRAY)
MHE_NAMES = ("arrival_centre, arrival_floor_variances_pct2, arrival_inflation, "
             "estimate_wind_errors, fault_model_coefficients, fault_model_scales_pct, "
             "fault_models, fault_names, handover_variances_pct2, horizon, lower_bounds_pct, "
             "model_fit_threshold_sigmas, model_fit_window_s, "
             "noise_calibration_file, noise_variance_factor, prior_pct, qos, solver_eps_abs, "
             "solver_max_iter, solver_method, state_file, update_budget_ms, upper_bounds_pct, "
             "vehicle, wait_for_subscribers, wind_error_coefficient, "
             "wind_error_handover_variance_m2ps2, wind_error_sigma_mps")


@pytest.mark.timeout(30)
@pytest.mark.parametrize("name", NODES)
def test_every_number_has_a_range_that_holds_its_default(name):
    specs = NODES[name]
    defaults = {parameter: spec.default for parameter, spec in specs.items()}
    for parameter, spec in specs.items():
        assert isinstance(spec, ParameterSpec) and spec.description, parameter
        kind = Parameter.Type.from_parameter_value(defaults[parameter])
        if kind in NUMBERS:
            assert spec.low is not None and spec.high is not None, parameter
            assert checked_value(parameter, defaults[parameter], kind, spec) == (
                defaults[parameter])
        else:
            assert spec.low is None and spec.high is None, parameter


@pytest.mark.timeout(30)
@pytest.mark.parametrize(("specs", "settings_type"), [
    (residual_node.PARAMETERS, ResidualSettings), (mhe_node.PARAMETERS, EstimatorSettings),
    (detector_node.PARAMETERS, DetectorSettings)], ids=["residual", "mhe", "detector"])
def test_a_nodes_first_parameters_are_its_cores_settings(specs, settings_type):
    """Declared once: the node's specs of its core's settings are the fields' own, first
    and in order, and the node's defaults are the settings' defaults."""
    fields = parameter_specs(settings_type)
    assert list(specs)[:len(fields)] == list(fields)
    assert all(specs[name] is spec for name, spec in fields.items())
    defaults = {name: spec.default for name, spec in specs.items()}
    assert settings_from(settings_type, defaults) == settings_type()


@pytest.mark.timeout(10)
def test_an_integer_is_taken_for_the_real_it_names_and_nothing_else_is_converted():
    real, count = ParameterSpec("a real", 1.0, 0.0, 10.0), ParameterSpec("a count", 50, 2, 2000)
    value = checked_value("x", 4, Parameter.Type.DOUBLE, real)
    assert value == 4.0 and isinstance(value, float)
    values = checked_value("x", [1, 2], Parameter.Type.DOUBLE_ARRAY, real)
    assert values == [1.0, 2.0] and all(isinstance(v, float) for v in values)
    assert checked_value("x", [], Parameter.Type.DOUBLE_ARRAY, real) == []
    with pytest.raises(ParameterError, match=r"^parameter n: 50.0 is a real number; it must "
                                             r"be an integer in \[2, 2000\]$"):
        checked_value("n", 50.0, Parameter.Type.INTEGER, count)
    with pytest.raises(ParameterError, match="True is a boolean; it must be an integer"):
        checked_value("n", True, Parameter.Type.INTEGER, count)
    for bad in (math.nan, math.inf, -0.5, 10.5):
        with pytest.raises(ParameterError, match="is out of range"):
            checked_value("x", bad, Parameter.Type.DOUBLE, real)
    with pytest.raises(ParameterError, match=r"^parameter x: 11.0 is out of range; it must be "
                                             r"a real list of values in \[0, 10\]$"):
        checked_value("x", [1.0, 11.0], Parameter.Type.DOUBLE_ARRAY, real)


@pytest.mark.timeout(10)
def test_an_empty_choice_is_listed_with_what_it_means():
    spec = sim_node.PARAMETERS["vehicle"]
    assert checked_value("vehicle", "", Parameter.Type.STRING, spec) == ""
    with pytest.raises(ParameterError) as refused:
        checked_value("vehicle", "cessna", Parameter.Type.STRING, spec)
    assert str(refused.value) == ("parameter vehicle: 'cessna' is not a choice; it must be one "
                                  "of '' (the scenario's), aerosonde, carbon_z")
    qos = sim_node.PARAMETERS["qos"]  # no empty choice: the names alone
    assert qos.choices_text() == "reliable, sensor_data"


@pytest.fixture
def context():
    context = Context()
    rclpy.init(context=context)
    yield context
    context.try_shutdown()


@pytest.mark.timeout(30)
def test_declared_with_type_and_range_in_the_descriptor(context):
    node = Node("recorder_node", context=context, parameter_overrides=[
        Parameter("discovery_period_s", Parameter.Type.INTEGER, 1),
        Parameter("output_dir", Parameter.Type.STRING, "/tmp/somewhere")])
    try:
        values = declare_parameters(node, recorder_node.PARAMETERS)
        assert values == {"discovery_period_s": 1.0, "output_dir": "/tmp/somewhere"}
        assert isinstance(values["discovery_period_s"], float)
        descriptor = node.describe_parameter("discovery_period_s")
        assert descriptor.type == Parameter.Type.DOUBLE.value
        assert descriptor.description == recorder_node.PARAMETERS["discovery_period_s"].description
        (span,) = descriptor.floating_point_range
        assert (span.from_value, span.to_value) == (0.01, 60.0)
        # the range holds later too: rclpy refuses a value outside it
        result = node.set_parameters([Parameter("discovery_period_s", value=0.0)])[0]
        assert not result.successful
    finally:
        node.destroy_node()


@pytest.mark.timeout(30)
def test_an_unknown_override_is_named_before_anything_is_declared(context):
    node = Node("recorder_node", context=context, parameter_overrides=[
        Parameter("discovery_perod_s", Parameter.Type.DOUBLE, 1.0)])
    try:
        with pytest.raises(ParameterError, match=r"^unknown parameter discovery_perod_s "):
            declare_parameters(node, recorder_node.PARAMETERS)
        assert not node.has_parameter("output_dir")
    finally:
        node.destroy_node()


def params_file(tmp_path, text: str) -> list[str]:
    path = tmp_path / "params.yaml"
    path.write_text(text)
    return ["--params-file", str(path)]


def ros_params(node: str, lines: str) -> str:
    return f"{node}:\n  ros__parameters:\n" + "".join(f"    {line}\n" for line in lines.split(";"))


# (package, executable, ros args or a params file's text, the one line on stderr)
CASES = {
    "string_for_an_integer": (
        "uav_fault_estimator", "mhe_node", ros_params("/**", 'horizon: "fifty"'),
        "mhe_node: parameter horizon: 'fifty' is a string; it must be an integer in [2, 2000]"),
    "real_for_an_integer": (
        "uav_fault_estimator", "mhe_node", ros_params("mhe_node", "horizon: 50.0"),
        "mhe_node: parameter horizon: 50.0 is a real number; it must be an integer in "
        "[2, 2000]"),
    "params_file_that_does_not_parse": (
        "uav_fault_estimator", "mhe_node", "mhe_node:\n  ros__parameters:\n    horizon: [1,\n",
        "mhe_node: bad ROS arguments: Couldn't parse params file: '--params-file {file}'. "
        "Error: Error parsing a event near line 3"),
    "unknown_parameter_in_a_params_file": (
        "uav_fault_estimator", "mhe_node", ros_params("mhe_node", "horizon: 50;horizn: 60"),
        f"mhe_node: unknown parameter horizn (this node has: {MHE_NAMES})"),
    "solver_eps_abs_integer_out_of_range": (
        "uav_fault_estimator", "mhe_node", ["-p", "solver_eps_abs:=1"],
        "mhe_node: parameter solver_eps_abs: 1.0 is out of range; it must be a real number in "
        "[1e-12, 0.1]"),
    "solver_eps_abs_negative": (
        "uav_fault_estimator", "mhe_node", ["-p", "solver_eps_abs:=-1"],
        "mhe_node: parameter solver_eps_abs: -1.0 is out of range; it must be a real number in "
        "[1e-12, 0.1]"),
    "solver_max_iter_zero": (
        "uav_fault_estimator", "mhe_node", ["-p", "solver_max_iter:=0"],
        "mhe_node: parameter solver_max_iter: 0 is out of range; it must be an integer in "
        "[1, 100000]"),
    "solver_method_unknown": (
        "uav_fault_estimator", "mhe_node", ["-p", "solver_method:=fastest"],
        "mhe_node: solver method must be one of proxsuite, active_set, got 'fastest'"),
    "horizon_that_would_exhaust_memory": (
        "uav_fault_estimator", "mhe_node", ["-p", "horizon:=1000000"],
        "mhe_node: parameter horizon: 1000000 is out of range; it must be an integer in "
        "[2, 2000]"),
    "per_fault_value_out_of_range": (
        "uav_fault_estimator", "mhe_node", ["-p", "prior_pct:=[0.0, 0.0, 2000.0, 0.0]"],
        "mhe_node: parameter prior_pct: 2000.0 is out of range; it must be a real list of "
        "values in [-1000, 1000]"),
    "vehicle_unknown": (
        "uav_sim", "sim_node", ["-p", "vehicle:=cessna"],
        "sim_node: parameter vehicle: 'cessna' is not a choice; it must be one of '' (the "
        "scenario's), aerosonde, carbon_z"),
    "noise_calibration_file_a_scenario": (
        "uav_fault_estimator", "mhe_node", ["-p", f"noise_calibration_file:={SCENARIO}"],
        f"mhe_node: noise calibration {SCENARIO}: not a noise calibration "
        "(scripts/calibrate_estimator.py's file, a vehicle's residual_noise.yaml), whose keys "
        "are vehicle, air_data, pitot, filtered_wind; this file holds the keys name, "
        "duration_s, seed, initial, waypoints_ne_m, guidance, wind, sensors, faults"),
    "sensor_rate_zero": (
        "uav_sim", "sim_node", ["-p", "sensor_rate_hz:=0.0"],
        "sim_node: parameter sensor_rate_hz: 0.0 is out of range; it must be a real number in "
        "[1, 480]"),
    "real_time_factor_negative": (
        "uav_sim", "sim_node", ["-p", "real_time_factor:=-1.0"],
        "sim_node: parameter real_time_factor: -1.0 is out of range; it must be a real number "
        "in [0, 1000]"),
    "sensitivity_period_negative": (
        "uav_fault_estimator", "residual_node", ["-p", "sensitivity_period_s:=-0.5"],
        "residual_node: parameter sensitivity_period_s: -0.5 is out of range; it must be a "
        "real number in [0, 60]"),
    "recovery_negative": (
        "uav_fault_estimator", "residual_node", ["-p", "recovery_s:=-1.0"],
        "residual_node: parameter recovery_s: -1.0 is out of range; it must be a real number "
        "in [0, 600]"),
    "false_alarm_probability_nan": (
        "uav_fault_estimator", "detector_node", ["-p", "false_alarm_probability:=.nan"],
        "detector_node: parameter false_alarm_probability: nan is out of range; it must be a "
        "real number in [1e-09, 0.5]"),
    "sample_period_zero": (
        "uav_fault_estimator", "log_replay_node", ["-p", "sample_period_s:=0.0"],
        "log_replay_node: parameter sample_period_s: 0.0 is out of range; it must be a real "
        "number in [0.01, 10]"),
    "discovery_period_of_the_wrong_type": (
        "uav_fault_estimator", "recorder_node", ["-p", "discovery_period_s:=[1.0]"],
        "recorder_node: parameter discovery_period_s: [1.0] is a real list; it must be a real "
        "number in [0.01, 60]"),
}


# Bad-parameter runs at once: each is a process start-up (about 1 s of CPU) that ends
# before it joins the graph; three keep two cores busy.
CONCURRENT_RUNS = 3


@pytest.fixture(scope="module")
def bad_runs(tmp_path_factory) -> dict[str, tuple[subprocess.CompletedProcess, Path]]:
    """Each of CASES run as `ros2 run` to its end, CONCURRENT_RUNS at a time: its result and
    the folder of its params file."""
    def run(case: str) -> tuple[subprocess.CompletedProcess, Path]:
        package, executable, given, _ = CASES[case]
        folder = tmp_path_factory.mktemp(case)
        ros_args = params_file(folder, given) if isinstance(given, str) else given
        return subprocess.run(ros2_run_argv(package, executable, ros_args=ros_args),
                              capture_output=True, text=True, timeout=50), folder

    with ThreadPoolExecutor(max_workers=CONCURRENT_RUNS) as pool:
        return dict(zip(CASES, pool.map(run, CASES), strict=True))


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.timeout(120)
@pytest.mark.parametrize("case", CASES)
def test_a_bad_parameter_is_one_line_and_status_2(case, bad_runs):
    result, folder = bad_runs[case]
    assert result.returncode == 2, result
    expected = CASES[case][3].format(file=folder / "params.yaml")
    assert result.stderr.splitlines() == [expected], result.stderr
    assert result.stdout == ""  # nothing done: not even a log line


@pytest.mark.integration
@pytest.mark.timeout(60)
def test_integers_for_reals_fly(short_scenario, tmp_path):
    """`-p real_time_factor:=0`, `sensor_rate_hz: 20` in a params file: taken as the reals."""
    ros_args = [*params_file(tmp_path, ros_params("sim_node", "sensor_rate_hz: 20")),
                "-p", f"scenario:={short_scenario(1.0)}", "-p", "real_time_factor:=0",
                "-p", "wait_for_subscribers:=0"]
    result = subprocess.run(ros2_run_argv("uav_sim", "sim_node", ros_args=ros_args),
                            capture_output=True, text=True, timeout=50)
    assert result.returncode == 0, result
    assert "1 s at 20 Hz, real-time factor 0" in result.stderr + result.stdout, result
    assert "finished at 1 s of simulation time" in result.stderr + result.stdout, result


@pytest.mark.timeout(10)
def test_a_shared_files_wildcard_names_are_told_apart_from_the_nodes_own(tmp_path):
    shared = tmp_path / "shared.yaml"
    shared.write_text("/**:\n  ros__parameters:\n    horizon: 50\n    qos: {depth: 5}\n"
                      "    scenario: a.yaml\n"
                      "/uav1/sim_node:\n  ros__parameters:\n    scenario: b.yaml\n"
                      "mhe_node:\n  ros__parameters:\n    horizn: 3\n")
    argv = ["sim_node", "--ros-args", "--params-file", str(shared), "-p", "qos.depth:=1",
            "--", "--params-file", "not_a_ros_argument.yaml"]
    # scenario is named for sim_node, qos.depth given with -p: strict; horizon only shared
    assert wildcard_only_names(argv, "sim_node") == {"horizon"}
    assert wildcard_only_names(argv, "mhe_node") == {"scenario", "horizon"}
    assert wildcard_only_names(["sim_node"], "sim_node") == set()  # no ROS arguments
    unreadable = ["x", "--ros-args", "--params-file", str(tmp_path / "missing.yaml")]
    assert wildcard_only_names(unreadable, "sim_node") == set()  # rcl's to refuse


@pytest.mark.integration
@pytest.mark.timeout(60)
def test_a_shared_parameter_file_flies_and_names_what_it_ignores(short_scenario, tmp_path):
    """One file for every node, as ROS users write it: sim_node takes its own keys of the
    /** section and says, in one warning line, which it ignores."""
    ros_args = params_file(tmp_path, ros_params(
        "/**", f"scenario: {short_scenario(1.0)};real_time_factor: 0.0;"
        "wait_for_subscribers: 0;horizon: 50;false_alarm_probability: 0.001"))
    result = subprocess.run(ros2_run_argv("uav_sim", "sim_node", ros_args=ros_args),
                            capture_output=True, text=True, timeout=50)
    output = result.stderr + result.stdout
    assert result.returncode == 0, result
    warnings = [line for line in output.splitlines() if "ignoring" in line]
    assert len(warnings) == 1 and warnings[0].endswith(
        "ignoring false_alarm_probability, horizon of the parameter file's /** section: "
        "this node has no such parameters"), output
    assert "finished at 1 s of simulation time" in output, output


@pytest.mark.timeout(30)
def test_a_live_parameter_goes_to_the_node_checked_and_a_refusal_keeps_the_value(context):
    node = Node("detector_node", context=context)
    applied = []

    def apply_changes(changes: dict) -> None:
        if changes["false_alarm_probability"] > 0.1:
            raise ParameterError("too many false alarms")
        applied.append(changes)

    try:
        values = declare_parameters(node, detector_node.PARAMETERS, apply_changes)
        assert not node.describe_parameter("false_alarm_probability").read_only
        assert node.describe_parameter("calibration_file").read_only
        (ok,) = node.set_parameters([Parameter("false_alarm_probability", value=0.001)])
        assert ok.successful and applied == [{"false_alarm_probability": 0.001}]
        assert values["false_alarm_probability"] == 0.001
        (refused,) = node.set_parameters([Parameter("false_alarm_probability", value=0.2)])
        assert (refused.successful, refused.reason) == (False, "too many false alarms")
        (wrong_type,) = node.set_parameters([Parameter("false_alarm_probability", value="x")])
        assert not wrong_type.successful
        assert values["false_alarm_probability"] == 0.001 == node.get_parameter(
            "false_alarm_probability").value
        assert len(applied) == 1
    finally:
        node.destroy_node()
