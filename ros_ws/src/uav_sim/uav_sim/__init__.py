"""Fixed-wing UAV flight simulation on JSBSim with seeded faults, one folder per aircraft
(core modules import no rclpy)."""
