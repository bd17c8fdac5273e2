"""A small `ros2` command for machines without ros2cli (see cli.py)."""
