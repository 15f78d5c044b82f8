"""Drives the box of the Gazebo world towards x = -3 m with a proportional force."""

import rclpy
import tf2_ros
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.time import Time  # noqa: F401 - Time() asks tf2 for the latest transform
from ros_gz_interfaces.msg import EntityWrench

WORLD = 'shapes_with_tf2_and_wrench'
TOPIC = f'/world/{WORLD}/wrench'
ENTITY = 'box'
ENTITY_ID = 9
TARGET_X = -3.0  # metres, in the world frame
GAIN = 5.0  # newtons per metre of error
PERIOD = 0.001  # seconds: the control loop runs at 1 kHz


def control_action(current: float, target: float, gain: float = GAIN) -> float:
    """The proportional law: a force (N) of -gain * (current - target), current and target in metres."""
    return 0.0  # TODO 12: the law


class ControlShapeThrustNode(Node):
    """A proportional controller of the box's x position."""

    def __init__(self) -> None:
        super().__init__('control_shape_thrust_node')
        self.publisher = self.create_publisher(EntityWrench, TOPIC, 1)
        while self.publisher.get_subscription_count() == 0:
            self.get_logger().info(f'waiting for a subscriber on {TOPIC}...')
            rclpy.spin_once(self, timeout_sec=1.0)  # unlike time.sleep, Ctrl+C ends it cleanly
        self.buffer = tf2_ros.Buffer()
        # TODO 13: a TransformListener on the buffer, and a timer of PERIOD calling timer_callback

    def timer_callback(self) -> None:
        """Look up the box's latest pose and publish the force that pushes it towards TARGET_X."""
        # TODO 14: look up the transform from WORLD to ENTITY (the latest: Time()); on tf2_ros.TransformException
        #          log a warning (throttle_duration_sec=1.0) and return
        # TODO 15: publish an EntityWrench for ENTITY_ID whose force.x is control_action(x, TARGET_X)
        pass


def main(args=None) -> None:
    """Run the controller until Ctrl+C."""
    try:
        rclpy.init(args=args)
        rclpy.spin(ControlShapeThrustNode())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
