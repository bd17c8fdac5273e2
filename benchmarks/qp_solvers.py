"""Reference and comparison solvers of a WindowQP: Clarabel, OSQP, PIQP and quadprog, each a
solvers.WindowSolver, and `solve_reference`, the exact solution the tests and the benchmark
check the estimator's answers against. The estimator never imports this module, so these
four are test and benchmark dependencies only.

Each solver is built on one WindowQP and a tolerance (quadprog: exact, none); each `solve`
reads the problem's current H and g. An outcome's `solver_time_ms` is the solver's own work
on that window, wall clock, and what it covers is part of each benchmark figure:
- OSQP and PIQP keep the QP: its fixed pattern (A, b, C, l, u, H's sparsity) goes into
  their form once, at construction, their set-up at the first solve; timed are the update
  of H and g and the solve, not the making of H's upper triangle, their input form.
- quadprog starts from scratch: its constraint rows are made at construction; timed are the
  dense copy of H it needs and its solve.
- Clarabel starts from scratch from the WindowQP: timed are its form of the QP
  (clarabel_form), its set-up and its solve.
None uses the guess (x0, y0, z0): OSQP warm-starts from its own previous solution, the
others have no warm start. Multipliers are returned in ProxSuite's convention (solvers.py).

Why the reference is polished: on these problems many inequalities are active but
degenerate (a flat monotonic fault), and an interior point method approaches such a
solution slowly; even at 1e-12 tolerances Clarabel stayed up to 1e-5 away from the optimum.
Polishing takes the constraints Clarabel found active, solves the equality-constrained KKT
system directly, and keeps the result only if it is feasible and no worse in objective.
"""

from __future__ import annotations

import time

import clarabel
import numpy as np
import osqp
import piqp
import quadprog
import scipy.sparse as sp
from uav_fault_estimator.estimation.qp_problem import WindowQP
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_fault_estimator.estimation.solvers import SolveOutcome

ACTIVE_SLACK = 1e-7
FEASIBILITY_TOLERANCE = 1e-9
REFERENCE_TOLERANCES = (1e-12, 1e-11, 1e-10)  # Clarabel's, tightest first
OSQP_MAX_ITERATIONS = 20_000


class _UpperTriangle:
    """The upper triangle of a fixed-pattern sparse H (canonical CSC), the input OSQP and
    PIQP take: its pattern worked out once, `of` refills it from H's current data."""

    def __init__(self, hessian: sp.csc_matrix) -> None:
        if not hessian.has_canonical_format:
            raise ValueError("H must be in canonical CSC form (sorted, each entry once)")
        marker = hessian.copy()
        marker.data = np.arange(1.0, hessian.nnz + 1.0)  # entry i + 1 marks H.data[i]
        self.matrix = sp.triu(marker, format="csc")
        self._source = self.matrix.data.astype(int) - 1

    def of(self, hessian: sp.csc_matrix) -> sp.csc_matrix:
        """The upper triangle of `hessian` (same pattern), in a matrix reused across calls."""
        np.take(hessian.data, self._source, out=self.matrix.data)
        return self.matrix


def _one_sided(problem: WindowQP) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray, np.ndarray]:
    """l <= Cx <= u as G x <= h: G, h, and the rows of C that have a finite upper limit
    (first in G) and a finite lower limit (negated, after them)."""
    upper_rows = np.flatnonzero(np.isfinite(problem.u))
    lower_rows = np.flatnonzero(np.isfinite(problem.l))
    matrix = sp.vstack([problem.C[upper_rows], -problem.C[lower_rows]], format="csc")
    rhs = np.concatenate([problem.u[upper_rows], -problem.l[lower_rows]])
    return matrix, rhs, upper_rows, lower_rows


def _two_sided(problem: WindowQP, upper: np.ndarray, lower: np.ndarray,
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
    inequality, inequality_rhs, _, _ = _one_sided(problem)
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
        _, _, self._upper_rows, self._lower_rows = _one_sided(problem)
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
            z=_two_sided(p, inequality[:upper_count], inequality[upper_count:],
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


class OSQPSolver:
    """OSQP (ADMM) on the fixed pattern, set up at the first solve from that window; then
    each window update(q, Px) and solve, warm-started from its own previous solution and
    polished; eps_abs at `tolerance`, eps_rel 0. Ax = b and l <= Cx <= u as its rows."""

    name = "osqp"
    exact = False

    def __init__(self, problem: WindowQP, tolerance: float) -> None:
        self.problem = problem
        self.tolerance = tolerance
        self._rows = sp.vstack([problem.A, problem.C], format="csc")
        self._lower = np.concatenate([problem.b, problem.l])
        self._upper = np.concatenate([problem.b, problem.u])
        self._hessian = _UpperTriangle(problem.H)
        self._solver: osqp.OSQP | None = None

    def solve(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray) -> SolveOutcome:
        p = self.problem
        hessian = self._hessian.of(p.H)
        if self._solver is None:
            self._solver = osqp.OSQP()
            self._solver.setup(hessian, p.g, self._rows, self._lower, self._upper,
                               eps_abs=self.tolerance, eps_rel=0.0, verbose=False,
                               polishing=True, max_iter=OSQP_MAX_ITERATIONS)
            start = time.perf_counter()
        else:
            start = time.perf_counter()
            self._solver.update(q=p.g, Px=hessian.data)
        result = self._solver.solve()
        elapsed_ms = (time.perf_counter() - start) * 1e3
        return SolveOutcome(
            x=result.x, y=result.y[: p.b.size], z=result.y[p.b.size :],
            status=_osqp_status(result.info.status_val), iterations=int(result.info.iter),
            solver_time_ms=elapsed_ms, solved_by=self.name)


def _osqp_status(value: int) -> SolveStatus:
    if value == osqp.constant("OSQP_SOLVED"):
        return SolveStatus.SOLVED
    infeasible = ("OSQP_PRIMAL_INFEASIBLE", "OSQP_PRIMAL_INFEASIBLE_INACCURATE",
                  "OSQP_DUAL_INFEASIBLE", "OSQP_DUAL_INFEASIBLE_INACCURATE")
    if value in {osqp.constant(name) for name in infeasible}:
        return SolveStatus.INFEASIBLE
    return SolveStatus.MAX_ITERATIONS


class PIQPSolver:
    """PIQP (proximal interior point), its sparse interface set up at the first solve from
    that window; then each window update(P, c) and solve (no warm start in its interface; an
    interior point method gains little from one); eps_abs at `tolerance`, eps_rel 0. Rows
    of C that are plain variable bounds go to its x_l <= x <= x_u, the others to
    h_l <= G x <= h_u."""

    name = "piqp"
    exact = False

    def __init__(self, problem: WindowQP, tolerance: float) -> None:
        self.problem = problem
        c = problem.C.tocsr()
        single = (np.diff(c.indptr) == 1) & np.isclose(c.data[c.indptr[:-1]], 1.0)
        self._bound_rows, self._general_rows = np.flatnonzero(single), np.flatnonzero(~single)
        self._bound_columns = c.indices[c.indptr[:-1][single]]
        x_l, x_u = np.full(problem.n_variables, -np.inf), np.full(problem.n_variables, np.inf)
        x_l[self._bound_columns], x_u[self._bound_columns] = problem.l[single], problem.u[single]
        self._form = {"G": c[~single].tocsc(), "h_l": problem.l[~single],
                      "h_u": problem.u[~single], "x_l": x_l, "x_u": x_u}
        if problem.b.size:
            self._form.update(A=problem.A, b=problem.b)
        self._hessian = _UpperTriangle(problem.H)
        self._solver = piqp.SparseSolver()
        self._solver.settings.eps_abs, self._solver.settings.eps_rel = tolerance, 0.0
        self._solver.settings.verbose = False
        self._set_up = False

    def solve(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray) -> SolveOutcome:
        p = self.problem
        hessian = self._hessian.of(p.H)
        if self._set_up:
            start = time.perf_counter()
            self._solver.update(P=hessian, c=p.g)
        else:
            self._solver.setup(hessian, p.g, **self._form)
            self._set_up = True
            start = time.perf_counter()
        status = self._solver.solve()
        elapsed_ms = (time.perf_counter() - start) * 1e3
        result = self._solver.result
        z = np.zeros(p.l.size)
        z[self._general_rows] = np.asarray(result.z_u) - np.asarray(result.z_l)
        z[self._bound_rows] = (np.asarray(result.z_bu) - np.asarray(result.z_bl))[
            self._bound_columns]
        return SolveOutcome(
            x=np.array(result.x), y=np.array(result.y), z=z,
            status=_piqp_status(status), iterations=int(result.info.iter),
            solver_time_ms=elapsed_ms, solved_by=self.name)


def _piqp_status(status: piqp.Status) -> SolveStatus:
    if status == piqp.PIQP_SOLVED:
        return SolveStatus.SOLVED
    if status in (piqp.PIQP_PRIMAL_INFEASIBLE, piqp.PIQP_DUAL_INFEASIBLE):
        return SolveStatus.INFEASIBLE
    return SolveStatus.MAX_ITERATIONS


class QuadprogSolver:
    """quadprog (dense Goldfarb-Idnani active set) from scratch on each window, the dense
    copy of H included in its time; exact, so `tolerance` is unused. H must be positive
    definite (ValueError otherwise: not with slack variables). Ax = b as equality rows,
    l <= Cx <= u as the one-sided rows Cx >= l (finite l) and -Cx >= -u (finite u)."""

    name = "quadprog"
    exact = True

    def __init__(self, problem: WindowQP, tolerance: float | None = None) -> None:
        self.problem = problem
        self._lower_rows = np.flatnonzero(np.isfinite(problem.l))
        self._upper_rows = np.flatnonzero(np.isfinite(problem.u))
        dense_c = problem.C.toarray()
        rows = np.vstack([problem.A.toarray(), dense_c[self._lower_rows],
                          -dense_c[self._upper_rows]])
        self._rows_t = rows.T if rows.size else None  # quadprog's C: one column per row
        self._bounds = np.concatenate([problem.b, problem.l[self._lower_rows],
                                       -problem.u[self._upper_rows]]) if rows.size else None

    def solve(self, x0: np.ndarray, y0: np.ndarray, z0: np.ndarray) -> SolveOutcome:
        p = self.problem
        start = time.perf_counter()
        x, _, _, iterations, multipliers, _ = quadprog.solve_qp(
            p.H.toarray(), -p.g, self._rows_t, self._bounds, p.b.size)
        elapsed_ms = (time.perf_counter() - start) * 1e3
        # quadprog: H x + g = C λ, λ >= 0 on its inequality rows
        lower = multipliers[p.b.size : p.b.size + self._lower_rows.size]
        upper = multipliers[p.b.size + self._lower_rows.size :]
        return SolveOutcome(
            x=x, y=-multipliers[: p.b.size],
            z=_two_sided(p, upper, lower, self._upper_rows, self._lower_rows),
            status=SolveStatus.SOLVED, iterations=int(iterations[0]),
            solver_time_ms=elapsed_ms, solved_by=self.name)


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
    inequality, inequality_rhs, _, _ = _one_sided(problem)
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
