"""System-identification manoeuvres: the inputs flight testers fly, as the autopilot adds them.

A manoeuvre is a signal on one axis (roll, pitch, yaw or throttle) at one level of the
autopilot: `attitude` (added to the commanded roll or pitch angle [deg]; on the yaw axis to
the commanded sideslip [deg], which the simulated autopilot's yaw loop holds), `rate` (added
to the roll or pitch rate the damping terms hold [deg/s]) or `surface` (added to the
surface's or the throttle's output after the loops [a fraction of full throw]). The loops
keep flying throughout, as ArduPlane's system-identification mode keeps them.

Kinds, with ArduPlane's `SID_*` meanings for the sweeps:

- `chirp`: a sine whose frequency rises exponentially from f_start_hz to f_stop_hz over
  duration_s, under a raised-cosine fade in over fade_in_s and fade out over fade_out_s
  (ArduPilot's AP_Math chirp: SID_F_START_HZ, SID_F_STOP_HZ, SID_T_REC, SID_T_FADE_IN,
  SID_T_FADE_OUT).
- `multisine`: the harmonics of 1/duration_s between f_start_hz and f_stop_hz at equal
  amplitude with Schroeder's phases (a low peak for its power; Morelli's orthogonal
  multisines give each axis its own harmonics), scaled to a peak of magnitude, under the
  same fades.
- `doublet`: +magnitude for step_s, then -magnitude for step_s.
- `3211`: +, -, +, - for 3, 2, 1 and 1 step_s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

KINDS = ("chirp", "multisine", "doublet", "3211")
SWEEPS = ("chirp", "multisine")
AXES = ("roll", "pitch", "yaw", "throttle")
LEVELS = ("attitude", "rate", "surface")
# Each step kind's pulses: (sign, length in step_s)
STEP_PULSES = {"doublet": ((1, 1), (-1, 1)), "3211": ((1, 3), (-1, 2), (1, 1), (-1, 1))}
# The levels each axis has in the simulated autopilot: no yaw-rate loop, throttle only at
# its output.
AXIS_LEVELS = {"roll": LEVELS, "pitch": LEVELS, "yaw": ("attitude", "surface"),
               "throttle": ("surface",)}
# The largest magnitude per level: a bank or sideslip beyond 45 deg, a rate beyond 180 deg/s
# or more than full throw is no identification input.
MAX_MAGNITUDE = {"attitude": 45.0, "rate": 180.0, "surface": 1.0}
MAX_SWEEP_HZ = 30.0  # a quarter of the autopilot's 120 Hz: four control steps per period
_PEAK_GRID_HZ = 400.0  # where a multisine's peak is found, fine against MAX_SWEEP_HZ


@dataclass(frozen=True)
class Manoeuvre:
    """One scheduled manoeuvre (the module docstring): from start_s [s], a kind on an axis
    at a level, of magnitude (deg, deg/s or a fraction of full throw), and the sweep's band
    [Hz], duration and fades [s] or the steps' length step_s [s]."""

    start_s: float
    kind: str
    axis: str
    level: str
    magnitude: float
    f_start_hz: float = 0.0
    f_stop_hz: float = 0.0
    duration_s: float = 0.0
    fade_in_s: float = 0.0
    fade_out_s: float = 0.0
    step_s: float = 0.0

    @property
    def length_s(self) -> float:
        """How long the input lasts [s]."""
        if self.kind in SWEEPS:
            return self.duration_s
        return self.step_s * sum(length for _, length in STEP_PULSES[self.kind])

    @property
    def end_s(self) -> float:
        return self.start_s + self.length_s

    def value(self, time_s: float) -> float:
        """The input at time_s [s of the flight] in the magnitude's unit (0 outside it)."""
        t = time_s - self.start_s
        if not 0.0 <= t <= self.length_s:
            return 0.0
        if self.kind == "chirp":
            return self.magnitude * self._window(t) * math.sin(self._chirp_phase(t))
        if self.kind == "multisine":
            return self.magnitude * self._window(t) * self._multisine(t) / self._multisine_peak
        return self.magnitude * _step_sign(STEP_PULSES[self.kind], t / self.step_s)

    def _window(self, t: float) -> float:
        """The raised-cosine fade in and out at t [s into the sweep]."""
        if t < self.fade_in_s:
            return 0.5 - 0.5 * math.cos(math.pi * t / self.fade_in_s)
        from_end_s = self.duration_s - t
        if from_end_s < self.fade_out_s:
            return 0.5 - 0.5 * math.cos(math.pi * from_end_s / self.fade_out_s)
        return 1.0

    def _chirp_phase(self, t: float) -> float:
        """The exponential sweep's phase [rad]: its frequency w_start e^(B t / T), B =
        ln(w_stop / w_start), integrated from 0 (a tone where the band is one frequency)."""
        w_start = 2.0 * math.pi * self.f_start_hz
        w_stop = 2.0 * math.pi * self.f_stop_hz
        if math.isclose(w_start, w_stop):
            return w_start * t
        rate = math.log(w_stop / w_start)
        return w_start * self.duration_s / rate * math.expm1(rate * t / self.duration_s)

    @cached_property
    def _harmonics(self) -> tuple[np.ndarray, np.ndarray]:
        """The multisine's frequencies [rad/s] and Schroeder phases [rad]: the harmonics of
        1/duration_s in the band (at least one), phase_k = -pi k (k + 1) / M."""
        base_hz = 1.0 / self.duration_s
        first = max(1, math.ceil(self.f_start_hz / base_hz - 1e-9))
        last = max(first, math.floor(self.f_stop_hz / base_hz + 1e-9))
        orders = np.arange(first, last + 1)
        index = np.arange(len(orders))
        return (2.0 * math.pi * base_hz * orders,
                -math.pi * index * (index + 1) / len(orders))

    def _multisine(self, t: float | np.ndarray) -> float | np.ndarray:
        frequencies, phases = self._harmonics
        return np.cos(np.multiply.outer(t, frequencies) + phases).sum(axis=-1)

    @cached_property
    def _multisine_peak(self) -> float:
        """The multisine's largest magnitude over its duration (sampled at _PEAK_GRID_HZ)."""
        grid = np.linspace(0.0, self.duration_s, int(self.duration_s * _PEAK_GRID_HZ) + 1)
        return float(np.max(np.abs(self._multisine(grid))))


def _step_sign(pulses: tuple[tuple[int, int], ...], steps: float) -> float:
    """The sign of the pulse train at `steps` step lengths from its start (0 after it)."""
    for sign, length in pulses:
        if steps < length:
            return float(sign)
        steps -= length
    return 0.0


@dataclass(frozen=True)
class Excitation:
    """What the manoeuvres add to the autopilot at one instant (SI, radians; 0: nothing):
    to the commanded roll, pitch and sideslip, to the roll and pitch rates held, to the
    surfaces' and throttle's outputs."""

    roll_rad: float = 0.0
    pitch_rad: float = 0.0
    sideslip_rad: float = 0.0
    roll_rate_radps: float = 0.0
    pitch_rate_radps: float = 0.0
    aileron_rad: float = 0.0
    elevator_rad: float = 0.0
    rudder_rad: float = 0.0
    throttle: float = 0.0


NO_EXCITATION = Excitation()
# Which Excitation field an (axis, level) drives, and whether its unit is degrees (else a
# fraction of the surface's full throw, or of the throttle's range)
_TARGETS = {("roll", "attitude"): ("roll_rad", True), ("pitch", "attitude"): ("pitch_rad", True),
            ("yaw", "attitude"): ("sideslip_rad", True),
            ("roll", "rate"): ("roll_rate_radps", True),
            ("pitch", "rate"): ("pitch_rate_radps", True),
            ("roll", "surface"): ("aileron_rad", False),
            ("pitch", "surface"): ("elevator_rad", False),
            ("yaw", "surface"): ("rudder_rad", False),
            ("throttle", "surface"): ("throttle", False)}


def excitation(manoeuvres: tuple[Manoeuvre, ...], time_s: float,
               surface_limit_rad: float) -> Excitation:
    """What the manoeuvres active at time_s [s] add (NO_EXCITATION outside all of them); a
    surface's fraction of full throw is of surface_limit_rad [rad]."""
    added: dict[str, float] = {}
    for manoeuvre in manoeuvres:
        if manoeuvre.start_s <= time_s <= manoeuvre.end_s:
            name, in_degrees = _TARGETS[(manoeuvre.axis, manoeuvre.level)]
            scale = (math.radians(1.0) if in_degrees
                     else 1.0 if name == "throttle" else surface_limit_rad)
            added[name] = added.get(name, 0.0) + scale * manoeuvre.value(time_s)
    return Excitation(**added) if added else NO_EXCITATION
