"""Play a flight log to a MAVLink link as its autopilot sent it, at real time or faster.

    ros2 run uav_mavlink log_streamer LOG [--connection udpout:127.0.0.1:14550] [--speed N]
    python -m uav_mavlink.log_streamer LOG [--connection ...] [--speed N] [--system ID]
    ros2 run uav_mavlink log_streamer LOG --write-params FILE [--airframe AIRFRAME.yaml]
        [--detector-calibration CAL.yaml]

LOG is an ALFA flight folder (per-topic CSV files) or a PX4 .ulg; its messages are
log_messages' (ATTITUDE, SERVO_OUTPUT_RAW, VFR_HUD, ... and a heartbeat each second), sent
as system --system, component 1 (the autopilot), each when its boot time comes, --speed
times faster than the flight flew (1: real time). mavlink_node listening on the link's other
end publishes the flight as the project's streams:

    ros2 run uav_mavlink mavlink_node --ros-args -p vehicle:=carbon_z \\
        -p airframe:=ros_ws/src/uav_aircraft/aircraft/carbon_z/airframes/carbon_z_alfa.yaml

The connection is pymavlink's (udpout:HOST:PORT, tcp:HOST:PORT, ...). Only a host on this
machine (127.0.0.0/8, ::1, localhost) is taken unless --beyond-loopback is given: a log
played to a real link would pose as an aircraft to whatever listens there.

The log's rates: the link interpolates a stream over gaps of at most its maximum age
(mavlink_node's `*_max_age_s`), which suits an autopilot at the onboard page's advised
rates; a log streamed slower (ALFA's ATTITUDE, from MAVROS's imu/data, at about 2.5 Hz)
needs them raised, or its samples go missing. The first line printed says which parameters this log
needs (link_max_ages_s: GAP_FACTOR times each message's median interval, as screen_logs.py's
resampling bridges a log's gaps, rounded up to 0.1 s; those above mavlink_node's defaults),
or that the defaults hold. --write-params FILE writes them as a ROS parameter file instead
of playing (for scripts/bringup.sh --params FILE, or the nodes' --params-file), with
--airframe the servo map mavlink_node reads the log's outputs with and the airframe
detector_node holds its calibration to, and with --detector-calibration that calibration
(checked against the airframe): what the chain needs to run the log, in one file.

Exit status: 0 played to its end, or the parameter file written; 2 bad input, one line (a
log that cannot be read, a connection beyond loopback, a speed not above 0, a connection
that cannot be opened, an airframe or calibration that cannot be used, a parameter file
that cannot be written).
"""

from __future__ import annotations

import argparse
import ipaddress
import itertools
import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml
from uav_aircraft.airframe import load_airframe
from uav_common.interpolation import GAP_FACTOR
from uav_fault_estimator.detection.calibration_file import read_calibration

os.environ.setdefault("MAVLINK20", "1")  # pymavlink reads it at its import

from pymavlink import mavutil

from uav_mavlink.autopilot_messages import read_message
from uav_mavlink.link import DIALECT
from uav_mavlink.log_messages import TimedMessage, log_messages
from uav_mavlink.sample_assembly import MAX_AGE_PARAMETERS

PROGRAM = "log_streamer"
DEFAULT_CONNECTION = "udpout:127.0.0.1:14550"
AUTOPILOT_COMPONENT = mavutil.mavlink.MAV_COMP_ID_AUTOPILOT1  # 1
_NETWORK_PREFIXES = ("udpout:", "udpin:", "udp:", "udpbcast:", "tcp:", "tcpin:", "mcast:",
                     "ws:", "wss:", "wsserver:")
AGE_STEP_S = 0.1  # the advised maximum ages are rounded up to this [s]
LISTENER, DETECTOR = "mavlink_node", "detector_node"


def on_loopback(connection: str) -> bool:
    """Whether a pymavlink connection string names a network address on this machine
    (127.0.0.0/8, ::1 or localhost); False for anything else (another host, a serial port,
    a broadcast or multicast link)."""
    prefix = next((p for p in _NETWORK_PREFIXES if connection.startswith(p)), None)
    if prefix is None or prefix in ("udpbcast:", "mcast:"):
        return False
    host = connection[len(prefix):].rsplit(":", 1)[0].strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def play(messages: Sequence[TimedMessage], send: Callable[[Any], None], speed: float,
         clock: Callable[[], float] = time.monotonic,
         sleep: Callable[[float], None] = time.sleep) -> int:
    """Send each message (send(message)) when its boot time comes, speed times faster than
    the flight [wall s per boot s: 1/speed], the first at once; the number sent."""
    if not messages:
        return 0
    started_s, first_s = clock(), messages[0].boot_time_s
    for timed in messages:
        wait_s = started_s + (timed.boot_time_s - first_s) / speed - clock()
        if wait_s > 0:
            sleep(wait_s)
        send(timed.message)
    return len(messages)


def message_timings(messages: Sequence[TimedMessage]) -> dict[str, tuple[str, float]]:
    """Per MAVLink message type the link reads (autopilot_messages.read_message, each
    message read once): its stream and the median interval between consecutive messages
    [s]; a type sent once: not given."""
    times: dict[str, tuple[str, list[float]]] = {}
    for timed in messages:
        if (reading := read_message(timed.message)) is not None:
            times.setdefault(timed.message.get_type(), (reading.stream, []))[1].append(
                timed.boot_time_s)
    return {kind: (stream, statistics.median(b - a for a, b in itertools.pairwise(sent)))
            for kind, (stream, sent) in times.items() if len(sent) > 1}


def link_max_ages_s(timings: Mapping[str, tuple[str, float]]) -> dict[str, tuple[float, str]]:
    """The maximum age each of mavlink_node's *_max_age_s parameters needs for the
    messages' timings (message_timings) [s], and the message that needs it: per parameter,
    GAP_FACTOR times the longest median interval of the messages of its streams
    (MAX_AGE_PARAMETERS), rounded up to AGE_STEP_S."""
    needed: dict[str, tuple[float, str]] = {}
    for kind, (stream, interval_s) in sorted(timings.items()):
        parameter = MAX_AGE_PARAMETERS[stream]
        age_s = round(math.ceil(round(GAP_FACTOR * interval_s / AGE_STEP_S, 6)) * AGE_STEP_S, 6)
        if parameter not in needed or age_s > needed[parameter][0]:
            needed[parameter] = (age_s, kind)
    return needed


def raised_max_ages_s(needed: Mapping[str, tuple[float, str]],
                      defaults_s: Mapping[str, float]) -> dict[str, tuple[float, str]]:
    """Those of the needed maximum ages (link_max_ages_s) above mavlink_node's defaults."""
    return {parameter: (age_s, kind) for parameter, (age_s, kind) in sorted(needed.items())
            if age_s > defaults_s[parameter]}


def rates_line(raised: Mapping[str, tuple[float, str]],
               timings: Mapping[str, tuple[str, float]]) -> str:
    """One line on the log's rates: the mavlink_node parameters they need, or that its
    defaults hold."""
    if not raised:
        return "this log's rates: mavlink_node's default maximum ages hold"
    slow = ", ".join(f"{kind} {1.0 / timings[kind][1]:.1f} Hz"
                     for kind in sorted({kind for _, kind in raised.values()}))
    return (f"this log's rates ({slow}) need mavlink_node --ros-args "
            + " ".join(f"-p {parameter}:={age_s!r}" for parameter, (age_s, _) in raised.items())
            + " (or in a parameter file: --write-params FILE)")


def chain_parameters(raised: Mapping[str, tuple[float, str]], airframe: Path | None,
                     calibration: Path | None) -> dict[str, Any]:
    """A ROS parameter file's mapping: mavlink_node's raised maximum ages; given an airframe,
    mavlink_node's servo map and the airframe detector_node checks its calibration against
    (its name: the vehicle's own calibration, of its simulated airframe, is then refused at
    start instead of run on the log); given a calibration, detector_node's. ValueError (one
    line) for an airframe or calibration that cannot be used, or a calibration without its
    airframe."""
    listener: dict[str, Any] = {parameter: age_s for parameter, (age_s, _) in raised.items()}
    nodes: dict[str, Any] = {LISTENER: {"ros__parameters": listener}}
    if calibration is not None and airframe is None:
        raise ValueError("--detector-calibration needs the --airframe it was made for")
    if airframe is not None:
        listener["airframe"] = str(airframe.resolve())
        detector = {"airframe": load_airframe(airframe).name}
        if calibration is not None:
            read_calibration(str(calibration), detector["airframe"])
            detector["calibration_file"] = str(calibration.resolve())
        nodes[DETECTOR] = {"ros__parameters": detector}
    return nodes


def write_parameters(path: Path, log: Path, nodes: Mapping[str, Any], line: str) -> None:
    """The ROS parameter file at path, its first lines saying what it is for."""
    path.write_text(f"# Written by log_streamer for {log}:\n# {line}\n"
                    "# For scripts/bringup.sh --params FILE, or a node's --params-file FILE.\n"
                    + yaml.safe_dump(dict(nodes), sort_keys=False))


def listener_defaults_s() -> dict[str, float]:
    """mavlink_node's default maximum ages [s], from its parameters (their one home)."""
    from uav_mavlink.ros.mavlink_node import PARAMETERS  # rclpy: the command's alone

    return {parameter: float(PARAMETERS[parameter].default)
            for parameter in set(MAX_AGE_PARAMETERS.values())}


def parser() -> argparse.ArgumentParser:
    """The command line (the module's docstring)."""
    arguments = argparse.ArgumentParser(prog=PROGRAM, description=__doc__.splitlines()[0])
    arguments.add_argument("log", type=Path, help="an ALFA flight folder or a PX4 .ulg")
    arguments.add_argument("--connection", default=DEFAULT_CONNECTION,
                           help=f"pymavlink connection to send on (default {DEFAULT_CONNECTION})")
    arguments.add_argument("--speed", type=float, default=1.0,
                           help="times faster than the flight flew (default 1: real time)")
    arguments.add_argument("--system", type=int, default=1,
                           help="the autopilot's MAVLink system id (default 1)")
    arguments.add_argument("--beyond-loopback", action="store_true",
                           help="allow a connection to another machine or a serial port")
    arguments.add_argument("--write-params", type=Path, metavar="FILE",
                           help="write the ROS parameters the chain needs for this log "
                           "(mavlink_node's maximum ages) to FILE instead of playing it")
    arguments.add_argument("--airframe", type=Path, metavar="AIRFRAME.yaml",
                           help="with --write-params: mavlink_node's servo map of the log's "
                           "outputs, and the airframe detector_node's calibration must be of")
    arguments.add_argument("--detector-calibration", type=Path, metavar="CAL.yaml",
                           help="with --write-params: detector_node's calibration (made for "
                           "--airframe)")
    return arguments


def main(argv: list[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    if not arguments.speed > 0:
        return _bad(f"--speed {arguments.speed:g}: must be above 0")
    if not arguments.beyond_loopback and not on_loopback(arguments.connection):
        return _bad(f"--connection {arguments.connection}: not on this machine's loopback; "
                    "give --beyond-loopback to send a recorded flight there")
    if (arguments.airframe or arguments.detector_calibration) and not arguments.write_params:
        return _bad("--airframe and --detector-calibration go with --write-params FILE")
    try:
        messages = log_messages(arguments.log)
    except ValueError as error:
        return _bad(str(error))
    timings = message_timings(messages)
    raised = raised_max_ages_s(link_max_ages_s(timings), listener_defaults_s())
    line = rates_line(raised, timings)
    print(line, flush=True)
    if arguments.write_params:
        return _write_params(arguments, raised, line)
    try:
        link = mavutil.mavlink_connection(arguments.connection, source_system=arguments.system,
                                          source_component=AUTOPILOT_COMPONENT,
                                          dialect=DIALECT, autoreconnect=False)
    except (OSError, ValueError) as error:
        return _bad(f"--connection {arguments.connection}: cannot be opened ({error})")
    duration_s = messages[-1].boot_time_s - messages[0].boot_time_s if messages else 0.0
    print(f"{arguments.log}: {len(messages)} messages over {duration_s:.1f} s of flight, "
          f"to {arguments.connection} at {arguments.speed:g}x", flush=True)
    try:
        sent = play(messages, link.mav.send, arguments.speed)
    finally:
        link.close()
    print(f"sent {sent} messages", flush=True)
    return 0


def _write_params(arguments: argparse.Namespace, raised: Mapping[str, tuple[float, str]],
                  line: str) -> int:
    """--write-params: the parameter file of the raised maximum ages (and the airframe and
    calibration given) written, status 0; or one line why not, status 2."""
    try:
        nodes = chain_parameters(raised, arguments.airframe, arguments.detector_calibration)
        write_parameters(arguments.write_params, arguments.log, nodes, line)
    except ValueError as error:
        return _bad(str(error))
    except OSError as error:
        return _bad(f"--write-params {arguments.write_params}: cannot be written "
                    f"({error.strerror})")
    print(f"written: {arguments.write_params}", flush=True)
    return 0


def _bad(line: str) -> int:
    print(f"{PROGRAM}: {line}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
