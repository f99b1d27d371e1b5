"""Unit tests of the ROS-free helpers of the nodes (no rclpy: test/ros tests the nodes)."""
