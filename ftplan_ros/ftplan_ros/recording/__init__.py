"""Recordings of a run: every topic in a rosbag2-compatible MCAP file, and reading it back.

- definitions.py: the `ros2msg` schema of a message type (its .msg and those it nests),
  read from the installed interface packages as rosbag2 reads them.
- bag_writer.py: `BagWriter`, an MCAP file in the `ros2` profile with rosbag2's channel
  metadata (offered QoS profiles, type hash) and metadata record, so that `ros2 bag info`,
  `ros2 bag play` and Foxglove read it.
- bag_reader.py: `open_bag`, a recording checked and summarised as `ros2 bag info` does,
  its messages decoded from their schemas (mcap_ros2), without ROS.
- replay.py: the runs of a recorded `ftplan-bringup`, drawn by the bringup's own figure.

The node that records, nodes/recorder.py, is the only part that needs rclpy; the
bringup starts it with `--record FILE.mcap`, and `ftplan replay FILE.mcap` reads the file.
"""
