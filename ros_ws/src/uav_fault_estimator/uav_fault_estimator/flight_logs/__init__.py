"""Real flight logs (PX4 ULog, ROS 1/2 bags with MAVROS or the project's topics, per-topic
CSVs) read into time-stamped arrays, mapped through an airframe file and resampled onto the
detector's grid. No ROS here."""
