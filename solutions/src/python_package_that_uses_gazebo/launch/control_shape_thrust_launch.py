"""The thrust controller, on the world's clock, and the bridge its bridge file configures."""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch_ros.actions import Node

PACKAGE = 'python_package_that_uses_gazebo'


def generate_launch_description() -> LaunchDescription:
    """control_shape_thrust_node with use_sim_time, and parameter_bridge with config_bridge/control_shape_thrust.yaml."""
    config = os.path.join(get_package_share_directory(PACKAGE), 'config_bridge', 'control_shape_thrust.yaml')
    return LaunchDescription([
        Node(package='python_package_that_uses_gazebo', executable='control_shape_thrust_node',
             name='control_shape_thrust_node',
             output='screen', emulate_tty=True, parameters=[{'use_sim_time': True}]),
        Node(package='ros_gz_bridge', executable='parameter_bridge', output='screen',
             parameters=[{'config_file': config, 'use_sim_time': True}]),
    ])
