"""ROS domain reservations: a held id is refused naming its holder, an id let go or whose
holder has ended is free again, a later process with a holder's PID is not the holder, and
a process shares its id with the processes of its own line of descent."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator

import pytest
from uav_common import ros_domain
from uav_common.ros_domain import (
    DomainError,
    DomainHeldError,
    Holder,
    claim_domain_id,
    domain_holders,
    parse_domain_id,
    reserve_domain_id,
)


@pytest.fixture(autouse=True)
def own_lock_dir(tmp_path, monkeypatch) -> None:
    """Reservations of this test's own: lock files in its folder, two ids to give out."""
    monkeypatch.setattr(ros_domain, "LOCK_DIR", tmp_path)
    monkeypatch.setattr(ros_domain, "DOMAIN_IDS", range(1, 3))


@pytest.fixture
def sleepers() -> Iterator[list[subprocess.Popen]]:
    """Two processes to hold ids, neither started by the other: two runs."""
    started = [subprocess.Popen(["sleep", "60"]) for _ in range(2)]
    try:
        yield started
    finally:
        for process in started:
            process.kill()
            process.wait()


@pytest.mark.timeout(10)
def test_a_held_id_is_refused_naming_its_holder(sleepers) -> None:
    first, second = sleepers
    domain_id, _ = reserve_domain_id(first.pid)
    with pytest.raises(DomainHeldError) as refused:
        claim_domain_id(domain_id, second.pid)
    assert str(refused.value) == (f"ROS domain {domain_id} is held by another run of the "
                                  f"project, PID {first.pid} (sleep 60)")
    other_id, _ = reserve_domain_id(second.pid)
    assert other_id != domain_id
    with pytest.raises(DomainError, match=r"^every ROS domain id 1\.\.2 is held"):
        reserve_domain_id()


@pytest.mark.timeout(10)
def test_an_id_let_go_or_whose_holder_ended_is_free_again(sleepers) -> None:
    first, second = sleepers
    domain_id, reservation = reserve_domain_id(first.pid)
    reservation.close()
    reservation.close()  # a second time changes nothing
    assert domain_holders(domain_id) == []
    claim_domain_id(domain_id, second.pid)
    assert [holder.pid for holder in domain_holders(domain_id)] == [second.pid]

    second.kill()  # ended, not let go: its line stays until the next claim
    second.wait()
    assert domain_holders(domain_id) == []
    claim_domain_id(domain_id, first.pid)
    assert ros_domain.lock_path(domain_id).read_text() == Holder.of(first.pid).line() + "\n"


@pytest.mark.timeout(10)
def test_a_later_process_given_a_holders_pid_is_not_the_holder(sleepers) -> None:
    first, second = sleepers
    live = Holder.of(first.pid)
    earlier = Holder(live.pid, live.start_ticks - 1, live.boot_id)
    other_boot = Holder(live.pid, live.start_ticks, "another-boot")
    ros_domain.lock_path(1).write_text(f"{earlier.line()}\n{other_boot.line()}\nnot a line\n")
    assert domain_holders(1) == []
    claim_domain_id(1, second.pid)


@pytest.mark.timeout(10)
def test_an_id_passes_down_a_line_of_descent_and_is_held_while_any_of_it_lives(
        sleepers) -> None:
    domain_id, reservation = reserve_domain_id()  # this process
    child = sleepers[0]  # started by this process
    claim_domain_id(domain_id)  # its own again: no second line
    claim_domain_id(domain_id, child.pid)
    assert [holder.pid for holder in domain_holders(domain_id)] == [os.getpid(), child.pid]
    reservation.close()  # the child holds it on
    with pytest.raises(DomainHeldError, match=f"PID {child.pid} "):
        claim_domain_id(domain_id, sleepers[1].pid)


@pytest.mark.timeout(10)
@pytest.mark.parametrize("text", ["abc", "-1", "102", "3.5", " 7", "٣"])
def test_a_requested_id_that_is_not_one_is_one_clear_message(text) -> None:
    with pytest.raises(DomainError) as refused:
        parse_domain_id(text)
    assert str(refused.value) == (f"ROS_DOMAIN_ID='{text}' is not a ROS domain id (a whole "
                                  "number 0..101)")
    assert parse_domain_id("0") == 0 and parse_domain_id("101") == 101


@pytest.mark.timeout(20)
def test_the_command_prints_the_id_it_reserved_for_a_shell_or_refuses_in_one_line(
        sleepers, tmp_path) -> None:
    first, second = sleepers

    def run(*arguments: str) -> subprocess.CompletedProcess:
        code = ("import sys; from pathlib import Path; from uav_common import ros_domain; "
                f"ros_domain.LOCK_DIR = Path({str(tmp_path)!r}); "
                "sys.exit(ros_domain.main(sys.argv[1:]))")
        return subprocess.run([sys.executable, "-c", code, "--caller", "env.sh", *arguments],
                              capture_output=True, text=True, timeout=10)

    given = run("--pid", str(first.pid), "--requested", "")
    assert given.returncode == 0, given.stderr
    domain_id = int(given.stdout)
    assert [holder.pid for holder in domain_holders(domain_id)] == [first.pid]

    refused = run("--pid", str(second.pid), "--requested", str(domain_id))
    assert refused.returncode == 1 and refused.stdout == ""
    assert refused.stderr == (f"env.sh: ROS domain {domain_id} is held by another run of the "
                              f"project, PID {first.pid} (sleep 60); unset ROS_DOMAIN_ID to "
                              "be given a free one\n")
