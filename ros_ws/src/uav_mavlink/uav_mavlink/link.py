"""The MAVLink link to an autopilot, read-only to the aircraft.

`open_link` opens a connection as pymavlink takes it (`udpin:127.0.0.1:14550`,
`/dev/ttyACM0,921600`, `tcp:HOST:PORT`) on MAVLink 2 with the ardupilotmega dialect (a
superset of common), as an onboard computer (component 191), bad packets reported as BAD_DATA
rather than raised. Everything the link sends goes through its MAVLink instance's `send`,
which `open_link` guards: only the message types in SENT_TYPES leave, anything else raises
ReadOnlyLinkError, so no command, mode change, parameter set or stream request can reach the
aircraft from this package.
"""

from __future__ import annotations

import os
import socket
from typing import Any

# pymavlink reads MAVLINK20 when mavutil is imported: set before that import.
os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil

DIALECT = "ardupilotmega"
ONBOARD_COMPONENT = mavutil.mavlink.MAV_COMP_ID_ONBOARD_COMPUTER  # 191
# What the link may send: its own heartbeat, parameter reads, and messages for the ground
# station's screen. Nothing that commands the aircraft.
SENT_TYPES = frozenset({"HEARTBEAT", "PARAM_REQUEST_READ", "STATUSTEXT", "NAMED_VALUE_FLOAT"})
# A UDP link has no flow control: while the node is held up, datagrams beyond its socket's
# receive buffer are lost. The kernel's usual default (208 KiB, counted per datagram with
# its overhead) holds a few hundred of MAVLink's small datagrams, under a second of PX4's
# onboard streams; this asks for many seconds (the kernel caps it at net.core.rmem_max).
RECEIVE_BUFFER_BYTES = 4 * 1024 * 1024
AUTOPILOTS = {mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA: "ArduPilot",
              mavutil.mavlink.MAV_AUTOPILOT_PX4: "PX4"}


class ReadOnlyLinkError(RuntimeError):
    """A message of a type outside SENT_TYPES was about to be sent."""


def open_link(connection: str, source_system: int) -> Any:
    """The pymavlink connection (mavutil.mavfile) for `connection`, sending as
    (source_system, ONBOARD_COMPONENT) and only SENT_TYPES, a UDP link with a receive buffer
    of RECEIVE_BUFFER_BYTES. OSError or ValueError when it cannot be opened."""
    link = mavutil.mavlink_connection(connection, source_system=source_system,
                                      source_component=ONBOARD_COMPONENT, dialect=DIALECT,
                                      robust_parsing=True, autoreconnect=False)
    if isinstance(link, mavutil.mavudp):
        link.port.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
    send = link.mav.send

    def guarded_send(message: Any, *args: Any, **kwargs: Any) -> None:
        if message.get_type() not in SENT_TYPES:
            raise ReadOnlyLinkError(f"{message.get_type()} is not sent: the link is read-only "
                                    f"to the aircraft (it sends {', '.join(sorted(SENT_TYPES))})")
        send(message, *args, **kwargs)

    link.mav.send = guarded_send
    return link


def send_heartbeat(link: Any) -> None:
    """The onboard computer's heartbeat: not an autopilot, active."""
    mavlink = mavutil.mavlink
    link.mav.heartbeat_send(mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavlink.MAV_AUTOPILOT_INVALID,
                            0, 0, mavlink.MAV_STATE_ACTIVE)


def is_autopilot_heartbeat(message: Any) -> bool:
    """A heartbeat from a flight controller of a known stack (not a ground station, an
    onboard computer or another peripheral)."""
    return (message.get_type() == "HEARTBEAT" and message.autopilot in AUTOPILOTS
            and message.type not in (mavutil.mavlink.MAV_TYPE_GCS,
                                     mavutil.mavlink.MAV_TYPE_ONBOARD_CONTROLLER))
