"""Real ROS programs the benchmark runs under the system Python (package data, not lab code)."""
