"""Running the main job's chain: offline without ROS, through the node graph (the demo), and
the calibration commands' output."""
