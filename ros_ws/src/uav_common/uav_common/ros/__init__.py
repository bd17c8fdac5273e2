"""ROS glue every node uses: parameters, diagnostics, spinning, messages, paced publishing."""
