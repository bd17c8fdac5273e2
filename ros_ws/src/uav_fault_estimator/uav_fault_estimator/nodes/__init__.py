"""The ROS 2 nodes: thin adapters around the core, and the stamp matching they share."""
