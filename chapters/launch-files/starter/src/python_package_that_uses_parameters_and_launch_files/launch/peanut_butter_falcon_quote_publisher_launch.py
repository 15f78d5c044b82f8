"""Start the configurable quote publisher with a truly inspirational quote (lesson: launch-files)."""

from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        Node(
            output='screen',
            emulate_tty=True,
            package='python_package_that_uses_parameters_and_launch_files',
            executable='amazing_quote_configurable_publisher_node',
            # TODO: name the node 'peanut_butter_falcon_quote_publisher_node'
            # TODO: parameters=[{...}] with topic_name, period, quote and philosopher_name
        ),
    ])
