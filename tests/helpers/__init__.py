"""Test harness: ROS domains of their own, node processes that are always stopped."""
