#!/usr/bin/env python3
"""Benchmark of the campaign layer: estimator flights in this process against two local
Dask workers, the per-task cost of the Dask path against a process pool, and what a
10,000-flight detectability map would take.

    python -m benchmarks.bench_campaigns [--flights 40] [--tiny-tasks 400] [--json FILE]

Flights: the shipped default and fault_free scenarios in turn, each in a wind of its own
(turbulence seeds from 401, 5-6.25 m/s in --flights directions); each a 300 s flight through
the offline chain, the estimator on it, summarised by its fault metrics. Per-task cost: a
task that returns its input, run warm (after a first round) through Campaign on two workers
and through a two-process ProcessPoolExecutor (spawned), wall time per task; the cluster's
start-up apart. The same through a scheduler address, as --cluster reaches one: a local
cluster of two workers on 127.0.0.1 over plain TCP and over TLS (certificates of
cluster_security.make_certificates), and TLS_FLIGHTS of the flights over TLS, whose results
must equal the serial run's bit for bit (as JSON: each float's repr is exact). The plan
scales the measured seconds per flight, result size and worker memory to 10,000 flights.
"""

from __future__ import annotations

import argparse
import json
import logging
import multiprocessing
import os
import pickle
import resource
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import dask.config
from distributed import LocalCluster
from uav_common.channels import DETECTION_THRESHOLD_PCT
from uav_fault_estimator.campaigns.campaign import (
    LOCALHOST,
    QUIET_WORKERS,
    Campaign,
    CampaignOptions,
)
from uav_fault_estimator.campaigns.cluster_security import ROLES, make_certificates, security
from uav_fault_estimator.chain.offline import fly_and_estimate, wind_variant
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_fault_estimator.reporting.metrics import fault_metrics
from uav_sim.scenario import Scenario, default_scenario_path, load_scenario

WORKERS = 2
MAP_FLIGHTS = 10_000
FIRST_SEED = 401  # other seeds than the calibrations' (101-112, 201-212, 301-304)
TLS_FLIGHTS = 6


def benchmark_flights(count: int) -> list[Scenario]:
    """count flights: the default and fault_free scenarios in turn, each in its own wind."""
    shipped = default_scenario_path()
    bases = (load_scenario(shipped), load_scenario(shipped.parent / "fault_free.yaml"))
    return [wind_variant(bases[i % 2], FIRST_SEED + i, 360.0 * i / count, 5.0 + 0.25 * (i % 6))
            for i in range(count)]


def flight_figures(scenario: Scenario) -> dict:
    """One flight's fault metrics (per fault: rmse, delay, ...), the campaign's result."""
    estimates, seeded = fly_and_estimate(scenario)
    return fault_metrics(estimates, seeded, SETTLE_S, DETECTION_THRESHOLD_PCT)[0]


def echo(value: int) -> int:
    """The cheapest task: its input."""
    return value


def peak_memory_mb() -> float:
    """This process's largest resident memory so far [MB] (Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3


def flights_serial_and_parallel(count: int) -> tuple[dict, list]:
    """count benchmark flights in this process and on WORKERS local workers, the two
    results equal (the campaign layer's promise): the figures, and the serial results."""
    scenarios = benchmark_flights(count)
    started = time.perf_counter()
    serial = Campaign(CampaignOptions(workers=0, progress=False)).run(
        flight_figures, scenarios, "serial")
    serial_s = time.perf_counter() - started
    started = time.perf_counter()
    with Campaign(CampaignOptions(workers=WORKERS, progress=False)) as campaign:
        campaign.client()  # the cluster's start-up, timed apart
        startup_s = time.perf_counter() - started
        parallel = campaign.run(flight_figures, scenarios, "two workers")
        memory_mb = max(campaign.client().run(peak_memory_mb).values())
    parallel_s = time.perf_counter() - started
    assert serial.failures == parallel.failures == [] and serial.results == parallel.results
    result_bytes = [len(pickle.dumps(result)) for result in serial.results]
    return {"flights": count, "serial_s": serial_s, "workers": WORKERS,
            "parallel_s": parallel_s, "cluster_startup_s": startup_s,
            "speedup": serial_s / parallel_s, "seconds_per_flight": serial_s / count,
            "result_bytes_mean": sum(result_bytes) / count,
            "worker_memory_mb_largest": memory_mb, "equal_results": True}, serial.results


def tls_against_tcp(tasks: int, scenarios: list[Scenario], serial_results: list) -> dict:
    """Wall time per cheapest task [ms], warm, through a local cluster's address over plain
    TCP and over TLS; and the scenarios flown over TLS, their results compared with the
    serial run's bit for bit (JSON of each: a float's repr is the shortest that reads back
    as the same double)."""
    figures = {}
    with tempfile.TemporaryDirectory() as folder, dask.config.set(QUIET_WORKERS):
        certificates = Path(folder)
        make_certificates(certificates)
        for protocol in ("tcp", "tls"):
            tls = protocol == "tls"
            with LocalCluster(n_workers=WORKERS, threads_per_worker=1, processes=True,
                              host=LOCALHOST, protocol=f"{protocol}://",
                              security=security(certificates, ROLES) if tls else None,
                              dashboard_address=None, silence_logs=logging.ERROR) as cluster:
                options = CampaignOptions(cluster=cluster.scheduler_address, progress=False,
                                          tls_certs=certificates if tls else None)
                with Campaign(options) as campaign:
                    figures[f"{protocol}_ms_per_task"] = warm_ms_per_task(campaign, tasks)
                    if tls:
                        flown = campaign.results(flight_figures, scenarios, "over TLS")
    equal = [json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
             for a, b in zip(flown, serial_results, strict=True)]
    return {"tasks": tasks, **figures, "tls_flights": len(scenarios),
            "tls_flights_equal_serial": all(equal)}


def warm_ms_per_task(campaign: Campaign, tasks: int) -> float:
    """Wall time per cheapest task [ms] of tasks run through the campaign after as many to
    warm it."""
    items = list(range(tasks))
    campaign.run(echo, items, "warm-up")
    started = time.perf_counter()
    campaign.run(echo, items, "timed")
    return 1e3 * (time.perf_counter() - started) / tasks


def per_task_cost(tasks: int) -> dict:
    """Wall time per cheapest task [ms], warm: Dask on WORKERS workers against a process
    pool of as many."""
    items = list(range(tasks))
    with Campaign(CampaignOptions(workers=WORKERS, progress=False)) as campaign:
        dask_ms = warm_ms_per_task(campaign, tasks)
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=WORKERS, mp_context=context) as pool:
        list(pool.map(echo, items))
        started = time.perf_counter()
        list(pool.map(echo, items))
        pool_s = time.perf_counter() - started
    return {"tasks": tasks, "dask_ms_per_task": dask_ms,
            "process_pool_ms_per_task": 1e3 * pool_s / tasks}


def plan(measured: dict, workers: int) -> dict:
    """MAP_FLIGHTS flights on `workers` workers like the measured ones."""
    cpu_hours = MAP_FLIGHTS * measured["seconds_per_flight"] / 3600
    return {"flights": MAP_FLIGHTS, "tasks": MAP_FLIGHTS, "cpu_hours": cpu_hours,
            "workers": workers, "wall_hours": cpu_hours / workers,
            "worker_memory_mb": measured["worker_memory_mb_largest"],
            "results_mb": MAP_FLIGHTS * measured["result_bytes_mean"] / 1e6}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", type=int, default=40)
    parser.add_argument("--tiny-tasks", type=int, default=400)
    parser.add_argument("--json", type=Path, help="write the figures here")
    arguments = parser.parse_args()
    measured, serial_results = flights_serial_and_parallel(arguments.flights)
    print(f"{measured['flights']} flights: serial {measured['serial_s']:.1f} s, "
          f"{WORKERS} workers {measured['parallel_s']:.1f} s (cluster start-up "
          f"{measured['cluster_startup_s']:.1f} s): {measured['speedup']:.2f} times faster; "
          f"{measured['seconds_per_flight']:.2f} s per flight, result "
          f"{measured['result_bytes_mean']:.0f} B, worker memory up to "
          f"{measured['worker_memory_mb_largest']:.0f} MB", flush=True)
    cost = per_task_cost(arguments.tiny_tasks)
    print(f"per task, warm: Dask {cost['dask_ms_per_task']:.2f} ms, process pool "
          f"{cost['process_pool_ms_per_task']:.2f} ms", flush=True)
    flights = min(TLS_FLIGHTS, arguments.flights)
    cluster = tls_against_tcp(arguments.tiny_tasks, benchmark_flights(arguments.flights)[
        :flights], serial_results[:flights])
    print(f"per task through a scheduler's address, warm: TCP "
          f"{cluster['tcp_ms_per_task']:.2f} ms, TLS {cluster['tls_ms_per_task']:.2f} ms; "
          f"{flights} flights over TLS equal to the serial run: "
          f"{cluster['tls_flights_equal_serial']}", flush=True)
    plans = [plan(measured, workers) for workers in (os.cpu_count() or 1, 64)]
    for entry in plans:
        print(f"{entry['flights']} flights: {entry['cpu_hours']:.1f} CPU hours, "
              f"{entry['wall_hours']:.1f} h on {entry['workers']} workers of "
              f"{entry['worker_memory_mb']:.0f} MB; results {entry['results_mb']:.1f} MB")
    if arguments.json:
        arguments.json.write_text(json.dumps({"flights": measured, "per_task": cost,
                                              "cluster": cluster, "plans": plans},
                                             indent=2) + "\n")


if __name__ == "__main__":
    main()
