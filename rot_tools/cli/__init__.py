"""``rot-tools``: the command line over the math, for people with no ROS at hand."""
