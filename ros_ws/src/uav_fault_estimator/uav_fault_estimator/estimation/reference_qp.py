"""Independent reference solution of a WindowQP with Clarabel (interior point), polished.

Used by the tests and the benchmark to check ProxSuite's answers; the estimator itself
never imports it, so Clarabel is a test/benchmark dependency only.

Why polish: on these problems many inequalities are active but degenerate (a flat
monotonic fault), and an interior point method approaches such a solution slowly; even at
1e-12 tolerances Clarabel stayed up to 1e-5 away from the optimum. Polishing takes the
constraints Clarabel found active, solves the equality-constrained KKT system directly,
and keeps the result only if it is feasible and no worse in objective.
"""

from __future__ import annotations

import clarabel
import numpy as np
import scipy.sparse as sp

from uav_fault_estimator.estimation.qp_problem import WindowQP

ACTIVE_SLACK = 1e-7
FEASIBILITY_TOLERANCE = 1e-9


def clarabel_form(problem: WindowQP) -> tuple:
    """(P, q, A, b, cones) of the QP in Clarabel's form: min 1/2 x'Px + q'x, s = b - Ax in
    the cones. Ax = b becomes zero-cone rows; l <= Cx <= u the nonnegative-cone rows
    u - Cx >= 0 (finite u) and Cx - l >= 0 (finite l)."""
    inequality, inequality_rhs = _one_sided(problem)
    constraint = sp.vstack([problem.A, inequality], format="csc")
    rhs = np.concatenate([problem.b, inequality_rhs])
    cones = [clarabel.ZeroConeT(problem.b.size)] if problem.b.size else []
    if inequality_rhs.size:
        cones.append(clarabel.NonnegativeConeT(inequality_rhs.size))
    return sp.triu(problem.H, format="csc"), problem.g, constraint, rhs, cones


def _one_sided(problem: WindowQP) -> tuple[sp.csc_matrix, np.ndarray]:
    """l <= Cx <= u as G x <= h."""
    upper_rows, lower_rows = np.isfinite(problem.u), np.isfinite(problem.l)
    matrix = sp.vstack([problem.C[upper_rows], -problem.C[lower_rows]], format="csc")
    return matrix, np.concatenate([problem.u[upper_rows], -problem.l[lower_rows]])


def solve_reference(problem: WindowQP) -> np.ndarray:
    """The QP's solution x from Clarabel, polished; RuntimeError if Clarabel fails.

    Clarabel runs at the tightest of 1e-12, 1e-11, 1e-10 that it reports as Solved.
    """
    inequality, inequality_rhs = _one_sided(problem)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    for tolerance in (1e-12, 1e-11, 1e-10):
        settings.tol_gap_abs = settings.tol_gap_rel = tolerance
        settings.tol_feas = settings.tol_ktratio = tolerance
        solution = clarabel.DefaultSolver(*clarabel_form(problem), settings).solve()
        if str(solution.status) == "Solved":
            break
    else:
        raise RuntimeError(f"Clarabel did not solve the reference QP: {solution.status}")
    x = np.asarray(solution.x)
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
