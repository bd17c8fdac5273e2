"""The evolving-faults paper's examples on synthetic data (section VI-A and VII-A).

Rocket ascent (batch): four faults of four kinds (thrust loss monotonic, drag increase a
step, gimbal sluggishness constant, pitch-sensor offset a random walk) seen through four
residuals with uniform noise, 0.1 s samples, an update every 15 s; estimates at 70, 115
and 150 s improve as data accrue. Aerosonde lift loss (MHE): one fault, a step at 50 s,
N = 30.
"""

from __future__ import annotations

import numpy as np
import pytest
from uav_fault_estimator.estimation.batch import BatchEstimator
from uav_fault_estimator.estimation.estimator_config import EstimatorConfig, FaultConfig
from uav_fault_estimator.estimation.mhe import MovingHorizonEstimator
from uav_fault_estimator.estimation.solve_status import SolveStatus

DT_S = 0.1
CYCLE_S = 15.0
ROCKET_FAULTS = ("thrust_loss", "drag_increase", "gimbal_sluggishness", "pitch_sensor_offset")
NOISE_HALF_WIDTH = 2.0  # uniform residual noise on [-a, a]


def rocket_faults_pct(time_s: np.ndarray) -> np.ndarray:
    """Seeded faults (samples, 4) [%]."""
    thrust = 8.0 * np.clip((time_s - 20.0) / 80.0, 0.0, 1.0)
    drag = np.where(time_s >= 60.0, 5.0, 0.0)
    gimbal = np.full_like(time_s, 3.0)
    offset = 1.5 * np.sin(2 * np.pi * time_s / 100.0)
    return np.stack([thrust, drag, gimbal, offset], axis=1)


def rocket_signatures(time_s: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """S(t) (samples, 4 residuals, 4 faults): distinct columns, slowly varying in flight."""
    base = np.array([[-1.0, -0.5, 0.1, 0.0],
                     [-0.2, 0.8, 0.2, 0.3],
                     [0.3, -0.1, -1.0, 0.8],
                     [0.0, 0.0, 1.2, 0.6]])
    phase = rng.uniform(0, 2 * np.pi, size=base.shape)
    return base * (1.0 + 0.3 * np.sin(2 * np.pi * time_s[:, None, None] / 150.0 + phase))


ROCKET_CONFIG = EstimatorConfig(
    horizon=2,  # unused by the batch estimator
    q_diag=(NOISE_HALF_WIDTH**2 / 3,) * 4,  # variance of the uniform noise
    r_diag_pct2=(100.0,) * 4,               # a vague prior on the first cycle
    faults=[
        FaultConfig("thrust_loss", "monotonic", {"lambda_pct": 1.0}),
        FaultConfig("drag_increase", "monotonic", {"lambda_pct": 1.0}),
        FaultConfig("gimbal_sluggishness", "constant", {}),
        FaultConfig("pitch_sensor_offset", "random_walk", {"sigma": 1.0}),
    ],
)
ESTIMATE_TIMES_S = (70, 115, 150)
FIRST_CYCLES = 4  # the cycles every estimate covers: 0-60 s


def rocket_flight(seed: int) -> tuple[dict, np.ndarray]:
    """Batch estimates at ESTIMATE_TIMES_S of one noisy flight, and the seeded cycle means."""
    rng = np.random.default_rng(seed)
    time_s = np.arange(1, 1501) * DT_S
    faults = rocket_faults_pct(time_s)
    signatures = rocket_signatures(time_s, rng)
    noise = rng.uniform(-NOISE_HALF_WIDTH, NOISE_HALF_WIDTH, size=(time_s.size, 4))
    residuals = np.einsum("tmp,tp->tm", signatures, faults) + noise
    estimator = BatchEstimator(ROCKET_CONFIG, cycle_samples=round(CYCLE_S / DT_S))
    estimates = {}
    for k, t in enumerate(time_s):
        estimator.add(residuals[k], signatures[k])
        if round(t / DT_S) in {10 * t_s for t_s in ESTIMATE_TIMES_S}:
            estimates[round(t)] = estimator.estimate()
    seeded = faults.reshape(-1, round(CYCLE_S / DT_S), 4).mean(axis=1)
    return estimates, seeded


@pytest.mark.timeout(120)
def test_rocket_batch_estimates_improve_as_data_accrue():
    """Over 8 noisy flights: the first four cycles' estimates get better as later data
    arrive. The constant fault carries it (every sample informs its one value); the other
    faults' early values rest on their own cycles' data. Every estimate keeps its model."""
    first_cycle_errors = []
    for seed in range(8):
        estimates, seeded = rocket_flight(seed)
        errors = []
        for estimate in estimates.values():
            assert estimate.status is SolveStatus.SOLVED
            cycles = estimate.cycles_pct
            assert np.all(np.diff(cycles[:, :2], axis=0) >= -1e-6)  # monotonic faults
            # the constant fault: each increment 0 within the solver's tolerance
            assert np.abs(np.diff(cycles[:, 2])).max() <= ROCKET_CONFIG.solver.eps_abs
            assert np.abs(cycles - seeded[: len(cycles)]).max() < 1.0
            errors.append(np.abs(cycles[:FIRST_CYCLES] - seeded[:FIRST_CYCLES]).mean(axis=0))
        first_cycle_errors.append(errors)
    mean_errors = np.mean(first_cycle_errors, axis=0)  # (times, faults)
    for time_s, errors in zip(ESTIMATE_TIMES_S, mean_errors, strict=True):
        print(f"t = {time_s:3d} s: mean |error| over 0-60 s, 8 flights: "
              + ", ".join(f"{name} {value:.3f}" for name, value in
                          zip(ROCKET_FAULTS, errors, strict=True)) + " %")
    gimbal = mean_errors[:, ROCKET_FAULTS.index("gimbal_sluggishness")]
    assert gimbal[1] < 0.8 * gimbal[0] and gimbal[2] < 0.8 * gimbal[0]
    assert mean_errors[2].sum() < mean_errors[0].sum()


@pytest.mark.timeout(60)
def test_mhe_follows_a_lift_loss_step_with_a_window_of_30():
    """Vertical-speed residual of the Aerosonde: y = s f + uniform noise, s constant."""
    rng = np.random.default_rng(5)
    period_s, step_s, step_pct, sensitivity = 0.5, 50.0, 10.0, -0.07
    half_width = 0.15
    config = EstimatorConfig(
        horizon=30, q_diag=(half_width**2 / 3,), r_diag_pct2=(1.0,),
        faults=[FaultConfig("lift_loss", "monotonic", {"lambda_pct": 1.0}, lower_pct=0.0)],
    )
    estimator = MovingHorizonEstimator(config)
    times_s = np.arange(1, 241) * period_s
    estimates = []
    for time_s in times_s:
        fault = step_pct if time_s >= step_s else 0.0
        y = np.array([sensitivity * fault + rng.uniform(-half_width, half_width)])
        result = estimator.update(y, np.array([[sensitivity]]))
        assert result.status is SolveStatus.SOLVED
        estimates.append(result.fault_pct[0])
    estimates = np.array(estimates)
    before = estimates[(times_s >= 30 * period_s) & (times_s < step_s)]  # a full window
    settled = estimates[times_s >= step_s + 30 * period_s]
    reached = times_s[(times_s >= step_s) & (estimates >= step_pct / 2)][0]
    print(f"before the step (full window): max {before.max():.2f} %; settled: {settled.mean():.2f} "
          f"+- {settled.std():.2f} %; half the step reached {reached - step_s:.1f} s after it")
    assert before.max() < 1.0
    assert abs(settled.mean() - step_pct) < 0.5 and settled.std() < 0.5
    assert reached - step_s <= 5.0
