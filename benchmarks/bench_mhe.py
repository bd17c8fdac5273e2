#!/usr/bin/env python3
"""Benchmark of the moving-horizon fault estimator against PIQP, OSQP, quadprog and Clarabel.

    python -m benchmarks.bench_mhe [--updates 300] [--turbulence light] [--json FILE]

1. A realistic sequence: the default scenario flown by the core simulator (turbulence as
   given), its residuals and sensitivities from the residual core every 0.5 s, and
   mhe_node's default configuration (EstimatorSettings: N = 50, four monotonic faults
   bounded to [0, 100] %), first with the four faults alone (p = 4), then, on the same
   flight with a pitot and no vanes, with the three wind-error columns as well (the window
   of an aircraft without vanes: `estimate_wind_errors`, N = 70, the pitot suite's Q). The project's
   estimator runs it (the whole `update` call, as the node makes it); the same QPs then go,
   through the estimator's solver interface (solvers.WindowSolver), to the solvers of
   benchmarks/qp_solvers.py: PIQP (sparse, set up once, `update(P, c)`), OSQP (same
   pattern, warm start, polish), quadprog (dense active set, from scratch, exact) and
   Clarabel (interior point, from scratch), each timed by its own solve's account. Each
   tolerant solver gets the loosest tolerance that reaches the project's deviation from the
   reference (Clarabel at 1e-12, polished on its active set; untimed) on the first updates,
   so that none works harder than the estimate needs. Per solver: its tolerance, median and
   p99 time and its largest deviation from the reference.
   The estimator again with solver_method: active_set (the exact primal-dual active-set
   method, monotone_active_set.py), where its faults are monotonic.
2. The estimator's median and p99 update time for N = 25 ... 400 (p = 4) on the flown
   sequence, and for p = 4, 8, 16 (N = 50) on synthetic sequences (seeded ramps through
   slowly varying signatures), by ProxSuite and by the active set: the residual core has
   only the paper's four wing faults.
3. Where ProxSuite's update goes (setup, solve, the Python around it), what ProxSuite costs
   when handed each window's exact solution (the floor of any warm start), and what the QP
   reduced to its known active set costs ProxSuite's dense backend.
Every timing is per update the fastest of REPEATS passes over the same sequence (fastest).
--json FILE writes the figures as docs/results.md reads them (tools/results_page.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from proxsuite import proxqp
from uav_common.channels import PAPER_FAULT_NAMES
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig
from uav_fault_estimator.estimation.estimator_settings import (
    EstimatorSettings,
    config_from_settings,
    sensor_overrides,
)
from uav_fault_estimator.estimation.mhe import EstimateResult, MovingHorizonEstimator
from uav_fault_estimator.estimation.noise_model import load_noise_calibration
from uav_fault_estimator.estimation.prediction import residual_sampler
from uav_fault_estimator.estimation.proxqp_solver import ProxQPSolver
from uav_fault_estimator.estimation.qp_problem import WindowQP
from uav_fault_estimator.estimation.reference_solution import ClarabelSolver, solve_reference
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import WIND_PITOT
from uav_fault_estimator.reporting.report import residual_update_period_s
from uav_sim.scenario import TURBULENCE_LEVELS, default_scenario_path, load_scenario
from uav_sim.simulation import Simulation

from benchmarks.qp_solvers import OSQPSolver, PIQPSolver, QuadprogSolver

UPDATE_PERIOD_S = residual_update_period_s()  # residual_node's, as the node publishes
ACTIVE_PCT = 1e-6  # an increment or a bound this close to its limit counts as active [%]
BIG = 1e20  # "no bound" in a ProxSuite row
REPEATS = 7  # passes over the same sequence per timing (see fastest)


def node_config(wind_errors: bool = False) -> EstimatorConfig:
    """mhe_node's defaults; faults only (Q of the air data), or as for an aircraft without
    vanes: with the three wind-error columns, Q of the pitot suite."""
    settings = EstimatorSettings(**sensor_overrides(air_data=True, vanes=not wind_errors))
    noise = load_noise_calibration(vehicle=settings.vehicle)
    config = config_from_settings(settings, noise)
    if wind_errors:
        config = dataclasses.replace(config, q_diag=tuple(
            noise.q_diag(WIND_PITOT, settings.noise_variance_factor)))
    return config


def flown_sequence(samples: int, turbulence: str, vanes: bool = True) -> tuple[np.ndarray, ...]:
    """y (samples, 6), S (samples, 6, 4 + 3), valid (samples, 6) every 0.5 s of the
    default scenario from the first valid residual on, from the core simulator and residual
    generator (residual_node's defaults, the models flying the air data, or without vanes
    the pitot, with the three wind-error columns after the four faults)."""
    scenario = load_scenario(default_scenario_path())
    scenario = dataclasses.replace(
        scenario, wind=dataclasses.replace(scenario.wind, turbulence=turbulence),
        duration_s=max(scenario.duration_s, samples * UPDATE_PERIOD_S + 30.0),
        sensors=dataclasses.replace(scenario.sensors, vanes=vanes),
    )
    simulation = Simulation(scenario)
    sampler = residual_sampler(ResidualSettings())
    rows = []
    sample = simulation.sample()
    while len(rows) < samples:
        result = sampler.update(sample.time_s, sample.state, sample.controls,
                                sample.wind_filtered_ned_mps, sample.air_data)
        # from the first fully valid residual on (the filters settled): every window's
        # QP is then strictly convex, as quadprog requires
        if result is not None and (rows or result.valid.all()):
            rows.append((result.residual, result.sensitivity, result.valid))
        sample = simulation.step()
    return tuple(np.array(column) for column in zip(*rows, strict=True))


def synthetic_sequence(samples: int, faults: int, seed: int) -> tuple[np.ndarray, ...]:
    """Faults ramping monotonically through slowly varying signatures, noisy residuals:
    y (samples, 6), S (samples, 6, p), valid (samples, 6)."""
    rng = np.random.default_rng(seed)
    t = np.arange(samples)[:, None, None]
    base = 0.02 * rng.normal(size=(6, faults))
    base[2, 0::2] += 0.05   # lift-like columns: vertical force and roll
    base[3, 0::2] += 0.6 * np.where(np.arange(0, faults, 2) % 4 == 0, 1.0, -1.0)
    base[0, 1::2] -= 0.0035  # drag-like columns: deceleration and yaw
    base[5, 1::2] += 0.02 * np.where(np.arange(1, faults, 2) % 4 == 1, 1.0, -1.0)
    phase = rng.uniform(0, 2 * np.pi, size=(6, faults))
    s = base * (1.0 + 0.3 * np.sin(2 * np.pi * t / 120.0 + phase))
    start = rng.integers(0, samples // 2, size=faults)
    ramp = rng.integers(20, 80, size=faults)
    size_pct = rng.uniform(5.0, 25.0, size=faults)
    f_pct = size_pct * np.clip((np.arange(samples)[:, None] - start) / ramp, 0.0, 1.0)
    noise_sd = np.sqrt(node_config().q_diag)
    y = np.einsum("tmp,tp->tm", s, f_pct) + noise_sd * rng.normal(size=(samples, 6))
    return y, s, np.ones((samples, 6), dtype=bool)


def synthetic_config(horizon: int, faults: int) -> EstimatorConfig:
    base = node_config()
    return dataclasses.replace(
        base, horizon=horizon, r_diag_pct2=(1.0,) * faults, arrival_floor_pct2=None,
        faults=[dataclasses.replace(base.faults[0], name=f"fault_{k}") for k in range(faults)],
    )


def fastest(run: Callable[..., tuple], *arguments: Any, **keywords: Any) -> tuple:
    """run(*arguments, **keywords) REPEATS times, each returning per-update times [ms]
    first: per update the fastest of its runs, with the last run's other outputs. The work
    of an update is the same in every run (same data, same warm starts), so the fastest is
    its cost without what else shared the machine at that moment: on this 2-core VM the
    median of single passes of the same work moved between 0.18 and 0.41 ms within a
    minute, the faster and slower phases lasting a pass or more, so that three passes in a
    row could all be slow."""
    runs = [run(*arguments, **keywords) for _ in range(REPEATS)]
    return (np.min([result[0] for result in runs], axis=0), *runs[-1][1:])


def full_window_updates(estimator: MovingHorizonEstimator,
                        sequence: tuple[np.ndarray, ...]) -> Iterator[EstimateResult]:
    """Feed the sequence (y, S, valid) to the estimator; yield each update's result once the
    window is full (the estimator's QP then holds that update's H and g)."""
    for index, (y, s, valid) in enumerate(zip(*sequence, strict=True)):
        result = estimator.update(y, s, valid)
        if index >= estimator.config.horizon - 1:
            yield result


def run_estimator(config: EstimatorConfig, sequence: tuple[np.ndarray, ...],
                  keep_qps: bool = False) -> tuple[np.ndarray, list, WindowQP]:
    """Update times [ms] once the window is full, and (H, g, x) of each of those QPs."""
    estimator = MovingHorizonEstimator(config)
    times, snapshots = [], []
    for result in full_window_updates(estimator, sequence):
        times.append(result.update_time_ms)
        if keep_qps:
            problem = estimator.problem
            snapshots.append((problem.H.copy(), problem.g.copy(),
                              estimator._x[problem.f_index].copy()))
    return np.array(times), snapshots, estimator.problem


def load(problem: WindowQP, hessian, gradient: np.ndarray) -> None:
    """Put one update's H and g into the problem (same pattern)."""
    problem.H.data[:] = hessian.data
    problem.g[:] = gradient


def run_solver(solver_class: type, problem: WindowQP, qps: list,
               eps: float | None) -> tuple[np.ndarray, list]:
    """solver_class(problem, eps), a solvers.WindowSolver, on each of the QPs (H, g, _) in
    turn, from the previous solution shifted one stage: its own time per solve [ms] and the
    faults of each solution."""
    solver = solver_class(problem, eps)
    guess = (np.zeros(problem.n_variables), np.zeros(problem.b.size), np.zeros(problem.l.size))
    times, solutions = [], []
    for h, g, _ in qps:
        load(problem, h, g)
        outcome = solver.solve(*guess)
        times.append(outcome.solver_time_ms)
        solutions.append(outcome.x[problem.f_index])
        guess = (outcome.x[problem.x_shift], outcome.y[problem.y_shift],
                 outcome.z[problem.z_shift])
    return np.array(times), solutions


def references(problem: WindowQP, qps: list) -> list[np.ndarray]:
    solutions = []
    for h, g, _ in qps:
        load(problem, h, g)
        solutions.append(solve_reference(problem)[problem.f_index])
    return solutions


def add_row(figures: dict, name: str, times_ms: np.ndarray, deviation: float,
            eps: float | None) -> None:
    """One solver's figures: a table row printed, {median_ms, p99_ms, max_deviation, eps}
    stored as figures[name]."""
    figures[name] = {"median_ms": round(float(np.median(times_ms)), 4),
                     "p99_ms": round(float(np.percentile(times_ms, 99)), 4),
                     "max_deviation": deviation, "eps": eps}
    tolerance = "exact" if eps is None else f"{eps:.0e}"
    print(f"| {name:<36} | {tolerance:>6} | {np.median(times_ms):8.3f} | "
          f"{np.percentile(times_ms, 99):8.3f} | {deviation:9.1e} |")


def faults_only(sequence: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """The sequence with S cut to the four fault columns."""
    y, s, valid = sequence
    return y, s[:, :, : len(PAPER_FAULT_NAMES)], valid


# name: solver class (benchmarks/qp_solvers.py). Each but the exact ones is given the
# loosest tolerance of TOLERANCES that reaches the project's deviation from the reference on
# the first FIT_UPDATES updates (a fair comparison: no solver works harder than the estimate
# needs).
SOLVERS = {
    "piqp (sparse, set up once, update)": PIQPSolver,
    "osqp (update + warm start + polish)": OSQPSolver,
    "quadprog (dense, from scratch)": QuadprogSolver,
    "clarabel (from scratch)": ClarabelSolver,
}
TOLERANCES = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
FIT_UPDATES = 40
ESTIMATOR = "proxsuite: project estimator update"
ACTIVE_SET = "active set: project estimator update"  # solver_method: active_set


def with_method(config: EstimatorConfig, method: str) -> EstimatorConfig | None:
    """config solved by the given SOLVER_METHODS entry; None where that method does not
    apply (the active set with other than monotonic faults)."""
    changed = dataclasses.replace(config, solver=dataclasses.replace(config.solver,
                                                                     method=method))
    try:
        changed.validate()
    except ValueError:
        return None
    return changed


def compare_solvers(config: EstimatorConfig, sequence: tuple[np.ndarray, ...],
                    title: str) -> dict:
    """The project's update and every other solver on the same QPs: a table printed, and
    {name: {median_ms, p99_ms, max_deviation, eps}} returned."""
    times, qps, problem = fastest(run_estimator, config, sequence, keep_qps=True)
    exact = references(problem, qps)
    scale = max(1.0, max(float(np.abs(x).max()) for x in exact))

    def deviation(solutions: list) -> float:
        return max(float(np.abs(x - r).max()) for x, r in zip(solutions, exact,
                                                               strict=False)) / scale

    target = deviation([x for *_, x in qps])
    print(f"\n{title}: N = {config.horizon}, {len(config.faults)} columns, {len(qps)} "
          "updates; deviation: max |x - x_ref| / max(1, max |x_ref|) (reference: Clarabel "
          "at 1e-12, polished)")
    print("| solver                               |    eps | median ms |   p99 ms | deviation |")
    print("|---|---|---|---|---|")
    figures: dict = {}
    add_row(figures, ESTIMATOR, times, target, config.solver.eps_abs)
    active_config = with_method(config, "active_set")
    if active_config is not None:
        active_times, active_qps, _ = fastest(
            run_estimator, active_config, sequence, keep_qps=True)
        add_row(figures, ACTIVE_SET, active_times, deviation([x for *_, x in active_qps]), None)
    for name, solver_class in SOLVERS.items():
        eps = None if solver_class.exact else matched_tolerance(
            solver_class, problem, qps[:FIT_UPDATES], deviation, target)
        solver_times, solutions = fastest(run_solver, solver_class, problem, qps, eps)
        add_row(figures, name, solver_times, deviation(solutions), eps)
    return figures


def matched_tolerance(solver_class: type, problem: WindowQP, qps: list,
                      deviation: Callable[[list], float], target: float) -> float:
    """The loosest of TOLERANCES with which the solver's solutions deviate no more than
    target (the tightest if none does)."""
    for eps in TOLERANCES:
        if deviation(run_solver(solver_class, problem, qps, eps)[1]) <= max(target, 1e-9):
            return eps
    return TOLERANCES[-1]


def scaling(flown: tuple[np.ndarray, ...], updates: int) -> dict:
    """The project's update time against N (flown, p = 4) and p (synthetic, N = 50), by
    ProxSuite and by the active set: a table printed; {"horizon_median_ms",
    "horizon_p99_ms", "fault_count_median_ms", "fault_count_p99_ms"} (ProxSuite) and the
    same keys prefixed "active_set_" returned, each {str(N or p): ms}."""
    figures: dict = {}
    print("\nProject estimator, update time [ms]: N on the flown sequence (4 faults), p on "
          "synthetic ones (seed 1, N = 50)")
    print("| solver | N | p | median | p99 |")
    print("|---|---|---|---|---|")
    cases = [(dataclasses.replace(node_config(), horizon=horizon),
              tuple(a[: horizon + updates] for a in flown), "horizon", horizon)
             for horizon in (25, 50, 100, 200, 400)]
    cases += [(synthetic_config(50, faults), synthetic_sequence(50 + updates, faults, seed=1),
               "fault_count", faults) for faults in (4, 8, 16)]
    for method, prefix in (("proxsuite", ""), ("active_set", "active_set_")):
        for config, sequence, axis, value in cases:
            times, _, _ = fastest(run_estimator, with_method(config, method), sequence)
            print(f"| {method} | {config.horizon} | {len(config.faults)} | "
                  f"{np.median(times):.3f} | {np.percentile(times, 99):.3f} |")
            for statistic, figure in (("median", np.median(times)),
                                      ("p99", np.percentile(times, 99))):
                figures.setdefault(f"{prefix}{axis}_{statistic}_ms", {})[str(value)] = round(
                    float(figure), 4)
    return figures


def anatomy(config: EstimatorConfig, sequence: tuple[np.ndarray, ...]) -> dict:
    """Where the project's update goes (config's N, p; once the window is full): ProxSuite's
    own setup (taking the new H and g) and solve, the rest (Python: arrival cost, data
    terms, refill, the call), iterations and penalty (mu) updates, at the median and over
    the slowest 1 % of updates [ms]. A table printed; the figures returned."""
    estimator = MovingHorizonEstimator(config)
    rows = []
    for result in full_window_updates(estimator, sequence):
        info = estimator.solver.info
        rows.append((result.update_time_ms, info.setup_time * 1e-3, info.solve_time * 1e-3,
                     info.iter, info.mu_updates))
    table = np.array(rows)
    slowest = table[table[:, 0] >= np.percentile(table[:, 0], 99)]
    names = ("update_ms", "proxsuite_setup_ms", "proxsuite_solve_ms", "iterations",
             "penalty_updates")
    figures = {"horizon": config.horizon,
               "median": dict(zip(names, np.round(np.median(table, axis=0), 4).tolist(),
                                  strict=True)),
               "slowest_1pct_mean": dict(zip(names, np.round(slowest.mean(axis=0), 4).tolist(),
                                             strict=True))}
    for label, values in (("median", figures["median"]),
                          ("slowest 1 %", figures["slowest_1pct_mean"])):
        rest = values["update_ms"] - values["proxsuite_setup_ms"] - values["proxsuite_solve_ms"]
        print(f"| {config.horizon} | {label} | {values['update_ms']:.3f} | "
              f"{values['proxsuite_setup_ms']:.3f} | {values['proxsuite_solve_ms']:.3f} | "
              f"{rest:.3f} | {values['iterations']:.1f} | {values['penalty_updates']:.1f} |")
    return figures


def proxsuite_floor(config: EstimatorConfig, sequence: tuple[np.ndarray, ...]) -> dict:
    """What ProxSuite costs on each window's QP when handed its exact solution (primal and
    dual, solved to 1e-10) as the warm start: no warm start can do better, so this call plus
    the update's Python bounds the ProxSuite estimator from below. A line printed; figures
    (the call's median and p99 [ms], ProxSuite's setup and solve, iterations) returned."""
    estimator = MovingHorizonEstimator(config)
    problem = estimator.problem
    tight = ProxQPSolver(problem, dataclasses.replace(config.solver, eps_abs=1e-10,
                                                      max_iter=10_000))
    handed = ProxQPSolver(problem, config.solver)
    rows = []
    for _ in full_window_updates(estimator, sequence):
        exact = tight.solve(estimator._x, estimator._y_dual, estimator._z_dual)
        start = time.perf_counter()
        handed.solve(exact.x, exact.y, exact.z)
        info = handed.info
        rows.append(((time.perf_counter() - start) * 1e3, info.setup_time * 1e-3,
                     info.solve_time * 1e-3, info.iter))
    table = np.array(rows[1:])  # the first call also sets ProxSuite up
    figures = {"call_median_ms": round(float(np.median(table[:, 0])), 4),
               "call_p99_ms": round(float(np.percentile(table[:, 0], 99)), 4),
               "setup_median_ms": round(float(np.median(table[:, 1])), 4),
               "solve_median_ms": round(float(np.median(table[:, 2])), 4),
               "iterations_max": int(table[:, 3].max())}
    print(f"\nProxSuite handed each window's exact solution (N = {config.horizon}): the call "
          f"{figures['call_median_ms']:.3f} ms median (p99 {figures['call_p99_ms']:.3f}; setup "
          f"{figures['setup_median_ms']:.3f}, solve {figures['solve_median_ms']:.3f}), at most "
          f"{figures['iterations_max']} iterations")
    return figures


def active_set_bound(config: EstimatorConfig, sequence: tuple[np.ndarray, ...]) -> dict:
    """What a QP reduced to its active set would cost ProxSuite, for monotonic faults (the
    node's four): each window's solution taken as known (solved to 1e-9), stages whose
    increment is 0 merged and a first stage at its lower bound fixed, the reduced QP solved
    by ProxSuite's dense backend from scratch at the estimator's tolerance (a new QP
    object, init and solve timed; the reduced matrices, plain numpy here, not); and how
    often the previous window's active set, shifted one stage, is this one's, or within it
    (merging no more than this one's active set: what a guess-and-verify reduction needs
    to be exact at once). A line printed; figures returned."""
    eps = config.solver.eps_abs
    estimator = MovingHorizonEstimator(dataclasses.replace(  # the solution, to 1e-9
        config, solver=dataclasses.replace(config.solver, eps_abs=1e-9)))
    problem = estimator.problem
    lower = np.array([fault.lower_pct for fault in config.faults])
    upper = np.array([fault.upper_pct for fault in config.faults])
    times, sizes, deviations, previous, repeated, contained = [], [], [], None, 0, 0
    for result in full_window_updates(estimator, sequence):
        window = result.window_pct
        active = np.vstack([np.diff(window, axis=0) <= ACTIVE_PCT,
                            window[:1] <= lower + ACTIVE_PCT])
        if previous is not None:
            guess = np.vstack([previous[1:-1], previous[-2:]])
            repeated += np.array_equal(guess, active)
            contained += bool(np.all(active[guess]))
        previous = active
        merged, fixed, limits = reduced_form(problem, active, lower, upper)
        hessian = problem.H.toarray()
        reduced_hessian = merged.T @ hessian @ merged
        gradient = merged.T @ (problem.g + hessian @ fixed)
        start = time.perf_counter()
        qp = proxqp.dense.QP(merged.shape[1], 0, limits[0].shape[0])
        qp.settings.eps_abs, qp.settings.eps_rel = eps, 0.0
        qp.init(reduced_hessian, gradient, None, None, *limits)
        qp.solve()
        times.append((time.perf_counter() - start) * 1e3)
        x = fixed + merged @ qp.results.x
        deviations.append(float(np.abs(x[problem.f_index] - window).max()))
        sizes.append(merged.shape[1])
    figures = {"variables_median": float(np.median(sizes)), "variables_max": int(max(sizes)),
               "proxsuite_dense_median_ms": round(float(np.median(times)), 4),
               "proxsuite_dense_p99_ms": round(float(np.percentile(times, 99)), 4),
               "max_deviation": max(deviations), "shifted_active_set_right": repeated,
               "shifted_active_set_within": contained, "windows": len(times) - 1}
    print(f"\nThe QP reduced to its active set (N = {config.horizon}): "
          f"{figures['variables_median']:.0f} variables median (max {figures['variables_max']}, "
          f"full {problem.n_variables}); ProxSuite dense from scratch "
          f"{figures['proxsuite_dense_median_ms']:.3f} ms median, "
          f"{figures['proxsuite_dense_p99_ms']:.3f} p99; deviation from the full QP's "
          f"{figures['max_deviation']:.1e}; the previous window's active set, shifted, right "
          f"in {repeated} of {figures['windows']} windows, within this one's (what a reduction "
          f"may merge) in {contained}")
    return figures


def reduced_form(problem: WindowQP, active: np.ndarray, lower: np.ndarray,
                 upper: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple]:
    """x = fixed + merged @ w for the active set of monotonic faults: active (N, p), rows
    0 … N-2 whether the increment after each stage is 0, row N-1 whether the first stage
    sits at its lower bound. Returns merged (n, r), fixed (n,) and (C, l, u) of the
    reduced QP: a fault's segments non-decreasing, its first at least its lower bound, its
    last at most its upper bound."""
    fixed = np.zeros(problem.n_variables)
    columns, constraints = [], []  # constraints: (coefficients by column, lower, upper)
    for k in range(problem.n_faults):
        segment = np.concatenate([[0], np.cumsum(~active[:-1, k])])
        if active[-1, k]:
            fixed[problem.f_index[segment == 0, k]] = lower[k]
        first = len(columns)
        for j in range(int(active[-1, k]), segment[-1] + 1):
            columns.append(np.isin(np.arange(problem.n_variables),
                                   problem.f_index[segment == j, k]).astype(float))
        if first == len(columns):
            continue
        if not active[-1, k]:
            constraints.append(({first: 1.0}, lower[k], BIG))
        constraints.append(({len(columns) - 1: 1.0}, -BIG, upper[k]))
        constraints += [({a: -1.0, a + 1: 1.0}, 0.0, BIG) for a in range(first, len(columns) - 1)]
    c = np.zeros((len(constraints), len(columns)))
    for row, (coefficients, _, _) in enumerate(constraints):
        c[row, list(coefficients)] = list(coefficients.values())
    bounds = np.array([(low, high) for _, low, high in constraints]).reshape(-1, 2)
    return np.array(columns).T, fixed, (c, bounds[:, 0], bounds[:, 1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--updates", type=int, default=300)
    parser.add_argument("--turbulence", default="light",
                        choices=TURBULENCE_LEVELS)
    parser.add_argument("--json", type=Path, help="write the figures here (docs/design.md)")
    arguments = parser.parse_args()
    flown = flown_sequence(400 + arguments.updates, arguments.turbulence)
    first = tuple(a[: 50 + arguments.updates] for a in flown)
    where = f"Default scenario, {arguments.turbulence} turbulence"
    report = {"estimator": ESTIMATOR, "solvers": compare_solvers(
        node_config(), faults_only(first), f"{where}, the four faults (p = 4)")}
    vaneless = flown_sequence(50 + arguments.updates, arguments.turbulence, vanes=False)
    try:
        report["solvers_with_wind_errors"] = compare_solvers(
            node_config(wind_errors=True), vaneless,
            f"{where} without vanes, four faults and three wind errors (estimate_wind_errors)")
    except RuntimeError as error:  # the reference could not solve it: no deviation to show
        print(f"\nfour faults and three wind errors: not compared ({error})")
    report.update(scaling(faults_only(flown), arguments.updates))
    print("\nWhere the update goes [ms] (p = 4): ProxSuite's setup (new H, g) and solve, the "
          "rest Python")
    print("| N | updates | whole | setup | solve | rest | iterations | penalty updates |")
    print("|---|---|---|---|---|---|---|---|")
    report["anatomy"] = [anatomy(dataclasses.replace(node_config(), horizon=horizon),
                                 tuple(a[: horizon + arguments.updates]
                                       for a in faults_only(flown)))
                         for horizon in (50, 400)]
    report["active_set_bound"] = active_set_bound(node_config(), faults_only(first))
    report["proxsuite_floor"] = proxsuite_floor(node_config(), faults_only(first))
    if arguments.json:
        arguments.json.write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
