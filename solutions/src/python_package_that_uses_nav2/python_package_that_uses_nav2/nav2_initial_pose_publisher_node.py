"""Gives nav2 its initial pose estimate: one PoseWithCovarianceStamped on /initialpose, then ends.

nav2's localisation (amcl) and rviz2 both subscribe to /initialpose; a message published
before they listen is lost (the topic is VOLATILE), so the node waits for two subscribers.
"""

import math

import rclpy
from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

TOPIC = '/initialpose'
SUBSCRIBERS = 2  # rviz2 and amcl in the real demo
FRAME = 'map'
X, Y = -2.1, -0.3  # metres, in the map frame; facing along the map's x axis (no rotation)
XY_VARIANCE = 0.25  # square metres: a standard deviation of 0.5 m on x and on y
YAW_VARIANCE = (math.pi / 12) ** 2  # square radians: 15 degrees of standard deviation, as rviz2 sends


class Nav2InitialPosePublisherNode(Node):
    """Waits for two subscribers on /initialpose, publishes the pose once, then sets ``done``."""

    def __init__(self) -> None:
        super().__init__('nav2_initial_pose_publisher_node')
        self.publisher = self.create_publisher(PoseWithCovarianceStamped, TOPIC, 1)
        self.done = False
        self.timer = self.create_timer(0.1, self.timer_callback)

    def timer_callback(self) -> None:
        """Until two nodes listen, say so (once a second); then publish once."""
        count = self.publisher.get_subscription_count()
        if count < SUBSCRIBERS:
            self.get_logger().info(f'{count} of {SUBSCRIBERS} subscribers on {TOPIC}, waiting...',
                                   throttle_duration_sec=1.0)
            return
        self.timer.cancel()
        message = self.initial_pose()
        self.publisher.publish(message)
        self.get_logger().info(f'Initial pose published in {FRAME}: ({X:.2f}, {Y:.2f})')
        # RELIABLE: give every subscriber a moment to confirm it got the message before the node goes
        self.publisher.wait_for_all_acked(Duration(seconds=1.0))
        self.done = True

    def initial_pose(self) -> PoseWithCovarianceStamped:
        """The pose, stamped now, with its 6x6 covariance (row-major: x, y, z, roll, pitch, yaw)."""
        message = PoseWithCovarianceStamped()
        message.header.stamp = self.get_clock().now().to_msg()
        message.header.frame_id = FRAME
        message.pose.pose.position.x = X
        message.pose.pose.position.y = Y
        message.pose.pose.orientation.w = 1.0
        covariance = [0.0] * 36
        covariance[0] = XY_VARIANCE  # row x, column x
        covariance[7] = XY_VARIANCE  # row y, column y
        covariance[35] = YAW_VARIANCE  # row yaw, column yaw
        message.pose.covariance = covariance
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
