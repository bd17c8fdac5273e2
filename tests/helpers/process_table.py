"""The machine's processes as /proc shows them: to find nodes that scripts started, by their
command line and environment, to check that none outlived its script, and to see where a
process group listens."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

NODE_NAMES = ("sim_node", "residual_node", "mhe_node", "detector_node", "recorder_node",
              "foxglove_node", "log_replay_node", "standard_topics_node")
TCP_LISTEN = "0A"  # the state column of /proc/net/tcp for a listening socket


@dataclass(frozen=True)
class ProcessInfo:
    pid: int
    cmdline: str
    environ: dict[str, str]


def processes(where: Callable[[ProcessInfo], bool]) -> list[ProcessInfo]:
    """The processes (other than this one) for which where() holds; those whose /proc
    entries cannot be read (other users', ended meanwhile) are left out."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            raw = (entry / "environ").read_bytes().split(b"\0")
        except OSError:
            continue
        environ = dict(item.decode(errors="replace").partition("=")[::2] for item in raw if item)
        info = ProcessInfo(int(entry.name), cmdline.strip(), environ)
        if cmdline and where(info):
            found.append(info)
    return found


def nodes_logging_under(folder: Path) -> list[ProcessInfo]:
    """Node processes whose ROS_LOG_DIR is folder or inside it."""
    folder_text = str(folder.resolve())
    return processes(lambda info: any(name in info.cmdline for name in NODE_NAMES)
                     and info.environ.get("ROS_LOG_DIR", "").startswith(folder_text))


def kill_all(found: list[ProcessInfo]) -> None:
    """SIGKILL each process (a test's last resort at teardown)."""
    for info in found:
        with contextlib.suppress(ProcessLookupError):
            os.kill(info.pid, signal.SIGKILL)


def listening_tcp(pgid: int) -> list[tuple[str, int]]:
    """The (address, port) of every TCP socket listening in the processes of group pgid,
    IPv4 and IPv6, from /proc/net/tcp and tcp6 (a socket is its processes' fd's inode)."""
    inodes = set()
    for entry in Path("/proc").iterdir():
        try:
            if not entry.name.isdigit() or os.getpgid(int(entry.name)) != pgid:
                continue
            links = [os.readlink(fd) for fd in (entry / "fd").iterdir()]
        except OSError:  # ended meanwhile, or another user's
            continue
        inodes.update(link[len("socket:["):-1] for link in links if link.startswith("socket:["))
    found = []
    for table, family in (("tcp", socket.AF_INET), ("tcp6", socket.AF_INET6)):
        for row in Path(f"/proc/net/{table}").read_text().splitlines()[1:]:
            columns = row.split()
            local, state, inode = columns[1], columns[3], columns[9]
            if state == TCP_LISTEN and inode in inodes:
                address, port = local.split(":")
                found.append((_proc_net_address(address, family), int(port, 16)))
    return found


def listening_port(pgid: int, timeout_s: float) -> int:
    """The port of the one TCP socket the processes of group pgid listen on, once they do
    (within timeout_s: a server that binds after it starts); AssertionError otherwise."""
    deadline = time.monotonic() + timeout_s
    while not (found := listening_tcp(pgid)) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert len(found) == 1, found
    return found[0][1]


def _proc_net_address(hex_address: str, family: int) -> str:
    """An address as /proc/net/tcp* writes it (32-bit words in host byte order, in hex)."""
    words = [hex_address[i:i + 8] for i in range(0, len(hex_address), 8)]
    packed = b"".join(int(word, 16).to_bytes(4, sys.byteorder) for word in words)
    return socket.inet_ntop(family, packed)
