"""ProxSuite (ProxQP, sparse backend) on a fixed-pattern WindowQP, with status mapping.

- Sparse backend: the time-major QP's KKT matrix is banded (qp_problem.py).
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
from proxsuite import proxqp

from uav_fault_estimator.estimation.estimator_config import SolverSettings
from uav_fault_estimator.estimation.qp_problem import WindowQP
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



class ProxQPSolver:
    """Holds one ProxSuite sparse QP for a WindowQP; `solve` pushes the new H and g. A
    solvers.WindowSolver that always answers."""

    name = "proxsuite"

    def __init__(self, problem: WindowQP, settings: SolverSettings) -> None:
        self.problem = problem
        qp = proxqp.sparse.QP(problem.n_variables, problem.b.size, problem.l.size)
        self.settings = qp.settings
        self.apply(settings)
        self.settings.nb_iterative_refinement = ITERATIVE_REFINEMENT_STEPS
        self.settings.initial_guess = proxqp.InitialGuess.WARM_START
        self.settings.compute_timings = True
        self.settings.sparse_backend = proxqp.SparseBackend.SparseCholesky
        self._qp = qp
        self._scaled_h = problem.H.copy()
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
        p = self.problem
        scale = p.objective_scale()
        np.multiply(p.H.data, 1.0 / scale, out=self._scaled_h.data)
        scaled_g = p.g / scale
        if self._initialised:
            self._qp.update(H=self._scaled_h, g=scaled_g, mu_in=WARM_START_MU_IN)
        else:
            self._qp.init(
                self._scaled_h,
                scaled_g,
                p.A if p.b.size else None,
                p.b if p.b.size else None,
                p.C if p.l.size else None,
                p.l if p.l.size else None,
                p.u if p.l.size else None,
            )
            self._initialised = True
        self._qp.solve(x0, y0 / scale if y0.size else None, z0 / scale if z0.size else None)
        results = self._qp.results
        status = _STATUS_OF.get(results.info.status, SolveStatus.MAX_ITERATIONS)
        if status is SolveStatus.SOLVED and not np.all(np.isfinite(results.x)):
            status = SolveStatus.INVALID_DATA
        return SolveOutcome(
            x=results.x.copy(),
            y=results.y * scale,
            z=results.z * scale,
            status=status,
            iterations=int(results.info.iter),
            solver_time_ms=results.info.run_time * 1e-3,
            solved_by=self.name,
        )

