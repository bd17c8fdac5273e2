"""The template test: each failure's learned shape, slid over the whitened residuals.

A failure drives each generator's residual with the parameters fixed (the fast test's,
y - phiᵀ theta0) along a shape in time that the failure, the autopilot and the aircraft
make together: an engine cut first pitches the aircraft down, then drops the body-x force,
while the fault-free residuals swing with turns and climbs. The test that finds a known
shape soonest at a given false-alarm rate is its matched filter, on residuals whitened by
the fault-free residuals' own colour. Here:

- whitening_filters / whitened: per generator, the prediction-error filter of an
  autoregressive model (order WHITENING_ORDER) fitted to fault-free residuals, and residuals
  through it (their innovations).
- matched_filter: a shape (L, G) slid over residuals (K, G): at each window's last sample,
  sum of shape * (residual - the mean of the `reference` samples before the window) /
  spread^2, over the shape's norm; about N(0, 1) for white residuals of that spread.
- FailureTemplates: each failure kind's shape (the mean, over simulated failures, of the
  whitened residuals' difference from the failure's fault-free twin over the L samples after
  its onset), the cause it names, and the Weibull distribution of the statistic's largest
  value over blocks of L samples on fault-free flights, from which its threshold for a
  stated rate of false alarms per flight hour follows (eq. 25 applied to block maxima: a
  block of L samples exceeds the threshold with probability rate * L * period / 1 h).
- TemplateTest: the same, sample by sample, as the detector runs it.

Learned by scripts/learn_signatures.py, stored beside the failure signatures. No ROS here.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from uav_fault_estimator.detection.change_detection import (
    Weibull,
    per_sample_probability,
    weibull_fit,
    weibull_threshold,
)
from uav_fault_estimator.detection.signatures import load_signatures_file

WHITENING_ORDER = 4  # the autoregressive model of the fault-free residuals' colour
# The template test's designed false alarms per flight hour, each template. Chosen on the
# simulated dev flights (seeds from 501, docs/detector.md): the largest of 0.1, 0.3 and 1
# at which none of either vehicle's 20 fault-free dev flights alarmed.
DEFAULT_TEMPLATE_FALSE_ALARMS_PER_HOUR = 0.1
TEMPLATES_KEY = "templates"  # the signatures file's key that holds them


def whitening_filters(fault_free: Sequence[np.ndarray], order: int = WHITENING_ORDER
                      ) -> np.ndarray:
    """Per generator, the prediction-error filter [1, -a_1, ..., -a_order] (G, order + 1)
    of an autoregressive model of that order, fitted by least squares to fault-free
    residuals (each (K_i, G), the RLS's settling left out), each flight's mean removed."""
    columns = []
    for g in range(fault_free[0].shape[1]):
        rows, targets = [], []
        for residuals in fault_free:
            x = residuals[:, g] - residuals[:, g].mean()
            rows.append(np.column_stack([x[order - i - 1:len(x) - i - 1]
                                         for i in range(order)]))
            targets.append(x[order:])
        coefficients, *_ = np.linalg.lstsq(np.vstack(rows), np.concatenate(targets),
                                           rcond=None)
        columns.append(np.concatenate(([1.0], -coefficients)))
    return np.array(columns)


def whitened(residuals: np.ndarray, filters: np.ndarray) -> np.ndarray:
    """Residuals (K, G) through each generator's prediction-error filter (the samples
    before the first taken as 0)."""
    from scipy.signal import lfilter  # imported here: detector_node never learns a filter

    return np.column_stack([lfilter(taps, [1.0], residuals[:, g])
                            for g, taps in enumerate(filters)])


def matched_filter(shape: np.ndarray, spread: np.ndarray, residuals: np.ndarray,
                   reference: int) -> np.ndarray:
    """The matched filter of a shape (L, G) slid over residuals (K, G) of spread (G,): at
    each window's last sample k, sum over the window's samples and generators of shape *
    (residual - the generator's mean over the reference samples before the window) /
    spread^2, over the shape's norm (about N(0, 1) for white residuals of that spread); NaN
    where the window and its reference do not fit."""
    length = len(shape)
    weights = shape / spread ** 2
    sums = np.vstack([np.zeros(residuals.shape[1]), np.cumsum(residuals, axis=0)])
    ends = np.arange(length - 1 + reference, len(residuals))
    starts = ends - length + 1
    means = (sums[starts] - sums[starts - reference]) / reference
    correlations = np.column_stack([np.correlate(residuals[:, g], weights[:, g], "valid")
                                    for g in range(residuals.shape[1])])
    statistic = np.full(len(residuals), np.nan)
    statistic[ends] = (np.sum(correlations[starts] - means * weights.sum(axis=0), axis=1)
                       / math.sqrt(np.sum((shape / spread) ** 2)))
    return statistic


def block_maxima(statistic: np.ndarray, length: int) -> np.ndarray:
    """The largest finite value of each whole block of `length` samples that has one."""
    x = statistic[np.isfinite(statistic)]
    blocks = x[:len(x) // length * length].reshape(-1, length)
    return blocks.max(axis=1)


@dataclass(frozen=True)
class FailureTemplates:
    """The template test's whitening filters (G, order + 1), the whitened fault-free
    residuals' spread (G,), the samples each window's mean is taken from (reference); per
    template, the failure kind it was learned from, the cause it names
    (signatures.CAUSES), its shape (N, L, G) and its statistic's block maxima's Weibull
    distribution on fault-free flights."""

    whitening: np.ndarray
    spread: np.ndarray
    reference: int
    kinds: tuple[str, ...]
    causes: tuple[str, ...]
    shapes: np.ndarray
    maxima: tuple[Weibull, ...]
    learned_from: str = ""

    def __post_init__(self) -> None:
        generators = len(self.spread)
        if (self.whitening.ndim != 2 or self.whitening.shape[0] != generators
                or self.shapes.ndim != 3 or self.shapes.shape[2] != generators
                or not len(self.kinds) == len(self.causes) == len(self.shapes)
                == len(self.maxima) or self.reference < 1 or not np.all(self.spread > 0.0)):
            raise ValueError(
                f"templates: whitening {self.whitening.shape}, spread {self.spread.shape}, "
                f"shapes {self.shapes.shape}, {len(self.kinds)} kinds, {len(self.causes)} "
                f"causes, {len(self.maxima)} distributions, reference {self.reference}: "
                "expected one filter and a positive spread per generator, and one kind, "
                "cause, shape (L, generators) and distribution per template")

    @property
    def length(self) -> int:
        """L, each shape's samples."""
        return self.shapes.shape[1]

    def thresholds(self, false_alarms_per_hour: float, sample_period_s: float) -> np.ndarray:
        """Each template's threshold for this designed rate of false alarms per flight hour
        (N,)."""
        probability = per_sample_probability(false_alarms_per_hour, self.length,
                                             sample_period_s)
        return np.array([weibull_threshold(maxima, probability) for maxima in self.maxima])


def maxima_distribution(shape: np.ndarray, spread: np.ndarray, reference: int,
                        fault_free: Sequence[np.ndarray]) -> Weibull:
    """The Weibull distribution of a shape's statistic's block maxima (blocks of its
    length) over whitened fault-free residuals (each (K_i, G), settling left out)."""
    return weibull_fit(np.concatenate([
        block_maxima(matched_filter(shape, spread, residuals, reference), len(shape))
        for residuals in fault_free]))


@dataclass(frozen=True)
class LearningFlight:
    """One simulated failure to learn from: its kind and cause (signatures.CAUSES), its
    whitened residuals with the parameters fixed (K, G), their difference from its
    fault-free twin's over the L samples after the failure's reference time (L, G), and
    which of its samples count as finding it in time (K,) (from the onset to 5 s after the
    reference)."""

    kind: str
    cause: str
    residuals: np.ndarray
    difference: np.ndarray
    in_time: np.ndarray


def learn_templates(filters: np.ndarray, reference: int, fault_free: Sequence[np.ndarray],
                    flights: Sequence[LearningFlight], false_alarms_per_hour: float,
                    sample_period_s: float, learned_from: str = ""
                    ) -> FailureTemplates | None:
    """A template per failure kind of flights, kept when it finds in time at least half of
    its kind's flights, each by the template learned without it, and no fault-free flight
    reaches its threshold (a shape that also fits fault-free manoeuvres only adds false
    alarms); thresholds for false_alarms_per_hour. filters: whitening_filters' of the
    fault-free residuals; fault_free: those residuals whitened (each (K_i, G), settling left
    out). None when no template is kept (or no flight given)."""
    if not flights:
        return None
    spread = np.std(np.vstack(fault_free), axis=0)
    probability = per_sample_probability(false_alarms_per_hour, flights[0].difference.shape[0],
                                         sample_period_s)

    def threshold(shape: np.ndarray) -> tuple[float, Weibull]:
        maxima = maxima_distribution(shape, spread, reference, fault_free)
        return weibull_threshold(maxima, probability), maxima

    kept: list[tuple[str, str, np.ndarray, Weibull]] = []
    for kind in dict.fromkeys(flight.kind for flight in flights):
        mine = [flight for flight in flights if flight.kind == kind]
        differences = np.array([flight.difference for flight in mine])
        found = 0
        for n, flight in enumerate(mine):
            shape = np.delete(differences, n, axis=0).mean(axis=0)
            statistic = matched_filter(shape, spread, flight.residuals, reference)
            found += bool(np.nanmax(statistic[flight.in_time], initial=-math.inf)
                          > threshold(shape)[0])
        shape = differences.mean(axis=0)
        limit, maxima = threshold(shape)
        quiet = all(np.nanmax(matched_filter(shape, spread, residuals, reference)) < limit
                    for residuals in fault_free)
        if 2 * found >= len(mine) and quiet:
            kept.append((kind, mine[0].cause, shape, maxima))
    if not kept:
        return None
    kinds, causes, shapes, maxima = zip(*kept, strict=True)
    return FailureTemplates(filters, spread, reference, kinds, causes, np.array(shapes),
                            maxima, learned_from)


class TemplateTest:
    """The template test sample by sample: feed each sample's residuals with the
    parameters fixed (G,); it gives each template's statistic (N,) once its window and
    reference are full, as matched_filter over whitened would."""

    def __init__(self, templates: FailureTemplates) -> None:
        self.templates = templates
        taps = templates.whitening
        self.taps = taps.T  # (order + 1, G): row i multiplies the residual i samples back
        # shape / spread^2 over the shape's norm, and each template's sum over its samples
        norms = np.sqrt(np.sum((templates.shapes / templates.spread) ** 2, axis=(1, 2)))
        self.weights = templates.shapes / templates.spread ** 2 / norms[:, None, None]
        self.weight_sums = self.weights.sum(axis=1)  # (N, G)
        self.reset()

    def reset(self) -> None:
        """From a start: no residual before."""
        generators = len(self.templates.spread)
        self.recent = np.zeros((len(self.taps), generators))  # newest first; 0 before a start
        self.window: deque[np.ndarray] = deque(
            maxlen=self.templates.length + self.templates.reference)

    def update(self, fixed_residual: np.ndarray) -> np.ndarray | None:
        """Each template's statistic (N,) after this sample; None until the window and its
        reference are full."""
        self.recent = np.vstack([fixed_residual, self.recent[:-1]])
        self.window.append(np.sum(self.taps * self.recent, axis=0))
        if len(self.window) < self.window.maxlen:
            return None
        values = np.array(self.window)
        length = self.templates.length
        reference_mean = values[:-length].mean(axis=0)
        return (np.einsum("nlg,lg->n", self.weights, values[-length:])
                - self.weight_sums @ reference_mean)


def templates_to_dict(templates: FailureTemplates) -> dict[str, Any]:
    """The templates as the signatures file's mapping under TEMPLATES_KEY (YAML-ready)."""
    def rounded(values: np.ndarray) -> list:
        return np.round(values, 8).tolist()

    return {"learned_from": templates.learned_from, "reference": templates.reference,
            "whitening": rounded(templates.whitening), "spread": rounded(templates.spread),
            "templates": [{"kind": kind, "cause": cause, "shape": rounded(shape),
                           "maxima_weibull": {"scale": maxima.scale, "shape": maxima.shape}}
                          for kind, cause, shape, maxima in zip(
                              templates.kinds, templates.causes, templates.shapes,
                              templates.maxima, strict=True)]}


def templates_from_dict(data: Mapping[str, Any]) -> FailureTemplates:
    """FailureTemplates from the file's mapping; KeyError, TypeError or ValueError when it
    is not one."""
    entries = data["templates"]
    return FailureTemplates(
        whitening=np.array(data["whitening"], dtype=float),
        spread=np.array(data["spread"], dtype=float),
        reference=int(data["reference"]),
        kinds=tuple(str(entry["kind"]) for entry in entries),
        causes=tuple(str(entry["cause"]) for entry in entries),
        shapes=np.array([entry["shape"] for entry in entries], dtype=float),
        maxima=tuple(Weibull(float(entry["maxima_weibull"]["scale"]),
                             float(entry["maxima_weibull"]["shape"])) for entry in entries),
        learned_from=str(data["learned_from"]))


def templates_in(data: Any, path: Path) -> FailureTemplates | None:
    """The templates a signatures file's parsed YAML holds (None: it holds none); ValueError
    with one line naming the file (path)."""
    templates = data.get(TEMPLATES_KEY) if isinstance(data, dict) else None
    try:
        return None if templates is None else templates_from_dict(templates)
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"templates in {path}: {type(error).__name__}: {error}") from None


def read_templates(path: Path) -> FailureTemplates | None:
    """The templates a signatures file holds (None: it holds none); ValueError with one
    line naming the file."""
    return templates_in(load_signatures_file(path), path)
