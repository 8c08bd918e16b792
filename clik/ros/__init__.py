"""clik in a ROS 2 graph: ``clik ros SCENARIO.toml`` (docs/guides/ros.md).

The scenario's ``[ros]`` table is read by :mod:`clik.scenarios.ros_table`;
:mod:`clik.ros.messages` checks and converts messages, :mod:`clik.ros.node` is the node.
Only the node imports rclpy (the ``ros`` extra, or a sourced ROS 2 install).
"""
