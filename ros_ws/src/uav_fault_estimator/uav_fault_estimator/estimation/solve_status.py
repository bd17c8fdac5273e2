"""The estimator's status codes: the one home of FaultEstimate's STATUS_* values (a test
ties them to the message). No ROS and no solver here."""

from __future__ import annotations

from enum import IntEnum


class SolveStatus(IntEnum):
    """Status of one estimator update; values equal the FaultEstimate message constants."""

    SOLVED = 0
    MAX_ITERATIONS = 1
    INFEASIBLE = 2
    INVALID_DATA = 3
    WAITING = 4  # no usable data in the window yet: values are the prior, not a failure
    HELD = 5  # the sample not used (air data lost, noise_model.SuiteNoise): estimate kept
