"""What configures the estimator step: mhe_node's settings, which estimator_step.EstimatorStep
takes, and the estimator's configuration (estimator_config.EstimatorConfig) they give with a
noise calibration. Each field is the mhe_node parameter of its name, declared here once with
its default, unit, range and meaning (uav_common.settings). No ROS here."""

from __future__ import annotations

from dataclasses import dataclass

from uav_aircraft.vehicle_parameter import VEHICLE_PARAMETER
from uav_common.channels import MODEL_FAULT_NAMES, PAPER_FAULT_NAMES
from uav_common.settings import declared_setting, setting

from uav_fault_estimator.estimation.estimator_config import (
    EstimatorConfig,
    FaultConfig,
    SolverSettings,
)
from uav_fault_estimator.estimation.mhe import SUSPECT_SIGMAS
from uav_fault_estimator.estimation.noise_model import NoiseCalibration
from uav_fault_estimator.estimation.residuals import (
    RESIDUAL_CHANNELS,
    WIND_AIR_DATA,
    WIND_ERROR_NAMES,
)

# Ranges: per-fault values in percent of the aircraft's own coefficient, at most ten times
# it; variances and scales positive where the estimator divides by them; the horizon at
# most 2000 samples (1000 s at 0.5 s, three times the default flight): the QP grows with it.
# Live: the weights and tolerances (MovingHorizonEstimator.retune); the rest shapes the QP.
PAPER_FAULTS = len(PAPER_FAULT_NAMES)  # the paper's setting: N = 50, four monotonic faults


@dataclass(frozen=True)
class EstimatorSettings:
    """The moving-horizon estimator's settings: the vehicle (its noise calibration), the
    estimated faults with their evolution models, bounds and prior (per fault, in
    fault_names order), the window, the noise and arrival-cost weights, the wind-error
    nuisance columns, the solver, and the model_fit status's window and threshold."""

    vehicle: str = declared_setting(VEHICLE_PARAMETER)
    fault_names: tuple[str, ...] = setting(
        "the estimated faults: columns of the residuals' S, by name", list(PAPER_FAULT_NAMES))
    fault_models: tuple[str, ...] = setting(
        "per fault: monotonic, monotonic_decreasing, random_walk, uniform, laplacian or "
        "constant", ["monotonic"] * PAPER_FAULTS)
    fault_model_scales_pct: tuple[float, ...] = setting(
        "per fault: the model's scale: lambda (monotonic: mean increment), sigma "
        "(random_walk), a (uniform: |increment| <= a; laplacian: cost |increment| / a); "
        "unused for constant [%/sample]", [0.5] * PAPER_FAULTS, 1e-6, 100.0)
    fault_model_coefficients: tuple[float, ...] = setting(
        "per fault: a in f(t+1) = a f(t) + gamma (random_walk only; 1 elsewhere)",
        [1.0] * PAPER_FAULTS, 0.0, 2.0)
    # a loss or an increase is never negative
    lower_bounds_pct: tuple[float, ...] = setting(
        "per fault: lower bound on f [%]", [0.0] * PAPER_FAULTS, -1000.0, 1000.0)
    upper_bounds_pct: tuple[float, ...] = setting(
        "per fault: upper bound on f [%]", [100.0] * PAPER_FAULTS, -1000.0, 1000.0)
    prior_pct: tuple[float, ...] = setting(
        "per fault: f before any data [%]", [0.0] * PAPER_FAULTS, -1000.0, 1000.0)
    horizon: int = setting("N: residual samples in the moving window", 50, 2, 2000)
    noise_calibration_file: str = setting(
        "residual noise per sensor suite (scripts/calibrate_estimator.py); empty: the "
        "vehicle's residual_noise.yaml", "")
    # 4: tuned on the default scenario (16, the AR(1) white equivalent of the 0.88
    # correlation after F_a, delays the ramps; docs/estimator.md)
    noise_variance_factor: float = setting(
        "Q = this factor times the calibrated variances of the sample's sensor suite "
        "(correlated noise: fewer independent samples than the window holds); a change "
        "reweights the window", 4.0, 1e-3, 1e6, live=True)
    handover_variances_pct2: tuple[float, ...] = setting(
        "R of eq. 17: per fault, the arrival cost's variance before any data [%^2]; a change "
        "restarts the arrival cost at its mean with this variance", [1.0] * PAPER_FAULTS,
        1e-6, 1e6, live=True)
    arrival_inflation: float = setting(
        "factor (>= 1) on the arrival cost's covariance every sample: forget old data "
        "faster", 1.0, 1.0, 10.0, live=True)
    arrival_floor_variances_pct2: tuple[float, ...] = setting(
        "per fault: the least variance of the arrival cost [%^2]", [0.0] * PAPER_FAULTS, 0.0,
        1e6, live=True)
    arrival_centre: str = setting(
        "where the arrival cost is centred: filter (the arrival filter's mean) or "
        "previous_window (the previous window's estimate, as the paper)", "filter")
    # off by default: with vanes the columns are 0 and only cost solve time (0.86 against
    # 0.47 ms median on the default flight, docs/estimator.md); on for a pitot without vanes
    estimate_wind_errors: bool = setting(
        "also estimate the errors of the wind the models flew (S columns *_error of "
        "residual_node; 0 where vanes measure the flow) as unknowns of the window, "
        "Gauss-Markov processes: on for an aircraft without vanes", False)
    wind_error_sigma_mps: float = setting(
        "Gauss-Markov step of each wind error per residual sample [m/s]", 0.2, 1e-4, 10.0)
    # 0.95 per 0.5 s: a correlation time of 10 s, the filtered wind's time constant, whose
    # misses the wind errors are
    wind_error_coefficient: float = setting(
        "a in e(t+1) = a e(t) + gamma of each wind error: exp(-period / correlation time)",
        0.95, 0.0, 1.0)
    wind_error_handover_variance_m2ps2: float = setting(
        "R of eq. 17 for each wind error [m^2/s^2]", 1.0, 1e-6, 1e4, live=True)
    # active_set: about half ProxSuite's update time (docs/results.md)
    solver_method: str = setting(
        "proxsuite (any fault model) or active_set (exact, for monotonic faults only; "
        "ProxSuite solves the windows where it does not settle in 30 rounds)", "proxsuite")
    solver_eps_abs: float = setting("ProxSuite's absolute tolerance (on the scaled problem)",
                                    SolverSettings.eps_abs, 1e-12, 0.1, live=True)
    solver_max_iter: int = setting("ProxSuite's iteration limit per update", 200, 1, 100000,
                                   live=True)
    update_budget_ms: float = setting(
        "an update longer than this drops the window's oldest sample beyond "
        f"{SUSPECT_SIGMAS:g} noise deviations, a glitch the gates let through [ms]", 100.0,
        0.01, 60000.0, live=True)
    model_fit_window_s: float = setting(
        "the model_fit status judges the fault-free residuals of this much sim time [s]", 60.0,
        5.0, 3600.0)
    # 6: fault-free flights of the model itself reach 3.7-5.0 (docs/model_calibration.md)
    model_fit_threshold_sigmas: float = setting(
        "model_fit says 'does not fit: recalibrate' when a residual's window mean is beyond "
        "this many of its deviations", 6.0, 0.5, 1000.0)


# The one scale parameter of each fault model [%/sample] that the flat
# fault_model_scales_pct sets (the models' own keyword names, fault_models.py).
SCALE_PARAMETER: dict[str, str | None] = {
    "monotonic": "lambda_pct",
    "monotonic_decreasing": "lambda_pct",
    "random_walk": "sigma",
    "uniform": "half_width_pct",
    "laplacian": "scale_pct",
    "constant": None,
}


# The window of an aircraft without vanes [samples]: each window knows the two wings' drag
# faults together about half as well as with vanes, so it averages over 35 s, not 25 s:
# of 50, 60, 70 and 100 the shortest that keeps the fault-free default flights' drag
# estimates within the threshold; the update's p99 within 5 ms (docs/estimator.md).
VANELESS_HORIZON = 70


def sensor_overrides(air_data: bool, vanes: bool) -> dict[str, object]:
    """mhe_node's parameters, beyond their defaults, that an aircraft's sensors call for:
    with a pitot and no vanes (any MAVLink link) the wind errors are unknowns of a longer
    window (docs/estimator.md)."""
    if air_data and not vanes:
        return {"estimate_wind_errors": True, "horizon": VANELESS_HORIZON}
    return {}


def config_from_settings(settings: EstimatorSettings,
                         noise: NoiseCalibration) -> EstimatorConfig:
    """The estimator's configuration from its settings and the noise calibration they name
    (loaded once by the caller); ValueError naming the first wrong entry. The estimated
    columns are the faults, then the wind-estimate errors when estimate_wind_errors. Q is
    the noise calibration's for air data (per sample the step may pass another suite's)."""
    s = settings
    names = list(s.fault_names)
    unknown = [name for name in names if name not in MODEL_FAULT_NAMES]
    if unknown or len(set(names)) != len(names) or not names:
        raise ValueError(f"fault_names {names}: each once, at least one, of "
                         + ", ".join(MODEL_FAULT_NAMES))
    per_fault = ("fault_models", "fault_model_scales_pct", "fault_model_coefficients",
                 "lower_bounds_pct", "upper_bounds_pct", "prior_pct", "handover_variances_pct2",
                 "arrival_floor_variances_pct2")
    for key in per_fault:
        if len(getattr(s, key)) != len(names):
            raise ValueError(f"{key} has {len(getattr(s, key))} entries for {len(names)} "
                             "faults")
    faults = []
    for k, name in enumerate(names):
        model = s.fault_models[k]
        if model not in SCALE_PARAMETER:
            raise ValueError(f"fault {name}: unknown model '{model}', known: "
                             + ", ".join(SCALE_PARAMETER))
        model_parameters: dict[str, float] = {}
        if SCALE_PARAMETER[model] is not None:
            model_parameters[SCALE_PARAMETER[model]] = s.fault_model_scales_pct[k]
        if model == "random_walk":
            model_parameters["coefficient"] = s.fault_model_coefficients[k]
        faults.append(FaultConfig(
            name, model, model_parameters, lower_pct=s.lower_bounds_pct[k],
            upper_pct=s.upper_bounds_pct[k], prior_pct=s.prior_pct[k],
        ))
    handover = list(s.handover_variances_pct2)
    floor = list(s.arrival_floor_variances_pct2)
    if s.estimate_wind_errors:  # nuisance parameters: random walks [m/s]
        faults += [FaultConfig(name, "random_walk", {"sigma": s.wind_error_sigma_mps,
                                                     "coefficient": s.wind_error_coefficient})
                   for name in WIND_ERROR_NAMES]
        handover += [s.wind_error_handover_variance_m2ps2] * len(WIND_ERROR_NAMES)
        floor += [0.0] * len(WIND_ERROR_NAMES)
    if not s.noise_variance_factor > 0:
        raise ValueError(f"noise_variance_factor must be positive, got "
                         f"{s.noise_variance_factor}")
    config = EstimatorConfig(
        horizon=s.horizon,
        q_diag=tuple(noise.q_diag(WIND_AIR_DATA, s.noise_variance_factor)),
        r_diag_pct2=tuple(handover),
        faults=faults,
        solver=SolverSettings(eps_abs=s.solver_eps_abs, max_iter=s.solver_max_iter,
                              budget_ms=s.update_budget_ms, method=s.solver_method),
        arrival_inflation=s.arrival_inflation,
        arrival_floor_pct2=tuple(floor),
        arrival_centre=s.arrival_centre,
    )
    if len(config.q_diag) != len(RESIDUAL_CHANNELS):
        raise ValueError(f"the noise calibration needs {len(RESIDUAL_CHANNELS)} channels")
    config.validate()
    return config
