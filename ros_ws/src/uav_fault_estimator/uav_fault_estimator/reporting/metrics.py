"""The run's figures of merit (docs/design.md, metrics.json) from estimates and seeded faults.

Per estimated fault, over estimate stamps at or after settle_s: the error of the estimate
against the seeded value at the same stamp (RMS and largest); the detection delay from the
first stamp at which the seeded value reaches the detection threshold (a step: its onset; a
ramp: where it crosses the threshold) to the first estimate stamp at or after it at which
the estimate reaches the threshold; and whether the estimate reached the threshold while the
seeded value was below it (a false alarm: of a fault never seeded, or of a seeded one whose
estimate rose before it did). Plus the solver's times and failures. No ROS here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from uav_fault_estimator.estimation.estimator_config import SolverSettings
from uav_fault_estimator.estimation.solve_status import SolveStatus


@dataclass(frozen=True)
class EstimateSeries:
    """What mhe_node published: stamps (K,) [s], values (K, p) [%], statuses (K,), update
    wall times (K,) [ms], the p fault names, the updates' CPU times (K,) [ms] (None for
    a recording made before they were published), the solver method it ran with
    (estimator_config.SOLVER_METHODS; None for one made before mhe_node reported it, when
    ProxSuite, the default, was the only one), and, from the offline chain, which knows the
    simulator's truth, the synthetic air data's angle of attack and sideslip minus the
    truth (K, 2) [rad] (NaN where none was published; None where unknown)."""

    names: Sequence[str]
    stamps_s: np.ndarray
    values_pct: np.ndarray
    statuses: np.ndarray
    solve_times_ms: np.ndarray
    cpu_times_ms: np.ndarray | None = None
    solver_method: str | None = None
    flow_angle_errors_rad: np.ndarray | None = None


@dataclass(frozen=True)
class SeededSeries:
    """What the simulator seeded: stamps (M,) [s] and values (M, q) [%] of q named faults."""

    names: Sequence[str]
    stamps_s: np.ndarray
    values_pct: np.ndarray

    def at(self, name: str, stamps_s: np.ndarray) -> np.ndarray:
        """The seeded value of `name` at each stamp: the latest sample at or before it."""
        column = self.values_pct[:, list(self.names).index(name)]
        index = np.searchsorted(self.stamps_s, stamps_s + 1e-9, side="right") - 1
        return np.where(index >= 0, column[np.clip(index, 0, None)], 0.0)

    def reaches_s(self, name: str, threshold_pct: float) -> float | None:
        """The first stamp at which the seeded value reaches threshold_pct; None if never."""
        column = self.values_pct[:, list(self.names).index(name)]
        reached = np.flatnonzero(column >= threshold_pct)
        return float(self.stamps_s[reached[0]]) if reached.size else None

    def start_s(self, name: str) -> float | None:
        """When the fault starts: the last stamp with value 0 before it first departs from
        0; None when it never does."""
        column = self.values_pct[:, list(self.names).index(name)]
        active = np.flatnonzero(column != 0.0)
        if active.size == 0:
            return None
        first = active[0]
        return float(self.stamps_s[first - 1] if first > 0 else self.stamps_s[0])


def fault_metrics(estimates: EstimateSeries, seeded: SeededSeries, settle_s: float,
                  threshold_pct: float) -> tuple[dict[str, dict], list[str]]:
    """Per estimated fault its figures, and the names of the false alarms."""
    faults: dict[str, dict] = {}
    false_alarms: list[str] = []
    settled = estimates.stamps_s >= settle_s
    for j, name in enumerate(estimates.names):
        values = estimates.values_pct[:, j]
        truth = (seeded.at(name, estimates.stamps_s) if name in seeded.names
                 else np.zeros_like(values))
        start_s = seeded.start_s(name) if name in seeded.names else None
        error = (values - truth)[settled]
        entry = {
            "seeded": start_s is not None,
            "seeded_final_pct": round(float(truth[-1]), 3) if truth.size else None,
            "estimate_final_pct": round(float(values[-1]), 3) if values.size else None,
            "rmse_pct": round(float(np.sqrt(np.mean(error**2))), 3) if error.size else None,
            "max_abs_error_pct": round(float(np.abs(error).max()), 3) if error.size else None,
            "detection_delay_s": None,
        }
        reached_s = seeded.reaches_s(name, threshold_pct) if start_s is not None else None
        if reached_s is not None:
            after = (estimates.stamps_s >= reached_s - 1e-9) & (values >= threshold_pct)
            if after.any():
                entry["detection_delay_s"] = round(
                    float(estimates.stamps_s[after][0] - reached_s), 3)
        if np.any(settled & (values >= threshold_pct) & (truth < threshold_pct)):
            false_alarms.append(name)
        faults[name] = entry
    return faults, false_alarms


def flow_angle_rms_deg(estimates: EstimateSeries, settle_s: float) -> list[float] | None:
    """RMS of the synthetic angle of attack's and sideslip's errors after settle_s [deg]
    (EstimateSeries.flow_angle_errors_rad); None where none are known."""
    errors = estimates.flow_angle_errors_rad
    if errors is None:
        return None
    published = errors[(estimates.stamps_s >= settle_s) & np.all(np.isfinite(errors), axis=1)]
    if not published.size:
        return None
    return np.degrees(np.sqrt(np.mean(np.square(published), axis=0))).round(3).tolist()


def solver_metrics(estimates: EstimateSeries) -> dict:
    """The solver method's name, solves (updates with a solution), their median, p99 and
    largest wall time, the median and p99 of their CPU time (None when not recorded),
    failures (updates that did not solve, other than waiting for data or holding)."""
    solved = estimates.statuses == SolveStatus.SOLVED
    failed = ~solved & ~np.isin(estimates.statuses, (SolveStatus.WAITING, SolveStatus.HELD))
    summary = {"name": estimates.solver_method or SolverSettings().method,
               "solves": int(solved.sum()), "failures": int(failed.sum())}
    cpu = None if estimates.cpu_times_ms is None else estimates.cpu_times_ms[solved]
    for prefix, times, statistics in (("", estimates.solve_times_ms[solved], _TIME_STATISTICS),
                                      ("cpu_", cpu, _TIME_STATISTICS[:2])):
        for key, value in statistics:
            summary[prefix + key] = (round(float(value(times)), 3)
                                     if times is not None and times.size else None)
    return summary


_TIME_STATISTICS = (("median_ms", np.median), ("p99_ms", lambda t: np.percentile(t, 99)),
                    ("max_ms", np.max))


@dataclass(frozen=True)
class AlarmSeries:
    """What detector_node published: stamps (K,) [s]; per-channel GLRT alarms (K, c), the
    parameter alarm (K,) and the combined alarm (K,); whether the tests ran (K,) (not while
    the window fills and the RLS settles); the designed P_FA; per-channel fast-test alarms
    (K, c); the template test's kinds (n, none without templates) and alarms (K, n)."""

    channel_names: Sequence[str]
    stamps_s: np.ndarray
    alarm: np.ndarray
    parameter_alarm: np.ndarray
    combined_alarm: np.ndarray
    tested: np.ndarray
    false_alarm_probability: float
    fast_alarm: np.ndarray
    template_kinds: Sequence[str] = ()
    template_alarm: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), bool))


def alarm_metrics(alarms: AlarmSeries, seeded: SeededSeries) -> dict:
    """Per test (each GLRT channel, the parameters, each fast-test channel, each template,
    the combined alarm): the alarms in
    fault-free time (tested samples before the first seeded fault starts, or the whole
    flight), as a count and as a rate per sample to hold against the designed P_FA, and the
    first alarm's delay after that start."""
    starts = [start for name in seeded.names if (start := seeded.start_s(name)) is not None]
    fault_start_s = min(starts) if starts else None
    before = (alarms.stamps_s < fault_start_s if fault_start_s is not None
              else np.ones(alarms.stamps_s.size, dtype=bool))
    fault_free = before & alarms.tested
    tests = {name: alarms.alarm[:, k] for k, name in enumerate(alarms.channel_names)}
    tests |= {"parameters": alarms.parameter_alarm}
    tests |= {f"fast_{name}": alarms.fast_alarm[:, k]
              for k, name in enumerate(alarms.channel_names)}
    tests |= {f"template_{kind}": alarms.template_alarm[:, k]
              for k, kind in enumerate(alarms.template_kinds)}
    tests |= {"combined": alarms.combined_alarm}
    summary = {}
    for name, raised in tests.items():
        raised = np.asarray(raised, dtype=bool)
        after = raised & ~before
        summary[name] = {
            "fault_free_alarms": int(raised[fault_free].sum()),
            "fault_free_alarm_rate": round(float(raised[fault_free].mean()), 5)
            if fault_free.any() else None,
            "first_alarm_delay_s": round(float(alarms.stamps_s[after][0] - fault_start_s), 3)
            if after.any() else None,
        }
    return {"false_alarm_probability": alarms.false_alarm_probability,
            "samples": int(alarms.stamps_s.size),
            "fault_free_samples": int(fault_free.sum()),
            "fault_start_s": fault_start_s, "tests": summary}
