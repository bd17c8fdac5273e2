"""Prediction residuals and fault sensitivities from p + 1 copies of a prediction model.

Embedded-estimation paper, section II (eq. 2-8); evolving-faults paper, eq. 15. Per sensor
sample k, with dt_k = t_k - t_{k-1}:

    observed   a_raw[k] = (v[k] - v[k-1]) / dt_k            exact mean of dv/dt on the interval
    predicted  P[k] = [phi(x_k | 0), S_raw(t)]               (6, 1 + p); eq. 6 and eq. 8 / 15:
               S_raw column j = (phi(x | s e_j) - phi(x | 0)) / s
               Pm[k] = (P[k] + P[k-1]) / 2                   trapezoidal mean on the same interval
    filtered   a = F_a a_raw,  [a_hat, S] = F_a Pm           eq. 5-6, F_a = 1/(tau_a s + 1)
    residual   y = a - a_hat                                  eq. 2

S is filtered exactly like a_hat: if the aircraft accelerates as phi(x | f) ~= phi(x | 0) +
S_raw f, then y = F_a (a_raw - phi(x | 0)) ~= F_a (S_raw f) = (F_a S_raw) f for a slowly
changing f, so the S for which y ~= S f holds is the filtered one.

Optionally S gets three more columns, the wind-estimate errors (WIND_ERROR_NAMES): the
model with the wind it flew shifted by a step along north, east or down, differenced the
same way. Gusts the 10 s filtered wind misses are the largest part of the residual in
turbulence; with these columns an estimator takes them out as unknowns of its window.

Air data: given measured airspeed, alpha and beta (uav_sim's AirData), the models fly the
measured air-relative velocity instead of C_bn (v - w_hat): the wind they get is the wind
triangle v - C_nb V(alpha, beta), which gives exactly that air velocity in body axes; the
vanes measure the flow, so the wind-error columns are 0. With a pitot and no vanes (the
angles NaN), they fly the pitot's airspeed along the air velocity of the filtered wind's
triangle (pitot_wind_ned_mps), and so does each wind-error column: the pitot measures the
gust along the air velocity, and the columns carry the two across it, which make the flow
angles. On those samples F_a's time constant is tau_a_pitot_s, short (1 s): through a 4 s
F_a the gusts of several seconds and the turns within them mix, so that no single wind
error per sample explains what they leave in the residuals (measured on a fault-free
flight, the true gust's mean over each sample: what it leaves is 0.8-3.7 times each row's
residual with the true wind flown when F_a is 4 s, 0.2-0.8 times when it is 1 s). A sample
whose air data is missing, non-finite or outside the range the aircraft model holds for
(the vehicle's air_data_range) falls back to the filtered wind; each sample says which it
flew (wind_source).

Frames: the model gives dv/dt of v = (NED ground velocity, body rates), so the linear rows
are filtered in NED. The output expresses them in body axes (x forward, y right, z down),
rotating y, a, a_hat and S's rows by the newest attitude: the same rotation on both sides
keeps y ~= S f, and body axes make the signatures readable (lift: z, drag: x).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from uav_aircraft.flown_aircraft import NO_BIAS, SensorBias, true_air_data
from uav_aircraft.frames import ned_to_body, wind_triangle_ned_mps
from uav_aircraft.vehicles import AirDataRange
from uav_common.channels import AIRSPEED_INDEX, STATE_CHANNELS, state_indices
from uav_common.filters import LowPass, SettlingLowPass
from uav_common.sample_grid import GRID_TOLERANCE_S

# phi(state (14,), controls (7,), filtered NED wind (3,)) -> (6,) [dv_ned/dt m/s^2, dpqr/dt rad/s^2]
Prediction = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
# A copy of the prediction model with the given faults [%] seeded into it.
PredictorFactory = Callable[[Mapping[str, float]], Prediction]

RESIDUAL_CHANNELS = (
    "linear_x", "linear_y", "linear_z", "angular_x", "angular_y", "angular_z",
)
VELOCITY = state_indices("velocity_north", "velocity_east", "velocity_down",
                         "roll_rate", "pitch_rate", "yaw_rate")
ATTITUDE = state_indices("roll", "pitch", "yaw")
[FUEL_MASS] = state_indices("fuel_mass")
# The fuel gauge's reading is smoothed before the models take it: a full tank's contents are
# clipped at its capacity, so a gauge's white noise (0.1 kg a sample) makes the models'
# mean mass too low (measured: lift residual biased by 0.36 of its noise deviation on
# fault-free flights). Fuel burns at 0.11 g/s: 30 s lag it by 3 g.
FUEL_MASS_TAU_S = 30.0

_AIR_DATA = ("velocity_north", "velocity_east", "velocity_down", "roll", "pitch", "yaw")
# The state channels each residual row cannot do without: its observed derivative, the
# rotation to body axes, and the model terms that dominate it (airspeed, alpha and beta come
# from velocity and attitude; thrust from engine speed; damping from the rates). Slow
# channels (position, altitude, fuel mass) and weak couplings are held at their last good
# value while missing instead. Every row needs the controls and the wind ("controls" and
# "wind" stand for all of their fields).
_EVERY_ROW = {*_AIR_DATA, "controls", "wind"}
ROW_NEEDS: tuple[frozenset[str], ...] = (
    frozenset({*_EVERY_ROW, "engine_speed"}),
    frozenset({*_EVERY_ROW, "engine_speed"}),
    frozenset({*_EVERY_ROW, "engine_speed"}),
    frozenset({*_EVERY_ROW, "roll_rate", "yaw_rate"}),
    frozenset({*_EVERY_ROW, "pitch_rate"}),
    frozenset({*_EVERY_ROW, "yaw_rate", "roll_rate"}),
)
# A gap this short [s] in what the rows need (a glitch the input gate took out: up to four
# samples at 20 Hz) is bridged: its samples leave the filters alone and give the last
# complete sample's residuals (at most BRIDGED_GAP_S old, against F_a's seconds), and the
# next complete sample's velocity difference spans the gap, which is exact (a mean
# acceleration over a longer interval): no row goes invalid. Longer, the inputs are
# missing: their last good values held, the rows that need them invalid until recovery_s
# after they are back.
BRIDGED_GAP_S = 0.2


# Where the models' wind came from (Residuals.WIND_FILTERED, WIND_AIR_DATA, WIND_PITOT).
WIND_FILTERED, WIND_AIR_DATA, WIND_PITOT = 0, 1, 2
WIND_SOURCE_NAMES = {WIND_FILTERED: "filtered wind", WIND_AIR_DATA: "air data",
                     WIND_PITOT: "pitot"}


def air_data_usable(air_data: np.ndarray | None, air_data_range: AirDataRange | None) -> bool:
    """Whether a measured (airspeed [m/s], alpha, beta [rad]) is finite and within the
    model's air_data_range ((low, high) per value; None: any finite). Outside it (a blocked
    pitot, a stuck vane, flight the model's data does not cover) the sample falls back."""
    if air_data is None or not np.all(np.isfinite(air_data)):
        return False
    return air_data_range is None or all(
        low <= value <= high for value, (low, high) in zip(air_data, air_data_range, strict=True))


def pitot_usable(air_data: np.ndarray | None, air_data_range: AirDataRange | None) -> bool:
    """Whether a measured air data's airspeed [m/s] alone is finite and within the model's
    airspeed range (air_data_usable's, for the airspeed)."""
    if air_data is None or not np.isfinite(air_data[AIRSPEED_INDEX]):
        return False
    low, high = (-math.inf, math.inf) if air_data_range is None else air_data_range[AIRSPEED_INDEX]
    return bool(low <= air_data[AIRSPEED_INDEX] <= high)


def pitot_wind_ned_mps(velocity_ned_mps: np.ndarray, wind_ned_mps: np.ndarray,
                       airspeed_mps: float) -> np.ndarray:
    """The wind [m/s, NED] whose triangle gives the air velocity v - wind_ned_mps the
    measured airspeed [m/s] and keeps its direction: the pitot measures the magnitude, the
    wind estimate the rest."""
    air_velocity_mps = velocity_ned_mps - wind_ned_mps
    return velocity_ned_mps - air_velocity_mps * (airspeed_mps / np.linalg.norm(air_velocity_mps))


# Columns of S beyond the faults: the error of the wind the models flew, w - w_flown [m/s].
# Turbulence reaches the residuals through it: y ~= S_f f + S_w (w - w_flown), so an
# estimator carries it as an unknown of its window.
WIND_ERROR_NAMES = ("wind_north_error", "wind_east_error", "wind_down_error")


@dataclass(frozen=True)
class _Column:
    """One column of S: a model copy, the wind shift it sees, and the secant step."""

    name: str
    faults_pct: Mapping[str, float]  # seeded into its model copy
    model: Prediction
    wind_shift_mps: np.ndarray
    step: float  # [%] for a fault, [m/s] for a wind error, a bias's own unit for a bias
    sensor_bias: SensorBias | None = None  # the bias its air data is corrected with


@dataclass(frozen=True)
class ResidualSample:
    """Residuals at one sensor time; linear rows in body axes, per the module docstring."""

    time_s: float
    residual: np.ndarray      # (6,) y = a - a_hat [m/s^2 x3, rad/s^2 x3]
    observed: np.ndarray      # (6,) a
    predicted: np.ndarray     # (6,) a_hat
    sensitivity: np.ndarray   # (6, columns) S [row unit per % of fault, or per m/s of wind]
    valid: np.ndarray         # (6,) bool: the row's needed channels were all present
    tau_a_s: float            # F_a's time constant on the newest sample [s]
    wind_flown_ned_mps: np.ndarray     # (3,) the wind the newest sample's models flew [m/s]
    air_velocity_body_mps: np.ndarray  # (3,) their air-relative velocity, body axes [m/s]
    attitude_rad: np.ndarray           # (3,) roll, pitch, yaw of the newest sample [rad]
    wind_source: int          # WIND_AIR_DATA, WIND_PITOT or WIND_FILTERED: what the newest
                              # sample flew


class ResidualGenerator:
    """Runs p + 1 model copies on every sensor sample and keeps the filtered residuals.

    Inputs per sample: time [s], state (14,) in STATE_CHANNELS order with NaN for missing
    channels, controls (7,), filtered NED wind [m/s] (3,); a non-finite value in controls
    or wind makes them missing as a whole (their last good values are used meanwhile).
    Sensitivities are recomputed every sensitivity_period_s and held in between. A row is
    invalid for recovery_s after the start, while a channel it needs is missing, and for
    recovery_s after the channel is back: the time its filters take to settle; a gap of at
    most BRIDGED_GAP_S is bridged instead (no row invalid, no filter disturbed). Channels
    no row needs (position, fuel) are held while missing.
    """

    def __init__(
        self,
        predictor_factory: PredictorFactory,
        fault_names: Sequence[str],
        secant_step_pct: float,
        tau_a_s: float,
        sensitivity_period_s: float,
        recovery_s: float,
        wind_error_step_mps: float = 0.0,
        sensor_bias: SensorBias = NO_BIAS,
        bias_steps: Mapping[str, float] | None = None,
        air_data_range: AirDataRange | None = None,
        unmeasured: frozenset[str] = frozenset(),
        tau_a_pitot_s: float | None = None,
    ) -> None:
        """sensor_bias: the air-data bias taken out of measured air data; bias_steps:
        SensorBias field -> secant step (its unit) for a column of S per bias, named by the
        field (0 on samples that fly no vanes); air_data_range: the air data the
        models may fly (air_data_usable; the vehicle's); unmeasured: state channels the
        aircraft does not measure and its models do without (engine_speed, when they turn
        the propeller at its steady speed): never missing, never needed; tau_a_pitot_s:
        F_a's time constant [s] on samples that fly a pitot without vanes (None: tau_a_s)."""
        if not secant_step_pct > 0:
            raise ValueError(f"secant step must be positive, got {secant_step_pct} %")
        if not wind_error_step_mps >= 0:
            raise ValueError(f"wind error step must be 0 (off) or positive, got "
                             f"{wind_error_step_mps} m/s")
        unknown = sorted(unmeasured - set(STATE_CHANNELS))
        if unknown:
            raise ValueError(f"unknown state channels {unknown}")
        self.measured = np.array([name not in unmeasured for name in STATE_CHANNELS])
        self.row_needs = tuple(needs - unmeasured for needs in ROW_NEEDS)
        self.needed = frozenset().union(*self.row_needs)
        self.sensitivity_period_s = sensitivity_period_s
        self.recovery_s = recovery_s
        self.air_data_range = air_data_range
        self.predictor_factory = predictor_factory
        self.nominal = predictor_factory({})
        self.columns = [
            _Column(name, {name: secant_step_pct}, predictor_factory({name: secant_step_pct}),
                    np.zeros(3), secant_step_pct)
            for name in fault_names
        ]
        if wind_error_step_mps > 0:
            self.columns += [
                _Column(name, {}, predictor_factory({}), wind_error_step_mps * np.eye(3)[axis],
                        wind_error_step_mps)
                for axis, name in enumerate(WIND_ERROR_NAMES)
            ]
        self.sensor_bias = sensor_bias
        self.columns += [
            _Column(name, {}, predictor_factory({}), np.zeros(3), step,
                    dataclasses.replace(sensor_bias,
                                        **{name: getattr(sensor_bias, name) + step}))
            for name, step in (bias_steps or {}).items()
        ]
        self.model_rebuilds = 0  # times the model copies gave NaN and were made anew
        self.column_names = tuple(column.name for column in self.columns)
        self.tau_a_s = tau_a_s  # F_a's time constant: how long a residual remembers a wind
        self.tau_a_pitot_s = tau_a_s if tau_a_pitot_s is None else tau_a_pitot_s
        self.observed_filter = LowPass(tau_a_s)
        self.predicted_filter = LowPass(tau_a_s)
        self.fuel_filter = SettlingLowPass(FUEL_MASS_TAU_S)
        self.reset()

    def reset(self) -> None:
        """Forget all history (a restarted source): the next sample starts afresh."""
        self.observed_filter.reset()
        self.predicted_filter.reset()
        self.fuel_filter.reset()
        self.last_time_s: float | None = None  # the last sample the filters took
        self.newest_time_s: float | None = None  # the last sample taken, bridged ones too
        self.last_complete = False  # the last sample taken had every needed input
        self.last_velocity: np.ndarray | None = None
        self.last_prediction: np.ndarray | None = None
        self.held_state = np.full(len(STATE_CHANNELS), np.nan)
        self.held_inputs: dict[str, np.ndarray] = {}
        self.raw_sensitivity: np.ndarray | None = None
        self.next_sensitivity_s = -math.inf
        self.row_invalid_until_s = np.full(6, math.inf)
        self.wind_source = WIND_FILTERED
        self.flown_wind_ned_mps = np.full(3, math.nan)  # of the newest sample taken
        self.latest: ResidualSample | None = None

    def _column_wind(self, column: _Column, state: np.ndarray, wind: np.ndarray,
                     air_data: np.ndarray | None) -> np.ndarray | None:
        """The wind [m/s, NED] column's model flies, or None for a column that is 0 here (a
        wind error where the vanes measure the flow; a bias where no air data is flown)."""
        if column.sensor_bias is not None:
            return (_air_data_wind(state, air_data, column.sensor_bias)
                    if self.wind_source == WIND_AIR_DATA else None)
        if not column.wind_shift_mps.any():
            return wind
        if self.wind_source == WIND_AIR_DATA:
            return None
        shifted = wind + column.wind_shift_mps
        return (pitot_wind_ned_mps(state[VELOCITY[:3]], shifted, air_data[AIRSPEED_INDEX])
                if self.wind_source == WIND_PITOT else shifted)

    def _prediction(self, state: np.ndarray, controls: np.ndarray, wind: np.ndarray,
                    time_s: float, air_data: np.ndarray | None) -> np.ndarray:
        """P = [phi(x|0), S_raw] (6, 1 + columns); S_raw recomputed when its period is due.
        wind: the wind the models fly (of self.wind_source); air_data: the measured air
        data, None where the models fly the filtered wind alone."""
        nominal = np.asarray(self.nominal(state, controls, wind), dtype=float)
        if time_s >= self.next_sensitivity_s or self.raw_sensitivity is None:
            self.raw_sensitivity = np.zeros((6, len(self.columns)))
            for j, column in enumerate(self.columns):
                column_wind = self._column_wind(column, state, wind, air_data)
                if column_wind is None:
                    continue
                shifted = column.model(state, controls, column_wind)
                self.raw_sensitivity[:, j] = (np.asarray(shifted) - nominal) / column.step
            self.next_sensitivity_s = time_s + self.sensitivity_period_s
        prediction = np.column_stack([nominal, self.raw_sensitivity])
        if not np.all(np.isfinite(prediction)):
            self.raw_sensitivity = None  # recomputed at the next sample
            self._rebuild_models()
            raise ValueError("the prediction model gave non-finite accelerations: its copies "
                             "were rebuilt")
        return prediction

    def _rebuild_models(self) -> None:
        """New model copies: a JSBSim instance that once gave NaN may keep giving it."""
        factory = self.predictor_factory
        self.nominal = factory({})
        self.columns = [dataclasses.replace(column, model=factory(column.faults_pct))
                        for column in self.columns]
        self.model_rebuilds += 1

    def _update_row_validity(self, missing: set[str], time_s: float) -> np.ndarray:
        """Rows usable now; rows coming back from a dropout wait recovery_s."""
        for row, needs in enumerate(self.row_needs):
            if needs & missing:
                self.row_invalid_until_s[row] = math.inf
            elif self.row_invalid_until_s[row] == math.inf:
                self.row_invalid_until_s[row] = time_s + self.recovery_s
        return self.row_invalid_until_s <= time_s

    def update(self, time_s: float, state: np.ndarray, controls: np.ndarray,
               wind_ned_mps: np.ndarray,
               air_data: np.ndarray | None = None) -> ResidualSample | None:
        """Process one sensor sample; the residuals at time_s, or None before any is formed.

        air_data (3,): measured true airspeed [m/s], alpha, beta [rad], or None; when usable
        (air_data_usable) the models fly it instead of the filtered wind wind_ned_mps; when
        only its airspeed is (pitot_usable), the pitot's airspeed on the filtered wind's
        triangle.
        Within a bridged gap (BRIDGED_GAP_S) the residuals are the last complete sample's,
        stamped time_s.
        Raises ValueError for a time that does not increase (call reset() first), and for a sample
        the models cannot evaluate (the model copies are then rebuilt).
        """
        if self.newest_time_s is not None and time_s <= self.newest_time_s:
            raise ValueError(f"time {time_s} s does not follow {self.newest_time_s} s: "
                             "reset first")
        finite = np.isfinite(state) | ~self.measured
        missing = {name for name, ok in zip(STATE_CHANNELS, finite, strict=True) if not ok}
        missing |= {name for name, value in (("controls", controls), ("wind", wind_ned_mps))
                    if not np.all(np.isfinite(value))}
        if missing & self.needed and self._bridges(time_s):
            self._filtered_fuel_kg(time_s, np.where(finite, state, self.held_state)[FUEL_MASS])
            return dataclasses.replace(self.latest, time_s=time_s)
        self.held_state = np.where(finite, state, self.held_state)
        for name, value in (("controls", controls), ("wind", wind_ned_mps)):
            if name not in missing:
                self.held_inputs[name] = np.array(value, dtype=float)
        if not np.all(np.isfinite(self.held_state[self.measured])) or len(self.held_inputs) < 2:
            return None  # some input never seen yet: nothing can be predicted
        state = self.held_state.copy()
        state[FUEL_MASS] = self._filtered_fuel_kg(time_s, state[FUEL_MASS])
        wind, self.wind_source = self.held_inputs["wind"], WIND_FILTERED
        if air_data_usable(air_data, self.air_data_range):
            wind = _air_data_wind(state, air_data, self.sensor_bias)
            self.wind_source = WIND_AIR_DATA
        elif pitot_usable(air_data, self.air_data_range):
            wind = pitot_wind_ned_mps(state[VELOCITY[:3]], wind, air_data[AIRSPEED_INDEX])
            self.wind_source = WIND_PITOT
        else:
            air_data = None
        self.flown_wind_ned_mps = wind
        tau_s = self.tau_a_pitot_s if self.wind_source == WIND_PITOT else self.tau_a_s
        self.observed_filter.tau_s = self.predicted_filter.tau_s = tau_s
        prediction = self._prediction(state, self.held_inputs["controls"], wind, time_s,
                                      air_data)
        velocity = state[VELOCITY]
        valid = self._update_row_validity(missing, time_s)
        if self.last_time_s is not None:
            dt_s = time_s - self.last_time_s
            observed_raw = (velocity - self.last_velocity) / dt_s
            predicted_mean = 0.5 * (prediction + self.last_prediction)
            if self.observed_filter.output is None:
                # Start F_a's a from the model's acceleration, not from the first velocity
                # difference: with 0.05 m/s INS noise at 20 Hz one difference is off by
                # about 1.4 m/s², which F_a would carry well past recovery_s (a drag-like
                # x residual of 0.05 m/s² still at 15 s, i.e. a 13 % drag estimate).
                self.observed_filter.update(predicted_mean[:, 0], dt_s)
            self.observed_filter.update(observed_raw, dt_s)
            self.predicted_filter.update(predicted_mean, dt_s)
            self.latest = self._sample(time_s, state, valid)
        self.last_time_s, self.last_velocity, self.last_prediction = time_s, velocity, prediction
        self.last_complete = not missing & self.needed
        return self.latest

    def _filtered_fuel_kg(self, time_s: float, fuel_kg: float) -> float:
        """The fuel gauge's reading [kg] through its filter, fed every sample the generator
        takes, bridged ones too (so a bridged gap leaves it as it would have been)."""
        elapsed_s = 0.0 if self.newest_time_s is None else time_s - self.newest_time_s
        self.newest_time_s = time_s
        return self.fuel_filter.update(fuel_kg, elapsed_s)

    def _bridges(self, time_s: float) -> bool:
        """Whether a sample missing a needed input at time_s [s] falls in a bridged gap: the
        last sample taken, BRIDGED_GAP_S ago or less, gave residuals and had every needed
        input (a gap begun earlier is a loss, and is not bridged from its middle)."""
        return (self.latest is not None and self.last_complete
                and time_s - self.last_time_s <= BRIDGED_GAP_S + GRID_TOLERANCE_S)

    def _sample(self, time_s: float, state: np.ndarray, valid: np.ndarray) -> ResidualSample:
        """The filtered quantities with their linear rows rotated to body axes."""
        rotation = np.eye(6)
        rotation[:3, :3] = ned_to_body(*state[ATTITUDE])
        air_velocity_ned_mps = state[VELOCITY[:3]] - self.flown_wind_ned_mps
        observed = rotation @ self.observed_filter.output
        predicted_and_s = rotation @ self.predicted_filter.output
        predicted = predicted_and_s[:, 0]
        return ResidualSample(
            time_s=time_s,
            residual=observed - predicted,
            observed=observed,
            predicted=predicted,
            sensitivity=predicted_and_s[:, 1:].copy(),
            valid=valid.copy(),
            tau_a_s=self.observed_filter.tau_s,
            wind_flown_ned_mps=self.flown_wind_ned_mps.copy(),
            air_velocity_body_mps=rotation[:3, :3] @ air_velocity_ned_mps,
            attitude_rad=state[ATTITUDE].copy(),
            wind_source=self.wind_source,
        )


def _air_data_wind(state: np.ndarray, air_data: np.ndarray, bias: SensorBias) -> np.ndarray:
    """The wind [m/s, NED] of the wind triangle with measured air data less its bias."""
    return wind_triangle_ned_mps(state[VELOCITY[:3]], *state[ATTITUDE],
                                 true_air_data(air_data, bias))
