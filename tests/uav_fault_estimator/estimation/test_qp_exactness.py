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
from uav_fault_estimator.estimation.proxqp_solver import LiftedWindow, ProxQPSolver
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


@pytest.mark.timeout(30)
def test_proxsuite_gets_a_stage_diagonal_hessian_and_time_major_rows() -> None:
    """What keeps ProxSuite's factor banded (LiftedWindow): no entry of its H ties two
    stages (a random walk's increments are variables of their own, tied by rows), and its
    rows come stage by stage; a guess goes there and back unchanged."""
    problem = random_problem(CASES["mix_all"], seed=0, bounded=True, lost_fraction=0.1)
    lifted = LiftedWindow(problem)
    assert problem.H[problem.f_index[1:].ravel()][:, problem.f_index[:-1].ravel()].nnz > 0
    stage = np.full(lifted.n_variables, -1)
    stage[problem.f_index] = np.arange(problem.stages)[:, None]
    rows, cols = lifted.H.nonzero()
    coupled = (rows != cols) & ((stage[rows] != stage[cols]) | (stage[rows] < 0))
    assert not coupled.any()
    walks = sum(term.quadratic_weight > 0.0 for term in problem.increment_terms)
    assert lifted.n_variables == problem.n_variables + walks * (problem.stages - 1)
    c = lifted.C.tocsr()
    row_stage = [stage[c.indices[c.indptr[i]:c.indptr[i + 1]]].max() for i in range(c.shape[0])]
    assert np.all(np.diff(row_stage) >= -1)  # a row's latest stage: at most one back
    rng = np.random.default_rng(1)
    x, y, z = (rng.normal(size=size) for size in
               (problem.n_variables, problem.b.size, problem.l.size))
    lifted_x, lifted_z = lifted.lift(x, y, z)
    back = lifted.lower(lifted_x, lifted_z)
    for returned, given in zip(back, (x, y, z), strict=True):
        np.testing.assert_array_equal(returned, given)
