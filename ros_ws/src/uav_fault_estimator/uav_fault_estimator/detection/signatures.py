"""Which failure an alarm resembles: its signature against learned ones.

An alarm's signature: each channel's fast-test change (detector.DetectorSample.fast_change:
the change of its fixed-parameter residual's mean over the last W samples, in units of its
fault-free spread), then each channel's parameters' signed deviations from their fault-free
means (DetectorSample.parameter_deviations, in fault-free spreads), as one direction
(signature_features names its entries). Its signs and sizes tell failures apart: a wing that
loses lift rolls the aircraft to its side whatever the autopilot commands and shifts the
roll loop's bias, an aileron stuck at 0 rolls it against the commands either way and lowers
the loop's gain, an engine cut drops the body-x force and pitches the aircraft to hold its
height, a wing's drag drops less of it and yaws it to that side. FailureSignatures holds
such directions, each of a simulated failure of known cause (scripts/learn_signatures.py),
and names an alarm's cause by its nearest neighbours among them: the cause most of the
`neighbours` learned directions closest to the alarm's (by the angle between them) have, a
tie to the closest's. No ROS here.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from uav_common.strict_yaml import kind_mismatch

from uav_fault_estimator.detection.calibration import Calibration
from uav_fault_estimator.detection.generators import GENERATORS

# The part each seeded fault is a failure of: what an alarm's cause names.
CAUSE_OF_FAULT: Mapping[str, str] = {
    "right_wing_lift_loss": "right_wing_lift", "right_wing_drag_increase": "right_wing_drag",
    "left_wing_lift_loss": "left_wing_lift", "left_wing_drag_increase": "left_wing_drag",
    "propulsion_loss": "engine", "pitch_moment": "elevator",
    "aileron_effectiveness_loss": "aileron",
    "aileron_stuck": "aileron", "left_aileron_stuck": "aileron",
    "right_aileron_stuck": "aileron", "elevator_stuck": "elevator",
    "rudder_stuck": "rudder", "engine_cut": "engine"}
CAUSES = tuple(dict.fromkeys(CAUSE_OF_FAULT.values()))
DEFAULT_NEIGHBOURS = 3
# What a signatures file is, for the line that refuses a file of another kind
SIGNATURES_FILE = "a failure signatures file (scripts/learn_signatures.py's)"
SIGNATURES_KEYS = ("features", "neighbours", "learned_from", "signatures")


@dataclass(frozen=True)
class FailureSignatures:
    """Learned failure signatures: their entries' names (signature_features of the
    calibration they were learned with), each one's cause (CAUSES) and unit direction (N,
    F), and how many neighbours vote."""

    features: tuple[str, ...]
    causes: tuple[str, ...]
    directions: np.ndarray
    neighbours: int = DEFAULT_NEIGHBOURS
    learned_from: str = ""  # which flights, for the file's reader

    def cause(self, signature: np.ndarray) -> str:
        """The cause an alarm's signature (F,) resembles most: the cause most of its
        `neighbours` nearest signatures have (a tie: the nearest's); empty for a signature
        with no direction (zero or not finite)."""
        size = float(np.linalg.norm(signature))
        if not (np.isfinite(size) and size > 0.0):
            return ""
        similarity = self.directions @ (np.asarray(signature, dtype=float) / size)
        nearest = [self.causes[i] for i in np.argsort(-similarity, kind="stable")
                   [:self.neighbours]]
        votes = Counter(nearest)
        most = max(votes.values())
        return next(cause for cause in nearest if votes[cause] == most)


def signature_of(fast_change: np.ndarray, parameter_deviations: np.ndarray) -> np.ndarray:
    """An alarm's signature (F,): each channel's fast-test change, then each channel's
    parameters' signed deviations, the order signature_features names."""
    return np.concatenate([fast_change, parameter_deviations])


def signature_features(calibration: Calibration) -> tuple[str, ...]:
    """The names of a signature's entries for the calibration: each channel's fast-test
    change (the channel's name), then each channel's parameters' deviations
    (<channel>.<parameter>), in the calibration's order."""
    return (*calibration.channel_names,
            *(f"{name}.{parameter}" for name in calibration.channel_names
              for parameter in GENERATORS[name].parameters))


def learned_signatures(features: tuple[str, ...], examples: Sequence[tuple[str, np.ndarray]],
                       neighbours: int = DEFAULT_NEIGHBOURS,
                       learned_from: str = "") -> FailureSignatures:
    """Signatures from examples (cause, the signature at the failure's first alarm (F,)):
    each as a unit direction; those without one (zero, not finite) left out. ValueError for
    a cause not in CAUSES, a signature of the wrong length, or fewer examples than
    neighbours."""
    causes, directions = [], []
    for cause, signature in examples:
        signature = np.asarray(signature, dtype=float)
        if cause not in CAUSES or signature.shape != (len(features),):
            raise ValueError(f"signature of {cause!r} over {signature.shape}: expected one "
                             f"of {', '.join(CAUSES)} over {len(features)} entries")
        size = float(np.linalg.norm(signature))
        if np.isfinite(size) and size > 0.0:
            causes.append(cause)
            directions.append(signature / size)
    if len(causes) < max(neighbours, 1):
        raise ValueError(f"{len(causes)} signatures for {neighbours} neighbours")
    return FailureSignatures(tuple(features), tuple(causes), np.array(directions),
                             neighbours, learned_from)


def signatures_to_dict(signatures: FailureSignatures) -> dict[str, Any]:
    """The signatures as the file's mapping (YAML-ready)."""
    return {"features": list(signatures.features), "neighbours": signatures.neighbours,
            "learned_from": signatures.learned_from,
            "signatures": [{"cause": cause, "direction": [round(float(x), 6) for x in row]}
                           for cause, row in zip(signatures.causes, signatures.directions,
                                                 strict=True)]}


def load_signatures_file(path: Path) -> Any:
    """A signatures file's parsed YAML (what signatures_from and templates.templates_in
    read); ValueError with one line naming it."""
    try:
        return yaml.safe_load(Path(path).read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        raise ValueError(f"signatures file {path}: {type(error).__name__}: {error}") from None


def signatures_from(data: Any, path: Path) -> FailureSignatures:
    """The signatures of a signatures file's parsed YAML; ValueError with one line naming
    the file (path)."""
    mismatch = kind_mismatch(data, SIGNATURES_KEYS, SIGNATURES_FILE)
    if mismatch:
        raise ValueError(f"signatures file {path}: {mismatch}")
    try:
        return learned_signatures(
            tuple(data["features"]), [(entry["cause"], entry["direction"])
                                      for entry in data["signatures"]],
            int(data["neighbours"]), str(data["learned_from"]))
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"signatures file {path}: {type(error).__name__}: {error}") from None


def read_signatures(path: Path) -> FailureSignatures:
    """The signatures file; ValueError with one line naming it."""
    return signatures_from(load_signatures_file(path), path)
