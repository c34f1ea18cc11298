"""ROS-free formats: the message boundary, reports, CSV text, bag reading, drawings."""
