"""Moving-horizon MAP fault estimator (embedded-estimation paper section III-C,
evolving-faults paper section VII).

Each `update` takes one residual sample y(t) ∈ R^m, its signature S(t) ∈ R^{mxp} and a
per-channel validity, and returns the MAP estimate over the last N samples. The QP
structure is built once; each update refills H and g in place and warm-starts ProxSuite
from the previous solution shifted by one sample. Nothing raises into the caller: bad
data or a failed solve keep the last good estimate and report the status.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from operator import attrgetter

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from uav_fault_estimator.estimation.arrival_cost import ArrivalCost, increment_prior
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig
from uav_fault_estimator.estimation.monotone_active_set import MonotoneActiveSet
from uav_fault_estimator.estimation.proxqp_solver import ProxQPSolver
from uav_fault_estimator.estimation.qp_problem import sample_normal_equations
from uav_fault_estimator.estimation.solve_status import SolveStatus
from uav_fault_estimator.estimation.solvers import SolveOutcome, WindowSolver, first_solution

# The most sample periods a gap advances the window by (advance): four windows of the
# default horizon; after them the window is empty and the arrival cost has widened by as
# many increments.
GAP_SAMPLES_MAX = 200
# An update over its budget (SolverSettings.budget_ms) drops the window's oldest sample
# that its fit leaves a residual of more than this many noise deviations (Q^½): a glitch
# the gates let through, which the fault models cannot explain, is the likeliest cause of
# a hard window, and the next updates go without it. (A fault's own residuals are
# explained by the fit, however large.)
SUSPECT_SIGMAS = 10.0


def median_period_s(stamps_s: Sequence[float]) -> float | None:
    """A stream's sample period [s]: the median interval of its stamps [s]; None while
    fewer than two stamps tell it."""
    return float(np.median(np.diff(stamps_s))) if len(stamps_s) >= 2 else None


def missing_samples(gap_s: float, stamps_s: Sequence[float]) -> int:
    """Sample periods missing in a gap of gap_s [s] of a stream stamped stamps_s [s] before
    it (median_period_s; 0 while it is not known)."""
    period_s = median_period_s(stamps_s)
    return max(round(gap_s / period_s) - 1, 0) if period_s else 0


@dataclass
class EstimateResult:
    """Output of one update.

    column_names (p,): what each column estimates (faults, then any nuisance parameters);
    fault_pct (p,): estimate of f(t) [%]; window_pct (N, p): estimates over the window,
    oldest first [%]; status; iterations of the solver (rounds of the active-set method);
    update_time_ms: the whole update call [ms]; update_cpu_ms: the same call's CPU time in
    the calling thread [ms] (what it costs, whatever shares the cores); solver_time_ms: the
    solver's own run time [ms] (0 when not solved); solved_by: the SOLVER_METHODS entry that
    solved this window ("" when none ran).
    """

    column_names: tuple[str, ...]
    fault_pct: np.ndarray
    window_pct: np.ndarray
    status: SolveStatus
    iterations: int
    update_time_ms: float
    update_cpu_ms: float
    solver_time_ms: float
    solved_by: str

    def columns(self, names: Sequence[str]) -> list[int]:
        """Indices of the named columns (ValueError for a name not estimated)."""
        return [self.column_names.index(name) for name in names]


class MovingHorizonEstimator:
    """MAP estimator over a window of the last `config.horizon` residual samples."""

    def __init__(self, config: EstimatorConfig) -> None:
        config.validate()
        self.config = config
        self.problem = config.window_qp(config.horizon)
        terms = self.problem.increment_terms
        self._increments = np.array([increment_prior(term) for term in terms])
        self._coefficients = np.array([term.coefficient for term in terms])
        self._q_inv = config.q_inv
        self.column_names = tuple(fault.name for fault in config.faults)
        self.overruns = 0  # updates over the budget, since the start
        self.dropped_suspects = 0  # samples dropped for it
        self.reset()

    def reset(self, prior_pct: np.ndarray | None = None) -> None:
        """Back to the state before any data (after a restart of the flight): empty window,
        arrival cost and warm start at the prior, and a new ProxSuite instance, whose
        preconditioner is made from the first window it solves. The QP's pattern is kept.
        prior_pct (p,) [%]: where to start instead of the configured prior (this estimator
        restarted within a flight: its last estimate), with the same handover covariance."""
        config = self.config
        prior = config.prior_pct if prior_pct is None else np.asarray(prior_pct, dtype=float)
        n, p = config.horizon, len(config.faults)
        self.solver = ProxQPSolver(self.problem, config.solver)
        self.active_set = (MonotoneActiveSet(self.problem)
                           if config.solver.method == "active_set" else None)
        # Tried in order: the active set where configured, ProxSuite for what it gives up.
        self.solvers: tuple[WindowSolver, ...] = (
            (self.solver,) if self.active_set is None else (self.active_set, self.solver))
        self.arrival = ArrivalCost(
            self._coefficients, self._increments[:, 0], self._increments[:, 1],
            prior, np.diag(config.r_diag_pct2), config.arrival_inflation,
            config.arrival_floor)
        # Each sample's data term (stage_normal_equations), made once when it arrives.
        self._gram = np.zeros((n, p, p))
        self._linear = np.zeros((n, p))
        self._has_data = np.zeros(n, dtype=bool)
        # Each sample whitened (W^½ y, W^½ S): what its fit leaves is measured in noise
        # deviations.
        self._whitened_y = np.zeros((n, self._q_inv.size))
        self._whitened_s = np.zeros((n, self._q_inv.size, p))
        # The last good solution, shifted once per update: the warm start, and at stage 0
        # the previous window's estimate of the new window's first point (UAV eq. 17).
        # The window starts empty: its first point is N - 1 samples before the first one.
        self._x = np.zeros(self.problem.n_variables)
        self._x[self.problem.f_index] = prior
        self._y_dual = np.zeros(self.problem.b.size)
        self._z_dual = np.zeros(self.problem.l.size)
        self._window_pct = np.tile(prior, (n, 1))

    def retune(self, config: EstimatorConfig) -> None:
        """Take config's weights from the next update on, keeping the window and its estimate.

        What may change at run time: Q by a factor common to every channel (the window's data
        terms are reweighted by it: exact, as if they had come in with the new Q), R (the
        arrival cost restarts at its mean with covariance diag R: a new handover), the
        arrival cost's inflation and floor, and the solver's tolerances. ValueError naming
        the first other difference (horizon, faults, their models, bounds or priors, the
        arrival centre): those shape the QP, built once.
        """
        config.validate()
        current = self.config
        for name in ("horizon", "faults", "arrival_centre", "solver.method"):
            if attrgetter(name)(config) != attrgetter(name)(current):
                raise ValueError(f"{name} shapes the estimator's QP: it changes only at a "
                                 "restart of the node")
        ratio = config.q_inv / self._q_inv
        if not np.allclose(ratio, ratio[0], rtol=1e-12, atol=0.0):
            raise ValueError("Q changes at run time only by a factor common to every channel")
        self._gram *= ratio[0]
        self._linear *= ratio[0]
        self._q_inv = config.q_inv
        if config.r_diag_pct2 != current.r_diag_pct2:
            self.arrival.information = np.diag(config.r_inv)
        self.arrival.inflation = config.arrival_inflation
        self.arrival.floor_variance = config.arrival_floor
        self.solver.apply(config.solver)
        self.config = config

    def advance(self, samples: int) -> None:
        """Let `samples` sample periods pass without data (a gap in the residual stream, the
        flight going on): each moves the window on by one empty stage, so the fault model's
        increments span the gap and the arrival cost takes what leaves the window, widened
        by one increment a step (EF eq. 3); no solve. The estimate and the monotonic faults'
        floor are kept; beyond GAP_SAMPLES_MAX steps the gap changes nothing more here."""
        for _ in range(min(samples, GAP_SAMPLES_MAX)):
            self.arrival.absorb(self._gram[0], self._linear[0])
            self.arrival.predict()
            for window in self._windows:
                window[:-1] = window[1:]
                window[-1] = 0
            self._shift_guess()
            self._window_pct = np.vstack([self._window_pct[1:], self._window_pct[-1:]])

    def hold(self) -> EstimateResult:
        """One sample period passes with its sample not used (advance(1)): HELD, the
        estimate kept."""
        start = (time.perf_counter(), time.thread_time())
        self.advance(1)
        return self._result(SolveStatus.HELD, None, start)

    def update(
        self, y: np.ndarray, s: np.ndarray, valid: np.ndarray | None = None,
        noise_variances: np.ndarray | None = None,
    ) -> EstimateResult:
        """Add one sample and re-estimate.

        Inputs: y (m,) residuals; s (m, p) signatures [residual unit / %]; valid (m,)
        booleans, False for a channel lost at this sample (left out of the fit);
        noise_variances (m,): this sample's Q when not the configured one (another sensor
        suite: noise_model.py).
        Returns the EstimateResult: WAITING (values = prior) while the window holds no
        valid residual row; INVALID_DATA for non-finite, implausible or misshapen data on valid
        channels. A window not yet full is solved with its empty samples weighted 0.
        """
        start = (time.perf_counter(), time.thread_time())
        # The oldest sample leaves the window: into the arrival cost, which then moves to
        # the new first point.
        self.arrival.absorb(self._gram[0], self._linear[0])
        self.arrival.predict()
        q_inv = self._q_inv if noise_variances is None else 1.0 / np.asarray(noise_variances)
        sample_ok = self._push_sample(y, s, valid, q_inv)
        self._shift_guess()
        if not sample_ok:
            return self._result(SolveStatus.INVALID_DATA, None, start)
        if not self._has_data.any():  # no usable residual in the window yet
            return self._result(SolveStatus.WAITING, None, start)
        centre = (self.arrival.mean if self.config.arrival_centre == "filter"
                  else self._x[self.problem.f_index[0]])
        self.problem.set_data(self._gram, self._linear, self.arrival.information, centre)
        outcome = self._solve()
        if outcome.status is SolveStatus.SOLVED:
            self._x, self._y_dual, self._z_dual = outcome.x, outcome.y, outcome.z
            self._window_pct = outcome.x[self.problem.f_index]
        if (time.perf_counter() - start[0]) * 1e3 > self.config.solver.budget_ms:
            self._drop_oldest_suspect()
        return self._result(outcome.status, outcome, start)

    def newest_covariance(self, columns: Sequence[int]) -> np.ndarray:
        """The covariance of the newest sample's estimate of the given columns (indices
        into column_names) (k, k) [column unit²], by the Laplace approximation: that block
        of H⁻¹, H the window QP's Hessian at the last update (UAV eq. 15-17; its
        constraints left out, so an estimate at a bound reads as free). A variable without
        curvature (a monotonic fault's on a sample without data: its prior is linear) is
        unbounded and touches no other: it gets unit curvature, which changes no other
        block. NaN where H is singular otherwise."""
        newest = self.problem.f_index[-1, list(columns)]
        unit = np.zeros((self.problem.n_variables, newest.size))
        unit[newest, np.arange(newest.size)] = 1.0
        hessian = self.problem.H
        regularised = hessian + sp.diags((hessian.diagonal() == 0.0).astype(float))
        try:
            solved = splu(regularised.tocsc()).solve(unit)
        except RuntimeError:  # exactly singular
            return np.full((newest.size, newest.size), np.nan)
        return solved[newest]

    def _drop_oldest_suspect(self) -> None:
        """After an update over budget: the window's oldest sample whose fit leaves a
        residual beyond SUSPECT_SIGMAS leaves the fit (its data term zeroed), if any."""
        self.overruns += 1
        fitted = np.einsum("tmp,tp->tm", self._whitened_s, self._window_pct)
        suspects = np.flatnonzero(np.abs(self._whitened_y - fitted).max(axis=1)
                                  > SUSPECT_SIGMAS)
        if suspects.size:
            oldest = suspects[0]
            for window in self._windows:
                window[oldest] = 0
            self.dropped_suspects += 1

    @property
    def _windows(self) -> tuple[np.ndarray, ...]:
        """The per-sample arrays of the window, oldest sample first."""
        return (self._gram, self._linear, self._has_data, self._whitened_y, self._whitened_s)

    def _solve(self) -> SolveOutcome:
        """This window's QP by the first of the solvers that settles, from the previous
        solution, shifted."""
        return first_solution(self.solvers, self._x, self._y_dual, self._z_dual)

    def _push_sample(self, y: np.ndarray, s: np.ndarray, valid: np.ndarray | None,
                     q_inv: np.ndarray) -> bool:
        """Append the sample's data term to the window, invalid or non-finite channels
        weighted 0.

        Returns False when the sample is unusable (wrong shape, non-finite on a channel
        marked valid); it then enters the window with all channels left out, so the next
        updates are not poisoned by it.
        """
        for window in self._windows:
            window[:-1] = window[1:]
        term = sample_normal_equations(y, s, valid, q_inv, self._linear.shape[1])
        self._gram[-1], self._linear[-1], self._has_data[-1] = term.gram, term.linear, term.entered
        self._whitened_y[-1], self._whitened_s[-1] = term.whitened_y, term.whitened_s
        return term.clean

    def _shift_guess(self) -> None:
        """Move the last good solution one sample back in time (warm start, handover)."""
        problem = self.problem
        self._x = self._x[problem.x_shift]
        self._y_dual = self._y_dual[problem.y_shift]
        self._z_dual = self._z_dual[problem.z_shift]

    def _result(
        self, status: SolveStatus, outcome: SolveOutcome | None, start: tuple[float, float]
    ) -> EstimateResult:
        """The result; start: (perf_counter, thread_time) at the update's start [s]."""
        return EstimateResult(
            column_names=self.column_names,
            fault_pct=self._window_pct[-1].copy(),
            window_pct=self._window_pct.copy(),
            status=status,
            iterations=outcome.iterations if outcome else 0,
            update_time_ms=(time.perf_counter() - start[0]) * 1e3,
            update_cpu_ms=(time.thread_time() - start[1]) * 1e3,
            solver_time_ms=outcome.solver_time_ms if outcome else 0.0,
            solved_by=outcome.solved_by if outcome else "",
        )
