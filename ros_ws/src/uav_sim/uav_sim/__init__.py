"""Fixed-wing UAV flight simulation on JSBSim with seeded faults, flying the aircraft of
uav_aircraft (core modules import no rclpy)."""
