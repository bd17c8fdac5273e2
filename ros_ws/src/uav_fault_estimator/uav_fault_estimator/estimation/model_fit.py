"""Whether the prediction model still fits the aircraft: the model_fit status of mhe_node.

A model calibrated (or shipped) for one aircraft stops fitting when the aircraft changes (a
new payload, a new antenna): its fault-free residuals then have a mean the calibrated noise
does not. Over the last window_s of residuals while no fault is reported (every estimate
below the detection threshold: the fault-free part of the flight), per channel c

    z_c = mean(y_c) / sqrt(variance_c / n_eff),   n_eff = n (1 - rho_c) / (1 + rho_c)

with the noise calibration's variance and one-step correlation rho of the suite each sample
flew (the AR(1) white equivalent: samples 0.5 s apart after F_a are not independent). Any
|z_c| above threshold_sigmas: the model does not fit, recalibrate.

A changed aircraft (a new payload) differs from its model from take-off on, so until the
window has first judged the model fit, every sample is taken, a reported fault or not: a
model error that reads as a fault from the start is called what it is once the window holds
judged_after_s of samples. Once the model has been judged fit, a reported fault stops the
assessment (the residuals then carry the fault: a fault that appears later is not the
model's), and the window keeps what it had. No ROS here.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from uav_fault_estimator.estimation.noise_model import SUITES, NoiseCalibration, white_share
from uav_fault_estimator.estimation.residuals import RESIDUAL_CHANNELS

ASSESSING, FITS, DOES_NOT_FIT, NOT_ASSESSED = "assessing", "fits", "does not fit", "not assessed"


@dataclass(frozen=True)
class FitVerdict:
    """The verdict (one of the module's constants), the largest |z| and its channel, and
    the samples in the window."""

    verdict: str
    largest_sigmas: float
    channel: str
    samples: int

    @property
    def text(self) -> str:
        """One line for /diagnostics."""
        if self.verdict == DOES_NOT_FIT:
            return (f"model does not fit: recalibrate ({self.channel} residual mean "
                    f"{self.largest_sigmas:+.1f} noise deviations)")
        if self.verdict == FITS:
            return f"model fits ({self.channel} at {self.largest_sigmas:+.1f} deviations)"
        if self.verdict == NOT_ASSESSED:
            return "not assessed while a fault is reported"
        return f"assessing ({self.samples} fault-free samples)"


class ModelFit:
    """The test of the module docstring over the samples of the last window_s [s]."""

    def __init__(self, noise: NoiseCalibration, window_s: float, threshold_sigmas: float,
                 judged_after_s: float) -> None:
        if not 0 < judged_after_s <= window_s or not threshold_sigmas > 0:
            raise ValueError(f"model fit needs 0 < judged_after_s <= window_s and a positive "
                             f"threshold, got {judged_after_s} s, {window_s} s and "
                             f"{threshold_sigmas}")
        self.window_s = window_s
        self.judged_after_s = judged_after_s
        self.threshold_sigmas = threshold_sigmas
        # per suite: 1/sigma and the AR(1) white-equivalent factor (1 - rho) / (1 + rho)
        self._whitening = {source: 1.0 / np.sqrt(noise.variances[suite])
                           for source, suite in SUITES.items()}
        self._white_share = {source: white_share(noise.correlations[suite])
                             for source, suite in SUITES.items()}
        self.reset()

    def reset(self) -> None:
        """Forget the window (a new flight)."""
        self._samples: deque[tuple[float, np.ndarray, np.ndarray, np.ndarray]] = deque()
        self.last = FitVerdict(ASSESSING, 0.0, RESIDUAL_CHANNELS[0], 0)
        self.judged_fit = False  # the model has been judged fit in this flight

    def update(self, time_s: float, residual: np.ndarray, valid: np.ndarray, wind_source: int,
               fault_reported: bool) -> FitVerdict:
        """Take one residual sample (6,) [residual units], its valid rows and suite (unless a
        fault is reported after the model was judged fit); the verdict on the window."""
        if fault_reported and self.judged_fit:
            self.last = FitVerdict(NOT_ASSESSED, self.last.largest_sigmas, self.last.channel,
                                   len(self._samples))
            return self.last
        usable = np.asarray(valid, dtype=bool) & np.isfinite(residual)
        self._samples.append((time_s, np.where(usable, residual, 0.0)
                              * self._whitening[wind_source], usable,
                              self._white_share[wind_source]))
        while self._samples and self._samples[0][0] <= time_s - self.window_s:
            self._samples.popleft()
        self.last = self._verdict(time_s)
        self.judged_fit = self.judged_fit or self.last.verdict == FITS
        return self.last

    def _verdict(self, time_s: float) -> FitVerdict:
        if self._samples[0][0] > time_s - self.judged_after_s:
            return FitVerdict(ASSESSING, 0.0, RESIDUAL_CHANNELS[0], len(self._samples))
        whitened = np.array([sample[1] for sample in self._samples])
        usable = np.array([sample[2] for sample in self._samples])
        shares = np.array([sample[3] for sample in self._samples])
        counts = usable.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = whitened.sum(axis=0) / counts
            z = np.nan_to_num(mean * np.sqrt((usable * shares).sum(axis=0)))
        worst = int(np.argmax(np.abs(z)))
        verdict = DOES_NOT_FIT if abs(z[worst]) > self.threshold_sigmas else FITS
        return FitVerdict(verdict, float(z[worst]), RESIDUAL_CHANNELS[worst],
                          len(self._samples))
