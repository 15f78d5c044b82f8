#!/usr/bin/python3
"""The seed's client (ch. 31.9) on the real sas Python bindings: swing every joint by up to 10 degrees."""
import time
from math import pi, sin

from dqrobotics.utils.DQ_Math import deg2rad
from sas_common import rclcpp_init, rclcpp_Node, rclcpp_spin_some, rclcpp_shutdown
from sas_core import Clock
from sas_robot_driver import RobotDriverClient


def main():
    try:
        rclcpp_init()
        node = rclcpp_Node("sas_robot_driver_myrobot_joint_space_example_node_cpp")
        clock = Clock(0.01)
        clock.init()
        rdi = RobotDriverClient(node, 'myrobot_1')
        while not rdi.is_enabled():
            rclcpp_spin_some(node)
            time.sleep(0.1)
        joint_positions = rdi.get_joint_positions()
        for i in range(0, 5000):
            clock.update_and_sleep()
            rdi.send_target_joint_positions(joint_positions + deg2rad([10.0 * sin(i / (50.0 * pi))] * 6))
            rclcpp_spin_some(node)
        rclcpp_shutdown()
    except KeyboardInterrupt:
        print("Interrupted by user")
    except Exception as e:
        print("Unhandled excepts", e)


if __name__ == '__main__':
    main()
