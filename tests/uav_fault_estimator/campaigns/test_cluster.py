"""Campaigns on a TLS Dask cluster started as processes on 127.0.0.1 (a scheduler and two
workers, as on other machines, with certificates of scripts/cluster_certs.py): a
calibration sent with --cluster writes the file the serial run writes, a worker killed
mid-campaign loses nothing (its tasks are redone on the other), and a client or a worker
with another CA's certificates is refused."""

from __future__ import annotations

import dataclasses
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
from distributed import Client
from distributed.comm.core import CommClosedError
from uav_common.ros_processes import wait_until
from uav_fault_estimator.campaigns.campaign import Campaign, CampaignOptions
from uav_fault_estimator.campaigns.cluster_security import (
    CA_CERTIFICATE,
    certificate_path,
    key_path,
    security,
)
from uav_fault_estimator.chain.offline import fly_on_grid
from uav_sim.scenario import default_scenario_path, load_scenario

pytestmark = pytest.mark.integration
cloudpickle.register_pickle_by_value(sys.modules[__name__])

DASK = str(Path(sys.executable).parent / "dask")
REPO = Path(__file__).resolve().parents[3]
LOOPBACK_DASHBOARD = ("--dashboard-address", "127.0.0.1:0")  # every port on 127.0.0.1
SCHEDULER_AT = re.compile(r"Scheduler at:\s+(tls://127\.0\.0\.1:\d+)")
TASK_S = 0.4  # wall time each task of the killed-worker campaign takes, at least


def make_certificates(folder: Path) -> Path:
    """folder, with scripts/cluster_certs.py's CA and certificates in it."""
    subprocess.run([sys.executable, str(REPO / "scripts/cluster_certs.py"), str(folder)],
                   check=True, capture_output=True, timeout=30)
    return folder


def tls_options(certificates: Path, role: str) -> list[str]:
    """dask scheduler's or dask worker's TLS options for a role's certificates."""
    return ["--tls-ca-file", str(certificates / CA_CERTIFICATE),
            "--tls-cert", str(certificate_path(certificates, role)),
            "--tls-key", str(key_path(certificates, role))]


def start_worker(start_process, address: str, certificates: Path, name: str, *extra: str):
    return start_process([DASK, "worker", address, "--nthreads", "1", "--host", "127.0.0.1",
                          *LOOPBACK_DASHBOARD, "--name", name, *extra,
                          *tls_options(certificates, "worker")], f"dask_{name}")


@pytest.fixture
def cluster(start_process, tmp_path):
    """A TLS scheduler on 127.0.0.1 and two single-threaded workers: (its address, the
    workers' processes, the certificates' folder)."""
    certificates = make_certificates(tmp_path / "certificates")
    scheduler = start_process([DASK, "scheduler", "--protocol", "tls", "--host", "127.0.0.1",
                               "--port", "0", *LOOPBACK_DASHBOARD,
                               *tls_options(certificates, "scheduler")], "dask_scheduler")
    assert wait_until(lambda: SCHEDULER_AT.search(scheduler.output()), timeout_s=30), \
        scheduler.output()
    address = SCHEDULER_AT.search(scheduler.output()).group(1)
    workers = [start_worker(start_process, address, certificates, f"worker{k}")
               for k in (1, 2)]
    with Campaign(cluster_options(address, certificates)) as campaign:
        campaign.client().wait_for_workers(2, timeout=60)
    yield address, workers, certificates
    for process in [*workers, scheduler]:  # on SIGINT they linger, reconnecting: 16 s
        process.stop(signal.SIGKILL)


def cluster_options(address: str, certificates: Path) -> CampaignOptions:
    return CampaignOptions(cluster=address, tls_certs=certificates, progress=False)


def slow_flight(scenario):
    """A 20 s flight on the detector's grid, taking at least TASK_S of wall time."""
    time.sleep(TASK_S)
    return fly_on_grid(scenario, 0.2)


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_calibration_sent_to_the_cluster_writes_the_serial_runs_file(cluster, tmp_path):
    address, _, certificates = cluster
    written = {}
    for where in (["--cluster", address, "--tls-certs", str(certificates)],
                  ["--workers", "0"]):
        out = tmp_path / f"calibration_{where[0].strip('-')}.yaml"
        result = subprocess.run([sys.executable, str(REPO / "scripts/calibrate_detector.py"),
                                 "--flights", "2", "--out", str(out), "--no-progress", *where],
                                capture_output=True, text=True, timeout=150)
        assert result.returncode == 0, result.stderr
        written[where[0]] = out.read_text()
    assert written["--cluster"] == written["--workers"]


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_worker_killed_mid_campaign_loses_nothing(cluster):
    address, workers, certificates = cluster
    scenario = load_scenario(default_scenario_path())
    tasks = [dataclasses.replace(scenario, duration_s=20.0, seed=seed) for seed in range(10)]
    killed_after_s = 3 * TASK_S  # a few tasks done on each worker, most to do
    killer = threading.Timer(killed_after_s, workers[0].send_signal, args=(signal.SIGKILL,))
    with Campaign(cluster_options(address, certificates)) as campaign:
        killer.start()
        result = campaign.run(slow_flight, tasks, "killed worker")
        left = len(campaign.client().scheduler_info()["workers"])
    killer.join()
    serial = [fly_on_grid(task, 0.2) for task in tasks]
    print(f"{result.computed} computed in {result.wall_s:.1f} s; workers left: {left}")
    assert not workers[0].running() and left == 1
    assert result.failures == [] and result.computed == len(tasks)
    assert result.wall_s > killed_after_s + TASK_S  # it went on after the kill
    assert all(np.array_equal(a, b, equal_nan=True) for x, y in zip(result.results, serial,
                                                                  strict=True)
               for a, b in zip(x, y, strict=True))


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_only_the_clusters_own_certificates_get_in(cluster, start_process, tmp_path):
    """A client, and a worker, with a certificate of another CA are refused at the TLS
    handshake; the cluster keeps its two workers and goes on."""
    address, _, certificates = cluster
    stranger = make_certificates(tmp_path / "another_ca")
    with pytest.raises((CommClosedError, OSError), match=r"TLS certificate does not match"):
        Client(address, security=security(stranger), timeout="5s")
    intruder = start_worker(start_process, address, stranger, "intruder",
                            "--death-timeout", "10")
    assert wait_until(lambda: not intruder.running(), timeout_s=60), intruder.output()
    assert "CERTIFICATE_VERIFY_FAILED" in intruder.output()
    with Campaign(cluster_options(address, certificates)) as campaign:
        assert len(campaign.client().scheduler_info()["workers"]) == 2
        assert campaign.results(len, [[1, 2], [3]], "after") == [2, 1]
