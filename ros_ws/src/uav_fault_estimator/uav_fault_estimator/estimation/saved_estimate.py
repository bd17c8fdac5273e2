"""mhe_node's last estimate on disk, so that a restart of the node within a flight starts
from what it had found rather than from the prior (a wing found damaged stays damaged).
One small JSON file, replaced whole on every write (a crash leaves the previous one). No
ROS here."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class SavedEstimate:
    """stamp_ns: the residual stamp of the estimate [ns of flight time]; names and
    values_pct [%]: the published faults and their estimates."""

    stamp_ns: int
    names: tuple[str, ...]
    values_pct: tuple[float, ...]


def save_estimate(path: Path, estimate: SavedEstimate) -> None:
    """Write the estimate to path atomically (a temporary file beside it, then renamed)."""
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_text(json.dumps({"stamp_ns": estimate.stamp_ns,
                                     "names": list(estimate.names),
                                     "values_pct": list(estimate.values_pct)}))
    os.replace(temporary, path)


def load_estimate(path: Path) -> SavedEstimate | None:
    """The saved estimate; None when there is no file; ValueError naming the file when it
    is not one (malformed, names and values of different lengths, a value not finite)."""
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"state file {path}: cannot be read ({error})") from None
    try:
        estimate = SavedEstimate(int(data["stamp_ns"]), tuple(str(n) for n in data["names"]),
                                 tuple(float(v) for v in data["values_pct"]))
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"state file {path}: not a saved estimate ({error!r})") from None
    if len(estimate.names) != len(estimate.values_pct) or not all(
            math.isfinite(v) for v in estimate.values_pct):
        raise ValueError(f"state file {path}: names and finite values, as many of each")
    return estimate


def resumed_prior(saved: SavedEstimate, first_stamp_ns: int, prior_pct: np.ndarray,
                  columns: Sequence[str]) -> np.ndarray | None:
    """The prior (p,) [%] a restarted estimator starts from: prior_pct with the saved
    faults' values in their columns (the estimator's column names), when its first residual
    (first_stamp_ns) is later than the saved estimate (the flight went on); None when it is
    not (another flight: start from prior_pct)."""
    if first_stamp_ns <= saved.stamp_ns:
        return None
    prior = np.array(prior_pct, dtype=float)
    prior[[list(columns).index(name) for name in saved.names]] = saved.values_pct
    return prior
