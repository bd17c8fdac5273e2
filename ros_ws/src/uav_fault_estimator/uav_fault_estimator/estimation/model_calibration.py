"""Model calibration: the prediction model's constant parameters from fault-free flights.

The faults' batch estimation with the model's parameters (model_parameters.py) in place of
the faults. Per flight, the residual generator runs the models as residual_node does (the
filtered residuals y and sensitivities S by secant differences of model copies, every
update_period_s), its columns the parameters: y ~= S d for a change d of the parameters
from the current model. Gauss-Newton on the pooled flights, each step a bounded least
squares on ProxSuite,

    min_d  sum_k ||y_k - S_k d||^2_W + ||theta + d||^2_P    s.t. lower <= theta + d <= upper

with W the fault-free noise per residual channel (NoiseCalibration, the air-data suite), each
sample weighted by its AR(1) white equivalent (1 - rho) / (1 + rho) (rho the one-step
correlation after F_a: samples 0.5 s apart are not independent), and P the prior toward the
nominal model, or the aircraft as measured on the ground (ModelParameter.prior_std). After
the last step the posterior covariance (sum S^T W S + P)^-1 is inflated by the fit's reduced
chi-square where it exceeds 1 (what the model still misses), and its correlations say which
parameters the flights cannot separate.
No ROS here.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from proxsuite import proxqp
from uav_aircraft.flown_aircraft import NOMINAL, FlownAircraft
from uav_aircraft.propeller import Propeller
from uav_aircraft.vehicles import load_vehicle

from uav_fault_estimator.estimation.model_parameters import (
    SCALE_STEP_PCT,
    ModelParameter,
    changed,
    model_parameter,
    values_of,
)
from uav_fault_estimator.estimation.noise_model import (
    SUITES,
    NoiseCalibration,
    white_share,
    without_wind_errors,
)
from uav_fault_estimator.estimation.prediction import AircraftPredictor
from uav_fault_estimator.estimation.qp_problem import sample_normal_equations
from uav_fault_estimator.estimation.residual_sampling import ResidualSampler
from uav_fault_estimator.estimation.residual_settings import ResidualSettings
from uav_fault_estimator.estimation.residuals import (
    WIND_AIR_DATA,
    WIND_FILTERED,
    WIND_PITOT,
    ResidualGenerator,
    ResidualSample,
)

MAX_STEPS = 10  # Gauss-Newton steps at most (the default set takes six to nine)
CONVERGED_SIGMAS = 0.05  # a step below this many posterior deviations in each parameter ends it
WORST_CORRELATIONS = 5  # pairs printed and written


@dataclass(frozen=True)
class SensorFlight:
    """A recorded flight at the sensor rate: times (K,) [s], states (K, 14), controls (K, 7),
    filtered wind (K, 3) [m/s NED] and air data (K, 3) (NaN rows without), in
    uav_common.channels order; name says where it came from."""

    name: str
    times_s: np.ndarray
    states: np.ndarray
    controls: np.ndarray
    winds_ned_mps: np.ndarray
    air_data: np.ndarray


@dataclass(frozen=True)
class FlightTerms:
    """One flight's normal equations at the current model: G (n, n) and h (n,) of
    sum_k S_k^T W S_k and S_k^T W y_k, and the weighted squared residual sum and its rows."""

    gram: np.ndarray
    linear: np.ndarray
    chi_square: float
    rows: int


def residual_weights(noise: NoiseCalibration) -> np.ndarray:
    """W (6,) [1 / residual unit²]: the air-data suite's inverse variances, each times its
    AR(1) white equivalent (noise_model.white_share)."""
    suite = SUITES[WIND_AIR_DATA]
    return white_share(noise.correlations[suite]) / noise.variances[suite]


def flight_terms(flight: SensorFlight, model: FlownAircraft, names: Sequence[str],
                 residual: ResidualSettings, weights: np.ndarray) -> FlightTerms:
    """Run the flight through a residual generator whose models are `model` (of the vehicle
    the residual settings name) and whose columns are the named parameters' sensitivities
    [residual unit per parameter unit]; its normal equations on residual_node's update grid
    (rows valid and plausible only)."""
    vehicle = load_vehicle(residual.vehicle)
    parameters = [model_parameter(name, vehicle) for name in names]
    generator = _generator(model, parameters, residual)
    n = len(parameters)
    gram, linear, chi_square, rows = np.zeros((n, n)), np.zeros(n), 0.0, 0
    order = [generator.column_names.index(p.name) for p in parameters]
    per_unit = np.array([_column_per_unit(p) for p in parameters])
    for sample in _grid_samples(generator, flight, residual, flight.air_data):
        term = sample_normal_equations(sample.residual, sample.sensitivity[:, order] * per_unit,
                                       sample.valid, weights, n)
        gram += term.gram
        linear += term.linear
        chi_square += float(term.whitened_y @ term.whitened_y)
        rows += int(np.count_nonzero(term.whitened_y))
    return FlightTerms(gram, linear, chi_square, rows)


@dataclass(frozen=True)
class SuiteResiduals:
    """A flight's residuals at one model per noise suite: rows (K, 6) and their times (K,)
    [s]."""

    residuals: dict[str, np.ndarray]
    times_s: dict[str, np.ndarray]


def noise_residuals(flight: SensorFlight, model: FlownAircraft,
                    residual: ResidualSettings) -> SuiteResiduals:
    """The model's residuals per noise suite on the flight: the samples that flew the air
    data, and the whole flight flown again on its pitot alone and on the filtered wind alone
    (the other suites' noise from the same flight; the pitot's beyond its wind errors,
    noise_model.without_wind_errors)."""
    vanes_lost, all_lost = flight.air_data.copy(), np.full_like(flight.air_data, np.nan)
    vanes_lost[:, 1:] = np.nan
    residuals, times = {}, {}
    for source, air_data in ((WIND_AIR_DATA, flight.air_data), (WIND_PITOT, vanes_lost),
                             (WIND_FILTERED, all_lost)):
        generator = _generator(model, (), residual, wind_errors=source == WIND_PITOT)
        samples = [s for s in _grid_samples(generator, flight, residual, air_data)
                   if s.wind_source == source]
        rows = np.array([s.residual for s in samples]).reshape(-1, 6)
        if source == WIND_PITOT and samples:
            rows = without_wind_errors(rows, np.array([s.sensitivity for s in samples]))
        residuals[SUITES[source]] = rows
        times[SUITES[source]] = np.array([s.time_s for s in samples])
    return SuiteResiduals(residuals, times)


def _grid_samples(generator: ResidualGenerator, flight: SensorFlight,
                  residual: ResidualSettings,
                  air_data: np.ndarray) -> Iterator[ResidualSample]:
    """The generator's samples on residual_node's update grid whose rows are all valid.
    Samples it refuses (a stamp that does not increase, a state the models cannot evaluate)
    are left out, as residual_node leaves them out."""
    sampler = ResidualSampler(generator, residual.update_period_s)
    for k, time_s in enumerate(flight.times_s):
        try:
            sample = sampler.update(time_s, flight.states[k], flight.controls[k],
                                    flight.winds_ned_mps[k], air_data[k])
        except ValueError:
            continue
        if sample is not None and sample.valid.all():
            yield sample


def _generator(model: FlownAircraft, parameters: Sequence[ModelParameter],
               residual: ResidualSettings, wind_errors: bool = False) -> ResidualGenerator:
    """residual_node's generator with `model`'s copies, columns per parameter: a model copy
    moved by the parameter's step, or for an air-data bias the bias moved by it; then the
    wind errors' when wind_errors."""
    vehicle = load_vehicle(residual.vehicle)
    propeller = Propeller.from_vehicle(vehicle)
    copies = [q.name for q in parameters if not q.is_bias]
    return ResidualGenerator(
        lambda changes: AircraftPredictor({}, vehicle, propeller, changed(model, changes)),
        copies, SCALE_STEP_PCT, residual.tau_a_s, residual.sensitivity_period_s,
        residual.recovery_s,
        wind_error_step_mps=residual.wind_error_step_mps if wind_errors else 0.0,
        sensor_bias=model.sensor_bias,
        bias_steps={q.name: q.step * q.native_per_unit for q in parameters if q.is_bias},
        air_data_range=vehicle.air_data_range, tau_a_pitot_s=residual.tau_a_pitot_s)


def _column_per_unit(parameter: ModelParameter) -> float:
    """What turns the generator's column into one per parameter unit: a model copy's is per
    % already, a bias's per SensorBias unit (per unit scale, or per degree)."""
    return parameter.native_per_unit if parameter.is_bias else 1.0


@dataclass(frozen=True)
class ModelCalibration:
    """A calibrated model: the aircraft its copies load, and per parameter (names order) its
    unit, value, prior mean (its measured value, 0 unless measured), prior deviation and
    posterior deviation [its unit], the posterior correlations
    (n, n), the Gauss-Newton steps taken, the fit's reduced chi-square, the posterior
    deviation each flight alone (with the prior) gives (flights, n) [its unit]: which flights
    inform which parameter, and the residuals per suite and flight at the calibrated model
    (for the noise calibration) with their times (for the fit's check, calibration_check.py)."""

    aircraft: FlownAircraft
    names: tuple[str, ...]
    units: tuple[str, ...]
    values: np.ndarray
    prior_mean: np.ndarray
    prior_std: np.ndarray
    posterior_std: np.ndarray
    correlations: np.ndarray
    steps: int
    reduced_chi_square: float
    flight_posterior_std: np.ndarray
    residuals: dict[str, list[np.ndarray]]
    residual_times_s: dict[str, list[np.ndarray]]

    def worst_correlations(self, count: int = WORST_CORRELATIONS) -> list[tuple[str, str, float]]:
        """The most correlated parameter pairs, largest |correlation| first."""
        n = len(self.names)
        pairs = [(self.names[i], self.names[j], float(self.correlations[i, j]))
                 for i in range(n) for j in range(i + 1, n)]
        return sorted(pairs, key=lambda pair: -abs(pair[2]))[:count]


MapFlights = Callable[[Callable, Iterable], Iterable]


class CalibrationError(RuntimeError):
    """A calibration that could not be made (one line: why)."""


def calibrate(flights: Sequence[SensorFlight], names: Sequence[str],
              residual: ResidualSettings, noise: NoiseCalibration,
              map_flights: MapFlights = map, log: Callable[[str], None] = print,
              measured: FlownAircraft = NOMINAL) -> ModelCalibration:
    """Identify the named parameters from the flights (the module docstring's problem).
    map_flights(function, flights) runs a function on every flight (a process pool's map,
    or map); log receives one line per step. measured: the aircraft as measured on the
    ground (its mass properties weighed and swung, say): the fit starts from it, its prior
    is about it, and every parameter not named keeps its value. The vehicle is the
    residual settings' (residual_node's `vehicle`)."""
    vehicle = load_vehicle(residual.vehicle)
    parameters = [model_parameter(name, vehicle) for name in names]
    names = tuple(names)
    prior_inverse = np.diag([1.0 / p.prior_std**2 for p in parameters])
    lower = np.array([p.bounds[0] for p in parameters])
    upper = np.array([p.bounds[1] for p in parameters])
    weights = residual_weights(noise)
    theta = np.zeros(len(names))
    for step in range(1, MAX_STEPS + 1):
        model = changed(measured, dict(zip(names, theta, strict=True)))
        terms = list(map_flights(_TermsAt(model, names, residual, weights), flights))
        gram = sum(t.gram for t in terms) + prior_inverse
        linear = sum(t.linear for t in terms) - prior_inverse @ theta
        chi_square = sum(t.chi_square for t in terms)
        rows = sum(t.rows for t in terms)
        covariance = np.linalg.inv(gram)
        delta = _bounded_step(gram, linear, lower - theta, upper - theta)
        theta = theta + delta
        deviation = np.sqrt(np.diag(covariance))
        log(f"step {step}: weighted residual {chi_square / max(rows, 1):.3f} per row, largest "
            f"move {np.max(np.abs(delta) / deviation):.2f} posterior deviations")
        if np.all(np.abs(delta) <= CONVERGED_SIGMAS * deviation):
            break
    model = changed(measured, dict(zip(names, theta, strict=True)))
    final = list(map_flights(_TermsAt(model, names, residual, weights), flights))
    rows = sum(t.rows for t in final)
    reduced = sum(t.chi_square for t in final) / max(rows - len(names), 1)
    covariance = np.linalg.inv(sum(t.gram for t in final) + prior_inverse) * max(reduced, 1.0)
    deviation = np.sqrt(np.diag(covariance))
    return ModelCalibration(
        aircraft=model, names=names, units=tuple(p.unit for p in parameters),
        values=np.array(list(values_of(model, names).values())),
        prior_mean=np.array(list(values_of(measured, names).values())),
        prior_std=np.array([p.prior_std for p in parameters]), posterior_std=deviation,
        correlations=covariance / np.outer(deviation, deviation), steps=step,
        reduced_chi_square=reduced,
        flight_posterior_std=np.array([np.sqrt(np.diag(np.linalg.inv(
            t.gram + prior_inverse) * max(reduced, 1.0))) for t in final]),
        **_per_suite(map_flights(_NoiseAt(model, residual),
                                                             flights)))


def _per_suite(flights: Iterable[SuiteResiduals]) -> dict[str, dict[str, list[np.ndarray]]]:
    """Per suite, the flights' residuals and their times (ModelCalibration's fields)."""
    flights = list(flights)
    return {"residuals": {suite: [f.residuals[suite] for f in flights]
                          for suite in SUITES.values()},
            "residual_times_s": {suite: [f.times_s[suite] for f in flights]
                                 for suite in SUITES.values()}}


@dataclass(frozen=True)
class _TermsAt:
    """flight_terms at one model, as a picklable callable of the flight (for process pools)."""

    model: FlownAircraft
    names: tuple[str, ...]
    residual: ResidualSettings
    weights: np.ndarray

    def __call__(self, flight: SensorFlight) -> FlightTerms:
        return flight_terms(flight, self.model, self.names, self.residual, self.weights)


@dataclass(frozen=True)
class _NoiseAt:
    """noise_residuals at one model, as a picklable callable of the flight."""

    model: FlownAircraft
    residual: ResidualSettings

    def __call__(self, flight: SensorFlight) -> SuiteResiduals:
        return noise_residuals(flight, self.model, self.residual)


def _bounded_step(gram: np.ndarray, linear: np.ndarray, lower: np.ndarray,
                  upper: np.ndarray) -> np.ndarray:
    """argmin_d 1/2 d^T G d - h^T d subject to lower <= d <= upper, on ProxSuite (dense:
    a handful of parameters)."""
    n = linear.size
    qp = proxqp.dense.QP(n, 0, 0, True)  # box constraints only
    qp.settings.eps_abs = 1e-9
    qp.settings.verbose = False
    qp.init(gram, -linear, None, None, None, None, None, l_box=lower, u_box=upper)
    qp.solve()
    if qp.results.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
        raise CalibrationError(f"the calibration's least squares did not solve "
                               f"({qp.results.info.status}): the flights may not excite the "
                               "parameters asked for")
    return np.array(qp.results.x)
