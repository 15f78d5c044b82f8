"""The driver node of myrobot (seed ch. 31.6, in Python)."""

import rclpy
from rclpy.node import Node

from sas_robot_driver_myrobot.robot_driver_myrobot import RobotDriverMyrobot, RobotDriverMyrobotConfiguration  # noqa: F401
from sas_robot_driver_myrobot.robot_driver_ros import RobotDriverROS, RobotDriverROSConfiguration  # noqa: F401


def main(args=None):
    rclpy.init(args=args)
    node = Node('sas_robot_driver_myrobot')
    # TODO: declare and read the parameters ip, joint_limits_min, joint_limits_max (degrees: convert
    #       them to radians) and thread_sampling_time_sec.
    # TODO: create RobotDriverMyrobot and RobotDriverROS (prefix: node.get_name()) and run control_loop().
    # TODO: Ctrl+C must end with exit code 0: catch KeyboardInterrupt and ExternalShutdownException,
    #       and always deinitialize() then disconnect() the driver.
    rclpy.spin(node)


if __name__ == '__main__':
    main()
