"""Batch MAP fault estimator: all data so far (evolving-faults paper, section VI).

Faults are constant within each update cycle of M samples, f(t) = F(tau) for
M (tau - 1) < t <= M tau (eq. 16-18), so cycle tau's data term is the sum of its samples'
normal equations, and the QP has one stage per cycle: the same WindowQP and fault models
as the moving-horizon estimator, grown by one stage per completed cycle and warm-started
from the previous cycle's solution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uav_fault_estimator.estimation.estimator_config import EstimatorConfig
from uav_fault_estimator.estimation.proxqp_solver import ProxQPSolver
from uav_fault_estimator.estimation.qp_problem import sample_normal_equations
from uav_fault_estimator.estimation.solve_status import SolveStatus


@dataclass(frozen=True)
class BatchEstimate:
    """F_tau (tau, p): the estimate of every completed cycle, oldest first [%]."""

    cycles_pct: np.ndarray
    status: SolveStatus
    iterations: int


class BatchEstimator:
    """Accumulates residual samples into cycles of `cycle_samples` and solves on demand."""

    def __init__(self, config: EstimatorConfig, cycle_samples: int) -> None:
        config.validate()
        if cycle_samples < 1:
            raise ValueError(f"an update cycle needs at least one sample, got {cycle_samples}")
        self.config = config
        self.cycle_samples = cycle_samples
        p = len(config.faults)
        self._gram: list[np.ndarray] = []      # per completed cycle (p, p)
        self._linear: list[np.ndarray] = []    # per completed cycle (p,)
        self._open = (np.zeros((p, p)), np.zeros(p), 0)
        self._last = BatchEstimate(np.zeros((0, p)), SolveStatus.WAITING, 0)

    @property
    def cycles(self) -> int:
        """Completed update cycles."""
        return len(self._gram)

    def add(self, y: np.ndarray, s: np.ndarray, valid: np.ndarray | None = None) -> None:
        """One residual sample: y (m,), s (m, p) [unit / %], valid (m,) rows to use.

        Non-finite rows are left out like invalid ones.
        """
        p = len(self.config.faults)
        term = sample_normal_equations(y, s, valid, self.config.q_inv, p)
        gram, linear = term.gram, term.linear
        open_gram, open_linear, count = self._open
        self._open = (open_gram + gram, open_linear + linear, count + 1)
        if count + 1 == self.cycle_samples:
            self._gram.append(self._open[0])
            self._linear.append(self._open[1])
            self._open = (np.zeros((p, p)), np.zeros(p), 0)

    def estimate(self) -> BatchEstimate:
        """Solve over every completed cycle; the last good estimate if the solve fails."""
        if not self._gram:
            return self._last
        config = self.config
        problem = config.window_qp(self.cycles)
        problem.set_data(np.array(self._gram), np.array(self._linear), np.diag(config.r_inv),
                         config.prior_pct)
        guess = np.zeros(problem.n_variables)
        previous = self._last.cycles_pct
        guess[problem.f_index] = config.prior_pct
        guess[problem.f_index[: len(previous)]] = previous
        if len(previous):
            guess[problem.f_index[len(previous):]] = previous[-1]
        outcome = ProxQPSolver(problem, config.solver).solve(
            guess, np.zeros(problem.b.size), np.zeros(problem.l.size)
        )
        if outcome.status is SolveStatus.SOLVED:
            self._last = BatchEstimate(outcome.x[problem.f_index], outcome.status,
                                       outcome.iterations)
            return self._last
        return BatchEstimate(self._last.cycles_pct, outcome.status, outcome.iterations)
