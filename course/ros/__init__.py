"""The ROS 2 install: activation, the source-built underlay, the ament index, interface types."""
