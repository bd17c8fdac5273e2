"""What mavlink_node tells a ground station: short names that fit NAMED_VALUE_FLOAT, and
STATUSTEXT lines said once per change, rate-limited, within MAVLink's 50 characters."""

from __future__ import annotations

import pytest
from uav_common.channels import DETECTION_THRESHOLD_PCT, MODEL_FAULT_NAMES, PAPER_FAULT_NAMES
from uav_mavlink.ground_reports import (
    NAME_CHARS,
    TEXT_CHARS,
    AlarmTexts,
    named_values,
    short_name,
)

pytestmark = pytest.mark.timeout(30)
BELOW, OVER = DETECTION_THRESHOLD_PCT - 0.5, DETECTION_THRESHOLD_PCT + 1.0


def test_every_estimated_fault_has_its_own_short_name_that_fits():
    names = [short_name(fault) for fault in MODEL_FAULT_NAMES]
    assert len(set(names)) == len(names)
    assert all(0 < len(name) <= NAME_CHARS for name in names)
    assert short_name("some_fault_not_known_here") == "some_fault"


def test_named_values_keep_the_estimates_order_and_values():
    values = named_values(PAPER_FAULT_NAMES, [1.5, 0.0, -0.25, 12.0])
    assert values == [("rw_lift", 1.5), ("rw_drag", 0.0), ("lw_lift", -0.25),
                      ("lw_drag", 12.0)]


def test_an_estimate_reaching_the_threshold_is_said_once_while_it_stays_over():
    texts = AlarmTexts(min_interval_s=5.0)
    names = PAPER_FAULT_NAMES[:2]
    assert texts.estimates(0.0, names, [BELOW, BELOW]) is None
    assert texts.estimates(1.0, names, [OVER, BELOW]) == "UAV FDI: rw_lift 3%"
    assert all(texts.estimates(t, names, [OVER + t, BELOW]) is None for t in range(2, 30))
    # below and over again: said again
    assert texts.estimates(30.0, names, [BELOW, BELOW]) is None
    assert texts.estimates(31.0, names, [OVER, BELOW]) == "UAV FDI: rw_lift 3%"


def test_lines_within_the_interval_wait_and_go_together():
    texts = AlarmTexts(min_interval_s=5.0)
    names = PAPER_FAULT_NAMES
    assert texts.estimates(0.0, names, [OVER, BELOW, BELOW, BELOW]) == "UAV FDI: rw_lift 3%"
    assert texts.estimates(1.0, names, [OVER, OVER, BELOW, BELOW]) is None
    assert texts.alarm(2.0, True, ["roll", "yaw"]) is None
    assert texts.alarm(3.0, True, ["roll", "yaw"]) is None  # still on: nothing new
    assert texts.estimates(5.0, names, [OVER, OVER, BELOW, BELOW]) == (
        "UAV FDI: rw_drag 3%; alarm roll,yaw")


def test_a_line_longer_than_statustext_carries_is_cut_visibly():
    texts = AlarmTexts(min_interval_s=1.0)
    line = texts.estimates(0.0, MODEL_FAULT_NAMES, [25.0] * len(MODEL_FAULT_NAMES))
    assert len(line) == TEXT_CHARS and line.endswith("...")


def test_the_combined_alarm_is_said_when_it_rises():
    texts = AlarmTexts(min_interval_s=1.0)
    assert texts.alarm(0.0, False, []) is None
    assert texts.alarm(1.0, True, ["pitch"]) == "UAV FDI: alarm pitch"
    assert texts.alarm(3.0, True, ["pitch"]) is None
    assert texts.alarm(4.0, False, []) is None
    assert texts.alarm(5.0, True, ["roll"]) == "UAV FDI: alarm roll"
