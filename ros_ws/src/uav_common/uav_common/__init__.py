"""What the simulator and the estimator share, owned by neither: the message contracts
(channels, the sample grid), the ROS glue of every node, strict YAML and package data."""
