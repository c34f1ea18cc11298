"""Everything that imports rclpy: rotation_node, rotation_client, the TF input, the runtime."""
