"""ProxSuite (ProxQP, sparse backend) on a fixed-pattern WindowQP, with status mapping.

- Sparse backend: the time-major QP's KKT matrix is banded (qp_problem.py), as ProxSuite
  takes it (LiftedWindow).
- The objective goes in scaled to a unit mean Hessian diagonal (`WindowQP.objective_scale`),
  so that the absolute tolerance means the same whatever the residual units and noise levels.
- Warm start from the shifted previous primal and dual solution, with a small initial
  penalty mu_in (WARM_START_MU_IN) on updates: the guess is close, so constraints are
  enforced stiffly at once and most updates need no penalty update (a refactorisation
  whose cost grows faster than N).
- Ruiz preconditioning computed on the first window only; two iterative refinement steps.
Why each, as measured: docs/estimator.md.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from proxsuite import proxqp

from uav_fault_estimator.estimation.estimator_config import SolverSettings
from uav_fault_estimator.estimation.qp_problem import WindowQP, pattern_positions
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_fault_estimator.estimation.solvers import SolveOutcome

WARM_START_MU_IN = 1e-5
ITERATIVE_REFINEMENT_STEPS = 2


_STATUS_OF = {
    proxqp.QPSolverOutput.PROXQP_SOLVED: SolveStatus.SOLVED,
    proxqp.QPSolverOutput.PROXQP_MAX_ITER_REACHED: SolveStatus.MAX_ITERATIONS,
    proxqp.QPSolverOutput.PROXQP_PRIMAL_INFEASIBLE: SolveStatus.INFEASIBLE,
    proxqp.QPSolverOutput.PROXQP_DUAL_INFEASIBLE: SolveStatus.INFEASIBLE,
}


class LiftedWindow:
    """A WindowQP as ProxSuite's sparse factorisation needs it to stay banded; the same
    solution.

    ProxSuite eliminates every variable before the constraint rows, and the rows in the
    order given, equalities before inequalities. A quadratic increment cost ½ w (f(τ+1) -
    a f(τ))² (a random walk, the wind errors' Gauss-Markov steps) couples the stages
    through H, and the rows' Schur complement then fills in densely: on the vane-less
    window a solve that needs no iteration took 1.7 ms. Here each such increment is a
    variable δ(τ) with the cost ½ w δ² and the row f(τ+1) - a f(τ) - δ(τ) = 0, so that H is
    block diagonal by stage, and all rows go in as rows of C (equalities with equal limits)
    in time-major order (0.14 ms). Variables: the WindowQP's n, then the increments.
    """

    def __init__(self, problem: WindowQP) -> None:
        n, stages = problem.n_variables, problem.stages
        later, earlier, coefficient, weight, increment_stage = [], [], [], [], []
        for k, term in enumerate(problem.increment_terms):
            if term.quadratic_weight > 0.0:
                later.append(problem.f_index[1:, k])
                earlier.append(problem.f_index[:-1, k])
                coefficient.append(np.full(stages - 1, term.coefficient))
                weight.append(np.full(stages - 1, term.quadratic_weight))
                increment_stage.append(np.arange(stages - 1))
        self._later, self._earlier = _joined(later, int), _joined(earlier, int)
        self._coefficient, self._weight = _joined(coefficient), _joined(weight)
        increments = self._later.size
        self.n_variables = n + increments
        delta = n + np.arange(increments)
        self.problem = problem

        # H: the WindowQP's entries within a stage, less the increments' curvature (all of
        # the WindowQP's model curvature is its quadratic increment costs), and w on every
        # increment
        stage_of = np.full(n, -1)
        stage_of[problem.f_index] = np.arange(stages)[:, None]
        h = problem.H
        h_cols = np.repeat(np.arange(n), np.diff(h.indptr))
        self._kept = np.flatnonzero(stage_of[h.indices] == stage_of[h_cols])
        self._kept_model = problem.model_curvature[self._kept]
        rows = np.concatenate([h.indices[self._kept], delta])
        cols = np.concatenate([h_cols[self._kept], delta])
        self.H = sp.csc_matrix((np.ones(rows.size), (rows, cols)),
                               shape=(self.n_variables, self.n_variables))
        self.H.sort_indices()
        self._kept_position = pattern_positions(self.H, rows[: self._kept.size],
                                                cols[: self._kept.size])
        self.H.data[pattern_positions(self.H, delta, delta)] = self._weight

        # rows: [A; C; increments], time-major
        ties = sp.csr_matrix(
            (np.concatenate([np.ones(increments), -self._coefficient, -np.ones(increments)]),
             (np.tile(np.arange(increments), 3),
              np.concatenate([self._later, self._earlier, delta]))),
            shape=(increments, self.n_variables))
        given = sp.vstack([problem.A, problem.C], format="csr")
        given.resize(given.shape[0], self.n_variables)
        self.order = np.argsort(
            np.concatenate([problem.row_stages, _joined(increment_stage, int)]), kind="stable")
        self.C = sp.vstack([given, ties], format="csr")[self.order].tocsc()
        self.l = np.concatenate([problem.b, problem.l, np.zeros(increments)])[self.order]
        self.u = np.concatenate([problem.b, problem.u, np.zeros(increments)])[self.order]
        self._equalities, self._given_rows = problem.b.size, given.shape[0]

    def refill(self) -> None:
        """H's data from the WindowQP's current H."""
        self.H.data[self._kept_position] = (self.problem.H.data[self._kept]
                                            - self._kept_model)

    def lift(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
        """A WindowQP guess (x, A's and C's multipliers) in this form: the increments of x,
        and their rows' multipliers w δ (where δ is optimal, stationarity in δ gives it)."""
        increments = x0[self._later] - self._coefficient * x0[self._earlier]
        return (np.concatenate([x0, increments]),
                np.concatenate([y0, z0, self._weight * increments])[self.order])

    def lower(self, x: np.ndarray, z: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A solution in this form as the WindowQP's: x, A's and C's multipliers."""
        stacked = np.empty(self.order.size)
        stacked[self.order] = z
        return (x[: self.problem.n_variables], stacked[: self._equalities],
                stacked[self._equalities: self._given_rows])


def _joined(parts: list[np.ndarray], dtype: type = float) -> np.ndarray:
    """The parts end to end; an empty array of dtype when there are none."""
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)


class ProxQPSolver:
    """Holds one ProxSuite sparse QP for a WindowQP (as a LiftedWindow); `solve` pushes the
    new H and g. A solvers.WindowSolver that always answers."""

    name = "proxsuite"

    def __init__(self, problem: WindowQP, settings: SolverSettings) -> None:
        self.problem = problem
        self._lifted = LiftedWindow(problem)
        qp = proxqp.sparse.QP(self._lifted.n_variables, 0, self._lifted.order.size)
        self.settings = qp.settings
        self.apply(settings)
        self.settings.nb_iterative_refinement = ITERATIVE_REFINEMENT_STEPS
        self.settings.initial_guess = proxqp.InitialGuess.WARM_START
        self.settings.compute_timings = True
        self.settings.sparse_backend = proxqp.SparseBackend.SparseCholesky
        self._qp = qp
        self._scaled_h = self._lifted.H.copy()
        self._scaled_g = np.zeros(self._lifted.n_variables)
        self._initialised = False

    @property
    def info(self) -> proxqp.Info:
        """ProxSuite's own account of the last solve (iterations, penalty updates, setup and
        solve time [µs]): for profiling."""
        return self._qp.results.info

    def apply(self, settings: SolverSettings) -> None:
        """Tolerances and iteration cap from the next solve on."""
        self.settings.eps_abs = settings.eps_abs
        self.settings.eps_rel = settings.eps_rel
        self.settings.max_iter = settings.max_iter

    def solve(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray) -> SolveOutcome:
        """Solve with the problem's current H and g from the guess (x0, y0, z0).

        The objective goes to ProxSuite divided by the mean of H's diagonal, so that its
        data part is of order one whatever the residual units and noise levels: the
        absolute tolerances then mean the same on every problem, and the penalties of the
        augmented Lagrangian meet a Hessian of a known scale. The solution is unchanged;
        multipliers scale with the objective and are converted both ways. The
        preconditioner is computed at the first call only (same pattern, same scale).
        """
        p, lifted = self.problem, self._lifted
        scale = p.objective_scale()
        lifted.refill()
        np.multiply(lifted.H.data, 1.0 / scale, out=self._scaled_h.data)
        self._scaled_g[: p.n_variables] = p.g / scale
        if self._initialised:
            self._qp.update(H=self._scaled_h, g=self._scaled_g, mu_in=WARM_START_MU_IN)
        else:
            rows = lifted.order.size > 0
            self._qp.init(self._scaled_h, self._scaled_g, None, None,
                          lifted.C if rows else None, lifted.l if rows else None,
                          lifted.u if rows else None)
            self._initialised = True
        x_guess, z_guess = lifted.lift(x0, y0, z0)
        self._qp.solve(x_guess, None, z_guess / scale if z_guess.size else None)
        results = self._qp.results
        status = _STATUS_OF.get(results.info.status, SolveStatus.MAX_ITERATIONS)
        if status is SolveStatus.SOLVED and not np.all(np.isfinite(results.x)):
            status = SolveStatus.INVALID_DATA
        x, y, z = lifted.lower(results.x, results.z * scale)
        return SolveOutcome(
            x=x.copy(), y=y, z=z, status=status,
            iterations=int(results.info.iter),
            solver_time_ms=results.info.run_time * 1e-3,
            solved_by=self.name,
        )
