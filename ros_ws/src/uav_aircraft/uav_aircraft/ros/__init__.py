"""ROS glue of the aircraft: the `vehicle` parameter every node of an aircraft declares."""
