"""The project's recordings: rosbag2 directories in MCAP written and read with rosbags, and
the type store of the project's messages."""
