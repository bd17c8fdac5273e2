"""Runs a pytest selection several rounds in a row, optionally with the cores kept busy, and
says per test in how many rounds it failed: the proof that a suite does not fail by chance.

    python scripts/repeat_tests.py --rounds N [--under-load] [PYTEST ARGS...]

(`./scripts/test.sh --repeat N [--under-load] [PYTEST ARGS...]` calls it in the project's
environment.) Each round is a pytest process of its own writing a JUnit XML report; a test
fails a round when its report has a failure or an error (a failing fixture counts). Under
load, one busy process per core spins for the whole run, at the tests' own priority.
Exit status 1 when any test failed in any round (or a round ended without a report), else 0.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ElementTree
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path

# Spins until its parent is gone: a repeat run killed outright (SIGTERM, SIGKILL: no
# `finally` runs) leaves no load behind to slow what runs next.
BUSY_LOOP = "import os\nparent = os.getppid()\nwhile os.getppid() == parent: pass"


def failed_tests(report: Path) -> tuple[list[str], int]:
    """The ids (`module.Class::name`) of the tests with a failure or error in a JUnit XML report,
    and how many tests it holds."""
    root = ElementTree.parse(report).getroot()
    failed, count = [], 0
    for case in root.iter("testcase"):
        count += 1
        if case.find("failure") is not None or case.find("error") is not None:
            failed.append(f"{case.get('classname')}::{case.get('name')}")
    return failed, count


@contextmanager
def busy_cores(count: int) -> Iterator[None]:
    """count processes spinning on the CPU while the block runs; killed after it."""
    busy = [subprocess.Popen([sys.executable, "-c", BUSY_LOOP]) for _ in range(count)]
    try:
        yield
    finally:
        for process in busy:
            process.kill()
            process.wait()


def run_round(index: int, pytest_args: list[str], folder: Path) -> tuple[list[str], int, float]:
    """One pytest run of the selection: the failed test ids, the tests run, the wall time
    [s]. A run that wrote no report (collection failed, pytest crashed) fails as a whole."""
    report = folder / f"round_{index}.xml"
    started = time.monotonic()
    status = subprocess.call([sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
                              f"--junitxml={report}", *pytest_args])
    wall_s = time.monotonic() - started
    if not report.exists():
        return [f"(round {index}: pytest exited with {status} and no report)"], 0, wall_s
    failed, count = failed_tests(report)
    if status not in (0, 1) and not failed:  # interrupted, internal error, no tests
        failed = [f"(round {index}: pytest exited with {status})"]
    return failed, count, wall_s


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False)
    parser.add_argument("--rounds", type=int, required=True, help="how many runs, N >= 1")
    parser.add_argument("--under-load", action="store_true",
                        help="keep every core busy with a spinning process for the whole run")
    args, pytest_args = parser.parse_known_args(argv)
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")
    failures: Counter[str] = Counter()
    load = busy_cores(os.cpu_count() or 1) if args.under_load else nullcontext()
    with tempfile.TemporaryDirectory(prefix="repeat_tests_") as folder, load:
        for index in range(1, args.rounds + 1):
            failed, count, wall_s = run_round(index, pytest_args, Path(folder))
            failures.update(failed)
            print(f"repeat: round {index} of {args.rounds}: {count} tests, "
                  f"{len(failed)} failed, {wall_s:.0f} s", flush=True)
    print(f"\nrepeat: {args.rounds} rounds{' under load' if args.under_load else ''}")
    if not failures:
        print("repeat: no test failed in any round")
        return 0
    print("failed rounds  test")
    for test, rounds in sorted(failures.items(), key=lambda item: (-item[1], item[0])):
        print(f"{rounds:>6} of {args.rounds}  {test}")
    return 1


if __name__ == "__main__":
    sys.exit(main())
