"""Gives nav2 its initial pose estimate: one PoseWithCovarianceStamped on /initialpose, then ends."""

import math

import rclpy
from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.duration import Duration  # noqa: F401 - for publisher.wait_for_all_acked(Duration(seconds=1.0))
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

TOPIC = '/initialpose'
SUBSCRIBERS = 2  # rviz2 and amcl in the real demo
FRAME = 'map'
X, Y = -2.1, -0.3  # metres, in the map frame; no rotation
XY_VARIANCE = 0.25  # square metres
YAW_VARIANCE = (math.pi / 12) ** 2  # square radians (0.0685...), as rviz2 sends


class Nav2InitialPosePublisherNode(Node):
    """Waits for two subscribers on /initialpose, publishes the pose once, then sets ``done``."""

    def __init__(self) -> None:
        super().__init__('nav2_initial_pose_publisher_node')
        self.publisher = self.create_publisher(PoseWithCovarianceStamped, TOPIC, 1)
        self.done = False
        # TODO 3: a timer (every 0.1 s) whose callback waits for the subscribers, then publishes once

    # TODO 4: timer_callback: while self.publisher.get_subscription_count() < SUBSCRIBERS, log that
    #         you wait (throttle_duration_sec=1.0) and return; then cancel the timer, publish
    #         self.initial_pose() once, wait_for_all_acked, and set self.done

    def initial_pose(self) -> PoseWithCovarianceStamped:
        """The pose, stamped now, with its 6x6 covariance (row-major: x, y, z, roll, pitch, yaw)."""
        message = PoseWithCovarianceStamped()
        # TODO 5: the stamp (the node's clock, now) and the frame
        # TODO 6: the position (X, Y, 0) and the orientation (no rotation: w = 1.0); mind the two .pose
        # TODO 7: the covariance: 36 numbers, 0 except x's variance, y's and the yaw's
        return message


def main(args=None) -> None:
    """Spin until the pose is out (or Ctrl+C)."""
    try:
        rclpy.init(args=args)
        node = Nav2InitialPosePublisherNode()
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
