"""Move myrobot_1 from Python (seed ch. 31.9)."""

import rclpy
from rclpy.node import Node

from sas_robot_driver_myrobot.sas_lite import Clock, RobotDriverClient  # noqa: F401


def main(args=None):
    rclpy.init(args=args)
    node = Node('sas_robot_driver_myrobot_joint_space_example_node_py')
    # TODO: a RobotDriverClient for 'myrobot_1'; spin until it is enabled.
    # TODO: read the joint positions once, then every 10 ms (Clock(0.01)) send a target that moves
    #       every joint by up to 10 degrees around them, e.g. 10.0 * sin(i / (50.0 * pi)) degrees.
    # TODO: Ctrl+C must end it with exit code 0 and no traceback: catch KeyboardInterrupt and
    #       ExternalShutdownException (spin_once and send_target_joint_positions raise it once Ctrl+C
    #       has shut ROS down), and call rclpy.try_shutdown() in a finally: block.
    rclpy.spin(node)


if __name__ == '__main__':
    main()
