"""The onset bound of studies/vaneless_bound.py on a short flight without vanes: before a
fault starts, and for a fault that never does, it is the one-window bound; a start costs
more, and most right after it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from uav_common.channels import PAPER_FAULT_NAMES
from uav_fault_estimator.estimation.estimator_step import SETTLE_S
from uav_sim.scenario import SeededFault, default_scenario_path, load_scenario

from studies.vaneless_bound import BoundModel, onset_bound, settled_samples, with_vanes

START_S = 40.0


@pytest.mark.timeout(300)
def test_the_onset_bound_is_the_window_bound_but_where_a_fault_starts():
    scenario = with_vanes(load_scenario(default_scenario_path()), False)
    scenario = dataclasses.replace(scenario, duration_s=60.0, faults=(SeededFault(
        name="left_wing_drag_increase", start_s=START_S, ramp_s=0.0, magnitude_pct=25.0),))
    samples, model = settled_samples(scenario), BoundModel.of(scenario)
    horizon = model.estimator.horizon
    whole = np.array([model.bound(samples[max(0, k + 1 - horizon):k + 1])
                      for k in range(len(samples))])
    rms_whole = np.sqrt(np.mean(whole**2, axis=0))
    onset = np.array(onset_bound(scenario))
    started = PAPER_FAULT_NAMES.index("left_wing_drag_increase")
    print(f"{len(samples)} samples after {SETTLE_S} s; one-window bound RMS "
          f"{rms_whole.round(3)}, onset bound {onset} [%]")
    assert len(samples) > 60
    others = [j for j in range(len(PAPER_FAULT_NAMES)) if j != started]
    assert onset[others] == pytest.approx(rms_whole[others], rel=1e-2)
    # the first sample after the start holds the drag with one sample's rows alone
    first_after = next(k for k, s in enumerate(samples) if s.time_s > START_S)
    alone = model.bound(samples[first_after:first_after + 1])[started]
    assert alone > 3 * whole[first_after, started]
    assert onset[started] > 1.2 * rms_whole[started]
