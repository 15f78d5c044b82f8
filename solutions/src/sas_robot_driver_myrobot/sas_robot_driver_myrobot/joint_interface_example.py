"""Move myrobot_1 from Python (seed ch. 31.9).

Waits until the driver is enabled (joint positions and both limits
received), then every 10 ms sends targets that swing every joint by up to
10 degrees around where it started.
"""

import itertools
from math import pi, sin

import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from sas_robot_driver_myrobot.sas_lite import Clock, RobotDriverClient


def main(args=None):
    try:
        rclpy.init(args=args)
        node = Node('sas_robot_driver_myrobot_joint_space_example_node_py')

        # 10 ms clock
        clock = Clock(0.01)
        clock.init()

        rdi = RobotDriverClient(node, 'myrobot_1')

        # Sending anything before the driver is enabled would command a robot we know nothing about.
        while not rdi.is_enabled():
            rclpy.spin_once(node, timeout_sec=0.1)

        node.get_logger().info(f'topic prefix = {rdi.get_topic_prefix()}')
        joint_positions = rdi.get_joint_positions()
        node.get_logger().info(f'joint positions = {joint_positions}')

        for i in itertools.count():
            clock.update_and_sleep()
            target_joint_positions = joint_positions + np.deg2rad([10.0 * sin(i / (50.0 * pi))] * 6)
            rdi.send_target_joint_positions(target_joint_positions)
            rclpy.spin_once(node, timeout_sec=0.0)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
