"""The pose client and the bridge that makes Gazebo's set_pose service a ROS 2 service."""

from launch import LaunchDescription
from launch_ros.actions import Node  # noqa: F401 - for the two Node actions


def generate_launch_description() -> LaunchDescription:
    """send_poses_to_gazebo_node, and parameter_bridge for /world/<world>/set_pose (a service: no direction)."""
    return LaunchDescription([
        # TODO 16: Node(...) of send_poses_to_gazebo_node, and Node(package='ros_gz_bridge',
        #          executable='parameter_bridge', arguments=['<service>@<ROS 2 type>'])
    ])
