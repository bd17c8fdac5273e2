"""Whether an address is this machine's own loopback, decided without the network: the
project's servers (the live view, a campaign's cluster) are open to others anywhere else.
No ROS here."""

from __future__ import annotations

import ipaddress
import socket

LOOPBACK_NAMES = ("localhost",)


def is_loopback(host: str) -> bool:
    """Whether host (an address, or a name) is this machine's loopback, without resolving
    it: loopback addresses (127.0.0.0/8, ::1) and LOOPBACK_NAMES only; any other name, and
    the wildcard 0.0.0.0 (every interface), is not."""
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def free_udp_port() -> int:
    """A UDP port of loopback no socket holds now (the system's pick: free when asked, not
    reserved)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]
