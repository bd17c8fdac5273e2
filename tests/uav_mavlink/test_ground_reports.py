"""What mavlink_node tells a ground station: short names that fit NAMED_VALUE_FLOAT, and
STATUSTEXT lines that a pilot can read: each alarm's onset (its cause and tests) and end,
each estimate crossing the threshold, whole within MAVLink's 50 characters, said once per
change, in order, at most one per interval."""

from __future__ import annotations

import itertools

import pytest
from uav_common.channels import DETECTION_THRESHOLD_PCT, MODEL_FAULT_NAMES, PAPER_FAULT_NAMES
from uav_fault_estimator.detection.signatures import CAUSES
from uav_mavlink.ground_reports import (
    ALARM_SEVERITY,
    END_SEVERITY,
    MAX_WAITING,
    NAME_CHARS,
    TEST_WORDS,
    TEXT_CHARS,
    GroundTexts,
    alarm_end_text,
    alarm_onset_text,
    alarm_tests,
    estimate_text,
    named_values,
    short_name,
)

pytestmark = pytest.mark.timeout(30)
BELOW, OVER = DETECTION_THRESHOLD_PCT - 0.5, DETECTION_THRESHOLD_PCT + 1.0


def drain(texts: GroundTexts, now_s: float) -> list[tuple[int, str]]:
    """Every text due at now_s, the interval passing between them."""
    said = []
    while (text := texts.due(now_s)) is not None:
        said.append((text.severity, text.text))
        now_s += texts.min_interval_s
    return said


def test_every_estimated_fault_has_its_own_short_name_that_fits():
    names = [short_name(fault) for fault in MODEL_FAULT_NAMES]
    assert len(set(names)) == len(names)
    assert all(0 < len(name) <= NAME_CHARS for name in names)
    assert short_name("some_fault_not_known_here") == "some_fault"


def test_named_values_keep_the_estimates_order_and_values():
    values = named_values(PAPER_FAULT_NAMES, [1.5, 0.0, -0.25, 12.0])
    assert values == [("rw_lift", 1.5), ("rw_drag", 0.0), ("lw_lift", -0.25),
                      ("lw_drag", 12.0)]


def test_every_text_of_every_cause_and_test_fits_whole():
    tests = [combo for n in range(len(TEST_WORDS) + 1)
             for combo in itertools.combinations(TEST_WORDS, n)]
    for cause, raised in itertools.product((*CAUSES, ""), tests):
        onset = alarm_onset_text(cause, raised)
        assert len(onset) <= TEXT_CHARS and (cause or "unknown") in onset
        assert all(word in onset for word in raised), onset
        end = alarm_end_text(cause, 3599.6)
        assert len(end) <= TEXT_CHARS and end.endswith(", 3600 s"), end
    for fault, value in itertools.product(MODEL_FAULT_NAMES, (-123.45, 2.0, 100.0)):
        text = estimate_text(short_name(fault), value, value >= DETECTION_THRESHOLD_PCT)
        assert len(text) <= TEXT_CHARS and text.endswith(f"{DETECTION_THRESHOLD_PCT:g}%")
    assert estimate_text("lw_lift", -0.001, False) == "UAV FDI: lw_lift 0.00% under 2%"


def test_the_tests_raising_an_alarm_are_named_from_the_alarm_message():
    # channel 0's GLRT alarms with its parameters over the threshold: the self-tuning test
    assert alarm_tests([True, False], [2.0, 5.0], 1.5, [False, False], []) == ("glrt",)
    # a GLRT alarm on a channel whose parameters stay within: not the self-tuning test
    assert alarm_tests([True, False], [1.0, 5.0], 1.5, [False, True], [True]) == (
        "fast", "shape")


def test_an_alarm_is_one_onset_and_one_end_however_it_flickers():
    texts = GroundTexts(min_interval_s=1.0, hold_s=3.0)
    flickers = [(10.0 + 0.2 * k, k % 3 != 2) for k in range(50)]  # on, on, off, ...
    for flight_s, on in [(9.8, False), *flickers]:
        texts.alarm(flight_s, on, "elevator", ("fast",))
    for k in range(1, 20):  # off from 20.0 s
        texts.alarm(20.0 + 0.2 * k, False, "", ())
    assert drain(texts, 0.0) == [(ALARM_SEVERITY, "UAV FDI alarm: elevator (fast)"),
                                 (END_SEVERITY, "UAV FDI alarm over: elevator, 10 s")]


def test_an_estimate_hovering_at_the_threshold_is_one_over_and_one_under():
    texts = GroundTexts(min_interval_s=5.0, hold_s=3.0)
    names = PAPER_FAULT_NAMES[:2]
    texts.estimates(0.0, names, [BELOW, BELOW])
    assert texts.due(0.0) is None
    for k in range(100):  # 1.99, 2.01, 1.99, ... from 1 s to 21 s
        value = DETECTION_THRESHOLD_PCT + (0.01 if k % 2 else -0.01)
        texts.estimates(1.0 + 0.2 * k, names, [max(value, OVER) if k == 1 else value, BELOW])
    assert drain(texts, 1.0) == [(ALARM_SEVERITY, "UAV FDI: rw_lift 3.00% over 2%")]
    for k in range(20):  # under from 21 s
        texts.estimates(21.0 + 0.2 * k, names, [1.994, BELOW])
    assert drain(texts, 10.0) == [(END_SEVERITY, "UAV FDI: rw_lift 1.99% under 2%")]


def test_texts_wait_their_turn_in_order_and_a_crossing_undone_meanwhile_is_withdrawn():
    texts = GroundTexts(min_interval_s=5.0, hold_s=0.0)
    names = PAPER_FAULT_NAMES
    texts.estimates(0.0, names, [OVER, BELOW, BELOW, BELOW])
    assert texts.due(0.0).text == "UAV FDI: rw_lift 3.00% over 2%"
    texts.estimates(1.0, names, [OVER, OVER, OVER, BELOW])
    texts.alarm(2.0, True, "right_wing_drag", ("glrt", "shape"))
    texts.estimates(3.0, names, [OVER, OVER, BELOW, BELOW])  # lw_lift back before it was said
    assert texts.due(4.9) is None
    assert [text.text for text in (texts.due(5.0), texts.due(10.0))] == [
        "UAV FDI: rw_drag 3.00% over 2%", "UAV FDI alarm: right_wing_drag (glrt,shape)"]
    assert texts.due(20.0) is None


def test_texts_beyond_the_waiting_limit_are_counted_not_sent():
    texts = GroundTexts(min_interval_s=1.0, hold_s=0.0)
    for k in range(MAX_WAITING + 5):  # onsets and ends, none sent meanwhile
        texts.alarm(2.0 * k, True, "aileron", ())
        texts.alarm(2.0 * k + 1.0, False, "", ())
        texts.alarm(2.0 * k + 1.5, False, "", ())
    assert len(texts.waiting) == MAX_WAITING and texts.dropped == 2 * (MAX_WAITING + 5) - (
        MAX_WAITING)
