"""The pose client and the bridge that makes Gazebo's set_pose service a ROS 2 service."""

from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description() -> LaunchDescription:
    """send_poses_to_gazebo_node, and parameter_bridge for /world/<world>/set_pose (a service: no direction)."""
    return LaunchDescription([
        Node(package='python_package_that_uses_gazebo', executable='send_poses_to_gazebo_node',
             name='send_poses_to_gazebo_node', output='screen', emulate_tty=True),
        Node(package='ros_gz_bridge', executable='parameter_bridge', output='screen',
             arguments=['/world/shapes_with_tf2_and_wrench/set_pose@ros_gz_interfaces/srv/SetEntityPose']),
    ])
