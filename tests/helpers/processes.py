"""Start ROS nodes and tools as processes the way a user would, and always stop them.

The code lives in the package (uav_fault_estimator.processes), shared with scripts/demo.py.
"""

from uav_fault_estimator.processes import (
    STOP_TIMEOUT_S,
    RosProcess,
    exit_status_text,
    ros2_run_argv,
    stop_all,
    wait_until,
)

__all__ = ["STOP_TIMEOUT_S", "RosProcess", "exit_status_text", "ros2_run_argv", "stop_all",
           "wait_until"]
