"""The math: rotations and rigid motions in NumPy and ``math``; no ROS, no file formats."""
