"""The exact solution of an estimator window's QP, to check the estimator's answers
against (the tests, benchmarks/bench_mhe.py): Clarabel (interior point) at its tightest
tolerances, then polished. The estimator never calls this module; it depends on clarabel,
a test and benchmark dependency only.

Why the reference is polished: on these problems many inequalities are active but
degenerate (a flat monotonic fault), and an interior point method approaches such a
solution slowly; even at 1e-12 tolerances Clarabel stayed up to 1e-5 away from the optimum.
Polishing takes the constraints Clarabel found active, solves the equality-constrained KKT
system directly, and keeps the result only if it is feasible and no worse in objective.
Multipliers are returned in ProxSuite's convention (solvers.py).
"""

from __future__ import annotations

import time

import clarabel
import numpy as np
import scipy.sparse as sp

from uav_fault_estimator.estimation.qp_problem import WindowQP
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_fault_estimator.estimation.solvers import SolveOutcome

ACTIVE_SLACK = 1e-7
FEASIBILITY_TOLERANCE = 1e-9
REFERENCE_TOLERANCES = (1e-12, 1e-11, 1e-10)  # Clarabel's, tightest first


def one_sided(problem: WindowQP) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray, np.ndarray]:
    """l <= Cx <= u as G x <= h: G, h, and the rows of C that have a finite upper limit
    (first in G) and a finite lower limit (negated, after them)."""
    upper_rows = np.flatnonzero(np.isfinite(problem.u))
    lower_rows = np.flatnonzero(np.isfinite(problem.l))
    matrix = sp.vstack([problem.C[upper_rows], -problem.C[lower_rows]], format="csc")
    rhs = np.concatenate([problem.u[upper_rows], -problem.l[lower_rows]])
    return matrix, rhs, upper_rows, lower_rows


def two_sided(problem: WindowQP, upper: np.ndarray, lower: np.ndarray,
               upper_rows: np.ndarray, lower_rows: np.ndarray) -> np.ndarray:
    """Multipliers of C's rows in ProxSuite's convention from nonnegative ones of its upper
    limits (`upper`, on upper_rows) and lower limits (`lower`, on lower_rows)."""
    z = np.zeros(problem.l.size)
    z[upper_rows] += upper
    z[lower_rows] -= lower
    return z


def clarabel_form(problem: WindowQP) -> tuple:
    """(P, q, A, b, cones) of the QP in Clarabel's form: min ½ x'Px + q'x, s = b - Ax in
    the cones. Ax = b becomes zero-cone rows; l <= Cx <= u the nonnegative-cone rows
    u - Cx >= 0 (finite u) and Cx - l >= 0 (finite l)."""
    inequality, inequality_rhs, _, _ = one_sided(problem)
    constraint = sp.vstack([problem.A, inequality], format="csc")
    rhs = np.concatenate([problem.b, inequality_rhs])
    cones = [clarabel.ZeroConeT(problem.b.size)] if problem.b.size else []
    if inequality_rhs.size:
        cones.append(clarabel.NonnegativeConeT(inequality_rhs.size))
    return sp.triu(problem.H, format="csc"), problem.g, constraint, rhs, cones


class ClarabelSolver:
    """Clarabel (interior point) from scratch on each window: its interface has no update or
    warm start, so each solve builds everything from the WindowQP, and all of it is timed:
    Clarabel's form of the QP (clarabel_form), its set-up and its solve. Its gap and
    feasibility tolerances at `tolerance`, more in `settings`; `solution` is its last
    answer."""

    name = "clarabel"
    exact = False

    def __init__(self, problem: WindowQP, tolerance: float) -> None:
        self.problem = problem
        _, _, self._upper_rows, self._lower_rows = one_sided(problem)
        self.settings = clarabel.DefaultSettings()
        self.settings.verbose = False
        self.settings.tol_gap_abs = self.settings.tol_gap_rel = tolerance
        self.settings.tol_feas = tolerance
        self.solution = None

    def solve(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray) -> SolveOutcome:
        p = self.problem
        start = time.perf_counter()
        solver = clarabel.DefaultSolver(*clarabel_form(p), self.settings)
        self.solution = solution = solver.solve()
        elapsed_ms = (time.perf_counter() - start) * 1e3
        z = np.asarray(solution.z)
        upper_count = self._upper_rows.size
        inequality = z[p.b.size :]
        return SolveOutcome(
            x=np.asarray(solution.x), y=z[: p.b.size],
            z=two_sided(p, inequality[:upper_count], inequality[upper_count:],
                         self._upper_rows, self._lower_rows),
            status=_CLARABEL_STATUS.get(str(solution.status), SolveStatus.MAX_ITERATIONS),
            iterations=int(solution.iterations), solver_time_ms=elapsed_ms, solved_by=self.name)


_CLARABEL_STATUS = {
    "Solved": SolveStatus.SOLVED,
    "PrimalInfeasible": SolveStatus.INFEASIBLE,
    "DualInfeasible": SolveStatus.INFEASIBLE,
    "AlmostPrimalInfeasible": SolveStatus.INFEASIBLE,
    "AlmostDualInfeasible": SolveStatus.INFEASIBLE,
}


def solve_reference(problem: WindowQP) -> np.ndarray:
    """The QP's solution x from Clarabel, polished; RuntimeError if Clarabel fails.

    Clarabel runs at the tightest of REFERENCE_TOLERANCES (its KKT ratio tolerance too)
    that it reports as Solved.
    """
    no_guess = (np.zeros(problem.n_variables), np.zeros(problem.b.size),
                np.zeros(problem.l.size))
    for tolerance in REFERENCE_TOLERANCES:
        solver = ClarabelSolver(problem, tolerance)
        solver.settings.tol_ktratio = tolerance
        outcome = solver.solve(*no_guess)
        if outcome.status is SolveStatus.SOLVED:
            break
    else:
        raise RuntimeError(f"Clarabel did not solve the reference QP: {solver.solution.status}")
    inequality, inequality_rhs, _, _ = one_sided(problem)
    x = outcome.x
    slack = inequality_rhs - inequality @ x
    active = slack <= ACTIVE_SLACK * (1.0 + np.abs(inequality_rhs))
    polished, multipliers = _solve_equality_qp(
        problem,
        sp.vstack([problem.A, inequality[active]]),
        np.concatenate([problem.b, inequality_rhs[active]]),
    )
    # Optimal only if feasible and the active inequalities push the right way (KKT).
    optimal = (
        np.all(inequality @ polished <= inequality_rhs + FEASIBILITY_TOLERANCE)
        and np.all(np.abs(problem.A @ polished - problem.b) <= FEASIBILITY_TOLERANCE)
        and np.all(multipliers[problem.b.size :] >= -FEASIBILITY_TOLERANCE)
    )
    return polished if optimal else x


def _solve_equality_qp(
    problem: WindowQP, matrix: sp.spmatrix, rhs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """argmin ½xᵀHx + gᵀx s.t. matrix·x = rhs, and its multipliers, through the KKT
    system in least squares (active rows may be linearly dependent; x is still unique)."""
    n = problem.n_variables
    kkt = sp.bmat([[problem.H, matrix.T], [matrix, None]]).toarray()
    solution = np.linalg.lstsq(kkt, np.concatenate([-problem.g, rhs]), rcond=None)[0]
    return solution[:n], solution[n:]
