"""The one interface every window-QP solver meets: the estimator's (ProxSuite, the active
set), the reference (reference_solution.py: Clarabel, polished) and the benchmark's
comparison solvers (benchmarks/qp_solvers.py).

A solver is built on a WindowQP and, at each call, solves it for the problem's current H
and g from a warm start: the previous window's primal x0 (n,), equality multipliers y0 and
inequality multipliers z0 (rows of C), shifted by one sample. Multipliers are in
ProxSuite's sign convention (H x + g + Aᵀ y + Cᵀ z = 0; z < 0 where a row's lower limit
holds, z > 0 where its upper does), so that one solver can hand over to another.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from uav_fault_estimator.estimation.solve_status import SolveStatus


@dataclass
class SolveOutcome:
    """One solve: primal x, multipliers y (equalities) and z (inequalities), status,
    iterations (rounds of the active-set method), the solver's own run time [ms] and which
    solver (its `name`)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    status: SolveStatus
    iterations: int
    solver_time_ms: float
    solved_by: str


class WindowSolver(Protocol):
    """A solver of one WindowQP's pattern; `name` says which (estimator_config.SOLVER_METHODS
    for the estimator's)."""

    name: str

    def solve(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray) -> SolveOutcome | None:
        """The current window's solution from the guess (x0, y0, z0); None when the solver
        gives up on this window and another should solve it."""
        ...


def first_solution(solvers: tuple[WindowSolver, ...], x0: np.ndarray, y0: np.ndarray,
                   z0: np.ndarray) -> SolveOutcome:
    """The outcome of the first solver in `solvers` that does not give up (the last one
    must always answer)."""
    for solver in solvers:
        outcome = solver.solve(x0, y0, z0)
        if outcome is not None:
            return outcome
    raise ValueError("every solver gave up: the last of a chain must always answer")
