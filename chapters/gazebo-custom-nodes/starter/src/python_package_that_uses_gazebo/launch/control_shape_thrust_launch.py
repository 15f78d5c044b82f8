"""The thrust controller, on the world's clock, and the bridge its bridge file configures."""

import os  # noqa: F401 - for os.path.join

from ament_index_python.packages import get_package_share_directory  # noqa: F401 - where the bridge file is
from launch import LaunchDescription
from launch_ros.actions import Node  # noqa: F401 - for the two Node actions

PACKAGE = 'python_package_that_uses_gazebo'


def generate_launch_description() -> LaunchDescription:
    """control_shape_thrust_node with use_sim_time, and parameter_bridge with config_bridge/control_shape_thrust.yaml."""
    return LaunchDescription([
        # TODO 18: the controller with parameters=[{'use_sim_time': True}], and the bridge with
        #          parameters=[{'config_file': <share/PACKAGE/config_bridge/control_shape_thrust.yaml>}]
    ])
