"""A ROS domain id reserved for one test session, so parallel runs never see each other."""

import fcntl
import os
from pathlib import Path
from typing import IO

# Fast DDS maps domain ids 0..101 to valid ports on Linux; leave 0 (the default) alone.
DOMAIN_IDS = range(1, 102)
LOCK_DIR = Path("/tmp")


def reserve_domain_id() -> tuple[int, IO[str]]:
    """Lock a free domain id for this process: (id, open lock file to keep while in use).

    The lock is released when the file is closed or the process ends, whatever the cause.
    """
    first = os.getpid() % len(DOMAIN_IDS)
    for offset in range(len(DOMAIN_IDS)):
        domain_id = DOMAIN_IDS[(first + offset) % len(DOMAIN_IDS)]
        lock = open(LOCK_DIR / f"uav_fault_ros_domain_{domain_id}.lock", "w")  # noqa: SIM115
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        return domain_id, lock
    raise RuntimeError(f"every ROS domain id in {DOMAIN_IDS} is in use by another test run")
