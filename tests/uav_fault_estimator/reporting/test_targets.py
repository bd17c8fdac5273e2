"""The estimator's default targets in their one home: a flight judged against them as the
docs state them, faults too late or too short to judge left out and said, and the docs'
sentence the module's."""

from __future__ import annotations

import pytest
from helpers.repo import REPO_ROOT
from uav_fault_estimator.reporting import targets
from uav_sim.scenario import default_scenario_path, load_scenario


def fault(seeded_final: float, final: float | None, rmse: float | None, delay: float | None,
          largest: float | None = 0.5) -> dict:
    """A fault's entry of metrics.json."""
    return {"seeded": seeded_final > 0, "seeded_final_pct": seeded_final,
            "estimate_final_pct": final, "rmse_pct": rmse, "max_abs_error_pct": largest,
            "detection_delay_s": delay}


@pytest.mark.timeout(10)
def test_a_flight_is_judged_on_each_fault_and_its_false_alarms():
    met = {"a": fault(20.0, 21.9, 2.9, 9.5), "b": fault(0.0, 0.3, 0.2, None, largest=1.99)}
    assert targets.judge(met, []) == targets.Verdict([], {})
    assert targets.judge(met, []).text() == "met"
    missed = targets.judge({"a": fault(20.0, 22.1, 3.1, 10.5),
                            "b": fault(0.0, 2.0, 1.0, None, largest=2.0),
                            "c": fault(10.0, 10.0, 1.0, None),
                            "d": fault(1.5, 3.0, 2.0, None)}, ["b"])  # d: below 2 %
    assert missed.missed == ["fault-free b 2.00 %", "false alarm b", "a RMS 3.10 % of 20",
                             "a found 10.5 s", "a final 22.10 % for 20", "c found never"]
    assert missed.text().startswith("missed: fault-free b 2.00 %, false alarm b, a RMS")


@pytest.mark.timeout(10)
def test_faults_too_late_or_without_figures_are_not_judged_and_said():
    verdict = targets.judge({"a": fault(25.0, 3.0, 20.0, None),
                             "b": fault(0.0, 0.0, None, None, largest=None),
                             "c": fault(10.0, 10.0, None, None, largest=None)}, [],
                            late=["a"])
    assert verdict.missed == []
    assert verdict.text() == ("met (not judged, no estimate after settle_s: b, c; at the "
                              "threshold within 10 s of the end: a)")


@pytest.mark.timeout(30)
def test_a_fault_is_late_when_it_reaches_the_threshold_in_the_last_10_s():
    default = load_scenario(default_scenario_path())
    late = {duration_s: targets.reached_late(duration_s, default.faults_pct)
            for duration_s in (300.0, 120.0, 115.0, 60.0, 57.0)}
    # the lift ramp from 50 s reaches 2 % at 58 s; the drag step comes at 110 s
    assert late == {300.0: [], 120.0: [], 115.0: ["left_wing_drag_increase"],
                    60.0: ["right_wing_lift_loss"], 57.0: []}


@pytest.mark.timeout(10)
def test_the_docs_quote_the_targets_from_their_home():
    page = (REPO_ROOT / "docs" / "estimator.md").read_text()
    assert "\n## Targets\n" in page
    assert targets.TARGETS_TEXT in " ".join(page.split())
    assert targets.TARGETS_PAGE == "docs/estimator.md#targets"
