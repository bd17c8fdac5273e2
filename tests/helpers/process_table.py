"""The machine's processes as /proc shows them: to find nodes that scripts started, by their
command line and environment, and to check that none outlived its script."""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

NODE_NAMES = ("sim_node", "residual_node", "mhe_node", "detector_node", "recorder_node")


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
