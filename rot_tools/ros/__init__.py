"""Everything that imports rclpy: the node (node/), its client (client/) and what both use."""
