"""The main job: fly a scenario through the nodes, record every topic, report.

    scripts/demo.sh [SCENARIO.yaml ...] [--out DIR] [--duration S]
        [--model-calibration MODEL.yaml] [--via-mavlink ardupilot|px4]

Starts recorder_node, mhe_node, residual_node, detector_node and sim_node as processes
(the executables `ros2 run` starts) on a ROS domain of the run's own, flies the scenario
(default: the shipped default scenario) as fast as the nodes keep up, shows progress in
simulated seconds, stops every node it started, then writes metrics.json and the figures
from the recording (reporting/recorded_run.py, as scripts/report.py does) and prints the
metrics as a table. DIR (default
runs/<scenario name>/) receives bag/ (rosbag2, MCAP), metrics.json, the figures and logs/
(each node's output, <node>.log). The scenario's `estimator:` mapping overrides mhe_node's
parameters. --model-calibration (scripts/calibrate_model.py's file): residual_node's models
are the calibrated aircraft (model_calibration_file), and mhe_node takes the noise
calibration made on the same flights (noise_calibration_file) where the file names one.
--duration S flies a shorter flight: each scenario cut at S seconds (a copy of its file with
that duration, logs/[uavk/]scenario.yaml, is what sim_node flies); faults starting later
are not reached, which the start and the report say. The last line says whether each
vehicle's run met the estimator's default targets (reporting/targets.py).

--via-mavlink ardupilot (or px4) puts an autopilot's MAVLink link between the simulator and
the chain, as on an aircraft: sim_node and autopilot_node (the stack it names, ArduPlane at
the onboard page's advised rates) run under /sim, autopilot_node sends the flight on a UDP
port of loopback to mavlink_node, and residual_node, mhe_node and detector_node take
mavlink_node's streams (node_graph.played_autopilot_ros_args). One scenario only.

Several scenarios fly several aircraft in the one domain: vehicle k flies the k-th under
the namespace /uavk with nodes of its own, the first simulator publishes /clock and the
others follow it (one clock for the domain, so the scenarios must last as long); one
recorder records them all, and each vehicle is reported from it (report.py --ns /uavk) into
DIR/uavk/ (default DIR: runs/<name 1>+<name 2>...), its logs in logs/uavk/. A node of one
vehicle ending during the run (not the recorder, nor the first simulator: it gives the
clock) fails that vehicle alone: it is said, the others fly on, every vehicle is reported as
far as it came, and the run ends with status 1 naming the failed vehicle.

The demo writes only into an output folder of its own: one it creates (or finds empty) and
marks with the file .uav-demo-run. A run into a marked folder replaces the bag/ and logs/ of
the earlier one; a folder that exists, is not empty and has no mark is refused, as is an
--out that is a file or cannot be written.

Exit status: 0 done, the targets met; 1 a node ended on its own during the run (its name
and exit status are printed; the recording so far is left readable) or the report failed; 2
a bad argument, scenario or output folder (one line, before any process starts); 3 done,
a target missed (the last line says which); 130 interrupted (Ctrl-C, SIGTERM).
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import yaml
from uav_aircraft.fdm import loaded_fuel_kg
from uav_aircraft.vehicles import DEFAULT_VEHICLE, load_vehicle
from uav_common.loopback import free_udp_port
from uav_common.message_fields import stamp_seconds
from uav_common.ros_domain import reserve_domain_id
from uav_common.ros_processes import (
    NO_LOG_FILE_ROS_ARGS,
    RosProcess,
    exit_status_text,
    fast_flight_ros_args,
    ros2_run_argv,
    stop_all,
)
from uav_sim.scenario import Scenario, ScenarioError, default_scenario_path, load_scenario

from uav_fault_estimator.chain import node_graph
from uav_fault_estimator.estimation.estimator_settings import sensor_overrides
from uav_fault_estimator.estimation.model_file import ModelCalibrationError
from uav_fault_estimator.nodes.mhe_node import PARAMETERS as MHE_PARAMETERS
from uav_fault_estimator.reporting import targets
from uav_fault_estimator.reporting.recorded_run import write_report
from uav_fault_estimator.reporting.report import residual_update_period_s, table

PROGRESS_EVERY_S = 30.0  # of simulated time
STARTUP_TIMEOUT_S = 60.0  # wall time for the nodes to start and find each other
STALL_TIMEOUT_S = 60.0  # wall time without simulated time going on, once flying
ESTIMATES_TIMEOUT_S = 30.0  # wall time for the last estimates after the simulator ended
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
STATE_SUBSCRIBERS = 3  # residual_node, detector_node and the recorder
PLAYED_STATE_SUBSCRIBERS = 2  # --via-mavlink: autopilot_node and the recorder
# Each node's output subscriptions before it takes its inputs: mhe_node and the recorder on
# residuals, the recorder and the demo on the estimates, the recorder on the alarms.
OUTPUT_SUBSCRIBERS = {"residual_node": 2, "mhe_node": 2, "detector_node": 1}
RECORDER = "/recorder_node"  # its status on /diagnostics counts what it has recorded
OUTPUT_MARK = ".uav-demo-run"  # in an output folder the demo made: its bag/ and logs/ are its own
REPLACED = ("bag", "logs")  # what a run replaces of an earlier one in the same folder
CUT_SCENARIO = "scenario.yaml"  # in a vehicle's logs: its scenario as --duration cut it
EXIT_TARGET_MISSED = 3


def subscribers_args(executable: str) -> list[str]:
    """A node's --ros-args to take its inputs once its output has its subscribers."""
    return ["-p", f"wait_for_subscribers:={OUTPUT_SUBSCRIBERS[executable]}"]


class OutputFolderError(Exception):
    """An output folder the demo may not or cannot write into (one line: which, what to do)."""


class NodeEndedError(Exception):
    """A node ended on its own while it should have run."""

    def __init__(self, name: str, status: int) -> None:
        super().__init__(f"{name} exited with {exit_status_text(status)}")
        self.name, self.status = name, status


class StalledError(Exception):
    """Nothing happened for too long (the message says while doing what)."""


@dataclass(frozen=True)
class DemoAircraft:
    """One aircraft of the run: its namespace ("" when it flies alone), scenario (as
    flown: cut short by --duration), mhe_node parameter file (None: the defaults), and what
    the cut left out of the scenario, in words ("" for none)."""

    namespace: str
    scenario: Scenario
    mhe_params: Path | None
    cut_note: str = ""

    def topic(self, name: str) -> str:
        """The absolute name of one of its nodes' topics."""
        return f"{self.namespace}/{name}"

    def node_name(self, executable: str) -> str:
        """How the demo names one of its nodes: `uav1/mhe_node`, or `mhe_node` alone."""
        return node_graph.node_key(self.namespace, executable)


class Progress:
    """A hidden rclpy node of the demo: simulated time (the newest estimate's stamp) and each
    vehicle's count of estimates. Not /clock: at 20 Hz of simulated time it cost the demo's
    process 1.25 s of CPU in a 9 s flight (its executor's wait set rebuilt per message), a
    core's worth the nodes could use; the estimates come 10 times less often."""

    def __init__(self, vehicles: list[DemoAircraft]) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        from uav_common.ros.qos import DIAGNOSTICS_QOS, STREAM_QOS
        from uav_fault_msgs.msg import FaultEstimate

        self._rclpy = rclpy
        self.context = rclpy.Context()
        # Ctrl-C stays Python's KeyboardInterrupt, handled by the demo; no rcl log file in
        # the run's logs/ (the node logs nothing)
        rclpy.init(args=["--ros-args", *NO_LOG_FILE_ROS_ARGS], context=self.context,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node("_demo", context=self.context,
                                      start_parameter_services=False, enable_rosout=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.time_s = 0.0
        self.estimates = {vehicle.namespace: 0 for vehicle in vehicles}
        self.recorded: dict[str, int] = {}  # the recorder's count of each topic so far
        for vehicle in vehicles:
            self.node.create_subscription(
                FaultEstimate, vehicle.topic("faults/estimate"),
                lambda message, key=vehicle.namespace: self._on_estimate(key, message),
                STREAM_QOS)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics,
                                      DIAGNOSTICS_QOS)

    def _on_estimate(self, namespace: str, message: Any) -> None:
        self.estimates[namespace] += 1
        self.time_s = max(self.time_s, stamp_seconds(message.header.stamp))

    def _on_diagnostics(self, message: Any) -> None:
        for status in message.status:
            if status.name == RECORDER:
                self.recorded = {item.key: int(item.value) for item in status.values
                                 if item.value.isdigit()}

    @property
    def received(self) -> int:
        """Estimates received, all vehicles together."""
        return sum(self.estimates.values())

    def subscriptions(self, topic: str) -> int:
        return self.node.count_subscribers(topic)

    def publishers(self, topic: str) -> int:
        return self.node.count_publishers(topic)

    def spin(self, timeout_s: float) -> None:
        """Handle what has arrived, waiting up to timeout_s for the first callback."""
        self.executor.spin_once(timeout_sec=timeout_s)
        for _ in range(1000):  # a burst of estimates: take them all now
            if not self._spin_ready():
                break

    def _spin_ready(self) -> bool:
        before = (self.time_s, self.received)
        self.executor.spin_once(timeout_sec=0.0)
        return (self.time_s, self.received) != before

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self._rclpy.try_shutdown(context=self.context)


class Demo:
    """One run: the node processes, their watch, and their stop."""

    def __init__(self, vehicles: list[DemoAircraft], out: Path,
                 calibration: node_graph.ModelCalibrationFiles | None = None,
                 via_mavlink: str = "") -> None:
        """calibration: a model calibration's files for every vehicle (None: none);
        via_mavlink: the stack (ardupilot, px4) whose link the one vehicle's flight goes
        through ("": none)."""
        self.vehicles = vehicles
        self.calibration = calibration
        self.via_mavlink = via_mavlink
        self.duration_s = vehicles[0].scenario.duration_s  # of every vehicle: one clock
        self.bag = out / "bag"
        self.logs = out / "logs"
        self.nodes: dict[str, RosProcess] = {}  # by DemoAircraft.node_name, in start order
        # A vehicle whose node ended during the run: namespace -> (node, exit status). The
        # other vehicles fly on; the run then ends with status 1 naming it.
        self.failed: dict[str, tuple[str, int]] = {}
        self.progress: Progress | None = None
        self.next_report_s = PROGRESS_EVERY_S
        # per vehicle, one estimate per residual: residual_node runs with its defaults here
        self.expected = round(self.duration_s / residual_update_period_s())

    def start(self, vehicle: DemoAircraft | None, executable: str,
              ros_args: list[str]) -> RosProcess:
        """Start a node, of a vehicle or of the run (None), wired as node_graph says (its
        namespace, the model calibration, /clock), with the demo's own ros_args."""
        name = vehicle.node_name(executable) if vehicle else executable
        wiring = node_graph.node_ros_args(
            executable, vehicle.namespace if vehicle else "",
            vehicle is self.vehicles[0] and executable == node_graph.SIMULATOR,
            self.calibration, vehicle.scenario.vehicle if vehicle else DEFAULT_VEHICLE)
        process = RosProcess(ros2_run_argv(node_graph.PACKAGES[executable], executable,
                                           [*ros_args, *wiring]),
                             self.logs / f"{name}.log")
        self.nodes[name] = process
        return process

    def watch(self, until: Callable[[], bool], timeout_s: float,
              finished: tuple[str, ...] = ()) -> bool:
        """Spin the demo's node and print progress until until() is true (True), or until
        timeout_s of wall time pass without simulated time going on or an estimate coming
        (False). NodeEndedError when a node ends, unless it is one of `finished` and ended
        with status 0."""
        progress = self.progress
        assert progress is not None
        last_seen, last_change = (progress.time_s, progress.received), time.monotonic()
        while not until():
            progress.spin(0.05)
            self.report_progress()
            for name, process in self.nodes.items():
                status = process.process.poll()
                if status is not None and not (name in finished and status == 0):
                    self.node_ended(name, status)
            if (progress.time_s, progress.received) != last_seen:
                last_seen, last_change = (progress.time_s, progress.received), time.monotonic()
            elif time.monotonic() - last_change > timeout_s:
                return False
        return True

    def node_ended(self, name: str, status: int) -> None:
        """A node ended during the run: with several vehicles, its vehicle is marked failed
        (said once) and the others fly on, unless it is the recorder or the simulator that
        gives the clock, or no vehicle is left; else NodeEndedError."""
        vehicle = next((v for v in self.vehicles if v.namespace
                        and name.startswith(v.namespace.strip("/") + "/")), None)
        if vehicle is not None and vehicle.namespace in self.failed:
            return
        clock = self.vehicles[0].node_name("sim_node")
        if vehicle is None or name == clock or len(self.failed) + 1 == len(self.vehicles):
            raise NodeEndedError(name, status)
        self.failed[vehicle.namespace] = (name, status)
        print(f"demo: {name} exited with {exit_status_text(status)} during the run (log: "
              f"{self.logs / (name + '.log')}); {vehicle.namespace} is reported as far as it "
              "came, the other vehicles fly on", file=sys.stderr, flush=True)

    def flying(self) -> list[DemoAircraft]:
        """The vehicles not failed."""
        return [v for v in self.vehicles if v.namespace not in self.failed]

    def report_progress(self, final: bool = False) -> None:
        progress = self.progress
        assert progress is not None
        if final or self.next_report_s <= progress.time_s < self.duration_s:
            each = "" if len(self.vehicles) == 1 else " (" + ", ".join(
                f"{vehicle.namespace}: {progress.estimates[vehicle.namespace]}"
                for vehicle in self.vehicles) + ")"
            print(f"  t = {progress.time_s:.0f} / {self.duration_s:g} s, "
                  f"{progress.received} estimates{each}", flush=True)
            while self.next_report_s <= progress.time_s:
                self.next_report_s += PROGRESS_EVERY_S

    def fly(self) -> dict[str, int]:
        """Start the nodes, fly, wait for the estimates: how many estimates of each vehicle
        (by namespace) the demo's node received. The nodes still run afterwards, whatever
        happened: stop() them. NodeEndedError when a node ends on its own, StalledError when
        nothing happens for too long."""
        self.progress = progress = Progress(self.vehicles)
        self.start(None, "recorder_node", ["-p", f"output_dir:={self.bag}"])
        if not self.watch(self.bag.exists, STARTUP_TIMEOUT_S):
            raise StalledError(
                f"recorder_node did not create {self.bag} in {STARTUP_TIMEOUT_S:g} s")
        for vehicle in self.vehicles:
            # each node takes its inputs once its output has every subscriber (OUTPUT_
            # SUBSCRIBERS), and each simulator starts once they take its state: then
            # nothing the nodes publish can be missed
            self.start(vehicle, "mhe_node",
                       (["--params-file", str(vehicle.mhe_params)] if vehicle.mhe_params else [])
                       + subscribers_args("mhe_node"))
            self.start(vehicle, "residual_node", subscribers_args("residual_node") + (
                node_graph.link_residual_ros_args(self.via_mavlink) if self.via_mavlink else []))
            self.start(vehicle, "detector_node", subscribers_args("detector_node"))
        outputs = {"residuals": "residual_node", "faults/estimate": "mhe_node",
                   "faults/alarm": "detector_node"}
        if not self.watch(lambda: all(  # as the demo sees the graph: to say so if not
                progress.subscriptions(vehicle.topic(topic)) >= OUTPUT_SUBSCRIBERS[node]
                for vehicle in self.vehicles for topic, node in outputs.items()),
                STARTUP_TIMEOUT_S):
            raise StalledError(f"the nodes did not find each other in {STARTUP_TIMEOUT_S:g} s")
        played = self.start_link() if self.via_mavlink else []
        started = time.monotonic()
        # the followers first: the first vehicle's simulator starts the clock
        state_subscribers = PLAYED_STATE_SUBSCRIBERS if played else STATE_SUBSCRIBERS
        sims = [self.start(vehicle, "sim_node",
                           fast_flight_ros_args(vehicle.scenario.path, state_subscribers)
                           + played)
                for vehicle in reversed(self.vehicles)]
        simulators = tuple(vehicle.node_name("sim_node") for vehicle in self.vehicles)
        print(f"flying {self.duration_s:g} s of simulated time as fast as the nodes keep up",
              flush=True)
        if not self.watch(lambda: not any(sim.running() for sim in sims), STALL_TIMEOUT_S,
                          finished=simulators):
            raise StalledError(f"simulated time stood still for {STALL_TIMEOUT_S:g} s")
        # the last estimates may still be on their way when the simulators end
        if not self.watch(lambda: min(progress.estimates[v.namespace] for v in self.flying())
                          >= self.expected, ESTIMATES_TIMEOUT_S, finished=simulators):
            print(f"demo: {progress.received} of {self.expected * len(self.vehicles)} "
                  f"estimates arrived within {ESTIMATES_TIMEOUT_S:g} s of the flight's end",
                  file=sys.stderr)
        # the recorder has them too (it says its counts on /diagnostics once a second)
        if not self.watch(lambda: all(progress.recorded.get(v.topic("faults/estimate"), 0)
                                      >= progress.estimates[v.namespace]
                                      for v in self.flying()),
                          ESTIMATES_TIMEOUT_S, finished=simulators):
            print(f"demo: recorder_node did not say within {ESTIMATES_TIMEOUT_S:g} s that it "
                  "had every estimate: the recording may lack the last ones", file=sys.stderr)
        self.report_progress(final=True)
        print(f"flown in {time.monotonic() - started:.1f} s of wall time", flush=True)
        return dict(progress.estimates)

    def start_link(self) -> list[str]:
        """--via-mavlink: start the one vehicle's mavlink_node and, once the chain listens to
        it, the autopilot_node that plays its autopilot; sim_node's arguments that put it
        beside that autopilot."""
        vehicle, progress = self.vehicles[0], self.progress
        assert progress is not None
        scenario = vehicle.scenario
        port = free_udp_port()
        fuel_kg = loaded_fuel_kg(load_vehicle(scenario.vehicle), scenario.aircraft)
        self.start(vehicle, node_graph.LISTENER, node_graph.played_autopilot_ros_args(
            node_graph.LISTENER, self.via_mavlink, port, fuel_kg, scenario.vehicle))
        if not self.watch(lambda: progress.publishers(vehicle.topic("state")) >= 1
                          and progress.subscriptions(vehicle.topic("state"))
                          >= STATE_SUBSCRIBERS, STARTUP_TIMEOUT_S):
            raise StalledError(f"mavlink_node and the nodes did not find each other in "
                               f"{STARTUP_TIMEOUT_S:g} s")
        self.start(vehicle, node_graph.AUTOPILOT, node_graph.played_autopilot_ros_args(
            node_graph.AUTOPILOT, self.via_mavlink, port, fuel_kg, scenario.vehicle))
        return node_graph.played_autopilot_ros_args(node_graph.SIMULATOR, self.via_mavlink,
                                                    port, fuel_kg, scenario.vehicle)

    def stop(self) -> list[str]:
        """Stop the demo's node and every node process still running (SIGINT to each group
        at once, SIGKILL to what remains after 10 s); the nodes that ended badly then (not
        those that ended by the SIGINT itself: a process stopped before its handler was
        installed)."""
        if self.progress is not None:
            self.progress.close()
            self.progress = None
        running = {name: node for name, node in self.nodes.items() if node.running()}
        statuses = stop_all(list(running.values()))
        return [f"{name} exited with {exit_status_text(status)} when stopped"
                for name, status in zip(running, statuses, strict=True)
                if status not in (0, -signal.SIGINT)]


def prepare_output(out: Path, *scenario_paths: Path) -> None:
    """Make out the run's output folder: create it and mark it (OUTPUT_MARK), or take a
    marked one and remove the earlier run's bag/ and logs/. OutputFolderError, with nothing
    removed, for a file, a folder that is not empty and not marked, a bag/ or logs/ that is
    not a plain folder, the scenario inside what would be removed, or a place that cannot be
    written."""
    what_to_do = "choose another --out (a new or empty folder)"
    if out.exists() and not out.is_dir():
        raise OutputFolderError(f"output folder {out} is a file, not a folder; {what_to_do}")
    mark = out / OUTPUT_MARK
    try:
        marked = mark.is_file() and not mark.is_symlink()
        if out.is_dir() and not marked and any(out.iterdir()):
            raise OutputFolderError(
                f"output folder {out} is not empty and not one demo.sh made (no {OUTPUT_MARK} "
                f"in it): nothing there is removed or overwritten; {what_to_do}")
        previous = [out / name for name in REPLACED if os.path.lexists(out / name)]
        for folder in previous:
            if folder.is_symlink() or not folder.is_dir():
                raise OutputFolderError(
                    f"{folder} is not a folder demo.sh made (a file or a link); move it away "
                    f"or {what_to_do}")
            inside = [path for path in scenario_paths if path.is_relative_to(folder.resolve())]
            if inside:
                raise OutputFolderError(
                    f"the scenario {inside[0]} is inside {folder}, which the run replaces; "
                    "move the scenario elsewhere")
        out.mkdir(parents=True, exist_ok=True)
        mark.write_text("An output folder of scripts/demo.sh: a run into it replaces bag/ "
                        "and logs/.\n")
        for folder in previous:  # of an earlier run into the same folder
            shutil.rmtree(folder)
        (out / "logs").mkdir()
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise OutputFolderError(
            f"cannot write into the output folder {out} ({reason}); {what_to_do}") from None


def check_duration(duration_s: float, scenarios: list[Scenario]) -> None:
    """ScenarioError (one line) unless --duration's duration_s [s] cuts every scenario
    short: a positive number of seconds, none longer than a scenario."""
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ScenarioError(f"--duration {duration_s:g}: a flight's duration is a positive "
                            "number of seconds")
    for scenario in scenarios:
        if duration_s > scenario.duration_s:
            raise ScenarioError(
                f"--duration {duration_s:g} s is longer than the scenario '{scenario.name}' "
                f"({scenario.duration_s:g} s): it cuts a scenario short")


def cut_scenario(scenario: Scenario, duration_s: float, folder: Path) -> Scenario:
    """The scenario flown only to duration_s [s]: a copy of its file with that duration, in
    folder (the vehicle's logs), the file sim_node flies."""
    data = yaml.safe_load(scenario.path.read_text())
    data["duration_s"] = duration_s
    path = folder / CUT_SCENARIO
    path.write_text(f"# {scenario.path}, cut at {duration_s:g} s by demo.sh --duration\n"
                    + yaml.safe_dump(data, sort_keys=False))
    return replace(scenario, duration_s=duration_s, path=path)


def cut_note(scenario: Scenario, duration_s: float) -> str:
    """What cutting the scenario at duration_s [s] leaves out, in words: the faults that
    start later are not reached."""
    note = (f"scenario '{scenario.name}' cut at {duration_s:g} s of its "
            f"{scenario.duration_s:g} s (--duration)")
    later = [fault for fault in scenario.faults if fault.start_s > duration_s]
    if later:
        note += ": not reached, starting later: " + ", ".join(
            f"{fault.name} at {fault.start_s:g} s" for fault in later)
    return note


def targets_line(verdicts: list[tuple[str, targets.Verdict | None]]) -> str:
    """Whether each vehicle's run (by namespace; "" alone) met the targets, in one line;
    None: its report failed."""
    said = [(f"{namespace} " if namespace else "")
            + (verdict.text() if verdict else "no report to judge")
            for namespace, verdict in verdicts]
    return f"targets ({targets.TARGETS_PAGE}): " + "; ".join(said)


def check_one_clock(scenarios: list[Scenario]) -> None:
    """ScenarioError unless the scenarios last as long: the vehicles fly on one clock."""
    durations = sorted({scenario.duration_s for scenario in scenarios})
    if len(durations) > 1:
        raise ScenarioError(
            "the scenarios last " + " and ".join(f"{d:g} s" for d in durations) + ": the "
            "vehicles fly on one clock, so their scenarios must last as long")


def mhe_overrides(scenario: Scenario, through_link: bool = False) -> dict[str, Any]:
    """What the scenario's aircraft calls for of mhe_node's parameters beyond their
    defaults: what its sensors do (estimator_settings.sensor_overrides; through_link: the
    sensors a MAVLink link carries, a pitot without vanes), then its `estimator:` overrides;
    ScenarioError for a parameter mhe_node does not have. Integers given for real
    parameters become reals (ROS parameters do not convert)."""
    air_data, vanes = node_graph.LINK_SENSORS if through_link else (
        scenario.sensors.air_data, scenario.sensors.vanes)
    defaults = {name: spec.default for name, spec in MHE_PARAMETERS.items()}
    overrides: dict[str, Any] = sensor_overrides(air_data, vanes)
    for name, value in scenario.estimator.items():
        if name not in defaults:
            raise ScenarioError(
                f"scenario {scenario.path}: unknown key 'estimator.{name}' (mhe_node's "
                f"parameters: {', '.join(sorted(defaults))})")
        overrides[name] = _like(defaults[name], value)
    return overrides


def write_parameter_file(path: Path, parameters: dict[str, Any]) -> Path | None:
    """A --params-file giving every node these parameters; None when there are none."""
    if not parameters:
        return None
    path.write_text(yaml.safe_dump({"/**": {"ros__parameters": parameters}}))
    return path


def _like(default: Any, value: Any) -> Any:
    """value, with integers made reals where the default is real."""
    if isinstance(default, list) and isinstance(value, list) and default:
        return [_like(default[0], item) for item in value]
    if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def main(runs_dir: Path) -> int:
    """demo.sh's command line; runs_dir: where the default output folders go."""
    parser = argparse.ArgumentParser(
        prog="demo.sh", description=__doc__.splitlines()[0],
        epilog="Exit status: 0 done and the targets met, 1 a node or the report failed, 2 "
        "bad arguments or scenario, 3 done and a target missed, 130 interrupted.")
    parser.add_argument("scenarios", nargs="*", type=Path, metavar="scenario",
                        help="scenario YAML (default: the shipped default scenario); several: "
                        "one aircraft each, under /uav1, /uav2, ...")
    parser.add_argument("--out", type=Path,
                        help="output directory (default: runs/<scenario name>[+<name>...]/)")
    parser.add_argument("--duration", type=float, metavar="S",
                        help="fly only the first S seconds: every scenario cut at S (faults "
                        "starting later are not reached)")
    parser.add_argument("--model-calibration", type=Path, metavar="MODEL.yaml",
                        help="the models' calibration (scripts/calibrate_model.py) for every "
                        "vehicle")
    parser.add_argument("--via-mavlink", choices=tuple(node_graph.LINK_REAL_TIME_FACTOR),
                        default="",
                        help="the flight through an autopilot's MAVLink link: the simulator "
                        "as this stack, the chain on mavlink_node (one scenario)")
    arguments = parser.parse_args()
    wall_started = time.monotonic()
    # Ctrl-C and SIGTERM: KeyboardInterrupt, whatever the caller left (an ignored SIGINT
    # would also be inherited by the nodes, which then could not be stopped cleanly)
    for sig in STOP_SIGNALS:
        signal.signal(sig, signal.default_int_handler)

    try:
        scenarios = [replace(scenario, path=scenario.path.resolve()) for scenario in
                     map(load_scenario, arguments.scenarios or [default_scenario_path()])]
        overrides = [mhe_overrides(scenario, bool(arguments.via_mavlink))
                     for scenario in scenarios]
        if arguments.via_mavlink and len(scenarios) > 1:
            raise ScenarioError("--via-mavlink flies one scenario through one link")
        if arguments.duration is None:
            check_one_clock(scenarios)
        else:  # every one cut to the same length
            check_duration(arguments.duration, scenarios)
        model_calibration = arguments.model_calibration and arguments.model_calibration.resolve()
        # refused here, before any process
        calibration = (node_graph.model_calibration_files(
            model_calibration, [scenario.vehicle for scenario in scenarios])
            if model_calibration else None)
    except (ScenarioError, ModelCalibrationError) as error:
        print(f"demo: {' '.join(str(error).split())}", file=sys.stderr)  # one line
        return 2
    out = (arguments.out or runs_dir / "+".join(
        scenario.name for scenario in scenarios)).resolve()
    namespaces = node_graph.vehicle_namespaces(len(scenarios))
    try:
        prepare_output(out, *(scenario.path for scenario in scenarios))
        vehicles = []
        for namespace, scenario, override in zip(namespaces, scenarios, overrides, strict=True):
            logs = out / "logs" / namespace.strip("/")
            logs.mkdir(exist_ok=True)
            cut = arguments.duration is not None
            vehicles.append(DemoAircraft(
                namespace, cut_scenario(scenario, arguments.duration, logs) if cut else scenario,
                write_parameter_file(logs / "mhe_node.params.yaml", override),
                cut_note(scenario, arguments.duration) if cut else ""))
    except OutputFolderError as error:
        print(f"demo: {error}", file=sys.stderr)  # one line
        return 2
    except OSError as error:
        print(f"demo: cannot write into the output folder {out} "
              f"({error.strerror or type(error).__name__})", file=sys.stderr)
        return 2

    domain_id, lock = reserve_domain_id()
    os.environ.update(ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                      ROS_LOG_DIR=str(out / "logs"))
    for vehicle, scenario in zip(vehicles, scenarios, strict=True):
        print(f"demo: {vehicle.namespace + ' flies ' if vehicle.namespace else ''}scenario "
              f"'{scenario.name}' ({scenario.path})", flush=True)
        if vehicle.cut_note:
            print(f"demo: {vehicle.cut_note}", flush=True)
    print(f"demo: ROS domain {domain_id}, output in {out}", flush=True)
    demo = Demo(vehicles, out, calibration, arguments.via_mavlink)
    aborted: tuple[int, bool] | None = None  # a run cut short: exit status, show the bag
    try:
        received = demo.fly()
    except NodeEndedError as ended:
        print(f"demo: {ended.name} exited with {exit_status_text(ended.status)} during the "
              f"run (log: {demo.logs / (ended.name + '.log')}); stopping the other nodes",
              file=sys.stderr, flush=True)
        aborted = (1, True)
    except StalledError as stalled:
        print(f"demo: {stalled}; stopping the nodes (logs: {demo.logs})", file=sys.stderr,
              flush=True)
        aborted = (1, False)
    except KeyboardInterrupt:
        print("\ndemo: interrupted: stopping the nodes", file=sys.stderr, flush=True)
        aborted = (130, True)
    finally:
        # the one place the nodes are stopped, however the run ended
        failed = _stop(demo)
        lock.close()
    if aborted is not None:
        status, show_recording = aborted
        if show_recording:  # said after the stop: the recording is complete by then
            _recorded(demo)
        return status

    missing = False
    verdicts: list[tuple[str, targets.Verdict | None]] = []
    for vehicle in vehicles:
        report_out = out / vehicle.namespace.strip("/")
        try:
            metrics, figures = write_report(demo.bag, report_out, vehicle.scenario.name,
                                            vehicle.namespace)
        except (ValueError, OSError) as error:  # a RecordingError is a ValueError
            print(f"demo: no report{' of ' + vehicle.namespace if vehicle.namespace else ''}: "
                  f"{error}", file=sys.stderr)
            missing = True
            verdicts.append((vehicle.namespace, None))
            continue
        except KeyboardInterrupt:
            print("\ndemo: interrupted while writing the report", file=sys.stderr)
            return 130
        print()
        if vehicle.namespace:
            print(f"{vehicle.namespace}:")
        print(table(metrics))
        if vehicle.cut_note:
            print(vehicle.cut_note)
        late = targets.reached_late(vehicle.scenario.duration_s, vehicle.scenario.faults_pct)
        verdicts.append((vehicle.namespace, targets.judge(
            metrics["faults"], metrics["false_alarms"], late)))
        print(f"written to {report_out}: " + ("" if vehicle.namespace else "bag/, logs/, ")
              + "metrics.json, " + ", ".join(path.name for path in figures))
        if received[vehicle.namespace] < demo.expected:
            missing = True
            print(f"demo: only {received[vehicle.namespace]} of {demo.expected} estimates "
                  f"of {vehicle.node_name('mhe_node')} arrived", file=sys.stderr)
    if len(vehicles) > 1:
        print(f"written to {out}: bag/ (every vehicle), logs/")
    for namespace, (name, status) in demo.failed.items():
        print(f"demo: {namespace} failed: {name} exited with {exit_status_text(status)} "
              "during the run", file=sys.stderr)
    print(f"demo: done in {time.monotonic() - wall_started:.1f} s of wall time; "
          + targets_line(verdicts))
    if failed or missing or demo.failed:
        return 1
    return EXIT_TARGET_MISSED if any(v and v.missed for _, v in verdicts) else 0


def _stop(demo: Demo) -> list[str]:
    """demo.stop(), not to be interrupted by a second Ctrl-C; says what ended badly, and
    returns those lines."""
    previous = {sig: signal.signal(sig, signal.SIG_IGN) for sig in STOP_SIGNALS}
    try:
        failed = demo.stop()
        for line in failed:
            print(f"demo: {line}", file=sys.stderr)
        return failed
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _recorded(demo: Demo) -> None:
    if demo.bag.exists():
        print(f"demo: what was recorded is in {demo.bag}", file=sys.stderr)

