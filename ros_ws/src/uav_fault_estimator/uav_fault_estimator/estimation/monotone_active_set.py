"""Exact solve of the window QP for monotonic increasing faults by a primal-dual active set.

For the paper's fault model (UAV eq. 10-11, 16; EF eq. 20-21: increments δ ≥ 0 of
exponential prior, cost δ/λ) the window QP (qp_problem.py) is

    minimise  Σ_τ ½ f(τ)ᵀ G(τ) f(τ) + g(τ)ᵀ f(τ)
    subject to  f_k(τ+1) ≥ f_k(τ),  f_k(0) ≥ lower_k,  f_k(T-1) ≤ upper_k,

G(τ) the data's pxp block (UAV eq. 15, with the arrival cost on τ = 0, eq. 17). Given which
increments are 0 and which bounds hold, the QP is a small unconstrained one: the stages of
a fault between two free increments merge into one segment value, a segment at a bound is
fixed, and the segment values solve one dense system of the segments' summed blocks. Its
multipliers follow in closed form: from stationarity at f_k(τ),

    λ_k(τ) = μ_k - Σ_{s ≤ τ} ∇_k(s)          (∇ = G f + g, the objective's gradient)

on the increment after τ, μ_k the lower bound's (the first segment's summed gradient when
fixed, else 0), and the upper bound's multiplier is λ_k(T-1). The primal-dual active-set method
(Hintermüller, Ito & Kunisch, SIAM J. Optim. 13(3), 2002) then fixes what is violated and
releases what has a negative multiplier, until the set repeats: the point is then a KKT
point of the QP, exact to the dense solve. Started from the previous window's solution,
shifted, it repeats after a few rounds on the benchmark's windows (docs/results.md).

Written by hand because no reachable library solves this structure: ProxSuite, PIQP and
OSQP treat the QP as general, and take longer a window (docs/results.md).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dposv  # Cholesky and solve in one LAPACK call

from uav_fault_estimator.estimation.fault_models import IncrementTerms
from uav_fault_estimator.estimation.qp_problem import WindowQP
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_fault_estimator.estimation.solvers import SolveOutcome

# Below these a primal violation or a negative multiplier is round-off, not a change of the
# active set: a degenerate constraint (increment and multiplier both 0) is then left where
# it is instead of flipping back and forth.
PRIMAL_TOLERANCE_PCT = 1e-9
DUAL_TOLERANCE = 1e-12  # times the objective's scale (WindowQP.objective_scale)
# Rounds before the caller's general solver takes over. The method can cycle where the
# summed blocks couple many faults: on bench_mhe's synthetic p = 16 sequence 42 of 201
# windows took more than 10 rounds and 7 more than 30 (each round about 0.06 ms at N = 50;
# p = 4 and 8 took at most 7).
MAX_ROUNDS = 30


@dataclass
class ActiveSetSolution:
    """One solve: x (n,) the QP's primal solution, z (rows of C,) its multipliers in
    ProxSuite's convention (H x + g + Cᵀ z = 0; z < 0 where a row's lower limit holds,
    z > 0 where its upper does), and the number of rounds (each one dense solve)."""

    x: np.ndarray
    z: np.ndarray
    rounds: int


def is_monotone(terms: Sequence[IncrementTerms]) -> bool:
    """Whether every fault's increments are those of a monotonic increasing model (δ ≥ 0, a
    linear cost at most, a = 1): the structure MonotoneActiveSet solves."""
    return all(term.coefficient == 1.0 and term.quadratic_weight == 0.0
               and term.abs_cost == 0.0 and term.lower_pct == 0.0
               and term.upper_pct == np.inf for term in terms)


class MonotoneActiveSet:
    """Primal-dual active-set solver for a WindowQP whose faults are all monotonic increasing.

    The active set is one boolean array `held` (T + 1, p): row 0 the lower bound on f(0),
    row τ = 1 … T-1 the increment into stage τ held at 0, row T the upper bound on f(T-1);
    `multiplier` and `slack` have the same layout. Inputs at construction: the problem (its
    pattern, bounds and constraint rows; ValueError if a fault is not monotonic increasing)
    and max_rounds, after which `solve` gives up. A solvers.WindowSolver through
    `solve`; `solve_faults` is the method itself.
    """

    name = "active_set"

    def __init__(self, problem: WindowQP, max_rounds: int = MAX_ROUNDS) -> None:
        if not is_monotone(problem.increment_terms):
            raise ValueError("the active-set solver needs every fault monotonic increasing")
        self.problem = problem
        self.max_rounds = max_rounds
        stages, p = problem.stages, problem.n_faults
        self.lower_pct, self.upper_pct, self._z_row, self._z_from, self._z_sign = \
            _constraint_rows(problem)
        self._faults = np.arange(p)
        self._starts = np.ones((stages, p), dtype=bool)  # stage τ starts a segment
        self._open = np.ones((stages, p), dtype=bool)  # increments not held, then the end
        self._slack = np.zeros((stages + 1, p))

    def solve(self, x0: np.ndarray, y0: np.ndarray, _z0: np.ndarray) -> SolveOutcome | None:
        """solvers.WindowSolver: the window from the active set of x0's faults; the
        equality multipliers y0 are passed through (the window QP has none of its own)."""
        start = time.perf_counter()
        solution = self.solve_faults(x0[self.problem.f_index])
        if solution is None:
            return None
        return SolveOutcome(solution.x, y0, solution.z, SolveStatus.SOLVED, solution.rounds,
                            (time.perf_counter() - start) * 1e3, self.name)

    def solve_faults(self, guess_pct: np.ndarray) -> ActiveSetSolution | None:
        """The QP's solution for the problem's current H and g, starting from the active set
        of guess_pct (T, p) [%]; None when the rounds run out or a reduced system is not
        positive definite (a direction without data: the caller's general solver decides)."""
        problem = self.problem
        blocks, gradient = problem.stage_blocks(), problem.g[problem.f_index]
        dual_tolerance = DUAL_TOLERANCE * problem.objective_scale()
        held = self._slacks(guess_pct) <= PRIMAL_TOLERANCE_PCT
        for rounds in range(1, self.max_rounds + 1):
            f_pct = self._segment_solution(blocks, gradient, held)
            if f_pct is None:
                return None
            multiplier = self._multipliers(blocks, gradient, f_pct, held)
            next_held = np.where(held, multiplier >= -dual_tolerance,
                                 self._slacks(f_pct) < -PRIMAL_TOLERANCE_PCT)
            if np.array_equal(next_held, held):
                z = np.zeros(problem.l.size)
                z[self._z_row] = self._z_sign * np.where(held, multiplier, 0.0).ravel()[
                    self._z_from]
                return ActiveSetSolution(f_pct.ravel(), z, rounds)
            held = next_held
        return None

    def _slacks(self, f_pct: np.ndarray) -> np.ndarray:
        """Each constraint's slack (T + 1, p) [%]: f(0) - lower, the increments, upper -
        f(T-1) (a view of a buffer: valid until the next call)."""
        slack = self._slack
        np.subtract(f_pct[0], self.lower_pct, out=slack[0])
        np.subtract(f_pct[1:], f_pct[:-1], out=slack[1:-1])
        np.subtract(self.upper_pct, f_pct[-1], out=slack[-1])
        return slack

    def _segment_solution(self, blocks: np.ndarray, gradient: np.ndarray,
                          held: np.ndarray) -> np.ndarray | None:
        """f (T, p) [%] minimising the objective with the held constraints as equalities:
        the stages between free increments merged into segments, a segment at a held bound
        fixed, one dense Cholesky solve over the free segments' values. None if that system
        is not positive definite or gives a non-finite value."""
        np.logical_not(held[1:-1], out=self._starts[1:])
        stages, p = self._starts.shape
        segment = (np.cumsum(self._starts.T) - 1).reshape(p, stages).T  # global, fault-major
        size = int(segment[-1, -1]) + 1
        pairs = (segment[:, :, None] * size + segment[:, None, :]).ravel()
        hessian = np.bincount(pairs, weights=blocks.ravel(), minlength=size * size)
        hessian = hessian.reshape(size, size)
        linear = np.bincount(segment.ravel(), weights=gradient.ravel(), minlength=size)
        value = np.zeros(size)
        fixed = np.zeros(size, dtype=bool)
        for row, bound_pct, ends in ((0, self.lower_pct, segment[0]),
                                     (-1, self.upper_pct, segment[-1])):
            fixed[ends[held[row]]] = True
            value[ends[held[row]]] = bound_pct[held[row]]
        free = ~fixed
        if not free.all():
            free_rows = hessian[free]
            linear = linear[free] + free_rows[:, fixed] @ value[fixed]
            hessian = free_rows[:, free]
        if linear.size:
            _, solution, info = dposv(hessian, linear)
            if info != 0:  # not positive definite
                return None
            value[free] = -solution
        f_pct = value[segment]
        return f_pct if np.all(np.isfinite(f_pct)) else None

    def _multipliers(self, blocks: np.ndarray, gradient: np.ndarray, f_pct: np.ndarray,
                     held: np.ndarray) -> np.ndarray:
        """Every constraint's multiplier (T + 1, p) from stationarity at f (module docstring):
        m(τ) = μ - Σ_{s < τ} ∇(s), μ the lower bound's: the first segment's summed gradient
        when held, else 0 (the first free increment's multiplier is then 0)."""
        slope = np.matmul(blocks, f_pct[:, :, None])[:, :, 0] + gradient
        multiplier = np.zeros((slope.shape[0] + 1, slope.shape[1]))
        np.cumsum(slope, axis=0, out=multiplier[1:])
        np.negative(multiplier, out=multiplier)
        np.logical_not(held[1:-1], out=self._open[:-1])
        first_free = np.argmax(self._open, axis=0) + 1
        multiplier += np.where(held[0], -multiplier[first_free, self._faults], 0.0)
        return multiplier


def _constraint_rows(problem: WindowQP) -> tuple[np.ndarray, ...]:
    """Each fault's lower and upper bound on f [%] (±inf for none), and how the (T + 1, p)
    multipliers map to C's rows in ProxSuite's sign convention: z[row] = sign ·
    multiplier.ravel()[source] (negative on a lower limit, positive on an upper)."""
    stages, p = problem.stages, problem.n_faults
    c = problem.C.tocsr()
    lower_pct, upper_pct = np.full(p, -np.inf), np.full(p, np.inf)
    rows, sources, signs = [], [], []
    for row in range(c.shape[0]):
        columns = c.indices[c.indptr[row]:c.indptr[row + 1]]
        stage, fault = divmod(int(columns.max()), p)
        if columns.size == 2:  # the increment into stage
            held_row, sign = stage, -1.0
        elif np.isfinite(problem.l[row]):
            held_row, sign, lower_pct[fault] = 0, -1.0, problem.l[row]
        else:
            held_row, sign, upper_pct[fault] = stages, 1.0, problem.u[row]
        rows.append(row)
        sources.append(held_row * p + fault)
        signs.append(sign)
    return lower_pct, upper_pct, np.array(rows), np.array(sources), np.array(signs)
