"""ProxSuite's solution of the fault QP matches Clarabel's to 1e-6 relative."""

from __future__ import annotations

import math

import numpy as np
import pytest
from uav_fault_estimator.estimation.estimator_config import SolverSettings
from uav_fault_estimator.estimation.fault_models import (
    Constant,
    LaplacianIncrements,
    Monotonic,
    RandomWalk,
    UniformIncrements,
)
from uav_fault_estimator.estimation.proxqp_solver import ProxQPSolver
from uav_fault_estimator.estimation.qp_problem import WindowQP, stage_normal_equations
from uav_fault_estimator.estimation.reference_solution import solve_reference
from uav_fault_estimator.estimation.solve_status import SolveStatus

TIGHT = SolverSettings(eps_abs=1e-9, eps_rel=0.0, max_iter=10_000)
FREE = (-math.inf, math.inf)

CASES = {
    "monotonic_up": [Monotonic(0.5)] * 3,
    "monotonic_down": [Monotonic(0.5, increasing=False)] * 2,
    "random_walk": [RandomWalk(0.3)] * 2,
    "random_walk_ar": [RandomWalk(0.3, coefficient=0.9)] * 2,
    "uniform": [UniformIncrements(0.2)] * 2,
    "laplacian": [LaplacianIncrements(0.2)] * 2,
    "constant": [Constant()] * 2,
    "mix_all": [
        Monotonic(0.5),
        RandomWalk(0.3, coefficient=0.95),
        UniformIncrements(0.4),
        LaplacianIncrements(0.2),
        Constant(),
        Monotonic(0.5, increasing=False),
    ],
    "paper_rocket": [Monotonic(1.0), Monotonic(1.0), Constant(), RandomWalk(0.5)],
}


def random_problem(models: list, seed: int, bounded: bool, lost_fraction: float) -> WindowQP:
    """A random window: Gaussian S (6xp), a random fault path, noisy residuals, some
    channels lost; bounds [-2, 20] % on every fault when `bounded`."""
    rng = np.random.default_rng(seed)
    stages, m, p = 40, 6, len(models)
    bounds = [(-2.0, 20.0) if bounded else FREE] * p
    problem = WindowQP(stages, models, bounds)
    s = rng.normal(size=(stages, m, p))
    f = np.cumsum(np.abs(rng.normal(scale=0.3, size=(stages, p))), axis=0)
    noise_sd = 0.1
    y = np.einsum("tmp,tp->tm", s, f) + rng.normal(scale=noise_sd, size=(stages, m))
    weight = np.where(rng.random((stages, m)) < lost_fraction, 0.0, 1.0 / noise_sd**2)
    gram, linear = stage_normal_equations(y, s, weight)
    problem.set_data(gram, linear, np.diag(np.full(p, 0.5)), rng.normal(size=p))
    return problem


def relative_deviation(problem: WindowQP) -> tuple[float, int, SolveStatus]:
    """max |x_proxsuite - x_clarabel| / max |x_clarabel| over the fault variables."""
    reference = solve_reference(problem)
    solver = ProxQPSolver(problem, TIGHT)
    outcome = solver.solve(
        np.zeros(problem.n_variables), np.zeros(problem.b.size), np.zeros(problem.l.size)
    )
    f_index = problem.f_index
    scale = max(1.0, float(np.abs(reference[f_index]).max()))
    deviation = float(np.abs(outcome.x[f_index] - reference[f_index]).max()) / scale
    return deviation, outcome.iterations, outcome.status


@pytest.mark.slow
@pytest.mark.timeout(60)
@pytest.mark.parametrize("bounded", [False, True])
@pytest.mark.parametrize("case", sorted(CASES))
def test_proxsuite_matches_clarabel(case: str, bounded: bool) -> None:
    worst = 0.0
    for seed in range(3):
        deviation, iterations, status = relative_deviation(
            random_problem(CASES[case], seed, bounded, lost_fraction=0.1)
        )
        assert status is SolveStatus.SOLVED
        worst = max(worst, deviation)
        print(f"{case} bounded={bounded} seed={seed}: rel dev {deviation:.2e}, {iterations} it")
    assert worst <= 1e-6
