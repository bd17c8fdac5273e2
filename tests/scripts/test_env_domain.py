"""scripts/env.sh gives a shell a ROS domain it holds for as long as it lives, and refuses a
ROS_DOMAIN_ID another run of the project holds in one line, leaving the shell as it was;
bringup.sh then ends with status 2 before any node starts."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Iterator

import pytest
from helpers.repo import REPO_ROOT, SCRIPTS
from uav_common.ros_domain import DomainReservation, domain_holders, reserve_domain_id

ENV_SH = SCRIPTS / "env.sh"


def shell_environment(**variables: str) -> dict[str, str]:
    """This process's environment as a fresh shell would have it: no venv, no domain."""
    environment = {name: value for name, value in os.environ.items()
                   if name not in ("VIRTUAL_ENV", "ROS_DOMAIN_ID")}
    return {**environment, **variables}


@pytest.fixture
def other_run() -> Iterator[tuple[subprocess.Popen, DomainReservation]]:
    """A process that holds a domain, started beside the shells of the test (not by them,
    nor one of their ancestors): another run."""
    holder = subprocess.Popen(["sleep", "60"])
    try:
        _, reservation = reserve_domain_id(holder.pid)
        yield holder, reservation
        reservation.close()
    finally:
        holder.kill()
        holder.wait()


@pytest.mark.timeout(30)
def test_a_shell_holds_its_domain_while_it_lives() -> None:
    shell = subprocess.Popen(
        ["bash", "-c", f"source {ENV_SH} && echo $ROS_DOMAIN_ID && cat >/dev/null"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=REPO_ROOT,
        env=shell_environment())
    try:
        domain_id = int(shell.stdout.readline())
        assert [holder.pid for holder in domain_holders(domain_id)] == [shell.pid]
        shell.stdin.close()  # cat sees the end of its input, the shell ends
        assert shell.wait(timeout=10) == 0
        assert domain_holders(domain_id) == []
    finally:
        shell.kill()
        shell.wait()


@pytest.mark.timeout(30)
def test_a_held_domain_id_is_refused_in_one_line_and_the_shell_left_as_it_was(
        other_run) -> None:
    holder, reservation = other_run
    result = subprocess.run(
        ["bash", "-c", f'source {ENV_SH}; echo "status $? ${{VIRTUAL_ENV:-no venv}}"'],
        capture_output=True, text=True, timeout=20, cwd=REPO_ROOT,
        env=shell_environment(ROS_DOMAIN_ID=str(reservation.domain_id)))
    assert result.stdout == "status 1 no venv\n"
    assert result.stderr == (
        f"env.sh: ROS domain {reservation.domain_id} is held by another run of the project, "
        f"PID {holder.pid} (sleep 60); unset ROS_DOMAIN_ID to be given a free one\n")


@pytest.mark.slow  # bringup.sh runs setup.sh first
@pytest.mark.timeout(120)
def test_bringup_on_a_held_domain_ends_with_status_2_before_any_node(
        other_run, tmp_path) -> None:
    holder, reservation = other_run
    logs = tmp_path / "logs"
    result = subprocess.run(
        [str(SCRIPTS / "bringup.sh"), "--logs", str(logs)], capture_output=True, text=True,
        timeout=100, env=shell_environment(ROS_DOMAIN_ID=str(reservation.domain_id)))
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stderr.strip().splitlines()[-1] == (
        f"env.sh: ROS domain {reservation.domain_id} is held by another run of the project, "
        f"PID {holder.pid} (sleep 60); unset ROS_DOMAIN_ID to be given a free one")
    assert not logs.exists() and "bringup.sh: ROS domain" not in result.stdout
