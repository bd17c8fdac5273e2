"""The campaign layer: short flights on a LocalCluster of two workers give the serial run's
results bit for bit; a failing task is reported with its input while the others finish; the
cache makes a rerun, or a campaign resumed after Ctrl-C, compute only what is missing."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
from uav_fault_estimator.campaigns.campaign import (
    CODE_PACKAGES,
    Campaign,
    CampaignOptions,
    TaskCache,
    exit_on_failed_tasks,
    run_campaign,
)
from uav_fault_estimator.chain.offline import GridFlight, fly_on_grid
from uav_sim.scenario import default_scenario_path, load_scenario

# workers import this module's functions by value: it is not on their path
cloudpickle.register_pickle_by_value(sys.modules[__name__])

SERIAL = CampaignOptions(workers=0, progress=False)
TWO_WORKERS = CampaignOptions(workers=2, progress=False)


def flights(count: int, duration_s: float = 10.0) -> list:
    """The default scenario cut short, with seeds 1..count."""
    scenario = load_scenario(default_scenario_path())
    return [dataclasses.replace(scenario, duration_s=duration_s, seed=seed)
            for seed in range(1, count + 1)]


def fly(scenario) -> GridFlight:
    return fly_on_grid(scenario, 0.2)


def fly_unless_seed_3(scenario) -> GridFlight:
    if scenario.seed == 3:
        raise ValueError("seed 3 refused")
    return fly(scenario)


def same(first: list[GridFlight], second: list[GridFlight]) -> bool:
    """Every array of every flight equal, NaN where NaN, bit for bit."""
    return all(np.array_equal(a, b, equal_nan=True) for x, y in zip(first, second, strict=True)
               for a, b in zip(x, y, strict=True))


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_two_local_workers_give_the_serial_results_bit_for_bit():
    tasks = flights(6)
    serial = run_campaign(fly, tasks, "serial", SERIAL)
    parallel = run_campaign(fly, tasks, "two workers", TWO_WORKERS)
    print(f"serial {serial.wall_s:.2f} s, two workers {parallel.wall_s:.2f} s")
    assert serial.failures == parallel.failures == []
    assert (serial.computed, parallel.computed) == (6, 6)
    assert same(serial.results, parallel.results)
    assert not same(serial.results[:1], serial.results[1:2])  # seeds make other flights


@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.parametrize("options", [SERIAL, TWO_WORKERS], ids=["serial", "two_workers"])
def test_a_failing_task_is_reported_with_its_input_and_the_others_finish(options):
    result = run_campaign(fly_unless_seed_3, flights(4), "failing", options)
    [failure] = result.failures
    assert (failure.index, failure.task.seed, failure.error) == (2, 3,
                                                                 "ValueError: seed 3 refused")
    assert "fly_unless_seed_3" in failure.traceback
    assert result.results[2] is None and all(result.results[i] for i in (0, 1, 3))
    with pytest.raises(RuntimeError, match=r"task 2 \(scenario 'default' seed 3\): ValueError"):
        result.raise_failures()


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_rerun_computes_only_what_the_interrupted_campaign_left(tmp_path):
    tasks = flights(5)
    cached = dataclasses.replace(SERIAL, cache_dir=tmp_path)
    first = run_campaign(fly, tasks[:2], "interrupted", cached)  # as if stopped after two
    rerun = run_campaign(fly, tasks, "rerun", dataclasses.replace(TWO_WORKERS,
                                                                 cache_dir=tmp_path))
    assert (first.computed, rerun.computed, rerun.cached) == (2, 3, 2)
    assert same(rerun.results, run_campaign(fly, tasks, "serial", SERIAL).results)
    again = run_campaign(fly, tasks, "again", cached)
    assert (again.computed, again.cached) == (0, 5)
    # one folder for this code version, a result per task; another function's tasks are
    # its own
    [version] = [path.name for path in tmp_path.iterdir()]
    assert len(list((tmp_path / version).glob("*.pkl"))) == 5
    assert TaskCache(tmp_path, fly_unless_seed_3).load(tasks[0]) == (False, None)


@pytest.mark.timeout(60)
def test_a_script_whose_tasks_failed_says_which_in_lines_and_exits_1(capsys):
    @exit_on_failed_tasks
    def main() -> int:
        return len(Campaign(SERIAL).results(fly_unless_seed_3, flights(3, 1.0), "failing"))

    assert main() == 1
    error = capsys.readouterr().err.splitlines()
    assert error[1:] == ["task 2 (scenario 'default' seed 3): ValueError: seed 3 refused"]
    assert error[0].endswith("1 of 3 tasks failed (the others' results are cached with "
                             "--cache):")


INTERRUPTED_AT_SEED = {"seed": None}  # the flight at which Ctrl-C "comes", in this process


def fly_or_be_interrupted(scenario) -> GridFlight:
    if scenario.seed == INTERRUPTED_AT_SEED["seed"]:
        raise KeyboardInterrupt  # not a task's failure: it stops the campaign
    return fly(scenario)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_campaign_stopped_by_ctrl_c_resumes_with_only_the_missing_tasks(tmp_path):
    tasks = flights(6)
    cached = dataclasses.replace(SERIAL, cache_dir=tmp_path)
    INTERRUPTED_AT_SEED["seed"] = 4
    try:
        with pytest.raises(KeyboardInterrupt):
            run_campaign(fly_or_be_interrupted, tasks, "interrupted", cached)
    finally:
        INTERRUPTED_AT_SEED["seed"] = None
    resumed = run_campaign(fly_or_be_interrupted, tasks, "resumed", cached)
    assert (resumed.cached, resumed.computed) == (3, 3)  # seeds 1-3 kept, 4-6 flown
    assert same(resumed.results, run_campaign(fly, tasks, "serial", SERIAL).results)


@pytest.mark.timeout(60)
def test_the_cache_key_covers_every_project_package_a_flight_imports():
    """A cached flight is stale when any project code it ran changed: every package of the
    workspace that the offline chain imports (in a process of its own) is one code_version
    hashes."""
    workspace_src = Path(__file__).resolve().parents[3] / "ros_ws" / "src"
    project = {path.name for path in workspace_src.iterdir() if (path / "setup.py").exists()}
    loaded = subprocess.run(
        [sys.executable, "-c", "import sys, uav_fault_estimator.chain.offline; "
                               "print(' '.join(name.split('.')[0] for name in sys.modules))"],
        check=True, capture_output=True, text=True, timeout=50).stdout.split()
    imported = set(loaded) & project
    assert "uav_aircraft" in imported
    assert imported <= set(CODE_PACKAGES), imported - set(CODE_PACKAGES)
