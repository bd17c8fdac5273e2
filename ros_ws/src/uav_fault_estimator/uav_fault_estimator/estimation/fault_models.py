"""Fault evolution models: how one fault's increments enter the MAP estimation QP.

Every model is the prior of Samar & Gorinevsky, "Model predictive estimation of evolving
faults" (EF below), section III: f(t+1) = a f(t) + gamma(t), with gamma(t) IID of density p(·).
Its negative log-density, summed over the window (EF eq. 14), is described here by
`IncrementTerms` on the increment δ(t) = f(t+1) - a f(t) (percent per sample):

    J_k = Σ_t  ½ w δ(t)²  +  c δ(t)  +  b |δ(t)|,   subject to  lo ≤ δ(t) ≤ hi.

Adding a model is adding one small class with an `increment_terms` method and a line in
`MODEL_CLASSES`. Fault values are in percent; model parameters are in percent per sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol


@dataclass(frozen=True)
class IncrementTerms:
    """Cost and range of the increment δ(t) = f(t+1) - coefficient · f(t) [%/sample].

    quadratic_weight: w in ½ w δ² [1/%²]; linear_cost: c in c δ [1/%];
    abs_cost: b in b |δ| [1/%] (made a QP with one slack per increment);
    lower_pct, upper_pct: the range of δ [%]; equal bounds make δ an equality.
    """

    coefficient: float = 1.0
    quadratic_weight: float = 0.0
    linear_cost: float = 0.0
    abs_cost: float = 0.0
    lower_pct: float = -math.inf
    upper_pct: float = math.inf


class FaultModel(Protocol):
    """A fault evolution model: anything that states its increment terms."""

    def increment_terms(self) -> IncrementTerms:
        """The cost and range of this fault's increments."""
        ...


def _require_positive(name: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"fault model parameter {name} must be positive and finite, got {value}")


@dataclass(frozen=True)
class Monotonic:
    """Exponential increments of mean lambda_pct [%/sample] (EF eq. 8, UAV eq. 10-11).

    -log p(δ) = δ/λ for δ ≥ 0 (EF eq. 20) and the increments may not change sign (EF
    eq. 21, UAV eq. 16). A decreasing fault mirrors both: cost -δ/λ and δ ≤ 0.
    """

    lambda_pct: float = 1.0
    increasing: bool = True

    def increment_terms(self) -> IncrementTerms:
        _require_positive("lambda_pct", self.lambda_pct)
        if self.increasing:
            return IncrementTerms(linear_cost=1.0 / self.lambda_pct, lower_pct=0.0)
        return IncrementTerms(linear_cost=-1.0 / self.lambda_pct, upper_pct=0.0)


@dataclass(frozen=True)
class MonotonicDecreasing(Monotonic):
    """A fault that can only decrease: the mirror of Monotonic."""

    increasing: bool = False


@dataclass(frozen=True)
class RandomWalk:
    """Gaussian increments gamma ~ N(0, sigma²) in f(t+1) = a f(t) + gamma (EF eq. 4-5).

    -log p(δ) = δ² / (2sigma²). (EF eq. 22 prints 1/(2sigma); the Gaussian density of eq. 5
    gives 1/(2sigma²), used here.)
    """

    sigma: float = 1.0  # per sample, in the column's unit: % for a fault, m/s for a wind error
    coefficient: float = 1.0

    def increment_terms(self) -> IncrementTerms:
        _require_positive("sigma", self.sigma)
        return IncrementTerms(
            coefficient=self.coefficient, quadratic_weight=1.0 / self.sigma**2
        )


@dataclass(frozen=True)
class UniformIncrements:
    """Uniform increments on [-a, a] (EF eq. 6): no cost, |δ| ≤ half_width_pct."""

    half_width_pct: float = 1.0

    def increment_terms(self) -> IncrementTerms:
        _require_positive("half_width_pct", self.half_width_pct)
        return IncrementTerms(lower_pct=-self.half_width_pct, upper_pct=self.half_width_pct)


@dataclass(frozen=True)
class LaplacianIncrements:
    """Laplacian increments of scale a (EF eq. 7): -log p(δ) = |δ| / a."""

    scale_pct: float = 1.0

    def increment_terms(self) -> IncrementTerms:
        _require_positive("scale_pct", self.scale_pct)
        return IncrementTerms(abs_cost=1.0 / self.scale_pct)


@dataclass(frozen=True)
class Constant:
    """A fault that does not change: f(t+1) = f(t) (EF eq. 23), no cost."""

    def increment_terms(self) -> IncrementTerms:
        return IncrementTerms(lower_pct=0.0, upper_pct=0.0)


MODEL_CLASSES: dict[str, type] = {
    "monotonic": Monotonic,
    "monotonic_decreasing": MonotonicDecreasing,
    "random_walk": RandomWalk,
    "uniform": UniformIncrements,
    "laplacian": LaplacianIncrements,
    "constant": Constant,
}


def make_model(name: str, **params: float | bool) -> FaultModel:
    """Build a fault model from its configuration name and parameters.

    Raises ValueError naming the model on an unknown name or parameter.
    """
    try:
        model_class = MODEL_CLASSES[name]
    except KeyError:
        raise ValueError(
            f"unknown fault model {name!r}; known: {', '.join(sorted(MODEL_CLASSES))}"
        ) from None
    try:
        model = model_class(**params)
    except TypeError as error:
        raise ValueError(f"fault model {name!r}: {error}") from None
    model.increment_terms()  # validates the parameters now rather than at the first update
    return model
