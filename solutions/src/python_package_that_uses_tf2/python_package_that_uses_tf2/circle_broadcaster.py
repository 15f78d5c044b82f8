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
    """(x, y, z, w) of a rotation of ``yaw`` radians about the z axis: a unit quaternion."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


class CircleBroadcaster(Node):
    """Broadcasts world -> robot on /tf every 0.05 s, and robot -> camera once on /tf_static."""

    def __init__(self) -> None:
        super().__init__('circle_broadcaster')
        self.broadcaster = TransformBroadcaster(self)
        # /tf_static is TRANSIENT_LOCAL: sent once, kept for every listener that starts later
        self.static_broadcaster = StaticTransformBroadcaster(self)
        camera = TransformStamped()
        camera.header.stamp = self.get_clock().now().to_msg()
        camera.header.frame_id = 'robot'
        camera.child_frame_id = 'camera'
        camera.transform.translation.x = 0.1
        camera.transform.translation.z = 0.2
        camera.transform.rotation.w = 1.0
        self.static_broadcaster.sendTransform(camera)
        self.start = self.get_clock().now()
        self.timer = self.create_timer(PERIOD, self.timer_callback)

    def timer_callback(self) -> None:
        """Where the robot is now: angle = speed * time, facing the direction it drives in."""
        now = self.get_clock().now()
        angle = ANGULAR_SPEED * (now - self.start).nanoseconds * 1e-9
        t = TransformStamped()
        t.header.stamp = now.to_msg()
        t.header.frame_id = 'world'
        t.child_frame_id = 'robot'
        t.transform.translation.x = RADIUS * math.cos(angle)
        t.transform.translation.y = RADIUS * math.sin(angle)
        t.transform.translation.z = 0.0
        qx, qy, qz, qw = yaw_to_quaternion(angle + math.pi / 2.0)
        t.transform.rotation.x = qx
        t.transform.rotation.y = qy
        t.transform.rotation.z = qz
        t.transform.rotation.w = qw
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
