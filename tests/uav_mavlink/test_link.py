"""The link is read-only to the aircraft: its heartbeat and the allowed reads and notes leave,
a command, a mode change, a parameter set or a stream request raises before any byte does;
and only a flight controller's heartbeat counts as the autopilot's."""

from __future__ import annotations

import socket

import pytest
from pymavlink import mavutil
from uav_mavlink.link import (
    ReadOnlyLinkError,
    is_autopilot_heartbeat,
    open_link,
    send_heartbeat,
)


@pytest.fixture
def receiver():
    """A UDP socket on loopback standing for the autopilot; what the link sends arrives here."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.bind(("127.0.0.1", 0))
        sink.settimeout(2.0)
        yield sink


def received_types(sink: socket.socket) -> list[str]:
    parser = mavutil.mavlink.MAVLink(None)
    sink.settimeout(0.2)
    types = []
    try:
        while True:
            for message in parser.parse_buffer(sink.recv(4096)) or []:
                types.append(message.get_type())
    except TimeoutError:
        return types


@pytest.mark.timeout(20)
def test_only_the_allowed_types_leave_the_link(receiver):
    link = open_link(f"udpout:127.0.0.1:{receiver.getsockname()[1]}", source_system=1)
    mavlink = mavutil.mavlink
    send_heartbeat(link)
    link.mav.param_request_read_send(1, 1, b"PTCH_TRIM_DEG", -1)
    link.mav.statustext_send(mavlink.MAV_SEVERITY_WARNING, b"DIAG: elevator")
    link.mav.named_value_float_send(0, b"diag_elev", 0.8)
    refused = {
        "COMMAND_LONG": lambda: link.mav.command_long_send(
            1, 1, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0, 30, 20000, 0, 0, 0, 0, 0),
        "SET_MODE": lambda: link.mav.set_mode_send(1, 1, 11),
        "PARAM_SET": lambda: link.mav.param_set_send(1, 1, b"SR1_EXTRA1", 20.0, 9),
        "REQUEST_DATA_STREAM": lambda: link.mav.request_data_stream_send(1, 1, 0, 20, 1),
    }
    for kind, send in refused.items():
        with pytest.raises(ReadOnlyLinkError, match=kind):
            send()
    assert received_types(receiver) == ["HEARTBEAT", "PARAM_REQUEST_READ", "STATUSTEXT",
                                        "NAMED_VALUE_FLOAT"]


@pytest.mark.timeout(10)
def test_a_flight_controllers_heartbeat_is_the_autopilots_and_a_ground_stations_is_not():
    mavlink = mavutil.mavlink
    heartbeat = mavlink.MAVLink_heartbeat_message
    assert is_autopilot_heartbeat(heartbeat(mavlink.MAV_TYPE_FIXED_WING,
                                            mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 10, 4, 3))
    assert is_autopilot_heartbeat(heartbeat(mavlink.MAV_TYPE_FIXED_WING,
                                            mavlink.MAV_AUTOPILOT_PX4, 0, 0, 4, 3))
    assert not is_autopilot_heartbeat(heartbeat(mavlink.MAV_TYPE_GCS,
                                                mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 4, 3))
    assert not is_autopilot_heartbeat(heartbeat(mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
                                                mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 4, 3))
