"""FaultAlarm messages held against the detector core's offline samples of the same flight."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest
from uav_common.message_fields import stamp_seconds


def assert_alarms_are_the_cores(alarms: Sequence[Any], offline: Sequence[Any]) -> None:
    """Every FaultAlarm message equals its DetectorSample: stamps (1e-9 s), statistics and
    parameter deviations and fast and template statistics (1e-9 relative, NaN where NaN),
    every test's alarm."""
    assert [stamp_seconds(m.header.stamp) for m in alarms] == pytest.approx(
        [s.time_s for s in offline], abs=1e-9)
    np.testing.assert_allclose([m.statistic for m in alarms],
                               [s.statistic for s in offline], rtol=1e-9, equal_nan=True)
    np.testing.assert_allclose([m.parameter_deviation for m in alarms],
                               [s.parameter_deviation for s in offline], rtol=1e-9,
                               equal_nan=True)
    assert [list(m.alarm) for m in alarms] == [s.alarm.tolist() for s in offline]
    assert [m.parameter_alarm for m in alarms] == [s.parameter_alarm for s in offline]
    np.testing.assert_allclose([m.fast_statistic for m in alarms],
                               [s.fast_statistic for s in offline], rtol=1e-9, equal_nan=True)
    assert [list(m.fast_alarm) for m in alarms] == [s.fast_alarm.tolist() for s in offline]
    for m, s in zip(alarms, offline, strict=True):
        np.testing.assert_allclose(m.template_statistic, s.template_statistic, rtol=1e-9,
                                   equal_nan=True)
    assert [list(m.template_alarm) for m in alarms] == [s.template_alarm.tolist()
                                                        for s in offline]
    assert [m.combined_alarm for m in alarms] == [s.combined_alarm for s in offline]
    assert [m.cause for m in alarms] == [s.cause for s in offline]
