"""The MAP fault estimation QP over T stages, built once and refilled in place.

A stage is one sample (moving horizon) or one update cycle of M samples (batch, EF eq. 18);
the fault vector f(τ) ∈ R^p is constant within a stage. The QP is

    minimise ½ xᵀ H x + gᵀ x   subject to  A x = b,  l ≤ C x ≤ u

with x = [f(0), f(1), …, f(T-1), slacks] and the constraint rows both time-major, so the
KKT matrix is banded and one factorisation costs O(T). Only the data part of H (block
diagonal, one pxp block per stage) and g change from one update to the next; the sparsity
pattern, A, b, C, l and u are fixed at construction.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from uav_fault_estimator.estimation.fault_models import FaultModel, IncrementTerms


def stage_normal_equations(
    y: np.ndarray, s: np.ndarray, weight: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample data term of the MAP objective, as normal-equation blocks.

    ½ (y - S f)ᵀ W (y - S f) = ½ fᵀ (SᵀWS) f - (SᵀWy)ᵀ f + const  (UAV eq. 15, EF eq. 13),
    with W = diag(weight) = Q⁻¹ on valid rows and 0 on rows left out (sensor loss).
    Inputs: y (T, m) residuals; s (T, m, p) signatures [residual unit / %]; weight (T, m)
    [1 / residual unit²]. Outputs: G (T, p, p) [1/%²] and h (T, p) [1/%].
    """
    weighted_s = s * weight[:, :, None]
    gram = np.matmul(weighted_s.transpose(0, 2, 1), s)
    linear = np.einsum("tmi,tm->ti", weighted_s, y)
    return gram, linear


# A residual beyond this many noise standard deviations (Q^½) is a data error, not a fault:
# losing a whole wing's lift moves the roll residual by about 200 of them (0.6 rad/s² per %
# against Q^½ = 0.36 rad/s² with air data). So is a sensitivity by which one percent of a
# fault (or one m/s of a wind error) would move its residual by more: the roll row's is
# about 1.7 per %. Such a row is left out like a non-finite one; a finite but huge S would
# otherwise reach the solver (1e300: seconds an update).
RESIDUAL_PLAUSIBLE_SIGMAS = 1e3


class SampleTerm(NamedTuple):
    """One residual sample's data term: G (p, p) [1/%²], h (p,) [1/%], whether any row
    entered, whether the sample was clean (shapes right, every row marked valid finite and
    plausible), and the whitened sample W^½ y (m,) and W^½ S (m, p) [noise deviations; 0 on
    rows left out], by which a fit's residuals are measured."""

    gram: np.ndarray
    linear: np.ndarray
    entered: bool
    clean: bool
    whitened_y: np.ndarray
    whitened_s: np.ndarray


def sample_normal_equations(
    y: np.ndarray, s: np.ndarray, valid: np.ndarray | None, q_inv: np.ndarray, columns: int
) -> SampleTerm:
    """One residual sample's data term, with Q⁻¹ on the rows that are valid and finite and
    0 on the others (a lost channel, a non-finite or implausible value: left out of the fit;
    implausible: |y|, or |S| of one unit of a column, beyond RESIDUAL_PLAUSIBLE_SIGMAS noise
    deviations).

    Inputs: y (m,) residuals; s (m, p) signatures [residual unit / %]; valid (m,) booleans
    or None for all; q_inv (m,) [1 / residual unit²]; columns p. A misshapen sample enters
    as no data.
    """
    m, p = q_inv.size, columns
    y, s = np.asarray(y, dtype=float), np.asarray(s, dtype=float)
    keep = np.ones(m, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    if y.shape != (m,) or s.shape != (m, p) or keep.shape != (m,):
        return SampleTerm(np.zeros((p, p)), np.zeros(p), False, False, np.zeros(m),
                          np.zeros((m, p)))
    limit = RESIDUAL_PLAUSIBLE_SIGMAS / np.sqrt(q_inv)
    # Comparisons with NaN are False: a non-finite entry is implausible too.
    finite = (np.abs(y) <= limit) & np.all(np.abs(s) <= limit[:, None], axis=1)
    weight = np.where(keep & finite, q_inv, 0.0)
    y, s = np.where(finite, y, 0.0), np.where(finite[:, None], s, 0.0)
    gram, linear = stage_normal_equations(y[None], s[None], weight[None])
    root = np.sqrt(weight)
    return SampleTerm(gram[0], linear[0], bool(weight.any()), bool(np.all(finite[keep])),
                      root * y, root[:, None] * s)


def _grid(first: int, stages: int, width: int) -> np.ndarray:
    """Indices first … first + stages·width - 1 as a (stages, width) time-major grid."""
    return first + np.arange(stages * width).reshape(stages, width)


def shift_source(grid: np.ndarray, source: np.ndarray) -> None:
    """Fill source[grid[τ, k]] = grid[min(τ + 1, last), k]: a one-stage shift map.

    Used for warm starts: entry i of the shifted vector is old[source[i]], so the newest
    stage repeats the last one (the best guess for a fault that persists).
    """
    if grid.size:
        later = np.minimum(np.arange(grid.shape[0]) + 1, grid.shape[0] - 1)
        source[grid] = grid[later]


class WindowQP:
    """The fault estimation QP for `stages` stages and the given per-fault models.

    Inputs at construction: stages T ≥ 1; models, one per fault; bounds_pct, one
    (lower, upper) per fault [%] (±inf for none). Per update, `set_data` refills H and g
    with the data and the arrival cost on the first stage.
    """

    def __init__(
        self,
        stages: int,
        models: Sequence[FaultModel],
        bounds_pct: Sequence[tuple[float, float]],
    ) -> None:
        if stages < 1:
            raise ValueError(f"the QP needs at least one stage, got {stages}")
        self.stages = stages
        self.n_faults = p = len(models)
        self.increment_terms = terms = [model.increment_terms() for model in models]
        laplacian = [k for k, term in enumerate(terms) if term.abs_cost > 0.0]
        self.f_index = _grid(0, stages, p)
        slack_index = _grid(stages * p, stages - 1, len(laplacian))
        self.n_variables = n = stages * p + slack_index.size

        self._rows = _RowBuilder(n)
        h_rows: list[np.ndarray] = []
        h_cols: list[np.ndarray] = []
        h_vals: list[np.ndarray] = []
        self.g_model = np.zeros(n)
        for k, term in enumerate(terms):
            self._add_increment_terms(k, term, h_rows, h_cols, h_vals)
        for j, k in enumerate(laplacian):
            self._add_absolute_cost(k, terms[k], slack_index[:, j])
        for k, bounds in enumerate(bounds_pct):
            self._add_bounds(k, terms[k], bounds)
        self._build_hessian(h_rows, h_cols, h_vals)
        self.A, self.b = self._rows.equalities()
        self.C, self.l, self.u = self._rows.inequalities()
        self.row_stages = self._rows.row_stages()  # of each row of [A; C]
        self.g = np.zeros(n)

        self.x_shift = np.arange(n)
        shift_source(self.f_index, self.x_shift)
        shift_source(slack_index, self.x_shift)
        self.y_shift = self._rows.eq_shift()
        self.z_shift = self._rows.in_shift()

    def _add_increment_terms(
        self,
        k: int,
        term: IncrementTerms,
        h_rows: list[np.ndarray],
        h_cols: list[np.ndarray],
        h_vals: list[np.ndarray],
    ) -> None:
        """Cost and range of fault k's increments δ(τ) = f(τ+1) - a f(τ) (EF eq. 14)."""
        later, earlier = self.f_index[1:, k], self.f_index[:-1, k]
        a = term.coefficient
        if term.quadratic_weight > 0.0:
            w = term.quadratic_weight
            # ½ w (f⁺ - a f)²: the four entries of its 2x2 Hessian block for every τ.
            for rows, cols, value in (
                (later, later, w),
                (earlier, earlier, w * a * a),
                (later, earlier, -w * a),
                (earlier, later, -w * a),
            ):
                h_rows.append(rows)
                h_cols.append(cols)
                h_vals.append(np.full(rows.size, value))
        np.add.at(self.g_model, later, term.linear_cost)
        np.add.at(self.g_model, earlier, -a * term.linear_cost)
        if math.isfinite(term.lower_pct) or math.isfinite(term.upper_pct):
            columns = np.stack([later, earlier], axis=1)
            values = np.tile([1.0, -a], (later.size, 1))
            if term.lower_pct == term.upper_pct:
                self._rows.add_equality(columns, values, term.lower_pct)
            else:
                self._rows.add_inequality(columns, values, term.lower_pct, term.upper_pct)

    def _add_bounds(self, k: int, term: IncrementTerms, bounds: tuple[float, float]) -> None:
        """lower <= f_k(tau) <= upper, on the stages where it can bind.

        For a fault whose increments cannot be negative (f_k(tau + 1) >= f_k(tau), a = 1)
        the lower bound binds at the first stage only and the upper at the last; mirrored
        for one that cannot increase. The other rows would be implied and degenerate, which
        slows the solver and changes no solution.
        """
        lower, upper = bounds
        stages = self.stages
        rising = term.coefficient == 1.0 and term.lower_pct >= 0.0
        falling = term.coefficient == 1.0 and term.upper_pct <= 0.0
        for value, is_lower in ((lower, True), (upper, False)):
            if not math.isfinite(value):
                continue
            if rising or falling:
                stage = 0 if rising == is_lower else stages - 1
                rows = slice(stage, stage + 1)
            else:
                stage, rows = 0, slice(None)
            self._rows.add_inequality(
                self.f_index[rows, k : k + 1], np.ones((self.f_index[rows].shape[0], 1)),
                value if is_lower else -math.inf, math.inf if is_lower else value,
                first_stage=stage,
            )

    def _add_absolute_cost(self, k: int, term: IncrementTerms, slack: np.ndarray) -> None:
        """b |δ(τ)| as b s(τ) with -s ≤ δ ≤ s (EF eq. 7 as a QP)."""
        later, earlier = self.f_index[1:, k], self.f_index[:-1, k]
        a = term.coefficient
        self.g_model[slack] += term.abs_cost
        columns = np.stack([later, earlier, slack], axis=1)
        ones = np.ones(later.size)
        self._rows.add_inequality(columns, np.stack([ones, -a * ones, -ones], 1), -math.inf, 0.0)
        self._rows.add_inequality(columns, np.stack([ones, -a * ones, ones], 1), 0.0, math.inf)

    def _build_hessian(
        self, h_rows: list[np.ndarray], h_cols: list[np.ndarray], h_vals: list[np.ndarray]
    ) -> None:
        """Fix H's pattern: model entries plus one dense pxp block per stage.

        Stores where each block entry lives in H.data so `set_data` writes in place.
        """
        n, p, stages = self.n_variables, self.n_faults, self.stages
        block_rows = np.repeat(self.f_index, p, axis=1).reshape(stages, p, p)
        block_cols = np.tile(self.f_index, (1, p)).reshape(stages, p, p)
        rows = np.concatenate([*h_rows, block_rows.ravel()])
        cols = np.concatenate([*h_cols, block_cols.ravel()])
        model_values = np.concatenate([*h_vals, np.zeros(0)])
        pattern = sp.csc_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
        pattern.sum_duplicates()
        pattern.sort_indices()
        self.H = pattern
        self._block_position = pattern_positions(pattern, block_rows, block_cols)
        on_diagonal = np.flatnonzero(pattern.diagonal())
        self._diagonal_position = pattern_positions(pattern, on_diagonal, on_diagonal)
        model_position = pattern_positions(pattern, rows[: model_values.size],
                                           cols[: model_values.size])
        # H.data's model part: the fault models' curvature (their quadratic increment
        # costs, proxqp_solver.LiftedWindow moves onto increment variables), the same at
        # every update
        self.model_curvature = np.zeros(pattern.nnz)
        np.add.at(self.model_curvature, model_position, model_values)

    def set_data(self, gram: np.ndarray, linear: np.ndarray, prior_information: np.ndarray,
                 prior_pct: np.ndarray) -> None:
        """Refill H and g in place from the data term and the arrival cost.

        Inputs: gram (T, p, p) and linear (T, p) from `stage_normal_equations` (summed per
        stage); the arrival cost ½ (f(0) - prior)ᵀ Π⁻¹ (f(0) - prior) (UAV eq. 17, EF eq. 26)
        as prior_information Π⁻¹ (p, p) [1/%²] and prior_pct (p,) [%].
        """
        data = self.H.data
        np.copyto(data, self.model_curvature)
        data[self._block_position] += gram
        data[self._block_position[0]] += prior_information
        g = self.g
        np.copyto(g, self.g_model)
        g[self.f_index] -= linear
        g[self.f_index[0]] -= prior_information @ prior_pct

    def stage_blocks(self) -> np.ndarray:
        """H's pxp block of every stage, (T, p, p) [1/%²], a copy: the data term, the arrival
        cost on the first stage and any model curvature on the blocks' diagonals."""
        return self.H.data[self._block_position]

    def objective_scale(self) -> float:
        """Mean of |diag H| over all n variables: the objective's scale (1 for an H without
        curvature)."""
        scale = float(np.abs(self.H.data[self._diagonal_position]).sum()) / self.n_variables
        return scale if np.isfinite(scale) and scale > 0.0 else 1.0


def pattern_positions(pattern: sp.csc_matrix, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Index into pattern.data of each (row, col) entry; all entries must be in the pattern.

    A sorted CSC matrix lists its entries in increasing col·n + row, so one searchsorted
    over that key finds them all.
    """
    n_rows = pattern.shape[0]
    entry_cols = np.repeat(np.arange(pattern.shape[1]), np.diff(pattern.indptr))
    keys = entry_cols.astype(np.int64) * n_rows + pattern.indices
    return np.searchsorted(keys, cols.astype(np.int64) * n_rows + rows)


class _RowBuilder:
    """Collects constraint rows grouped by stage, and their warm-start shift maps."""

    def __init__(self, n_variables: int) -> None:
        self.n_variables = n_variables
        # (columns, values, lower, upper, first stage) per group of rows
        self._eq: list[tuple[np.ndarray, np.ndarray, float, float, int]] = []
        self._in: list[tuple[np.ndarray, np.ndarray, float, float, int]] = []

    def add_equality(self, columns: np.ndarray, values: np.ndarray, rhs: float) -> None:
        """One row per stage: Σ_j values[τ, j] x[columns[τ, j]] = rhs."""
        self._eq.append((columns, values, rhs, rhs, 0))

    def add_inequality(
        self, columns: np.ndarray, values: np.ndarray, lower: float, upper: float,
        first_stage: int = 0,
    ) -> None:
        """One row per stage from first_stage on: lower ≤ Σ_j values[τ, j] x[columns[τ, j]]
        ≤ upper."""
        self._in.append((columns, values, lower, upper, first_stage))

    @staticmethod
    def _stages(groups: list) -> np.ndarray:
        """The stage of every row, group by group."""
        return np.concatenate([first + np.arange(columns.shape[0])
                               for columns, *_, first in groups])

    @classmethod
    def _stage_order(cls, groups: list) -> np.ndarray:
        """Row permutation to time-major order (stage, then group), so that the KKT matrix
        stays banded: every group has one row per stage."""
        group = np.concatenate([np.full(columns.shape[0], k) for k, (columns, *_) in
                                enumerate(groups)])
        return np.lexsort((group, cls._stages(groups)))

    def row_stages(self) -> np.ndarray:
        """The stage of each row of [A; C], as assembled."""
        return np.concatenate([self._stages(groups)[self._stage_order(groups)]
                               for groups in (self._eq, self._in) if groups]
                              or [np.zeros(0, dtype=int)])

    def _assemble(self, groups: list) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
        if not groups:
            return sp.csc_matrix((0, self.n_variables)), np.zeros(0), np.zeros(0)
        rows, cols, vals, lower, upper = [], [], [], [], []
        first = 0
        for columns, values, lo, hi, _ in groups:
            count, width = columns.shape
            rows.append(np.repeat(np.arange(first, first + count), width))
            cols.append(columns.ravel())
            vals.append(values.ravel())
            lower.append(np.full(count, lo))
            upper.append(np.full(count, hi))
            first += count
        matrix = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(first, self.n_variables),
        )
        order = self._stage_order(groups)
        matrix = matrix[order].tocsc()
        matrix.sort_indices()
        return matrix, np.concatenate(lower)[order], np.concatenate(upper)[order]

    def equalities(self) -> tuple[sp.csc_matrix, np.ndarray]:
        """A and b."""
        matrix, rhs, _ = self._assemble(self._eq)
        return matrix, rhs

    def inequalities(self) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
        """C, l and u."""
        return self._assemble(self._in)

    @classmethod
    def _shift(cls, groups: list) -> np.ndarray:
        """One-stage shift map of the rows' multipliers, in the assembled (time-major) order."""
        if not groups:
            return np.zeros(0, dtype=int)
        total = sum(columns.shape[0] for columns, *_ in groups)
        source = np.arange(total)
        first = 0
        for columns, *_ in groups:
            shift_source(_grid(first, columns.shape[0], 1), source)
            first += columns.shape[0]
        order = cls._stage_order(groups)
        position = np.empty(total, dtype=int)
        position[order] = np.arange(total)
        return position[source[order]]

    def eq_shift(self) -> np.ndarray:
        """One-stage shift map of the equality multipliers."""
        return self._shift(self._eq)

    def in_shift(self) -> np.ndarray:
        """One-stage shift map of the inequality multipliers."""
        return self._shift(self._in)
