"""The residual sampling step residual_node, the offline chain and the model calibration
share: one residual out per update period, on the period's grid, none lost to a refused
sample."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from uav_fault_estimator.estimation.residual_sampling import ResidualSampler

SENSOR_PERIOD_S, UPDATE_PERIOD_S = 0.1, 0.5


class ScriptedGenerator:
    """Stands in for the residual generator: a sample per call, except a ValueError at the
    `refused` times and None (its filters warming) before `first_s`."""

    def __init__(self, refused: tuple[float, ...] = (), first_s: float = 0.0) -> None:
        self.refused, self.first_s, self.resets = refused, first_s, 0

    def update(self, time_s, state, controls, wind_ned_mps, air_data):
        if any(abs(time_s - t) < 1e-9 for t in self.refused):
            raise ValueError("a state the model cannot evaluate")
        return None if time_s < self.first_s else SimpleNamespace(time_s=time_s)

    def reset(self) -> None:
        self.resets += 1


def outputs(sampler: ResidualSampler, times_s: np.ndarray) -> list[float]:
    """The times of the samples the sampler gives out over the sensor times."""
    out = []
    for time_s in times_s:
        try:
            sample = sampler.update(time_s, None, None, None, None)
        except ValueError:
            continue
        if sample is not None:
            out.append(round(sample.time_s, 6))
    return out


def sensor_times(start_s: float, end_s: float) -> np.ndarray:
    return np.round(np.arange(start_s, end_s + 1e-9, SENSOR_PERIOD_S), 6)


@pytest.mark.timeout(10)
def test_one_sample_out_per_period_on_its_grid():
    sampler = ResidualSampler(ScriptedGenerator(first_s=0.3), UPDATE_PERIOD_S)
    assert outputs(sampler, sensor_times(0.0, 2.0)) == [0.5, 1.0, 1.5, 2.0]


@pytest.mark.timeout(10)
def test_a_refused_sample_on_the_grid_moves_its_output_to_the_next_sample():
    sampler = ResidualSampler(ScriptedGenerator(refused=(1.0,)), UPDATE_PERIOD_S)
    assert outputs(sampler, sensor_times(0.0, 2.0)) == [0.0, 0.5, 1.1, 1.5, 2.0]
    assert sampler.newest is not None and sampler.newest.time_s == pytest.approx(2.0)


@pytest.mark.timeout(10)
def test_a_reset_starts_the_generator_and_the_grid_afresh():
    generator = ScriptedGenerator()
    sampler = ResidualSampler(generator, UPDATE_PERIOD_S)
    assert outputs(sampler, sensor_times(0.0, 1.2)) == [0.0, 0.5, 1.0]
    sampler.reset()
    assert generator.resets == 1 and sampler.newest is None
    # a restarted source whose first sample is off the grid: out at the next multiple
    assert outputs(sampler, sensor_times(0.2, 1.2)) == [0.5, 1.0]


@pytest.mark.timeout(10)
def test_a_period_that_is_not_a_time_is_refused():
    with pytest.raises(ValueError, match="positive"):
        ResidualSampler(ScriptedGenerator(), 0.0)
