"""clik in a ROS 2 graph: ``clik ros SCENARIO.toml`` (docs/guides/ros.md).

:mod:`clik.ros.settings` reads the scenario's ``[ros]`` table, :mod:`clik.ros.messages`
checks and converts messages, :mod:`clik.ros.node` is the node. Only the node imports
rclpy (the ``ros`` extra, or a sourced ROS 2 install).
"""
