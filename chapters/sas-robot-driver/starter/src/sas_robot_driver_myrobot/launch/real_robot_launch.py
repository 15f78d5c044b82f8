"""Start the myrobot driver (seed ch. 31.7)."""

from launch import LaunchDescription
from launch_ros.actions import Node  # noqa: F401  (you will need it)


def generate_launch_description():
    return LaunchDescription([
        # TODO: a Node(...) for sas_robot_driver_myrobot_node, named myrobot_1 (the name is the
        #       topic prefix), with the parameters ip, joint_limits_min, joint_limits_max (degrees,
        #       six floats each) and thread_sampling_time_sec (0.002 s, i.e. 500 Hz).
    ])
