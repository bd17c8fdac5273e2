"""mhe_node's state file: what is written is read back; no file is no estimate; anything
else is one ValueError naming the file."""

from __future__ import annotations

import pytest
from uav_fault_estimator.estimation.saved_estimate import (
    SavedEstimate,
    load_estimate,
    save_estimate,
)


@pytest.mark.timeout(30)
def test_an_estimate_round_trips_and_a_missing_file_is_none(tmp_path):
    path = tmp_path / "state.json"
    assert load_estimate(path) is None
    estimate = SavedEstimate(20_500_000_000, ("right_wing_lift_loss", "left_wing_lift_loss"),
                             (5.25, -0.125))
    save_estimate(path, estimate)
    assert load_estimate(path) == estimate
    assert [p.name for p in tmp_path.iterdir()] == ["state.json"]  # no temporary left


@pytest.mark.timeout(30)
@pytest.mark.parametrize("content", [
    b"", b"\xff\xfe", b"[1, 2]", b'{"stamp_ns": 1, "names": ["a"]}',
    b'{"stamp_ns": 1, "names": ["a", "b"], "values_pct": [1.0]}',
    b'{"stamp_ns": 1, "names": ["a"], "values_pct": [NaN]}',
    b'{"stamp_ns": "soon", "names": ["a"], "values_pct": [1.0]}',
])
def test_a_file_that_is_no_saved_estimate_is_one_line_naming_it(tmp_path, content):
    path = tmp_path / "state.json"
    path.write_bytes(content)
    with pytest.raises(ValueError, match=f"^state file {path}: ") as raised:
        load_estimate(path)
    assert "\n" not in str(raised.value)
