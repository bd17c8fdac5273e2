"""Plain configuration of the fault estimators (mhe_node's made from its settings,
estimator_settings.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from uav_common.channels import PAPER_FAULT_NAMES

from uav_fault_estimator.estimation.fault_models import FaultModel, make_model
from uav_fault_estimator.estimation.monotone_active_set import is_monotone
from uav_fault_estimator.estimation.qp_problem import WindowQP

ARRIVAL_CENTRES = ("filter", "previous_window")


@dataclass
class FaultConfig:
    """One estimated fault: its name, evolution model and bounds.

    model: a name in fault_models.MODEL_CLASSES; params: that model's parameters
    (e.g. lambda_pct for "monotonic"); lower_pct / upper_pct: bounds on f [%];
    prior_pct: f before any data [%].
    """

    name: str
    model: str = "monotonic"
    params: dict[str, Any] = field(default_factory=lambda: {"lambda_pct": 0.5})
    lower_pct: float = -math.inf
    upper_pct: float = math.inf
    prior_pct: float = 0.0

    def build_model(self) -> FaultModel:
        """The fault model this entry names (ValueError naming the fault if wrong)."""
        if self.lower_pct > self.upper_pct:
            raise ValueError(f"fault {self.name}: lower_pct > upper_pct")
        try:
            return make_model(self.model, **self.params)
        except ValueError as error:
            raise ValueError(f"fault {self.name}: {error}") from None


# How each window's QP is solved: ProxSuite (any fault model), or the exact active-set
# method for monotonic increasing faults (monotone_active_set.py; ProxSuite solves the
# windows where it does not settle).
SOLVER_METHODS = ("proxsuite", "active_set")
SOLVER_METHOD_KEY = "solver_method"  # mhe_node's /diagnostics value naming its method


@dataclass
class SolverSettings:
    """method: one of SOLVER_METHODS; ProxSuite's absolute/relative KKT tolerances and its
    iteration cap; budget_ms: the time an update may take [ms] before the window's oldest
    suspect sample is dropped (mhe.SUSPECT_SIGMAS)."""

    # 1e-7: at 1e-6 a vane-less window's estimate met the dual residual 0.45 % from its
    # optimum along a direction of little curvature; at 1e-7 within 0.002 % (bench_mhe)
    eps_abs: float = 1e-7
    eps_rel: float = 0.0
    max_iter: int = 200
    method: str = "proxsuite"
    budget_ms: float = 100.0


@dataclass
class EstimatorConfig:
    """Moving-horizon / batch MAP estimator parameters.

    horizon: N samples in the window (mhe_node's default: EstimatorSettings.horizon);
    q_diag: residual noise variances Q (one per residual channel) [residual unit²];
    r_diag_pct2: the arrival cost's covariance R before any data (one per fault) [%²];
    arrival_inflation (>= 1) and arrival_floor_pct2 (one per fault, or None for 0) [%²]: see
    arrival_cost.ArrivalCost; arrival_centre: "filter" (the arrival filter's mean) or
    "previous_window" (the previous window's estimate of the first point, as UAV eq. 17);
    faults: the estimated faults; solver: ProxSuite settings. Defaults of the rest: the
    embedded-estimation paper's setting, four monotonic increasing faults.
    """

    horizon: int
    q_diag: tuple[float, ...] = (1e-2, 1e-2, 1e-2, 1e-4, 1e-4, 1e-4)
    r_diag_pct2: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)
    faults: list[FaultConfig] = field(
        default_factory=lambda: [FaultConfig(name) for name in PAPER_FAULT_NAMES]
    )
    solver: SolverSettings = field(default_factory=SolverSettings)
    arrival_inflation: float = 1.0
    arrival_floor_pct2: tuple[float, ...] | None = None
    arrival_centre: str = "filter"

    def validate(self) -> None:
        """Raise ValueError naming the first inconsistent parameter."""
        if self.horizon < 2:
            raise ValueError(f"horizon must be at least 2, got {self.horizon}")
        if self.arrival_centre not in ARRIVAL_CENTRES:
            raise ValueError(f"arrival_centre must be one of {', '.join(ARRIVAL_CENTRES)}, "
                             f"got {self.arrival_centre!r}")
        if not (math.isfinite(self.arrival_inflation) and self.arrival_inflation >= 1.0):
            raise ValueError(f"arrival_inflation must be at least 1, got "
                             f"{self.arrival_inflation}")
        floor = self.arrival_floor
        if floor.size != len(self.faults) or not np.all(np.isfinite(floor) & (floor >= 0)):
            raise ValueError("arrival_floor_pct2 needs one non-negative entry per fault")
        if len(self.r_diag_pct2) != len(self.faults):
            raise ValueError("r_diag_pct2 needs one entry per fault")
        for name, values in (("q_diag", self.q_diag), ("r_diag_pct2", self.r_diag_pct2)):
            if not all(math.isfinite(v) and v > 0 for v in values):
                raise ValueError(f"{name} entries must be positive and finite")
        models = [fault.build_model() for fault in self.faults]
        if not self.solver.budget_ms > 0:
            raise ValueError(f"the update budget must be positive, got {self.solver.budget_ms} ms")
        if self.solver.method not in SOLVER_METHODS:
            raise ValueError(f"solver method must be one of {', '.join(SOLVER_METHODS)}, got "
                             f"{self.solver.method!r}")
        if self.solver.method == "active_set" and not is_monotone(
                [model.increment_terms() for model in models]):
            raise ValueError("the active_set solver method needs every estimated column "
                             "monotonic (increasing), without wind-error columns")

    def window_qp(self, stages: int) -> WindowQP:
        """The MAP QP over `stages` stages for these faults' models and bounds."""
        return WindowQP(stages, [fault.build_model() for fault in self.faults],
                        [(fault.lower_pct, fault.upper_pct) for fault in self.faults])

    @property
    def q_inv(self) -> np.ndarray:
        """Q⁻¹ diagonal [1/residual unit²]."""
        return 1.0 / np.asarray(self.q_diag, dtype=float)

    @property
    def r_inv(self) -> np.ndarray:
        """R⁻¹ diagonal [1/%²]."""
        return 1.0 / np.asarray(self.r_diag_pct2, dtype=float)

    @property
    def arrival_floor(self) -> np.ndarray:
        """The arrival cost's least variance per fault [%²]."""
        if self.arrival_floor_pct2 is None:
            return np.zeros(len(self.faults))
        return np.asarray(self.arrival_floor_pct2, dtype=float)

    @property
    def prior_pct(self) -> np.ndarray:
        """The faults before any data [%]."""
        return np.array([fault.prior_pct for fault in self.faults])
