"""The ROS glue every node shares (messages, node tools) and sim_node."""
