"""Running the main job's chain: offline without ROS and through the node graph (the demo)."""
