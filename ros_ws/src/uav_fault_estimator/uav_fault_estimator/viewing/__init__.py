"""What the viewing nodes serve, without ROS: the Foxglove live view's core and the state in
REP 103 frames."""
