"""The ROS node of the link."""
