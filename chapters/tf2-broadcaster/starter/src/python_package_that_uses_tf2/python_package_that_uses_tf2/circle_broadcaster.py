"""A robot frame driving on a circle around `world`, with a camera fixed on the robot (tf2)."""

import math

import rclpy
from geometry_msgs.msg import TransformStamped
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from tf2_ros import StaticTransformBroadcaster, TransformBroadcaster

RADIUS = 1.0  # metres from the world origin
ANGULAR_SPEED = 0.5  # radians per second, counter-clockwise
PERIOD = 0.05  # seconds between two transforms on /tf (20 Hz)


def yaw_to_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation of ``yaw`` radians about the z axis."""
    # TODO 4: a quaternion is not (0, 0, yaw, 1). A rotation of `yaw` about z is
    #         (0, 0, sin(yaw / 2), cos(yaw / 2)): a unit quaternion.
    return 0.0, 0.0, 0.0, 1.0


class CircleBroadcaster(Node):
    """Broadcasts world -> robot on /tf every 0.05 s, and robot -> camera once on /tf_static."""

    def __init__(self) -> None:
        super().__init__('circle_broadcaster')
        self.broadcaster = TransformBroadcaster(self)
        # TODO 5: the camera never moves on the robot: send robot -> camera (x 0.1 m, z 0.2 m, no
        #         rotation) ONCE, with a StaticTransformBroadcaster (it publishes on /tf_static).
        self.start = self.get_clock().now()
        self.timer = self.create_timer(PERIOD, self.timer_callback)

    def timer_callback(self) -> None:
        """Where the robot is now: angle = speed * time, facing the direction it drives in."""
        now = self.get_clock().now()
        angle = ANGULAR_SPEED * (now - self.start).nanoseconds * 1e-9
        t = TransformStamped()
        # TODO 2: stamp the transform with `now`, name the parent frame 'world' and the child 'robot'.
        # TODO 3: put the robot on the circle: x = RADIUS * cos(angle), y = RADIUS * sin(angle), z = 0,
        #         facing the direction of motion: yaw = angle + pi / 2 (use yaw_to_quaternion).
        self.broadcaster.sendTransform(t)


def main(args=None):
    try:
        rclpy.init(args=args)
        node = CircleBroadcaster()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
