"""Run as a script with a duration [s]: flies the default scenario that long through the
offline chain and the detector and prints, as JSON, flight_figures' sha256 of their arrays
and counts, and the thread count each OpenBLAS and OpenMP library loaded in this process
runs with ("threads", by the library's file name), as the libraries themselves report it."""

from __future__ import annotations

import ctypes
import dataclasses
import hashlib
import json
import sys
from pathlib import Path

import numpy as np
from uav_fault_estimator.chain.offline import fault_free_residuals, fly_and_estimate, fly_on_grid
from uav_fault_estimator.detection.detector import run_detector
from uav_fault_estimator.detection.detector_settings import DetectorSettings, detector_calibration
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_sim.scenario import default_scenario_path, load_scenario

# How each library reports its thread count, by a part of its file name: OpenBLAS as numpy
# (64-bit integers, suffixed symbols) and scipy bundle it, or as a system build; OpenMP.
THREAD_QUERIES = {
    "openblas": ("scipy_openblas_get_num_threads64_", "scipy_openblas_get_num_threads",
                 "openblas_get_num_threads64_", "openblas_get_num_threads"),
    "libgomp": ("omp_get_max_threads",),
}


def loaded_libraries() -> list[Path]:
    """The shared libraries mapped into this process."""
    maps = Path("/proc/self/maps").read_text().splitlines()
    return sorted({Path(line.split(maxsplit=5)[5]) for line in maps
                   if len(line.split(maxsplit=5)) == 6 and ".so" in line})


def library_thread_counts() -> dict[str, int]:
    """The thread count of every OpenBLAS and OpenMP library loaded, by file name."""
    counts = {}
    for path in loaded_libraries():
        for part, symbols in THREAD_QUERIES.items():
            if part not in path.name:
                continue
            library = ctypes.CDLL(str(path))  # already loaded: the same handle
            symbol = next(name for name in symbols if hasattr(library, name))
            counts[path.name] = int(getattr(library, symbol)())
    return counts


def sha256(arrays: list[np.ndarray]) -> str:
    """One hex digest of the arrays' bytes, in order."""
    digest = hashlib.sha256()
    for array in arrays:
        digest.update(np.ascontiguousarray(array).tobytes())
    return digest.hexdigest()


def flight_figures(duration_s: float) -> dict:
    """The default scenario flown for duration_s [s] through the offline chain and the
    detector (the shipped calibration, tested from its first full window on: no settling
    time): "digests", the sha256 of the residuals, of the estimates (stamps, values,
    statuses; not the update times) and of every sample's detector figures (residuals,
    GLRT statistics, parameter deviations, RLS parameters); "counts", how many residual
    rows, solved estimates and finite statistics went into them."""
    scenario = dataclasses.replace(load_scenario(default_scenario_path()),
                                   duration_s=duration_s)
    residuals = fault_free_residuals(scenario)
    estimates, _ = fly_and_estimate(scenario)
    settings = DetectorSettings()
    calibration = dataclasses.replace(detector_calibration(settings), settle_s=0.0)
    flight = fly_on_grid(scenario, calibration.sample_period_s).detector_flight
    samples = run_detector(calibration, flight,
                           settings.false_alarm_probability)
    statistics = np.array([s.statistic for s in samples])
    return {
        "digests": {
            "residuals": sha256([residuals]),
            "estimates": sha256([estimates.stamps_s, estimates.values_pct,
                                 estimates.statuses]),
            "detector": sha256([np.array([s.residual for s in samples]), statistics,
                                np.array([s.parameter_deviation for s in samples]),
                                np.array([np.concatenate(list(s.theta.values()))
                                          for s in samples])]),
        },
        "counts": {
            "residuals": len(residuals),
            "estimates": int(np.sum(estimates.statuses == SolveStatus.SOLVED)),
            "statistics": int(np.isfinite(statistics).sum()),
        },
    }


if __name__ == "__main__":
    json.dump({**flight_figures(float(sys.argv[1])), "threads": library_thread_counts()},
              sys.stdout)
