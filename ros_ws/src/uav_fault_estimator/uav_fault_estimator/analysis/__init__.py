"""Offline runs, recordings, figures of merit, the report and its figures (no rclpy here)."""
