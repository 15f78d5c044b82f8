"""The wrench publisher and the bridge that carries its messages from ROS 2 to Gazebo."""

from launch import LaunchDescription
from launch_ros.actions import Node  # noqa: F401 - for the two Node actions


def generate_launch_description() -> LaunchDescription:
    """send_wrenches_to_gazebo_node, and parameter_bridge for the wrench topic, ROS 2 to Gazebo (``]``)."""
    return LaunchDescription([
        # TODO 17: Node(...) of send_wrenches_to_gazebo_node, and the bridge with
        #          arguments=['<topic>@<ROS 2 type>]<Gazebo type>']
    ])
