"""Aerosonde UAV flight simulation on JSBSim with seeded faults (core modules import no rclpy)."""
