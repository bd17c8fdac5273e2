"""The primal-dual active-set method for monotonic faults: the QP's exact solution and
multipliers (checked against Clarabel and the KKT conditions), the estimator's updates as
ProxSuite's, ProxSuite where it gives up, and the configurations it refuses."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers.synthetic_residuals import SAMPLES, config, sequence
from uav_fault_estimator.estimation.estimator_config import FaultConfig, SolverSettings
from uav_fault_estimator.estimation.fault_models import Monotonic
from uav_fault_estimator.estimation.mhe import MovingHorizonEstimator
from uav_fault_estimator.estimation.monotone_active_set import MonotoneActiveSet
from uav_fault_estimator.estimation.qp_problem import WindowQP, stage_normal_equations
from uav_fault_estimator.estimation.reference_solution import solve_reference
from uav_fault_estimator.estimation.solve_status import SolveStatus

BOUNDS = {"lower_and_upper": (0.0, 6.0), "lower": (0.0, math.inf), "none": (-math.inf, math.inf)}


def monotone_problem(seed: int, bounds: tuple[float, float], stages: int = 40,
                     faults: int = 3) -> WindowQP:
    """A random window of monotonic faults: Gaussian S (6 x p), rising fault paths that
    reach the upper bound of BOUNDS, noisy residuals, a tenth of the channels lost."""
    rng = np.random.default_rng(seed)
    problem = WindowQP(stages, [Monotonic(0.5)] * faults, [bounds] * faults)
    s = rng.normal(size=(stages, 6, faults))
    f = np.cumsum(np.abs(rng.normal(scale=0.3, size=(stages, faults))), axis=0)
    y = np.einsum("tmp,tp->tm", s, f) + rng.normal(scale=0.1, size=(stages, 6))
    weight = np.where(rng.random((stages, 6)) < 0.1, 0.0, 100.0)
    problem.set_data(*stage_normal_equations(y, s, weight), np.eye(faults), np.zeros(faults))
    return problem


def objective(problem: WindowQP, x: np.ndarray) -> float:
    return float(0.5 * x @ (problem.H @ x) + problem.g @ x)


def kkt_residuals(problem: WindowQP, x: np.ndarray, z: np.ndarray) -> tuple[float, ...]:
    """Stationarity |H x + g + Cᵀ z|, primal infeasibility, wrong-signed multipliers and
    complementarity, each the largest over the QP (ProxSuite's sign convention)."""
    row = problem.C @ x
    stationarity = np.abs(problem.H @ x + problem.g + problem.C.T @ z).max()
    infeasible = max(0.0, float(np.max(problem.l - row)), float(np.max(row - problem.u)))
    wrong_sign = max(0.0, float(np.max(np.where(np.isfinite(problem.l), 0.0, -z))),
                     float(np.max(np.where(np.isfinite(problem.u), 0.0, z))))
    slack = np.where(z < 0, row - problem.l, np.where(z > 0, problem.u - row, 0.0))
    slack = np.where(np.isfinite(slack), slack, 0.0)  # a limit that is not there: wrong_sign
    return stationarity, infeasible, wrong_sign, float(np.max(np.abs(z) * slack))


@pytest.mark.timeout(60)
@pytest.mark.parametrize("bounds", sorted(BOUNDS))
def test_active_set_solution_satisfies_kkt_exactly_and_is_clarabels(bounds):
    for seed in range(4):
        problem = monotone_problem(seed, BOUNDS[bounds])
        reference = solve_reference(problem)
        start = reference[problem.f_index] * (1.0 + 0.05 * np.sin(np.arange(40)))[:, None]
        solution = MonotoneActiveSet(problem, max_rounds=50).solve_faults(start)
        assert solution is not None
        deviation = np.abs(solution.x - reference).max() / max(1.0, np.abs(reference).max())
        kkt = kkt_residuals(problem, solution.x, solution.z)
        print(f"{bounds} seed {seed}: {solution.rounds} rounds, deviation {deviation:.1e}, "
              f"KKT {np.array(kkt)}")
        assert max(kkt) <= 1e-9 * problem.objective_scale()
        least = objective(problem, reference)
        assert objective(problem, solution.x) <= least + 1e-10 * abs(least)
        assert deviation <= 1e-5  # the reference's own accuracy (estimation/reference_solution.py)


@pytest.mark.timeout(60)
def test_gives_up_on_a_direction_without_data_and_after_its_rounds():
    problem = monotone_problem(0, BOUNDS["lower"])
    problem.H.data[problem._block_position[-3:]] = 0.0  # the newest 3 stages without data
    problem.g[problem.f_index[-3:]] = 0.0
    reference = solve_reference(problem)[problem.f_index]
    free_end = reference.copy()
    free_end[-3:] += 1.0  # the increment into the data-less stages free: singular
    assert MonotoneActiveSet(problem).solve_faults(free_end) is None
    assert MonotoneActiveSet(problem, max_rounds=1).solve_faults(np.zeros_like(reference)) is None
    reference[-3:] = reference[-4]  # merged with a stage with data: solvable
    merged_end = MonotoneActiveSet(problem).solve_faults(reference)
    assert merged_end is not None


def active_set_estimator(**solver: object) -> MovingHorizonEstimator:
    return MovingHorizonEstimator(dataclasses.replace(
        config(), solver=SolverSettings(method="active_set", **solver)))


@pytest.mark.timeout(60)
def test_estimator_updates_equal_proxsuites_and_fall_back_to_it():
    y, s, f = sequence()
    tight = MovingHorizonEstimator(dataclasses.replace(
        config(), solver=SolverSettings(eps_abs=1e-10, max_iter=10_000)))
    proxsuite = MovingHorizonEstimator(config())
    fast, giving_up = active_set_estimator(), active_set_estimator()
    giving_up.active_set.max_rounds = 0  # every window to ProxSuite
    worst, rounds, filling = 0.0, [], []
    for k in range(SAMPLES):
        expected, usual = tight.update(y[k], s[k]), proxsuite.update(y[k], s[k])
        result, fallback = fast.update(y[k], s[k]), giving_up.update(y[k], s[k])
        assert result.status is fallback.status is expected.status
        if expected.status is SolveStatus.SOLVED:
            assert fallback.solved_by == "proxsuite"
            if k < fast.config.horizon - 1:  # stages without data yet: may be flat
                filling.append(result.solved_by)
            else:
                assert result.solved_by == "active_set"
                rounds.append(result.iterations)
                worst = max(worst, float(np.abs(result.window_pct - expected.window_pct).max()))
            assert fallback.window_pct == pytest.approx(usual.window_pct, abs=1e-12)
    print(f"largest window difference {worst:.1e} %, rounds {np.bincount(rounds)}; while the "
          f"window fills, ProxSuite in {filling.count('proxsuite')} of {len(filling)}; "
          f"final {result.fault_pct} % for seeded {f[-1]} %")
    assert worst <= 1e-6
    assert result.fault_pct == pytest.approx(f[-1], abs=0.5)


@pytest.mark.timeout(30)
def test_refused_for_other_models_unknown_methods_and_at_run_time():
    random_walk = dataclasses.replace(config(), faults=[
        *config().faults[:1], FaultConfig("drift", "random_walk", {"sigma": 0.1})],
        solver=SolverSettings(method="active_set"))
    with pytest.raises(ValueError, match="active_set solver method needs every estimated"):
        MovingHorizonEstimator(random_walk)
    with pytest.raises(ValueError, match="solver method must be one of proxsuite, active_set"):
        MovingHorizonEstimator(dataclasses.replace(config(), solver=SolverSettings(
            method="fastest")))
    estimator = MovingHorizonEstimator(config())
    with pytest.raises(ValueError, match=r"solver\.method shapes"):
        estimator.retune(dataclasses.replace(config(), solver=SolverSettings(
            method="active_set")))
