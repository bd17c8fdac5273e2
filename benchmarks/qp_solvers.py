"""Comparison solvers of a WindowQP: OSQP, PIQP and quadprog, each a solvers.WindowSolver,
beside Clarabel (estimation/reference_solution.py, which also gives the exact solution the
benchmark checks against). The estimator never imports this module, so these three are
benchmark dependencies only.

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
"""

from __future__ import annotations

import time

import numpy as np
import osqp
import piqp
import quadprog
import scipy.sparse as sp
from uav_fault_estimator.estimation.qp_problem import WindowQP
from uav_fault_estimator.estimation.reference_solution import two_sided
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_fault_estimator.estimation.solvers import SolveOutcome

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
            z=two_sided(p, upper, lower, self._upper_rows, self._lower_rows),
            status=SolveStatus.SOLVED, iterations=int(iterations[0]),
            solver_time_ms=elapsed_ms, solved_by=self.name)
