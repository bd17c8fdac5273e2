"""The node graph, described once: the nodes that fly and diagnose an aircraft, their
packages, their start order, and the ROS arguments that wire them for one aircraft or
several (namespaces, the one clock, a model calibration), on a simulator or on an
autopilot's MAVLink link (mavlink_node), and the simulated flight played through such a link
(autopilot_node). demo_run.py (demo.sh) and scripts/bringup.sh start what it says (no ROS
here).

    python -m uav_fault_estimator.chain.node_graph [--ns NS] [--scenario FILE ...]
        [--mavlink CONNECTION [--vehicle NAME]] [--params FILE]
        [--model-calibration FILE] [--foxglove] [--caller NAME]

prints bringup.sh's plan: one line per node in start order, `KEY PACKAGE EXECUTABLE` and
the node's ROS arguments, each word quoted for a POSIX shell (KEY: `uavk/node` with several
aircraft, else the node's name). A scenario or model calibration that cannot be used, or
--mavlink with a scenario, is one line on stderr, named as the caller (default node_graph),
and status 2.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from uav_aircraft.vehicles import DEFAULT_VEHICLE, load_vehicle, vehicle_names
from uav_common.ros_processes import NO_LOG_FILE_ROS_ARGS, SIM_TIME_ROS_ARGS
from uav_sim.scenario import SensorSuite, load_scenario

from uav_fault_estimator.estimation.estimator_settings import sensor_overrides
from uav_fault_estimator.estimation.model_file import load_model_calibration

SIMULATOR, LISTENER, AUTOPILOT = "sim_node", "mavlink_node", "autopilot_node"
# What a MAVLink link carries of an aircraft's air data, (air data, vanes): the pitot's
# airspeed, no flow angles
LINK_SENSORS = (True, False)
PACKAGES = {SIMULATOR: "uav_sim", "residual_node": "uav_fault_estimator",
            "mhe_node": "uav_fault_estimator", "detector_node": "uav_fault_estimator",
            "standard_topics_node": "uav_fault_estimator",
            "recorder_node": "uav_fault_estimator", "foxglove_node": "uav_fault_estimator",
            "log_replay_node": "uav_fault_estimator", LISTENER: "uav_mavlink",
            AUTOPILOT: "uav_mavlink"}
# Each aircraft's nodes in start order: the simulator last, once the others listen.
VEHICLE_NODES = ("residual_node", "mhe_node", "detector_node", "standard_topics_node",
                 SIMULATOR)
# The nodes that model the aircraft: each takes its `vehicle` parameter from the scenario
# (the link's two ends: for the vehicle's servo mapping).
MODELLING_NODES = ("residual_node", "mhe_node", "detector_node", SIMULATOR, LISTENER,
                   AUTOPILOT)
# The nodes that give an aircraft's time: the first aircraft's publishes /clock.
CLOCK_SOURCES = (SIMULATOR, LISTENER)
# demo.sh --via-mavlink: the simulator and the autopilot it plays in this namespace, on a
# loopback UDP link to mavlink_node, whose streams the chain takes at the graph's own names;
# the simulator's truth the report reads stays at its own names too.
PLAYED_AUTOPILOT_NS = "/sim"
TRUTH_TOPICS = ("faults/seeded", "wind/true")
LINK_HOST = "127.0.0.1"
# The link has no flow control: a simulator as fast as its subscribers acknowledge sends
# its samples in bursts, and a listener held up for a moment loses the datagrams beyond its
# socket's buffer (the default flight at about 16 times real time lost 8 s of it). Paced,
# the bursts are one sample's, and mavlink_node keeps up on two cores: ArduPlane's advised
# streams (about 100 messages per flight second) at 10 times real time; PX4's onboard set
# (about 270) lost 30 s of the default flight at 10, so it flies at 4
# [simulated s per wall s].
LINK_REAL_TIME_FACTOR = {"ardupilot": 10.0, "px4": 4.0}


def vehicle_namespaces(count: int, namespace: str = "") -> list[str]:
    """The aircraft's namespaces: one aircraft flies in namespace ("" for none), several
    under /uav1, /uav2, ... (ValueError when several are given one namespace)."""
    if count > 1 and namespace:
        raise ValueError("a namespace names one aircraft's; several fly /uav1, /uav2, ...")
    return [namespace] if count <= 1 else [f"/uav{k + 1}" for k in range(count)]


def node_key(namespace: str, executable: str) -> str:
    """How a launcher names a node of an aircraft in namespace ("" for the whole graph or a
    lone aircraft): `uav1/mhe_node`, or `mhe_node`; also its log's path under the logs."""
    return f"{namespace.strip('/')}/{executable}".lstrip("/")


@dataclass(frozen=True)
class ModelCalibrationFiles:
    """What a model calibration gives the nodes: residual_node's models (model_file) and
    the noise file it names for mhe_node (None: none)."""

    model_file: Path
    noise_file: Path | None = None


def model_calibration_files(model_file: Path, vehicles: Sequence[str]) -> ModelCalibrationFiles:
    """The model calibration for every one of the vehicles, read and checked before any
    node starts; ModelCalibrationError (one line) when it cannot be used for one of them."""
    noise_file = None
    for vehicle in sorted(set(vehicles)):
        noise_file = load_model_calibration(model_file, vehicle).noise_file
    return ModelCalibrationFiles(model_file, noise_file)


def scenario_vehicles(scenarios: Sequence[Path]) -> list[str]:
    """The vehicle each scenario flies (none given: the default, one aircraft);
    ScenarioError for a scenario that cannot be read."""
    return [load_scenario(path).vehicle for path in scenarios] or [DEFAULT_VEHICLE]


def scenario_sensors(scenarios: Sequence[Path]) -> list[tuple[bool, bool]]:
    """Each scenario's aircraft's sensors, (air data, vanes); the default scenario's without
    any. ScenarioError for a scenario that cannot be read."""
    suites = [load_scenario(path).sensors for path in scenarios] or [SensorSuite()]
    return [(suite.air_data, suite.vanes) for suite in suites]


def node_ros_args(executable: str, namespace: str, clock_leader: bool,
                  calibration: ModelCalibrationFiles | None = None,
                  vehicle: str = DEFAULT_VEHICLE) -> list[str]:
    """The ROS arguments that wire one of an aircraft's nodes (or, namespace "", one of the
    whole graph): its namespace, the vehicle it models, the model calibration's files, and
    /clock for every node but the clock source (CLOCK_SOURCES) that publishes it
    (clock_leader: the first aircraft's); and no rcl log file, as the launchers write the
    node's output to one."""
    args = [*NO_LOG_FILE_ROS_ARGS, *(["-r", f"__ns:={namespace}"] if namespace else [])]
    if executable in MODELLING_NODES:
        args += ["-p", f"vehicle:={vehicle}"]
    if calibration is not None and executable == "residual_node":
        args += ["-p", f"model_calibration_file:={calibration.model_file}"]
    if calibration is not None and calibration.noise_file and executable == "mhe_node":
        args += ["-p", f"noise_calibration_file:={calibration.noise_file}"]
    if not (executable in CLOCK_SOURCES and clock_leader):
        args += SIM_TIME_ROS_ARGS
    return args


def played_autopilot_ros_args(executable: str, stack: str, port: int,
                              fuel_mass_kg: float, vehicle: str) -> list[str]:
    """demo.sh --via-mavlink's ROS arguments, beyond node_ros_args', of the simulator, the
    autopilot it plays (stack: ardupilot or px4) and mavlink_node, linked on UDP port `port`
    of loopback (PLAYED_AUTOPILOT_NS), the simulator at the stack's LINK_REAL_TIME_FACTOR.
    mavlink_node stamps with the boot time itself (the simulation time: no offset measured
    at the first message), takes the fuel the simulated aircraft carries, fuel_mass_kg [kg],
    as its fuel mass (no autopilot streams it), and reads the outputs with the vehicle's
    simulated airframe (the one autopilot_node writes them with). residual_node:
    link_residual_ros_args.
    """
    namespace = ["-r", f"__ns:={PLAYED_AUTOPILOT_NS}"]
    truth = [arg for topic in TRUTH_TOPICS for arg in ("-r", f"{topic}:=/{topic}")]
    if executable == SIMULATOR:
        return [*namespace, *truth, "-p", f"real_time_factor:={LINK_REAL_TIME_FACTOR[stack]!r}"]
    if executable == AUTOPILOT:
        return [*namespace, *truth, "-p", f"connection:=udpout:{LINK_HOST}:{port}",
                "-p", f"stack:={stack}"]
    if executable == LISTENER:
        return ["-p", f"connection:=udpin:{LINK_HOST}:{port}",
                "-p", "boot_time_is_ros_time:=true", "-p", f"fuel_mass_kg:={fuel_mass_kg!r}",
                "-p", f"airframe:={load_vehicle(vehicle).simulated_airframe_file}"]
    raise ValueError(f"{executable} is not one of the link's nodes")


def sensor_ros_args(executable: str, air_data: bool, vanes: bool) -> list[str]:
    """mhe_node's ROS arguments for an aircraft's sensors (estimator_settings.
    sensor_overrides); none for the other nodes."""
    if executable != "mhe_node":
        return []
    return [arg for name, value in sensor_overrides(air_data, vanes).items()
            for arg in ("-p", f"{name}:={str(value).lower()}")]


def link_residual_ros_args(stack: str) -> list[str]:
    """residual_node's ROS arguments behind a stack's link: PX4 streams no engine speed, so
    the models turn the propeller at its steady speed."""
    return ["-p", "engine_speed_measured:=false"] if stack == "px4" else []


@dataclass(frozen=True)
class PlannedNode:
    """A node to start: its key (`uavk/node` with several aircraft, else its name), package,
    executable and ROS arguments."""

    key: str
    package: str
    executable: str
    ros_args: list[str]

    def line(self) -> str:
        """bringup.sh's line for it: words quoted for a POSIX shell."""
        return shlex.join([self.key, self.package, self.executable, *self.ros_args])


def live_plan(scenarios: Sequence[Path], namespace: str = "", params: Path | None = None,
              calibration: ModelCalibrationFiles | None = None,
              foxglove: bool = False, mavlink: str = "",
              vehicle: str = DEFAULT_VEHICLE) -> list[PlannedNode]:
    """bringup.sh's nodes in start order: every aircraft's (the last aircraft's first, so
    that the followers wait for the clock the first one's simulator starts), each simulator
    flying its scenario (none given: the shipped default, one aircraft) and each node
    modelling the scenario's vehicle, then foxglove_node for the whole graph; params: a
    parameter file for every node. mavlink (a connection, as mavlink_node takes it): one
    aircraft on an autopilot instead, mavlink_node listening on it and publishing /clock in
    the simulator's place, every node modelling `vehicle` (mavlink_node takes the fuel its
    model carries unless the parameter file says otherwise).
    ScenarioError (a ValueError) for a scenario that cannot be read, ValueError for mavlink
    with scenarios."""
    if mavlink and scenarios:
        raise ValueError("--mavlink listens to one aircraft's autopilot: it flies no scenario")
    namespaces = vehicle_namespaces(max(len(scenarios), 1), namespace)
    common = ["--params-file", str(params)] if params else []
    vehicles = [vehicle] if mavlink else scenario_vehicles(scenarios)
    sensors = [LINK_SENSORS] if mavlink else scenario_sensors(scenarios)
    plan = []
    for index in reversed(range(len(namespaces))):
        namespace = namespaces[index]
        for executable in VEHICLE_NODES:
            if mavlink and executable == SIMULATOR:
                executable = LISTENER
            args = [*common, *node_ros_args(executable, namespace, index == 0, calibration,
                                            vehicles[index])]
            if executable == SIMULATOR and scenarios:
                args += ["-p", f"scenario:={scenarios[index]}"]
            args += sensor_ros_args(executable, *sensors[index])
            if executable == LISTENER:
                args += ["-p", f"connection:={mavlink}", "-p", "publish_clock:=true"]
            key = node_key(namespace if len(namespaces) > 1 else "", executable)
            plan.append(PlannedNode(key, PACKAGES[executable], executable, args))
    if foxglove:
        only = namespaces[0] if len(namespaces) == 1 else ""
        plan.append(PlannedNode("foxglove_node", PACKAGES["foxglove_node"], "foxglove_node",
                                [*common, *node_ros_args("foxglove_node", only, False)]))
    return plan


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ns", default="")
    parser.add_argument("--scenario", action="append", type=Path, default=[])
    parser.add_argument("--params", type=Path)
    parser.add_argument("--model-calibration", type=Path)
    parser.add_argument("--foxglove", action="store_true")
    parser.add_argument("--mavlink", default="", metavar="CONNECTION")
    parser.add_argument("--vehicle", default=DEFAULT_VEHICLE, choices=vehicle_names())
    parser.add_argument("--caller", default="node_graph", help="the name errors start with")
    arguments = parser.parse_args(argv)
    try:
        vehicles = ([arguments.vehicle] if arguments.mavlink
                    else scenario_vehicles(arguments.scenario))
        calibration = (model_calibration_files(arguments.model_calibration, vehicles)
                       if arguments.model_calibration else None)
        plan = live_plan(arguments.scenario, arguments.ns, arguments.params, calibration,
                         arguments.foxglove, arguments.mavlink, arguments.vehicle)
    except ValueError as error:  # ScenarioError, ModelCalibrationError
        print(f"{arguments.caller}: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    print("\n".join(node.line() for node in plan))
    return 0


if __name__ == "__main__":
    sys.exit(main())
