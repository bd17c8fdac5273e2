"""scripts/repeat_tests.py (`./scripts/test.sh --repeat N`): per test, the rounds it failed
in, and status 1 when any did; the busy processes of --under-load gone afterwards."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import repeat_tests
from helpers.process_table import processes
from helpers.repo import REPO_ROOT, SCRIPTS

MARK = "REPEAT_TESTS_CHECK"
# A test that fails in every second round (a counter file beside it), one that always
# passes, and one whose fixture fails in the first round only.
FLAKY_SUITE = '''
from pathlib import Path

import pytest

COUNTER = Path(__file__).with_name("rounds.txt")


def rounds_so_far() -> int:
    return len(COUNTER.read_text()) if COUNTER.exists() else 0


def test_counts_the_round():
    COUNTER.write_text("x" * (rounds_so_far() + 1))


def test_fails_in_even_rounds():
    assert rounds_so_far() % 2 == 1


def test_always_passes():
    assert True


@pytest.fixture
def broken_first():
    assert rounds_so_far() > 1


def test_with_a_fixture_that_fails_first(broken_first):
    pass
'''


def run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    """repeat_tests.py on FLAKY_SUITE, its processes marked with tmp_path (MARK)."""
    (tmp_path / "test_flaky.py").write_text(FLAKY_SUITE)
    return subprocess.run(
        [sys.executable, str(SCRIPTS / "repeat_tests.py"), *args, "-q", "-p", "no:randomly",
         "--rootdir", str(tmp_path), str(tmp_path)],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
        env={**os.environ, MARK: str(tmp_path)})


@pytest.mark.timeout(150)
def test_each_failing_test_is_counted_by_round(tmp_path) -> None:
    result = run(tmp_path, "--rounds", "4")
    print(result.stdout)
    assert result.returncode == 1, result.stderr
    assert "repeat: round 1 of 4: 4 tests, 1 failed" in result.stdout
    assert "repeat: round 3 of 4: 4 tests, 0 failed" in result.stdout
    table = result.stdout.split("failed rounds  test\n")[1].splitlines()
    assert table == ["     2 of 4  test_flaky::test_fails_in_even_rounds",
                     "     1 of 4  test_flaky::test_with_a_fixture_that_fails_first"]


@pytest.mark.timeout(150)
def test_a_clean_selection_under_load_passes_and_leaves_no_busy_process(tmp_path) -> None:
    result = run(tmp_path, "--rounds", "1", "--under-load", "-k", "always")
    print(result.stdout)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "repeat: 1 rounds under load" in result.stdout
    assert "repeat: no test failed in any round" in result.stdout
    assert not processes(lambda info: repeat_tests.BUSY_LOOP in info.cmdline
                         and info.environ.get(MARK) == str(tmp_path))


@pytest.mark.timeout(30)
def test_a_round_without_a_report_fails(tmp_path) -> None:
    result = run(tmp_path, "--rounds", "1", "--no-such-pytest-option")
    assert result.returncode == 1
    assert "(round 1: pytest exited with 4 and no report)" in result.stdout


@pytest.mark.timeout(30)
@pytest.mark.parametrize("args", [["--repeat", "0"], ["--repeat", "x"], ["--under-load"]])
def test_test_sh_refuses_a_bad_repeat_request(args) -> None:
    result = subprocess.run([str(SCRIPTS / "test.sh"), *args], capture_output=True, text=True,
                            timeout=30, cwd=REPO_ROOT)
    assert result.returncode == 2
    assert result.stderr.startswith("test.sh: ") and len(result.stderr.splitlines()) == 1
