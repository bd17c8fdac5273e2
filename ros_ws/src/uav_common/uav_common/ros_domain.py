"""ROS domain ids reserved on this machine, so that the project's runs (shells that source
scripts/env.sh, bringup.sh, test sessions, demos) never see each other's nodes. Standard
library only, no ROS: scripts/env.sh runs it from the checkout, before it changes the shell.

How an id is held
-----------------
Each id has a file, LOCK_DIR/uav_fault_ros_domain_<id>.lock, whose lines name the processes
that hold the id: `PID START_TICKS BOOT_ID` (the process id, its start time in clock ticks
since boot from /proc/PID/stat, and the boot's id). The id is held while any process named
there lives; the same PID on a later process (a reused PID, or a reboot with /tmp kept) is
not the same process. A process that has gone, however it ended (an exit, SIGKILL, a
crash, the machine restarting), holds nothing: the next claim drops its line. So no helper
process stays behind to keep a lock, nothing needs cleaning up, and a shell can hold an id
although it cannot keep a Python lock open: env.sh runs

    python -m uav_common.ros_domain --pid $BASHPID [--requested $ROS_DOMAIN_ID]

which writes the shell's PID, not its own, and prints the id; the shell holds it for as long
as it lives (an `exec`, as in demo.sh, keeps the PID and so the id). A Python process
reserves for itself with reserve_domain_id() and lets go with close(), or by ending.

The file's flock(2) only serialises a claim's read, check and rewrite of the lines (a few
milliseconds). A file another process keeps locked counts as held, its holder unknown.

Why lines naming processes rather than a lock kept open for a shell: a helper process
holding the lock would have to leave `$(...)`, stay out of the shell's job control and
watch for the shell's end; a lock on a descriptor the shell keeps open would be inherited,
and kept, by every background process the shell starts, long after the shell has gone. A
line naming the shell holds the id exactly as long as the shell lives.

A requested id (a ROS_DOMAIN_ID already set) is taken when it is free, or when every process
holding it is of the claimant's own line of descent: the claimant itself, a process that
started it (a shell passes its id down to the bringup.sh it starts, a test session to the
nodes of its test) or one it started. The claimant then holds it too, so the id stays held
while any of them lives. Held by any other live process, it is refused, naming the holder.
"""

from __future__ import annotations

import argparse
import contextlib
import fcntl
import os
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

# Fast DDS maps domain ids 0..101 to valid ports on Linux: a requested id must be one.
VALID_IDS = range(0, 102)
# The ids given out: all valid ones but 0, the default of a ROS process started anywhere.
DOMAIN_IDS = range(1, 102)
LOCK_DIR = Path("/tmp")
CLAIM_WAIT_S = 1.0  # longest a claim of a requested id waits for another claim to finish
_POLL_S = 0.01
_COMMAND_CHARS = 80  # longest command line a message quotes
_BOOT_ID = Path("/proc/sys/kernel/random/boot_id")


class DomainError(Exception):
    """An id that cannot be reserved: bad, or held by another run; one line."""


class DomainHeldError(DomainError):
    """A requested id another run of the project holds."""


@dataclass(frozen=True)
class Holder:
    """A process holding a domain, told apart from a later one given the same PID."""

    pid: int
    start_ticks: int  # its start time [clock ticks since boot]
    boot_id: str

    @classmethod
    def of(cls, pid: int) -> Holder | None:
        """The live process pid, or None when there is none (or only its zombie)."""
        fields = _stat_fields(pid)
        if fields is None or fields[0] in ("Z", "X"):
            return None
        return cls(pid, int(fields[19]), _boot_id())

    @classmethod
    def parse(cls, line: str) -> Holder | None:
        """A holder from its line in a lock file; None for a line that is not one."""
        words = line.split()
        if len(words) != 3 or not (words[0].isdigit() and words[1].isdigit()):
            return None
        return cls(int(words[0]), int(words[1]), words[2])

    def line(self) -> str:
        """Its line in a lock file."""
        return f"{self.pid} {self.start_ticks} {self.boot_id}"

    def alive(self) -> bool:
        """Whether this very process still runs."""
        return Holder.of(self.pid) == self

    def description(self) -> str:
        """`PID 1234 (bash scripts/bringup.sh)`, as far as its command line is readable."""
        try:
            argv = Path(f"/proc/{self.pid}/cmdline").read_bytes().split(b"\0")
        except OSError:
            return f"PID {self.pid}"
        command = " ".join(arg.decode(errors="replace") for arg in argv if arg)
        if len(command) > _COMMAND_CHARS:
            command = command[:_COMMAND_CHARS - 3] + "..."
        return f"PID {self.pid} ({command})" if command else f"PID {self.pid}"


class DomainReservation:
    """A domain id held by one process until close() (or that process's end)."""

    def __init__(self, domain_id: int, holder: Holder) -> None:
        self.domain_id = domain_id
        self.holder = holder
        self._closed = False

    def close(self) -> None:
        """Let the id go: drop this holder's line (other holders keep theirs). Safe to call
        more than once; a file another process keeps locked keeps the line until the
        holder ends."""
        if self._closed:
            return
        self._closed = True
        with _locked(self.domain_id, CLAIM_WAIT_S) as lock_fd:
            if lock_fd is not None:
                _write_holders(lock_fd, [holder for holder in _live_holders(lock_fd)
                                         if holder != self.holder])

    def __enter__(self) -> DomainReservation:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def lock_path(domain_id: int) -> Path:
    """The file naming the holders of domain_id."""
    return LOCK_DIR / f"uav_fault_ros_domain_{domain_id}.lock"


def parse_domain_id(text: str) -> int:
    """A requested domain id from ROS_DOMAIN_ID's text; DomainError if it is not a whole
    number in VALID_IDS."""
    if not (text.isascii() and text.isdigit()) or int(text) not in VALID_IDS:
        raise DomainError(f"ROS_DOMAIN_ID='{text}' is not a ROS domain id (a whole number "
                          f"{VALID_IDS.start}..{VALID_IDS.stop - 1})")
    return int(text)


def reserve_domain_id(pid: int | None = None) -> tuple[int, DomainReservation]:
    """A domain id of DOMAIN_IDS no live process holds, now held by process pid (default:
    this one): (the id, its reservation). DomainError when every id is held."""
    holder = _holder_of(pid)
    first = holder.pid % len(DOMAIN_IDS)
    for offset in range(len(DOMAIN_IDS)):
        domain_id = DOMAIN_IDS[(first + offset) % len(DOMAIN_IDS)]
        with _locked(domain_id, 0.0) as lock_fd:
            if lock_fd is None:
                continue
            holders = _live_holders(lock_fd)
            if holders:
                continue
            _write_holders(lock_fd, [holder])
            return domain_id, DomainReservation(domain_id, holder)
    raise DomainError(f"every ROS domain id {DOMAIN_IDS.start}..{DOMAIN_IDS.stop - 1} is "
                      "held by another run of the project")


def claim_domain_id(domain_id: int, pid: int | None = None) -> DomainReservation:
    """Domain domain_id, now held by process pid (default: this one) too, when no live
    process outside pid's line of descent holds it; DomainHeldError naming the holder if one
    does."""
    holder = _holder_of(pid)
    with _locked(domain_id, CLAIM_WAIT_S) as lock_fd:
        if lock_fd is None:
            raise DomainHeldError(_unknown_holder(domain_id))
        holders = _live_holders(lock_fd)
        others = [other for other in holders if not related(holder.pid, other.pid)]
        if others:
            raise DomainHeldError(f"ROS domain {domain_id} is held by another run of the "
                              f"project, {others[0].description()}")
        _write_holders(lock_fd, holders if holder in holders else [*holders, holder])
    return DomainReservation(domain_id, holder)


def domain_holders(domain_id: int) -> list[Holder]:
    """The live processes holding domain_id; DomainHeldError if its file stays locked (or
    cannot be opened for writing)."""
    with _locked(domain_id, CLAIM_WAIT_S) as lock_fd:
        if lock_fd is None:
            raise DomainHeldError(_unknown_holder(domain_id))
        return _live_holders(lock_fd)


def ancestors(pid: int) -> list[int]:
    """The processes that started pid: its parent, the parent's parent, ... up to the first."""
    chain: list[int] = []
    while True:
        fields = _stat_fields(pid)
        parent = int(fields[1]) if fields else 0
        if parent <= 0 or parent in chain:
            return chain
        chain.append(parent)
        pid = parent


def related(first: int, second: int) -> bool:
    """Whether two processes are of one line of descent: the same, or one started
    (directly or not) by the other."""
    return first == second or first in ancestors(second) or second in ancestors(first)


def _unknown_holder(domain_id: int) -> str:
    return (f"ROS domain {domain_id} is held by another run of the project (a process keeps "
            f"{lock_path(domain_id)} locked, or it is not yours to write)")


def _holder_of(pid: int | None) -> Holder:
    holder = Holder.of(os.getpid() if pid is None else pid)
    if holder is None:
        raise DomainError(f"no running process {pid} to hold a ROS domain")
    return holder


@contextlib.contextmanager
def _locked(domain_id: int, wait_s: float) -> Iterator[int | None]:
    """The lock file of domain_id open and flock()ed by this process, waiting up to wait_s
    for another claim to finish; None if it stays locked or cannot be opened for writing."""
    try:
        lock_fd = os.open(lock_path(domain_id), os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        yield None
        return
    try:
        deadline = time.monotonic() + wait_s
        while True:
            try:
                fcntl.flock(lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    yield None
                    return
                time.sleep(_POLL_S)
        yield lock_fd
    finally:
        os.close(lock_fd)  # lets the flock go too


def _live_holders(lock_fd: int) -> list[Holder]:
    """The holders named in a locked file that still live."""
    os.lseek(lock_fd, 0, os.SEEK_SET)
    chunks = []
    while chunk := os.read(lock_fd, 4096):
        chunks.append(chunk)
    lines = b"".join(chunks).decode(errors="replace").splitlines()
    holders = [Holder.parse(line) for line in lines]
    return [holder for holder in holders if holder is not None and holder.alive()]


def _write_holders(lock_fd: int, holders: Sequence[Holder]) -> None:
    """Replace a locked file's lines by holders'."""
    os.ftruncate(lock_fd, 0)
    os.lseek(lock_fd, 0, os.SEEK_SET)
    os.write(lock_fd, "".join(holder.line() + "\n" for holder in holders).encode())


def _stat_fields(pid: int) -> list[str] | None:
    """/proc/PID/stat's fields after the command name (state, ppid, ...); None if no such
    process."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except (OSError, ValueError):
        return None
    return text[text.rindex(")") + 2:].split()


def _boot_id() -> str:
    return _BOOT_ID.read_text().strip()


def main(argv: Sequence[str] | None = None) -> int:
    """Reserve a domain for the process --pid (a shell) and print its id: the --requested
    one (ROS_DOMAIN_ID's value; empty: none) or a free one. A refusal is one line on
    stderr, named as --caller, and status 1."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pid", type=int, required=True, help="the process to hold the id")
    parser.add_argument("--requested", default="", help="the id asked for (empty: any free)")
    parser.add_argument("--caller", default="ros_domain", help="the name errors start with")
    arguments = parser.parse_args(argv)
    try:
        if arguments.requested:
            domain_id = claim_domain_id(parse_domain_id(arguments.requested),
                                        arguments.pid).domain_id
        else:
            domain_id, _ = reserve_domain_id(arguments.pid)
    except DomainError as error:
        advice = ("; unset ROS_DOMAIN_ID to be given a free one"
                  if isinstance(error, DomainHeldError) else "")
        print(f"{arguments.caller}: {error}{advice}", file=sys.stderr)
        return 1
    print(domain_id)
    return 0


if __name__ == "__main__":
    sys.exit(main())
