"""Drives the box of the Gazebo world towards x = -3 m with a proportional force.

Each tick it looks up where the box is (tf: the world's frame to the box's, published by Gazebo's
PosePublisher through ros_gz_bridge) and publishes a force on x proportional to the error.
"""

import rclpy
import tf2_ros
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.time import Time
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
    return -gain * (current - target)


class ControlShapeThrustNode(Node):
    """A proportional controller of the box's x position."""

    def __init__(self) -> None:
        super().__init__('control_shape_thrust_node')
        self.publisher = self.create_publisher(EntityWrench, TOPIC, 1)
        while self.publisher.get_subscription_count() == 0:
            self.get_logger().info(f'waiting for a subscriber on {TOPIC}...')
            rclpy.spin_once(self, timeout_sec=1.0)  # unlike time.sleep, Ctrl+C ends it cleanly
        self.buffer = tf2_ros.Buffer()
        self.listener = tf2_ros.TransformListener(self.buffer, self)
        self.timer = self.create_timer(PERIOD, self.timer_callback)

    def timer_callback(self) -> None:
        """Look up the box's latest pose and publish the force that pushes it towards TARGET_X."""
        try:
            transform = self.buffer.lookup_transform(WORLD, ENTITY, Time())
        except tf2_ros.TransformException as exc:
            self.get_logger().warn(f'no transform from {WORLD} to {ENTITY} yet: {exc}',
                                   throttle_duration_sec=1.0)
            return
        message = EntityWrench()
        message.entity.id = ENTITY_ID
        message.wrench.force.x = control_action(transform.transform.translation.x, TARGET_X)
        self.publisher.publish(message)


def main(args=None) -> None:
    """Run the controller until Ctrl+C."""
    try:
        rclpy.init(args=args)
        rclpy.spin(ControlShapeThrustNode())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
