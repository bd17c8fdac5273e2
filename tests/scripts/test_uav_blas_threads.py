"""scripts/uav_blas_threads.py, as scripts/setup.sh installs it into .venv: whatever thread
counts the caller's environment asks for, a fresh process flies a short flight to the same
residuals, estimates and detector figures bit for bit, and every OpenBLAS and OpenMP library
in it runs on BLAS_THREADS threads."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from helpers.repo import REPO_ROOT
from uav_blas_threads import BLAS_THREADS, THREAD_COUNT_VARIABLES

PROBE = REPO_ROOT / "tests" / "helpers" / "thread_counts.py"
FLIGHT_S = 20.0  # the first estimate comes at 12 s, the first full GLRT window at 5 s
# What a caller's environment may say: nothing (a thread per core), one or two threads,
# OpenMP's variable alone (which OpenBLAS reads without its own), what Dask's nanny gives.
ENVIRONMENTS = {
    "unset": {},
    "openblas_1": {"OPENBLAS_NUM_THREADS": "1"},
    "openblas_2": {"OPENBLAS_NUM_THREADS": "2"},
    "omp_2": {"OMP_NUM_THREADS": "2"},
    "dask_nanny": {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"},
}


def probe(environment: dict[str, str]) -> dict:
    """helpers/thread_counts.py's figures from a fresh process of the venv started with this
    environment's thread variables instead of this process's."""
    env = {name: value for name, value in os.environ.items()
           if name not in (*THREAD_COUNT_VARIABLES, "MKL_NUM_THREADS")}
    result = subprocess.run([sys.executable, str(PROBE), str(FLIGHT_S)],
                            env={**env, **environment}, capture_output=True, text=True,
                            timeout=100)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.fixture(scope="module")
def figures() -> dict[str, dict]:
    """Every environment's figures, by its name in ENVIRONMENTS."""
    return {name: probe(environment) for name, environment in ENVIRONMENTS.items()}


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_a_short_flight_is_the_same_bit_for_bit_under_every_thread_setting(figures):
    print({name: figure["counts"] for name, figure in figures.items()})
    counts = figures["unset"]["counts"]
    assert counts["residuals"] > 0 and counts["estimates"] > 0 and counts["statistics"] > 0
    for name, figure in figures.items():
        assert figure["digests"] == figures["unset"]["digests"], name
        assert figure["counts"] == counts, name


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_every_blas_and_openmp_library_runs_on_the_chosen_count(figures):
    for name, figure in figures.items():
        threads = figure["threads"]
        print(name, threads)
        # numpy's and scipy's OpenBLAS, and proxsuite's OpenMP
        assert sum("openblas" in library for library in threads) == 2, name
        assert any("gomp" in library for library in threads), name
        assert set(threads.values()) == {BLAS_THREADS}, \
            f"{name}: {threads}; is the venv's hook installed (scripts/setup.sh)?"
