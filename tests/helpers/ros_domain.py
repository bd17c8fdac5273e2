"""A ROS domain id reserved for one test session, so parallel runs never see each other.

The code lives in the package (uav_fault_estimator.processes), shared with scripts/demo.py.
"""

from uav_fault_estimator.processes import DOMAIN_IDS, LOCK_DIR, reserve_domain_id

__all__ = ["DOMAIN_IDS", "LOCK_DIR", "reserve_domain_id"]
