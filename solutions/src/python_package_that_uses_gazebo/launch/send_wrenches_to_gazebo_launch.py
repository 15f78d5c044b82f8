"""The wrench publisher and the bridge that carries its messages from ROS 2 to Gazebo."""

from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description() -> LaunchDescription:
    """send_wrenches_to_gazebo_node, and parameter_bridge for the wrench topic, ROS 2 to Gazebo (``]``)."""
    return LaunchDescription([
        Node(package='python_package_that_uses_gazebo', executable='send_wrenches_to_gazebo_node',
             name='send_wrenches_to_gazebo_node', output='screen', emulate_tty=True),
        Node(package='ros_gz_bridge', executable='parameter_bridge', output='screen',
             arguments=['/world/shapes_with_tf2_and_wrench/wrench@ros_gz_interfaces/msg/EntityWrench]gz.msgs.EntityWrench']),
    ])
