"""Play a flight log to a MAVLink link as its autopilot sent it, at real time or faster.

    ros2 run uav_mavlink log_streamer LOG [--connection udpout:127.0.0.1:14550] [--speed N]
    python -m uav_mavlink.log_streamer LOG [--connection ...] [--speed N] [--system ID]

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

Exit status: 0 played to its end; 2 bad input, one line (a log that cannot be read, a
connection beyond loopback, a speed not above 0, a connection that cannot be opened).
"""

from __future__ import annotations

import argparse
import ipaddress
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

os.environ.setdefault("MAVLINK20", "1")  # pymavlink reads it at its import

from pymavlink import mavutil

from uav_mavlink.link import DIALECT
from uav_mavlink.log_messages import TimedMessage, log_messages

PROGRAM = "log_streamer"
DEFAULT_CONNECTION = "udpout:127.0.0.1:14550"
AUTOPILOT_COMPONENT = mavutil.mavlink.MAV_COMP_ID_AUTOPILOT1  # 1
_NETWORK_PREFIXES = ("udpout:", "udpin:", "udp:", "udpbcast:", "tcp:", "tcpin:", "mcast:",
                     "ws:", "wss:", "wsserver:")


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
    return arguments


def main(argv: list[str] | None = None) -> int:
    arguments = parser().parse_args(argv)
    if not arguments.speed > 0:
        return _bad(f"--speed {arguments.speed:g}: must be above 0")
    if not arguments.beyond_loopback and not on_loopback(arguments.connection):
        return _bad(f"--connection {arguments.connection}: not on this machine's loopback; "
                    "give --beyond-loopback to send a recorded flight there")
    try:
        messages = log_messages(arguments.log)
    except ValueError as error:
        return _bad(str(error))
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


def _bad(line: str) -> int:
    print(f"{PROGRAM}: {line}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
